// The DataService handlers (private to the service library). Each handler
// checks the caller, validates the request, converts it to catalogue types,
// calls the catalogue and converts the result back; toGrpcStatus() is the one
// place where a crackvis Status becomes a grpc::Status.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>

#include <grpcpp/grpcpp.h>

#include "crackvis/v1/data.grpc.pb.h"
#include "describe_cache.hpp"
#include "hdf5_workers.hpp"
#include "walk_threads.hpp"
#include <crackvis/dataservice_config/server_config.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/rpc_server/access_log.hpp>
#include <crackvis/rpc_server/call.hpp>
#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::dataservice {

using rpc::AccessLog;
using rpc::AccessRecord;
using rpc::Authenticator;
using rpc::Caller;
using rpc::toGrpcStatus;  // the one mapping, shared with the render service

// The streams in progress: counts them against the limits (server-wide and
// per user), and cancels those
// that run past their time limit even when the client has stopped reading
// (a stalled client never triggers another write callback).
class StreamRegistry {
 public:
  using Clock = std::chrono::steady_clock;

  StreamRegistry(int limit, int perUserLimit, std::uint64_t memoryLimit)
      : m_limit(limit), m_perUserLimit(perUserLimit), m_memoryLimit(memoryLimit) {}

  // `user` is counted against the per-user limit; "" (users off): none.
  // Each stream reserves kStreamBufferBytes of the memory budget until it is
  // released.
  Result<std::uint64_t> acquire(grpc::CallbackServerContext* context, Clock::time_point deadline,
                                const std::string& user);
  void release(std::uint64_t id);
  // Cancels every stream past its deadline; returns how many.
  int cancelOverdue(Clock::time_point now);
  int active() const;
  std::uint64_t reservedBytes() const;

 private:
  struct Entry {
    grpc::CallbackServerContext* context = nullptr;
    Clock::time_point deadline;
    bool cancelled = false;
    std::string user;
  };
  const int m_limit;
  const int m_perUserLimit;
  const std::uint64_t m_memoryLimit;
  std::uint64_t m_reservedBytes = 0;
  std::map<std::string, int> m_perUser;
  mutable std::mutex m_mutex;
  std::map<std::uint64_t, Entry> m_entries;
  std::uint64_t m_nextId = 1;
};

// Read and Fetch are raw methods: their chunks are written as a small
// serialized header followed by the data in a slice gRPC takes over, so the
// bulk bytes are not copied once more by protobuf serialization. Describe
// is raw too: a held answer goes out as the bytes it is held as, not parsed
// and serialized again on every call.
using DataServiceBase = crackvis::v1::DataService::WithRawCallbackMethod_Read<
    crackvis::v1::DataService::WithRawCallbackMethod_Fetch<
        crackvis::v1::DataService::WithRawCallbackMethod_Describe<
            crackvis::v1::DataService::CallbackService>>>;

class DataServiceImpl final : public DataServiceBase {
 public:
  // Every HDF5 call goes to `workers`; the catalogue here only lists files
  // and streams them as stored.
  DataServiceImpl(Catalogue catalogue, Hdf5Workers& workers, Authenticator& authenticator,
                  const Limits& limits, AccessLog& log)
      : m_catalogue(std::move(catalogue)),
        m_workers(workers),
        m_authenticator(authenticator),
        m_limits(limits),
        m_log(log),
        m_streams(limits.maxConcurrentStreams, limits.maxStreamsPerUser, limits.maxMemoryBytes),
        m_descriptions(limits.describeCacheBytes) {}

  grpc::ServerUnaryReactor* ListFiles(grpc::CallbackServerContext* context,
                                      const crackvis::v1::ListFilesRequest* request,
                                      crackvis::v1::ListFilesResponse* response) override;
  using DataServiceBase::Describe;
  grpc::ServerUnaryReactor* Describe(grpc::CallbackServerContext* context,
                                     const grpc::ByteBuffer* request,
                                     grpc::ByteBuffer* response) override;
  grpc::ServerUnaryReactor* Resolve(grpc::CallbackServerContext* context,
                                    const crackvis::v1::ResolveRequest* request,
                                    crackvis::v1::ResolveResponse* response) override;
  using DataServiceBase::Fetch;
  using DataServiceBase::Read;
  grpc::ServerWriteReactor<grpc::ByteBuffer>* Read(grpc::CallbackServerContext* context,
                                                   const grpc::ByteBuffer* request) override;
  grpc::ServerWriteReactor<grpc::ByteBuffer>* Fetch(grpc::CallbackServerContext* context,
                                                    const grpc::ByteBuffer* request) override;

  // Shared by the handlers and the stream reactors.
  const Catalogue& catalogue() const { return m_catalogue; }
  Hdf5Workers& workers() { return m_workers; }
  const Limits& limits() const { return m_limits; }
  AccessLog& log() { return m_log; }
  StreamRegistry& streams() { return m_streams; }
  // Checks the caller's credentials; fills the record's user and peer.
  Result<Caller> authenticate(grpc::CallbackServerContext* context, AccessRecord& record) const;
  // Resolves a file for a caller: path rules, then the caller's folders.
  Result<ResolvedPath> resolveFor(const Caller& caller, const std::string& path) const;

 private:
  // A unary call: its access-log line, the handler boundary, the status;
  // `body(caller, record)` handles it.
  template <typename Body>
  grpc::ServerUnaryReactor* unaryCall(grpc::CallbackServerContext* context, const char* method,
                                      const std::string& file, Body&& body);
  // The same with a typed response, whose size the record gets.
  template <typename Body>
  grpc::ServerUnaryReactor* unary(grpc::CallbackServerContext* context, const char* method,
                                  const std::string& file,
                                  const google::protobuf::Message& response, Body&& body);
  // Describe's walk of a file in an HDF5 worker, on a thread of m_walks;
  // stores the answer in the cache (when the file has a stamp) and in
  // `response`.
  Status walk(grpc::CallbackServerContext* context, const Caller& caller,
              const ResolvedPath& resolved, const std::string& key,
              const std::optional<FileStamp>& stamp, grpc::ByteBuffer* response,
              AccessRecord& record);

  Catalogue m_catalogue;
  Hdf5Workers& m_workers;
  Authenticator& m_authenticator;
  Limits m_limits;
  AccessLog& m_log;
  StreamRegistry m_streams;
  DescribeCache m_descriptions;
  // Last: destroyed first, it waits for running walks, which use the rest.
  WalkThreads m_walks{16, 64};
};

}  // namespace crackvis::dataservice
