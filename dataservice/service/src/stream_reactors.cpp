// The server-streaming calls Read and Fetch: one reactor per call, writing
// the chunks of a hyperslab read or of a file as stored, one at a time.
#include <atomic>
#include <cstring>
#include <mutex>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "data_service.hpp"
#include "data_service_internal.hpp"
#include "describe_proto.hpp"
#include <crackvis/dataservice_protocol/packed_chunk.hpp>

namespace crackvis::dataservice {
namespace v1 = crackvis::v1;
using Clock = std::chrono::steady_clock;

namespace {

// Longer dataset paths are refused before any lookup (HDF5 names are short;
// a huge one is an attack, and must not come back in a message).
constexpr std::size_t kMaxDatasetPathBytes = 4096;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

Clock::time_point deadlineAfter(double seconds) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// ------------------------------------------------------------ conversion --

std::vector<Hyperslab> fromProto(const v1::ReadRequest& request) {
  std::vector<Hyperslab> slabs;
  slabs.reserve(static_cast<size_t>(request.slabs_size()));
  for (const v1::Hyperslab& slab : request.slabs()) {
    slabs.push_back({slab.dataset(),
                     {slab.start().begin(), slab.start().end()},
                     {slab.count().begin(), slab.count().end()}});
  }
  return slabs;
}

// Dataset paths are checked here, before the catalogue sees them: a NUL
// would cut the name HDF5 looks up short.
Status checkDatasetPaths(const v1::ReadRequest& request) {
  for (int i = 0; i < request.slabs_size(); ++i) {
    const std::string& dataset = request.slabs(i).dataset();
    if (dataset.find('\0') != std::string::npos) {
      return invalidArgument(
          fmt::format("Read of {}: hyperslab {}: the dataset path '{}' "
                      "contains a NUL character",
                      echoed(request.file()), i, echoed(dataset)));
    }
    if (dataset.size() > kMaxDatasetPathBytes) {
      return invalidArgument(
          fmt::format("Read of {}: hyperslab {}: the dataset path '{}' is over {} bytes",
                      echoed(request.file()), i, echoed(dataset), kMaxDatasetPathBytes));
    }
  }
  return Status::ok();
}

// ------------------------------------------------------------- streaming --

// The bulk bytes of one chunk, handed to gRPC inside a slice that frees
// them when gRPC is done with them.
static_assert(kStreamBufferBytes >= kMaxChunkBytes + 64,
              "a stream's reservation covers one chunk and its header");

// Chunk buffers kept for the next chunk. A fresh 1 MiB buffer is mapped
// anew by malloc and page-faults on every page the read writes into: a
// fifth of a view's Read and a tenth of a Fetch on the server
// (docs/benchmarks.md). Buffers come back when gRPC has sent their slice;
// at most kKept idle ones are held (16 MiB beyond the streams' reservations).
class ChunkPool {
 public:
  static char* take() {
    {
      const std::lock_guard lock(mutex());
      if (!idle().empty()) {
        char* buffer = idle().back();
        idle().pop_back();
        return buffer;
      }
    }
    return new char[kMaxChunkBytes];
  }
  static void give(void* buffer) {
    {
      const std::lock_guard lock(mutex());
      if (idle().size() < kKept) {
        idle().push_back(static_cast<char*>(buffer));
        return;
      }
    }
    delete[] static_cast<char*>(buffer);
  }

 private:
  static constexpr std::size_t kKept = 16;
  // Never destroyed: gRPC may hand a buffer back while the process exits,
  // and the held buffers stay reachable rather than leaked.
  static std::mutex& mutex() {
    static auto* instance = new std::mutex;
    return *instance;
  }
  static std::vector<char*>& idle() {
    static auto* instance = new std::vector<char*>;
    return *instance;
  }
};

class ChunkData {
 public:
  explicit ChunkData(std::size_t size) : m_data(ChunkPool::take()), m_size(size) {}
  ChunkData(ChunkData&& other) noexcept
      : m_data(std::exchange(other.m_data, nullptr)), m_size(other.m_size) {}
  ChunkData(const ChunkData&) = delete;
  ChunkData& operator=(const ChunkData&) = delete;
  ChunkData& operator=(ChunkData&&) = delete;
  ~ChunkData() {
    if (m_data != nullptr) {
      ChunkPool::give(m_data);
    }
  }
  char* data() { return m_data; }
  std::size_t size() const { return m_size; }
  void shrink(std::size_t size) { m_size = std::min(m_size, size); }
  grpc::Slice release() {
    return grpc::Slice(std::exchange(m_data, nullptr), m_size, &ChunkPool::give);
  }

