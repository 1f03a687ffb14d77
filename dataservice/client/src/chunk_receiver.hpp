// The receiving end of a Read (private to the client library): each chunk
// as gRPC hands it over, parsed without a copy and its data put straight
// into the caller's buffer for its slab (DataClient::SlabSink), checked
// against the slab it belongs to.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <grpcpp/support/byte_buffer.h>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_client/data_client.hpp>

namespace crackvis::dataservice {

// Where the chunks of one Read go: each chunk is checked against its slab
// (in byte order, inside the slab), and a slab's buffer is asked of the sink
// when its first chunk announces its dtype, shape and size.
class SlabReceiver {
 public:
  struct ChunkHeader {
    std::uint64_t slabIndex = 0;
    int dtype = 0;
    std::vector<std::uint64_t> shape;
    std::uint64_t slabBytes = 0;
    std::uint64_t offset = 0;
    int encoding = 0;  // v1::ChunkEncoding
    std::optional<std::uint64_t> decodedBytes;
  };

  SlabReceiver(const DataClient::SlabSink& sink, std::size_t slabs, bool acceptsPacked)
      : m_sink(sink), m_destinations(slabs), m_acceptsPacked(acceptsPacked) {}

  // Whether the request listed CHUNK_ENCODING_PACKED.
  bool acceptsPacked() const { return m_acceptsPacked; }

  // Where the `size` data bytes of the chunk `header` describes go.
  Result<std::byte*> place(const ChunkHeader& header, std::uint64_t size);

  // Every slab that started arrived whole.
  Status complete() const;

 private:
  struct Destination {
    std::byte* data = nullptr;
    std::uint64_t bytes = 0;
    std::uint64_t received = 0;
    bool started = false;
  };
  const DataClient::SlabSink& m_sink;
  std::vector<Destination> m_destinations;
  bool m_acceptsPacked;
};

// Where one chunk's data went.
struct PlacedChunk {
  std::size_t slab = 0;
  std::uint64_t offset = 0;
  std::uint64_t bytes = 0;      // in the slab
  std::uint64_t wireBytes = 0;  // as it came (fewer when packed)
};

// Parses one serialized ReadChunk and copies its data from gRPC's receive
// buffers straight into the slab's buffer. Parsing into a v1::ReadChunk
// would first copy the data into the message's string, one more pass over
// every byte, which is a tenth of the client's CPU time on a view's Read.
// The fields are read as protobuf defines them: in any order, shape packed
// or not, unknown fields skipped, the last value of a field winning. The
// data goes straight to its place when it is the last field (the server
// always sends it last), so that no later field can change where it goes;
// otherwise it is held until the message has been read.
Result<PlacedChunk> receiveChunk(grpc::ByteBuffer& message, SlabReceiver& receiver);

}  // namespace crackvis::dataservice
