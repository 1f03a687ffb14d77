#include "data_service.hpp"

#include <mutex>
#include <utility>

#include <fmt/format.h>

#include "data_service_internal.hpp"

namespace crackvis::dataservice {
namespace v1 = crackvis::v1;
using Clock = std::chrono::steady_clock;

// --------------------------------------------------------- StreamRegistry

Result<std::uint64_t> StreamRegistry::acquire(grpc::CallbackServerContext* context,
                                              Clock::time_point deadline, const std::string& user) {
  std::lock_guard lock(m_mutex);
  if (static_cast<int>(m_entries.size()) >= m_limit) {
    return resourceExhausted(fmt::format(
        "the server is already serving {} streams, its limit (max_concurrent_streams); retry "
        "later",
        m_limit));
  }
  if (m_reservedBytes + kStreamBufferBytes > m_memoryLimit) {
    return resourceExhausted(fmt::format(
        "the server's streams already buffer {} of its {} budget (max_memory_bytes); retry later",
        formatBytes(m_reservedBytes), formatBytes(m_memoryLimit)));
  }
  int& own = m_perUser[user];
  if (!user.empty() && own >= m_perUserLimit) {
    return resourceExhausted(fmt::format(
        "user '{}' already has {} streams open, the limit per user (max_streams_per_user); "
        "retry later",
        user, own));
  }
  ++own;
  m_reservedBytes += kStreamBufferBytes;
  const std::uint64_t id = m_nextId++;
  m_entries.emplace(id, Entry{context, deadline, false, user});
  return id;
}

void StreamRegistry::release(std::uint64_t id) {
  std::lock_guard lock(m_mutex);
  auto it = m_entries.find(id);
  if (it == m_entries.end()) {
    return;
  }
  if (auto user = m_perUser.find(it->second.user); user != m_perUser.end() && --user->second <= 0) {
    m_perUser.erase(user);
  }
  m_reservedBytes -= kStreamBufferBytes;
  m_entries.erase(it);
}

std::uint64_t StreamRegistry::reservedBytes() const {
  std::lock_guard lock(m_mutex);
  return m_reservedBytes;
}

int StreamRegistry::cancelOverdue(Clock::time_point now) {
  std::lock_guard lock(m_mutex);
  int cancelled = 0;
  for (auto& [id, entry] : m_entries) {
    if (!entry.cancelled && now > entry.deadline) {
      // The context stays valid until the reactor's OnDone, which releases
      // its entry under this same lock.
      entry.context->TryCancel();
      entry.cancelled = true;
      ++cancelled;
    }
  }
  return cancelled;
}

int StreamRegistry::active() const {
  std::lock_guard lock(m_mutex);
  return static_cast<int>(m_entries.size());
}

// -------------------------------------------------------- DataServiceImpl

Result<Caller> DataServiceImpl::authenticate(grpc::CallbackServerContext* context,
                                             AccessRecord& record) const {
  return rpc::authenticateCall(m_authenticator, *context, record);
}

Result<ResolvedPath> DataServiceImpl::resolveFor(const Caller& caller,
                                                 const std::string& path) const {
  auto normalized = DataRoot::normalize(path);
  if (!normalized) {
    return normalized.status();
  }
  CRACKVIS_RETURN_IF_ERROR(rpc::checkNamedPath(caller, *normalized));
  auto resolved = m_catalogue.root().resolveFile(*normalized);
  if (!resolved) {
    return resolved.status();
  }
  CRACKVIS_RETURN_IF_ERROR(rpc::checkResolvedPath(caller, *normalized, resolved->relative));
  return resolved;
}

template <typename Body>
grpc::ServerUnaryReactor* DataServiceImpl::unaryCall(grpc::CallbackServerContext* context,
                                                     const char* method, const std::string& file,
                                                     Body&& body) {
  const auto start = Clock::now();
  AccessRecord record;
  record.method = method;
  record.file = file;
  const Status status = rpc::guarded(kProgram, record, [&]() -> Status {
    auto caller = authenticate(context, record);
    if (!caller) {
      return caller.status();
    }
    return body(*caller, record);
  });
  auto* reactor = context->DefaultReactor();
  reactor->Finish(rpc::finishCall(m_log, record, start, status));
  return reactor;
}

template <typename Body>
grpc::ServerUnaryReactor* DataServiceImpl::unary(grpc::CallbackServerContext* context,
                                                 const char* method, const std::string& file,
                                                 const google::protobuf::Message& response,
                                                 Body&& body) {
  return unaryCall(context, method, file, [&](const Caller& caller, AccessRecord& record) {
    const Status status = body(caller);
    record.bytes = status.isOk() ? response.ByteSizeLong() : 0;
    return status;
  });
}

grpc::ServerUnaryReactor* DataServiceImpl::ListFiles(grpc::CallbackServerContext* context,
                                                     const v1::ListFilesRequest* request,
                                                     v1::ListFilesResponse* response) {
  return unary(context, "ListFiles", request->folder(), *response, [&](const Caller& caller) {
    auto folder = DataRoot::normalize(request->folder());
    if (!folder) {
      return folder.status();
    }
    // Another user's folder answers as a missing one: no existence oracle.
    if (!caller.mayList(*folder)) {
      return DataRoot::notFound(*folder, /*folder=*/true);
    }
    auto files = m_catalogue.listFiles(*folder, request->recursive(), [&](const std::string& real) {
      return caller.mayRead(real);
    });
    if (!files) {
      return files.status();
    }
    for (const FileEntry& file : *files) {
      // The catalogue checked the real path; the name shown must be in the
      // caller's folders too.
      auto resolved = m_catalogue.root().resolveFile(file.path);
      if (!resolved || !rpc::checkResolvedPath(caller, file.path, resolved->relative).isOk()) {
        continue;
      }
      v1::FileEntry* entry = response->add_files();
      entry->set_path(file.path);
      entry->set_size_bytes(file.sizeBytes);
      entry->set_modified_unix_seconds(file.modifiedUnixSeconds);
      entry->set_is_hdf5(file.isHdf5);
      entry->set_resolved_path(resolved->relative);
    }
    return Status::ok();
  });
}

namespace {

// The bytes of an answer handed to gRPC as they are, freed when it is done
// with them.
grpc::ByteBuffer ownedBuffer(std::string bytes) {
  auto* owned = new std::string(std::move(bytes));
  grpc::Slice slice(
      owned->data(), owned->size(), [](void* held) { delete static_cast<std::string*>(held); },
      owned);
  return grpc::ByteBuffer(&slice, 1);
}

}  // namespace

Status DataServiceImpl::walk(grpc::CallbackServerContext* context, const Caller& caller,
                             const ResolvedPath& resolved, const std::string& key,
                             const std::optional<FileStamp>& stamp, grpc::ByteBuffer* response,
                             AccessRecord& record) {
  // A client that gave up (or whose deadline passed) stops the walk (its
  // worker is replaced): a hostile file must not hold a worker for a caller
  // who is gone.
  auto described = m_workers.describe(
      resolved, m_limits.describe, [context] { return context->IsCancelled(); }, caller.name);
  if (!described) {
    return described.status();
  }
  if (v1::DescribeResponse check; !check.ParseFromString(*described)) {
    return internalError(fmt::format("Describe of {}: an HDF5 worker sent an unreadable answer",
                                     echoed(resolved.requested)));
  }
  // The file as it was before the walk, and still is after it.
  if (stamp && settled(*stamp) && stampOf(resolved.absolute.string()) == stamp) {
    // A message's serialized fields may be appended to it: the revision is
    // added to the worker's answer (checked above) without parsing it again.
    v1::DescribeResponse revision;
    revision.set_revision(revisionOf(*stamp));
    described->append(revision.SerializeAsString());
    m_descriptions.store(key, *stamp, *described);
  }
  record.bytes = described->size();
  *response = ownedBuffer(std::move(*described));
  return Status::ok();
}

grpc::ServerUnaryReactor* DataServiceImpl::Describe(grpc::CallbackServerContext* context,
                                                    const grpc::ByteBuffer* request,
                                                    grpc::ByteBuffer* response) {
  // What the walk needs after this handler has returned.
  struct Call {
    AccessRecord record;
    Clock::time_point start = Clock::now();
    v1::DescribeRequest request;
    std::optional<Caller> caller;
    std::optional<ResolvedPath> resolved;
    std::string key;
    std::optional<FileStamp> stamp;
  };
  auto call = std::make_shared<Call>();
  const Status readable = parseRequest(request, call->request);
  call->record.method = "Describe";
  call->record.file = call->request.file();
  auto* reactor = context->DefaultReactor();
  bool walking = false;
  const Status status = rpc::guarded(kProgram, call->record, [&]() -> Status {
    auto caller = authenticate(context, call->record);
    if (!caller) {
      return caller.status();
    }
    CRACKVIS_RETURN_IF_ERROR(readable);
    auto resolved = resolveFor(*caller, call->request.file());
    if (!resolved) {
      return resolved.status();
    }
    // The answer is the file's as named by the caller (it echoes the name).
    call->key = resolved->absolute.string() + '\n' + resolved->requested;
    call->stamp = stampOf(resolved->absolute.string());
    if (call->stamp && !call->request.uncached()) {
      if (auto held = m_descriptions.find(call->key, *call->stamp)) {
        call->record.bytes = held->size();
        *response = ownedBuffer(std::move(*held));  // checked when it was stored
        return Status::ok();
      }
    }
    call->caller = std::move(*caller);
    call->resolved = std::move(*resolved);
    // The walk waits for an HDF5 worker and takes up to Describe's time
    // limit: on a thread of its own, never one of gRPC's few.
    CRACKVIS_RETURN_IF_ERROR(
        m_walks.start(call->caller->name, [this, call, context, reactor, response] {
          const Status walked = rpc::guarded(kProgram, call->record, [&] {
            return walk(context, *call->caller, *call->resolved, call->key, call->stamp, response,
                        call->record);
          });
          reactor->Finish(rpc::finishCall(m_log, call->record, call->start, walked));
        }));
    walking = true;
    return Status::ok();
  });
  if (!walking) {
    reactor->Finish(rpc::finishCall(m_log, call->record, call->start, status));
  }
  return reactor;
}

grpc::ServerUnaryReactor* DataServiceImpl::Resolve(grpc::CallbackServerContext* context,
                                                   const v1::ResolveRequest* request,
                                                   v1::ResolveResponse* response) {
  return unary(context, "Resolve", request->file(), *response, [&](const Caller& caller) {
    auto resolved = resolveFor(caller, request->file());
    if (!resolved) {
      return resolved.status();
    }
    response->set_file(resolved->requested);
    response->set_resolved_file(resolved->relative);
    return Status::ok();
  });
}
}  // namespace crackvis::dataservice