 private:
  char* m_data;  // kMaxChunkBytes, from the pool
  std::size_t m_size;
};

// A serialized chunk message: `header` is the message without its bytes
// field, `field` that field's number; the data follows as the field's value.
grpc::ByteBuffer chunkMessage(std::string header, int field, ChunkData data) {
  header += static_cast<char>((field << 3) | 2);  // length-delimited
  for (std::uint64_t length = data.size();; length >>= 7) {
    if (length < 0x80) {
      header += static_cast<char>(length);
      break;
    }
    header += static_cast<char>((length & 0x7f) | 0x80);
  }
  grpc::Slice slices[2] = {grpc::Slice(header), data.release()};
  return grpc::ByteBuffer(slices, 2);
}

// Common to Read and Fetch: one stream slot, the time limit, the access
// record, and the Finish-once bookkeeping of a write reactor.
class StreamReactor : public grpc::ServerWriteReactor<grpc::ByteBuffer> {
 public:
  StreamReactor(DataServiceImpl& service, grpc::CallbackServerContext* context, const char* method)
      : m_service(service), m_context(context), m_start(Clock::now()) {
    m_record.method = method;
  }

  void OnWriteDone(bool ok) override {
    if (!ok) {
      // The client went away or the call was cancelled (by the client's
      // deadline or the server's time limit).
      finish(cancelled(cancelReason()), grpc::Status::CANCELLED);
      return;
    }
    m_record.bytes += m_pendingBytes;
    m_pendingBytes = 0;
    if (secondsSince(m_start) > m_service.limits().maxCallSeconds) {
      finish(resourceExhausted(fmt::format("{} of {} exceeded the server's limit of {} s per call",
                                           m_record.method, echoed(m_record.file),
                                           m_service.limits().maxCallSeconds)));
      return;
    }
    step();
  }

  void OnCancel() override { m_cancelled = true; }

  void OnDone() override {
    releaseSlot();
    delete this;
  }

 protected:
  // Parses the request and opens the stream (open() of the subclass), then
  // sends the first chunk; a failure or an exception ends only this call.
  template <typename Request>
  void start(const grpc::ByteBuffer& buffer) {
    bool opened = false;
    const Status status = rpc::guarded(kProgram, m_record, [&] {
      Request request;
      CRACKVIS_RETURN_IF_ERROR(parseRequest(&buffer, request));
      CRACKVIS_RETURN_IF_ERROR(open(request));
      opened = true;
      return Status::ok();
    });
    if (!opened) {
      finish(status.isOk() ? internalError("the stream did not open") : status);
      return;
    }
    step();
  }

  // Authenticates the caller and resolves the file; takes a stream slot.
  Result<ResolvedPath> begin(const std::string& file) {
    m_record.file = file;
    auto caller = m_service.authenticate(m_context, m_record);
    if (!caller) {
      return caller.status();
    }
    auto resolved = m_service.resolveFor(*caller, file);
    if (!resolved) {
      return resolved.status();
    }
    auto slot =
        m_service.streams().acquire(m_context, deadlineAfter(m_service.limits().maxCallSeconds),
                                    caller->restricted ? caller->name : std::string());
    if (!slot) {
      return slot.status();
    }
    m_slot = *slot;
    m_user = caller->name;
    return resolved;
  }

  // Sends a chunk, counting its data bytes once the write completes.
  void write(std::string header, int field, ChunkData data) {
    m_pendingBytes = data.size();
    m_message = chunkMessage(std::move(header), field, std::move(data));
    this->StartWrite(&m_message);
  }

  void finish(const Status& status) {
    releaseSlot();
    this->Finish(rpc::finishCall(m_service.log(), m_record, m_start, status));
  }
  void finish(const Status& logged, const grpc::Status& sent) {
    releaseSlot();
    rpc::finishCall(m_service.log(), m_record, m_start, logged);
    this->Finish(sent);
  }
  // At Finish, not when gRPC is done with the call (OnDone): the client has
  // its status by then and may start its next Read at once (a view's bond
  // list, then its step), which a server with one stream per user would
  // otherwise refuse. Every write has completed: nothing is buffered.
  void releaseSlot() {
    if (m_slot != 0) {
      m_service.streams().release(m_slot);
      m_slot = 0;
    }
  }

