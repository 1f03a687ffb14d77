// The typed client of crackvis-data for the rest of crackvis (the render
// server, the bench command, tests). Connects once with mutual TLS and turns
// the DataService's calls into typed arrays and Status errors; no gRPC type
// appears in this header (the relay calls for crackvis-render take the wire
// messages of crackvis/v1/data.pb.h, only declared here).
//
// A DataClient is cheap to copy (copies share one channel) and safe to use
// from several threads at once; each call has the options' deadline.
#pragma once

#include <bit>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_protocol/types.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::v1 {
class ListFilesRequest;
class ListFilesResponse;
class DescribeRequest;
class DescribeResponse;
}  // namespace crackvis::v1

namespace crackvis::dataservice {

struct ClientOptions {
  std::string target = "localhost:50051";  // host:port of crackvis-data
  tls::TlsFiles tls =
      tls::defaultTlsFiles("client");  // certs/generated/{ca,client}.pem, client.key
  bool insecure = false;               // plaintext, for a server started with --insecure
  std::string token;                   // sent as "authorization: Bearer <token>"
  std::string user;                    // with `password`: sent as Basic credentials
  std::string password;
  std::string serverName;         // name the server certificate must carry; default: target's host
  double timeoutSeconds = 120.0;  // deadline of each call
  // Accept Read chunks of integers packed to a few bits a value (lossless;
  // docs/protocol.md "Packed chunks"). Off: every chunk comes as raw bytes,
  // for comparison.
  bool packedReads = true;
};

// One hyperslab as received: its elements in C order, little-endian.
struct TypedArray {
  std::string dataset;
  DataType dtype = DataType::kUnspecified;
  std::vector<std::uint64_t> shape;
  std::vector<std::byte> bytes;

  std::uint64_t elementCount() const {
    std::uint64_t count = 1;
    for (auto d : shape) {
      count *= d;
    }
    return count;
  }

  // The values as T; INVALID_ARGUMENT when T is not the array's dtype.
  template <typename T>
  Result<std::vector<T>> values() const {
    static_assert(std::endian::native == std::endian::little,
                  "arrays arrive little-endian; a big-endian host must swap them");
    if (dataTypeOf<T>() != dtype) {
      return invalidArgument(fmt::format("{} holds {}, not {}", dataset, dataTypeName(dtype),
                                         dataTypeName(dataTypeOf<T>())));
    }
    std::vector<T> out(bytes.size() / sizeof(T));
    if (!out.empty()) {
      std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
    }
    return out;
  }
};

class DataClient {
 public:
  // Reads the TLS files (FAILED_PRECONDITION naming a missing or bad one) and
  // creates the channel; the connection is made on the first call.
  static Result<DataClient> connect(const ClientOptions& options);

  const ClientOptions& options() const;
  // Starts making the connection (TCP and the TLS handshake) now, without
  // waiting for it, so that the first call finds it made. A server that is
  // not up yet is tried again, about 5 s apart at most.
  void startConnecting() const;
  // Whether the connection is made and ready for calls now.
  bool connected() const;
  // The data bytes all Reads of this client (and its copies) have received
  // so far as they travelled, packed or not: for benchmarks.
  std::uint64_t readWireBytes() const;

  // grpc.health.v1 Check: OK when the server reports SERVING. Health is
  // served by crackvis-render too: a failure's message names neither.
  Status checkHealth(const std::string& service = "") const;
  // Which crackvis server answers ("crackvis-data", "crackvis-render"), as
  // its health service tells; empty when it names neither.
  std::string serverProgram() const;
  Result<std::vector<FileEntry>> listFiles(const std::string& folder = "",
                                           bool recursive = true) const;
  // `uncached`: the server walks the file even when it holds an answer for
  // it unchanged (what a file's first Describe costs; for benchmarks).
  Result<FileDescription> describe(const std::string& file, bool uncached = false) const;
  // All slabs in one call; the arrays come back in request order.
  Result<std::vector<TypedArray>> read(const std::string& file,
                                       const std::vector<Hyperslab>& slabs) const;
  // The same call, with the bytes going straight where the caller wants
  // them: `sink` is called once per slab, when its first chunk announces its
  // dtype, shape and size, and returns a buffer of exactly `bytes` bytes (or
  // an error that ends the call). A slab of zero bytes gets no call.
  struct SlabHeader {
    std::size_t index = 0;
    DataType dtype = DataType::kUnspecified;
    std::vector<std::uint64_t> shape;
    std::uint64_t bytes = 0;
  };
  using SlabSink = std::function<Result<std::byte*>(const SlabHeader& slab)>;
  Status readInto(const std::string& file, const std::vector<Hyperslab>& slabs,
                  const SlabSink& sink) const;
  // readInto in two steps: startRead() sends the request and returns at
  // once, so the caller can allocate its buffers while the server opens the
  // file and reads the first piece; receive() then takes the chunks.
  class PendingRead;
  PendingRead startRead(const std::string& file, const std::vector<Hyperslab>& slabs) const;
  // Streams the whole file to `sink` (offset, bytes, file size) in chunks of
  // at most 1 MiB; returns the bytes received. A sink error ends the call.
  using FetchSink = std::function<Status(std::uint64_t offset, const std::byte* data,
                                         std::size_t size, std::uint64_t fileBytes)>;
  Result<std::uint64_t> fetch(const std::string& file, const FetchSink& sink) const;

  // For crackvis-render, which applies its callers' folder rules to what
  // crackvis-data says and passes crackvis-data's answers on. Each call ends
  // at `deadline` (its own caller's) or at the options' timeout, whichever
  // comes first; a failure names the call "crackvis-data <call>", for a
  // client that never called crackvis-data itself, with the same
  // connection advice as the other calls.
  using Deadline = std::chrono::system_clock::time_point;
  // The real file a normalized path leads to, from the data root, after
  // symlinks.
  Result<std::string> resolve(const std::string& file, Deadline deadline) const;
  // ListFiles and Describe as the messages travel.
  Status relayListFiles(const v1::ListFilesRequest& request, v1::ListFilesResponse& response,
                        Deadline deadline) const;
  Status relayDescribe(const v1::DescribeRequest& request, v1::DescribeResponse& response,
                       Deadline deadline) const;

 private:
  struct Impl;
  explicit DataClient(std::shared_ptr<Impl> impl) : m_impl(std::move(impl)) {}
  std::shared_ptr<Impl> m_impl;
};

// A Read whose request is on its way (DataClient::startRead). Dropping it
// without receive() cancels the call.
class DataClient::PendingRead {
 public:
  PendingRead(PendingRead&&) noexcept;
  PendingRead& operator=(PendingRead&&) noexcept;
  ~PendingRead();

  // Called after each chunk's bytes are in place: the slab's index, the
  // offset of the chunk's first byte in the slab and its size. Chunks of a
  // slab come in byte order, so a caller can check the data while it is
  // still in the cache; an error ends the call.
  using ChunkCallback =
      std::function<Status(std::size_t slab, std::uint64_t offset, std::uint64_t bytes)>;
  // Receives the whole Read as readInto does; once only.
  Status receive(const SlabSink& sink, const ChunkCallback& arrived = {});

 private:
  friend class DataClient;
  struct Call;
  explicit PendingRead(std::unique_ptr<Call> call);
  std::unique_ptr<Call> m_call;
};

}  // namespace crackvis::dataservice
