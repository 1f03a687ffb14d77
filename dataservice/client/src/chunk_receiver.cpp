#include "chunk_receiver.hpp"

#include <climits>
#include <string>

#include <fmt/format.h>
#include <google/protobuf/io/coded_stream.h>
#include <grpcpp/support/proto_buffer_reader.h>

#include "crackvis/v1/data.pb.h"
#include <crackvis/dataservice_protocol/packed_chunk.hpp>

namespace crackvis::dataservice {
namespace v1 = crackvis::v1;

Result<std::byte*> SlabReceiver::place(const ChunkHeader& header, std::uint64_t size) {
  const std::uint64_t index = header.slabIndex;
  if (index >= m_destinations.size()) {
    return internalError(
        fmt::format("Read: chunk for slab {} of {}", index, m_destinations.size()));
  }
  Destination& destination = m_destinations[index];
  if (!destination.started) {
    DataClient::SlabHeader slab{static_cast<std::size_t>(index), dataTypeFromInt(header.dtype),
                                header.shape, header.slabBytes};
    std::uint64_t expected = elementSize(slab.dtype);
    for (auto d : slab.shape) {
      expected *= d;
    }
    if (expected != slab.bytes) {
      return internalError(
          fmt::format("Read: slab {} announces {} bytes for its shape and dtype, expected {}",
                      index, slab.bytes, expected));
    }
    auto buffer = m_sink(slab);
    if (!buffer) {
      return buffer.status();
    }
    destination = {*buffer, slab.bytes, 0, true};
  }
  if (header.offset != destination.received || size > destination.bytes - destination.received) {
    return internalError(fmt::format("Read: slab {}: chunk at offset {} out of order or too long",
                                     index, header.offset));
  }
  destination.received += size;
  return destination.data + header.offset;
}

Status SlabReceiver::complete() const {
  for (std::size_t i = 0; i < m_destinations.size(); ++i) {
    const Destination& destination = m_destinations[i];
    if (destination.started && destination.received != destination.bytes) {
      return internalError(fmt::format("Read: slab {} ended after {} of {} bytes", i,
                                       destination.received, destination.bytes));
    }
  }
  return Status::ok();
}

namespace {

// Protobuf's wire types (the low three bits of a tag), spelled out here
// rather than taken from protobuf's internal namespace.
enum WireType : std::uint32_t { kVarint = 0, kFixed64 = 1, kLengthDelimited = 2, kFixed32 = 5 };

// Skips a field this client does not read; false for a malformed one (and
// for groups, which proto3 messages never hold).
bool skipField(google::protobuf::io::CodedInputStream& input, std::uint32_t wire) {
  switch (wire) {
    case kVarint: {
      std::uint64_t ignored = 0;
      return input.ReadVarint64(&ignored);
    }
    case kFixed64:
      return input.Skip(8);
    case kLengthDelimited: {
      std::uint32_t length = 0;
      return input.ReadVarint32(&length) && length <= static_cast<std::uint32_t>(INT32_MAX) &&
             input.Skip(static_cast<int>(length));
    }
    case kFixed32:
      return input.Skip(4);
    default:
      return false;
  }
}

// The data of one chunk in its place: RAW bytes copied straight from
// gRPC's buffers, PACKED ones unpacked from them (or, when they span
// buffers, from a copy).
Result<PlacedChunk> placeData(const SlabReceiver::ChunkHeader& header, std::uint32_t wireBytes,
                              google::protobuf::io::CodedInputStream& input,
                              SlabReceiver& receiver) {
  if (header.encoding == v1::CHUNK_ENCODING_RAW) {
    if (header.decodedBytes && *header.decodedBytes != wireBytes) {
      return internalError(fmt::format("Read: slab {}: a raw chunk of {} bytes says it holds {}",
                                       header.slabIndex, wireBytes, *header.decodedBytes));
    }
    auto place = receiver.place(header, wireBytes);
    if (!place) {
      return place.status();
    }
    if (!input.ReadRaw(*place, static_cast<int>(wireBytes))) {
      return internalError(fmt::format("Read: slab {}: chunk cut short", header.slabIndex));
    }
    return PlacedChunk{header.slabIndex, header.offset, wireBytes, wireBytes};
  }
  if (header.encoding != v1::CHUNK_ENCODING_PACKED) {
    return internalError(fmt::format("Read: slab {}: chunk in an unknown encoding {}",
                                     header.slabIndex, header.encoding));
  }
  if (!receiver.acceptsPacked()) {
    return internalError(fmt::format(
        "Read: slab {}: a packed chunk, which the request did not accept", header.slabIndex));
  }
  // A packed chunk is smaller than the at most 1 MiB it decodes to, so
  // neither a copy nor the slab grows beyond what a raw chunk could ask.
  if (!header.decodedBytes || *header.decodedBytes > kMaxChunkBytes ||
      wireBytes >= *header.decodedBytes) {
    return internalError(fmt::format(
        "Read: slab {}: a packed chunk of {} bytes says it holds {} (at most {}, and more than "
        "it takes)",
        header.slabIndex, wireBytes, header.decodedBytes.value_or(0), kMaxChunkBytes));
  }
  const std::uint64_t decoded = *header.decodedBytes;
  auto place = receiver.place(header, decoded);
  if (!place) {
    return place.status();
  }
  const void* direct = nullptr;
  int available = 0;
  const std::byte* packed = nullptr;
  thread_local std::vector<std::byte> copy;
  if (input.GetDirectBufferPointer(&direct, &available) &&
      static_cast<std::uint32_t>(available) >= wireBytes) {
    packed = static_cast<const std::byte*>(direct);
  } else {
    copy.resize(wireBytes);
    if (!input.ReadRaw(copy.data(), static_cast<int>(wireBytes))) {
      return internalError(fmt::format("Read: slab {}: chunk cut short", header.slabIndex));
    }
    packed = copy.data();
    direct = nullptr;
  }
  if (Status unpacked =
          unpackChunk(dataTypeFromInt(header.dtype), packed, wireBytes, *place, decoded);
      !unpacked) {
    return internalError(fmt::format("Read: slab {}: chunk at offset {}: {}", header.slabIndex,
                                     header.offset, unpacked.message()));
  }
  if (direct != nullptr) {
    input.Skip(static_cast<int>(wireBytes));
  }
  return PlacedChunk{header.slabIndex, header.offset, decoded, wireBytes};
}

}  // namespace

Result<PlacedChunk> receiveChunk(grpc::ByteBuffer& message, SlabReceiver& receiver) {
  const std::size_t total = message.Length();
  grpc::ProtoBufferReader stream(&message);
  google::protobuf::io::CodedInputStream input(&stream);
  SlabReceiver::ChunkHeader header;
  bool hasData = false;
  std::uint32_t dataSize = 0;
  std::string heldData;
  bool ok = stream.status().ok();
  while (ok) {
    const std::uint32_t tag = input.ReadTag();
    if (tag == 0) {
      break;  // the end of the message, or a malformed tag (checked below)
    }
    const std::uint32_t field = tag >> 3;
    const std::uint32_t wire = tag & 7;
    if (wire == kVarint && ((field >= 1 && field <= 5) || field == 7 || field == 8)) {
      std::uint64_t value = 0;
      ok = input.ReadVarint64(&value);
      switch (field) {
        case 1:  // slab_index, uint32: protobuf keeps the low 32 bits
          header.slabIndex = static_cast<std::uint32_t>(value);
          break;
        case 2:  // dtype, an enum (int32)
          header.dtype = static_cast<int>(static_cast<std::int32_t>(value));
          break;
        case 3:  // shape, one unpacked element
          header.shape.push_back(value);
          break;
        case 4:
          header.slabBytes = value;
          break;
        case 5:
          header.offset = value;
          break;
        case 7:  // encoding, an enum (int32)
          header.encoding = static_cast<int>(static_cast<std::int32_t>(value));
          break;
        case 8:
          header.decodedBytes = value;
          break;
      }
    } else if (wire == kLengthDelimited && field == 3) {
      std::uint32_t length = 0;  // shape, packed
      ok = input.ReadVarint32(&length) && length <= total;
      if (ok) {
        const auto limit = input.PushLimit(static_cast<int>(length));
        while (ok && input.BytesUntilLimit() > 0) {
          std::uint64_t value = 0;
          ok = input.ReadVarint64(&value);
          header.shape.push_back(value);
        }
        input.PopLimit(limit);
      }
    } else if (wire == kLengthDelimited && field == 6) {
      ok = input.ReadVarint32(&dataSize) && dataSize <= total;
      hasData = ok;
      heldData.clear();
      if (ok && static_cast<std::size_t>(input.CurrentPosition()) + dataSize == total) {
        return placeData(header, dataSize, input, receiver);  // data came last
      }
      if (ok) {
        heldData.resize(dataSize);
        ok = input.ReadRaw(heldData.data(), static_cast<int>(dataSize));
      }
    } else {
      ok = skipField(input, wire);
    }
  }
  if (!ok || static_cast<std::size_t>(input.CurrentPosition()) != total) {
    return internalError(fmt::format("Read: malformed chunk of {} bytes", total));
  }
  // A chunk without data, or with its data before other fields: placed from
  // the held copy once every field is known.
  google::protobuf::io::CodedInputStream held(
      reinterpret_cast<const std::uint8_t*>(heldData.data()), static_cast<int>(heldData.size()));
  return placeData(header, hasData ? dataSize : 0, held, receiver);
}

}  // namespace crackvis::dataservice