  // Who the stream is for (set by begin()): the HDF5 workers share
  // themselves fairly between users.
  const std::string& user() const { return m_user; }

  virtual Status open(const v1::ReadRequest& /*request*/) { return internalError("not a Read"); }
  virtual Status open(const v1::FetchRequest& /*request*/) { return internalError("not a Fetch"); }
  virtual void writeNext() = 0;

 private:
  // writeNext() at the handler boundary: an exception ends only this call.
  void step() {
    bool wrote = false;
    const Status status = rpc::guarded(kProgram, m_record, [&] {
      writeNext();
      wrote = true;
      return Status::ok();
    });
    if (!wrote) {
      finish(status);
    }
  }

 private:
  std::string cancelReason() const {
    if (secondsSince(m_start) > m_service.limits().maxCallSeconds) {
      return fmt::format("cancelled by the server's limit of {} s per call",
                         m_service.limits().maxCallSeconds);
    }
    return m_cancelled ? "cancelled by the client or its deadline" : "client went away";
  }

 protected:
  DataServiceImpl& m_service;
  grpc::CallbackServerContext* m_context;
  std::string m_user;
  Clock::time_point m_start;
  AccessRecord m_record;
  std::uint64_t m_slot = 0;
  std::uint64_t m_pendingBytes = 0;
  grpc::ByteBuffer m_message;
  std::atomic<bool> m_cancelled{false};
};

class ReadReactor final : public StreamReactor {
 public:
  ReadReactor(DataServiceImpl& service, grpc::CallbackServerContext* context,
              const grpc::ByteBuffer& buffer)
      : StreamReactor(service, context, "Read"), m_service(service) {
    start<v1::ReadRequest>(buffer);
  }

 private:
  using StreamReactor::open;
  Status open(const v1::ReadRequest& request) override {
    if (request.slabs_size() > m_service.limits().maxSlabsPerRead) {
      return invalidArgument(fmt::format("Read of {}: {} hyperslabs, the server's limit is {}",
                                         echoed(request.file()), request.slabs_size(),
                                         m_service.limits().maxSlabsPerRead));
    }
    CRACKVIS_RETURN_IF_ERROR(checkDatasetPaths(request));
    auto resolved = begin(request.file());
    if (!resolved) {
      return resolved.status();
    }
    auto plan = m_service.workers().planRead(*resolved, fromProto(request),
                                             m_service.limits().maxReadBytes, user());
    if (!plan) {
      return plan.status();
    }
    m_file = std::move(*resolved);
    m_plan = std::move(*plan);
    for (int encoding : request.accept_encodings()) {
      m_acceptsPacked = m_acceptsPacked || encoding == v1::CHUNK_ENCODING_PACKED;
    }
    return Status::ok();
  }

  // The chunk's fields but its data (field 6).
  std::string header(std::uint64_t offset, std::uint64_t decodedBytes, bool packed) {
    const SlabPlan& slab = m_plan.slabs[m_piece.slab];
    v1::ReadChunk chunk;
    chunk.set_slab_index(static_cast<std::uint32_t>(m_piece.slab));
    chunk.set_dtype(toProto(slab.dtype));
    chunk.mutable_shape()->Add(slab.count.begin(), slab.count.end());
    chunk.set_slab_bytes(slab.bytes);
    chunk.set_offset(offset);
    if (packed) {
      chunk.set_encoding(v1::CHUNK_ENCODING_PACKED);
    }
    chunk.set_decoded_bytes(decodedBytes);
    return chunk.SerializeAsString();
  }

  // Packs the piece in `data` in place when the client accepts packed
  // chunks and that makes it smaller; true when it did.
  bool pack(ChunkData& data) const {
    const SlabPlan& slab = m_plan.slabs[m_piece.slab];
    const DataType dtype = slab.dtype;
    if (!m_acceptsPacked || !packableType(dtype)) {
      return false;
    }
    // The slab's last dimension gives the columns ([M,2] bond pairs: two)
    // when the piece holds whole rows of it; a row split across pieces
    // goes as one column.
    const bool wholeRows = slab.count.size() >= 2 && m_piece.count.size() == slab.count.size() &&
                           m_piece.count.back() == slab.count.back();
    const std::size_t columns = wholeRows && slab.count.back() <= kMaxPackedColumns
                                    ? static_cast<std::size_t>(slab.count.back())
                                    : 1;
    // Packed into a scratch buffer of the thread and copied back (a few
    // hundred KiB): a stream holds one chunk buffer, as its memory
    // reservation counts.
    thread_local std::vector<std::byte> scratch(kMaxChunkBytes);
    const std::size_t packed =
        packChunk(dtype, columns, reinterpret_cast<const std::byte*>(data.data()), data.size(),
                  scratch.data(), scratch.size());
    if (packed == 0) {
      return false;
    }
    std::memcpy(data.data(), scratch.data(), packed);
    data.shrink(packed);
    return true;
  }

  // Every piece is at most one chunk (rows larger than a chunk are split),
  // so a call holds one chunk's buffer whatever the dataset's shape. Each
  // piece is read by whichever HDF5 worker is free.
  void writeNext() override {
    auto piece = m_pieces.next(m_plan.slabs);
    if (!piece) {
      finish(Status::ok());
      return;
    }
    m_piece = std::move(*piece);
    if (m_piece.bytes > kMaxChunkBytes) {  // the planner splits pieces to a chunk
      finish(internalError(fmt::format("a piece of {} bytes is over the chunk size {}",
                                       m_piece.bytes, kMaxChunkBytes)));
      return;
    }
    ChunkData data(m_piece.bytes);
    const bool first = m_first;
    m_first = false;
    if (first && m_plan.firstPiece.size() == m_piece.bytes) {
      // It came with the plan.
      std::memcpy(data.data(), m_plan.firstPiece.data(), m_piece.bytes);
      m_plan.firstPiece = std::string();
    } else if (Status status = m_service.workers().readPiece(m_file, m_plan.slabs[m_piece.slab],
                                                             m_piece, data.data(), user());
               !status) {
      finish(status);
      return;
    }
    const bool packed = pack(data);
    write(header(m_piece.offset, m_piece.bytes, packed), 6, std::move(data));
  }

  DataServiceImpl& m_service;
  ResolvedPath m_file;
  ReadPlan m_plan;
  PieceCursor m_pieces;
  bool m_acceptsPacked = false;
  bool m_first = true;
  Piece m_piece;
};

class FetchReactor final : public StreamReactor {
 public:
  FetchReactor(DataServiceImpl& service, grpc::CallbackServerContext* context,
               const grpc::ByteBuffer& buffer)
      : StreamReactor(service, context, "Fetch"), m_service(service) {
    start<v1::FetchRequest>(buffer);
  }

 private:
  using StreamReactor::open;
  Status open(const v1::FetchRequest& request) override {
    auto resolved = begin(request.file());
    if (!resolved) {
      return resolved.status();
    }
    auto reader = m_service.catalogue().openFetch(*resolved, m_service.limits().maxFetchBytes);
    if (!reader) {
      return reader.status();
    }
    m_reader = std::move(*reader);
    return Status::ok();
  }

  void writeNext() override {
    if (m_offset >= m_reader->size()) {
      finish(Status::ok());
      return;
    }
    ChunkData data(
        static_cast<size_t>(std::min<std::uint64_t>(kMaxChunkBytes, m_reader->size() - m_offset)));
    auto got = m_reader->readAt(m_offset, data.data(), data.size());
    if (!got) {
      finish(got.status());
      return;
    }
    if (*got == 0) {
      finish(failedPrecondition("the file shrank while it was being sent"));
      return;
    }
    data.shrink(*got);
    v1::FetchChunk chunk;  // the fields but data (field 3)
    chunk.set_file_bytes(m_reader->size());
    chunk.set_offset(m_offset);
    m_offset += *got;
    write(chunk.SerializeAsString(), 3, std::move(data));
  }

  DataServiceImpl& m_service;
  std::unique_ptr<FileReader> m_reader;
  std::uint64_t m_offset = 0;
};

}  // namespace

grpc::ServerWriteReactor<grpc::ByteBuffer>* DataServiceImpl::Read(
    grpc::CallbackServerContext* context, const grpc::ByteBuffer* request) {
  return new ReadReactor(*this, context, *request);
}

grpc::ServerWriteReactor<grpc::ByteBuffer>* DataServiceImpl::Fetch(
    grpc::CallbackServerContext* context, const grpc::ByteBuffer* request) {
  return new FetchReactor(*this, context, *request);
}

}  // namespace crackvis::dataservice
