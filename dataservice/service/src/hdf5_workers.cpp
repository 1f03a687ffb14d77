#include "hdf5_workers.hpp"

#include <algorithm>
#include <csignal>
#include <cstring>
#include <optional>
#include <string_view>
#include <utility>

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "worker_protocol.hpp"
#include <crackvis/common/child_process.hpp>
#include <crackvis/common/huge_pages.hpp>
#include <crackvis/common/log.hpp>
#include <crackvis/common/unique_fd.hpp>

namespace crackvis::dataservice {
namespace {

using namespace worker_protocol;

constexpr const char* kProgram = "crackvis-data";

// Kills a worker (a no-op for one that has died already) and waits for it;
// how it ended, as waitpid tells it.
int killAndReap(pid_t pid) {
  ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}
// A worker loads its program and libhdf5 in milliseconds (a sanitizer
// build in a second); much longer is a program that hangs.
constexpr std::chrono::seconds kWorkerStartTime{30};

}  // namespace

// ------------------------------------------------------------ supervisor --

Hdf5Workers::Hdf5Workers(DataRoot root, Settings settings)
    : m_root(std::move(root)), m_settings(settings), m_environment(helperTunablesEntry()) {}

Result<std::unique_ptr<Hdf5Workers>> Hdf5Workers::start(const DataRoot& root, Settings settings) {
  if (settings.workers < 1) {
    return invalidArgument("at least one HDF5 worker is needed");
  }
  std::unique_ptr<Hdf5Workers> workers(new Hdf5Workers(root, settings));
  workers->m_workers.resize(static_cast<std::size_t>(settings.workers));
  for (Worker& worker : workers->m_workers) {
    CRACKVIS_RETURN_IF_ERROR(workers->spawn(worker));
  }
  return workers;
}

Hdf5Workers::~Hdf5Workers() {
  for (Worker& worker : m_workers) {
    if (worker.socket >= 0) {
      ::close(worker.socket);
    }
    if (worker.shared != nullptr) {
      ::munmap(worker.shared, kMaxChunkBytes);
    }
    if (worker.pid > 0) {
      (void)killAndReap(worker.pid);
    }
  }
}

Status Hdf5Workers::spawn(Worker& worker) {
  auto started = startWorker();
  if (!started) {
    return started.status();
  }
  std::lock_guard lock(m_mutex);
  worker.pid = started->pid;
  worker.socket = started->socket;
  worker.shared = started->shared;
  return Status::ok();
}

Hdf5Workers::SpawnThread::SpawnThread() {
  m_thread = std::thread([this] {
    std::unique_lock lock(m_mutex);
    for (;;) {
      m_wake.wait(lock, [&] { return m_stop || m_work != nullptr; });
      if (m_work == nullptr) {
        return;
      }
      (*m_work)();
      m_work = nullptr;
      ++m_finished;
      m_done.notify_all();
    }
  });
}

Hdf5Workers::SpawnThread::~SpawnThread() {
  {
    std::lock_guard lock(m_mutex);
    m_stop = true;
  }
  m_wake.notify_all();
  m_thread.join();
}

void Hdf5Workers::SpawnThread::run(const std::function<void()>& work) {
  std::unique_lock lock(m_mutex);
  m_done.wait(lock, [&] { return m_work == nullptr; });  // one at a time
  m_work = &work;
  const std::uint64_t ticket = m_finished + 1;
  m_wake.notify_all();
  m_done.wait(lock, [&] { return m_finished >= ticket; });
}

Result<Hdf5Workers::Started> Hdf5Workers::startWorker() {
  Result<Started> started = internalError("the spawn thread did not run");
  m_spawns->run([&] { started = spawnWorker(); });
  return started;
}

namespace {

// Copies of the two descriptors above the ones the worker gets, so that
// placing one at 3 or 4 cannot overwrite the other.
constexpr int kAboveWorkerFds = 10;

}  // namespace

// The worker is a program of its own, started with posix_spawn, not a fork
// of the service: no copy of the service's memory (its TLS key, other
// users' data) lives in a process that parses hostile files, and nothing
// runs between fork and exec (under GCC 12's libasan a forked child of the
// threaded service could stall on a lock another thread held).
Result<Hdf5Workers::Started> Hdf5Workers::spawnWorker() {
  auto failed = [](std::string_view what) {
    return unavailable(
        fmt::format("cannot start an HDF5 worker: {}: {}", what, std::strerror(errno)));
  };
  int sockets[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sockets) != 0) {
    return failed("socketpair");
  }
  UniqueFd ours(sockets[0]);
  UniqueFd theirs(sockets[1]);
  // The piece buffer both map: a memfd, as an anonymous mapping does not
  // outlive exec.
  UniqueFd buffer(::memfd_create("crackvis-hdf5-pieces", MFD_CLOEXEC));
  if (buffer.get() < 0 || ::ftruncate(buffer.get(), kMaxChunkBytes) != 0) {
    return failed("memfd");
  }
  // Mapped in at once (the worker writes its side before it is ready): a
  // first touch per page on the first Read costs a fault each, at several
  // microseconds apiece on a virtual machine.
  void* shared = ::mmap(nullptr, kMaxChunkBytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE,
                        buffer.get(), 0);
  if (shared == MAP_FAILED) {
    return failed("mmap");
  }
  const UniqueFd socketCopy(::fcntl(theirs.get(), F_DUPFD_CLOEXEC, kAboveWorkerFds));
  const UniqueFd bufferCopy(::fcntl(buffer.get(), F_DUPFD_CLOEXEC, kAboveWorkerFds));
  const std::string service = std::to_string(::getpid());
  const std::string root = m_root.path().string();
  char* argv[] = {const_cast<char*>(m_settings.program.c_str()), const_cast<char*>(root.c_str()),
                  const_cast<char*>(service.c_str()), nullptr};
  // The service's environment is none of a worker's business; the worker
  // gets only malloc's tunables for huge pages (common/huge_pages.hpp).
  char* envp[] = {m_environment.empty() ? nullptr : const_cast<char*>(m_environment.c_str()),
                  nullptr};
  posix_spawn_file_actions_t actions;
  posix_spawnattr_t attributes;
  ::posix_spawn_file_actions_init(&actions);
  ::posix_spawnattr_init(&attributes);
  // dup2 clears close-on-exec: the worker keeps these two and nothing else.
  ::posix_spawn_file_actions_adddup2(&actions, socketCopy.get(), kWorkerSocket);
  ::posix_spawn_file_actions_adddup2(&actions, bufferCopy.get(), kWorkerBuffer);
  ::posix_spawn_file_actions_addclosefrom_np(&actions, kWorkerBuffer + 1);
  // Signals as a new program expects them, whatever this thread blocks.
  sigset_t none;
  sigemptyset(&none);
  ::posix_spawnattr_setsigmask(&attributes, &none);
  sigset_t all;
  sigfillset(&all);
  ::posix_spawnattr_setsigdefault(&attributes, &all);
  ::posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  pid_t pid = -1;
  const int error = socketCopy.get() < 0 || bufferCopy.get() < 0
                        ? errno
                        : ::posix_spawn(&pid, argv[0], &actions, &attributes, argv, envp);
  ::posix_spawn_file_actions_destroy(&actions);
  ::posix_spawnattr_destroy(&attributes);
  if (error != 0) {
    ::munmap(shared, kMaxChunkBytes);
    errno = error;
    return failed(m_settings.program);
  }
  // A worker counts once it says it is ready: a signal sent to it earlier
  // could meet the handlers of its start (a sanitizer's turned a SIGSEGV
  // into exit status 1), and a program that cannot set itself up is one
  // clear error here rather than a fault blamed on the first caller's file.
  FrameHeader ready;
  if (receiveAll(ours.get(), &ready, sizeof ready, Clock::now() + kWorkerStartTime, {}) !=
          Wait::kReady ||
      ready.kind != kReady || ready.length != 0) {
    const int status = killAndReap(pid);
    ::munmap(shared, kMaxChunkBytes);
    return unavailable(fmt::format("cannot start an HDF5 worker: {} did not get ready ({})",
                                   m_settings.program, describeExit(status)));
  }
  return Started{pid, ours.release(), shared};
}

bool Hdf5Workers::isNext(const Ticket& ticket) const {
  const Ticket* next = nullptr;
  int nextHeld = 0;
  for (const Ticket* waiting : m_waiting) {
    if (waiting->lane == Lane::kWalk && m_walking >= walkLimit()) {
      continue;  // cannot take a worker now; others go first
    }
    const auto held = m_held.find(*waiting->user);
    const int count = held == m_held.end() ? 0 : held->second;
    if (next == nullptr || count < nextHeld ||
        (count == nextHeld && waiting->order < next->order)) {
      next = waiting;
      nextHeld = count;
    }
  }
  return next == &ticket;
}

Hdf5Workers::Worker* Hdf5Workers::checkOut(Lane lane, const std::string& user) {
  std::unique_lock lock(m_mutex);
  const Ticket ticket{m_tickets++, &user, lane};
  m_waiting.push_back(&ticket);
  auto leave = [&] { m_waiting.erase(std::find(m_waiting.begin(), m_waiting.end(), &ticket)); };
  for (;;) {
    const bool anyAlive = std::any_of(m_workers.begin(), m_workers.end(), [](const Worker& worker) {
      return worker.pid > 0 || worker.starting;
    });
    if (!anyAlive) {
      leave();
      m_idle.notify_all();
      return nullptr;
    }
    auto idle = std::find_if(m_workers.begin(), m_workers.end(),
                             [](const Worker& worker) { return !worker.busy && worker.pid > 0; });
    if (idle != m_workers.end() && isNext(ticket)) {
      idle->busy = true;
      ++m_held[user];
      m_walking += lane == Lane::kWalk ? 1 : 0;
      leave();
      m_idle.notify_all();  // the next in line may find another free worker
      return &*idle;
    }
    m_idle.wait(lock);
  }
}

void Hdf5Workers::checkIn(Worker* worker, Lane lane, const std::string& user) {
  {
    std::lock_guard lock(m_mutex);
    worker->busy = false;
    if (auto held = m_held.find(user); held != m_held.end() && --held->second <= 0) {
      m_held.erase(held);
    }
    m_walking -= lane == Lane::kWalk ? 1 : 0;
  }
  m_idle.notify_all();
}

std::string Hdf5Workers::replace(Worker& worker, const std::string& file, const std::string& why) {
  const std::string ended = describeExit(killAndReap(worker.pid));
  ::close(worker.socket);
  ::munmap(worker.shared, kMaxChunkBytes);
  const pid_t old = worker.pid;
  {
    std::lock_guard lock(m_mutex);
    worker.pid = -1;
    worker.socket = -1;
    worker.shared = nullptr;
    worker.starting = true;
    ++m_replaced;
  }
  const Status spawned = spawn(worker);
  {
    std::lock_guard lock(m_mutex);
    worker.starting = false;
  }
  m_idle.notify_all();  // a caller waiting for any worker may find none will come
  log::event(stderr, kProgram, "hdf5_worker_replaced",
             {{"pid", std::to_string(old)},
              {"file", echoed(file)},
              {"why", why},
              {"ended", ended},
              {"new_pid", spawned ? std::to_string(worker.pid) : std::string("none")}});
  return ended;
}

Status Hdf5Workers::call(std::uint32_t kind, Lane lane, const std::string& user,
                         const std::string& request, const std::string& file,
                         Clock::time_point deadline, const std::function<bool()>& isCancelled,
                         Answer answer) {
  Worker* worker = checkOut(lane, user);
  if (worker == nullptr) {
    return unavailable("no HDF5 worker is running (they could not be restarted)");
  }
  // Every way out gives the worker back (replaced when it failed).
  struct Return {
    Hdf5Workers* workers;
    Worker* worker;
    Lane lane;
    const std::string& user;
    ~Return() { workers->checkIn(worker, lane, user); }
  } giveBack{this, worker, lane, user};

  // Only a fault during this call's own HDF5 work may be blamed on its file:
  // a worker found dead before it took the request (it died while idle, or
  // the request could not be handed to it) is replaced and the call goes to
  // the new one.
  bool sent = false;
  for (int attempt = 0; attempt < 2 && !sent; ++attempt) {
    if (worker->pid <= 0) {
      break;  // could not be restarted
    }
    if (hungUp(worker->socket)) {
      replace(*worker, file, "died while idle");
      continue;
    }
    sent = sendFrame(worker->socket, kind, request);
    if (!sent) {
      replace(*worker, file, "died before taking a request");
    }
  }
  if (worker->pid <= 0) {
    return unavailable("no HDF5 worker is running (they could not be restarted)");
  }
  if (!sent) {  // neither worker took it: nothing about the file is known
    return unavailable(fmt::format(
        "{}: two HDF5 workers in a row died before taking the request; retry", echoed(file)));
  }
  FrameHeader header;
  Wait waited = receiveAll(worker->socket, &header, sizeof header, deadline, isCancelled);
  if (waited == Wait::kReady && header.kind == kOkShared) {
    // A piece, in the worker's buffer: it wrote all of it before answering.
    if (answer.bytes != nullptr && header.length == 0 && answer.size <= kMaxChunkBytes) {
      std::memcpy(answer.bytes, worker->shared, answer.size);
      return Status::ok();
    }
    replace(*worker, file, "malformed answer");
    return internalError(fmt::format("{}: an HDF5 worker answered out of turn", echoed(file)));
  }
  const bool known = header.kind == kOk || header.kind == kError;
  if (waited == Wait::kReady && known && answer.bytes == nullptr &&
      header.length <= (std::uint64_t{256} << 20)) {
    std::string text;
    std::string& into = answer.text != nullptr ? *answer.text : text;
    into.resize(header.length);
    waited = receiveAll(worker->socket, into.data(), header.length, deadline, isCancelled);
    if (waited == Wait::kReady) {
      if (header.kind != kOk) {
        return decodeStatus(into);
      }
      if (answer.shared && !answer.shared(worker->shared)) {
        return internalError(
            fmt::format("{}: an HDF5 worker sent an unreadable answer", echoed(file)));
      }
      return Status::ok();
    }
  } else if (waited == Wait::kReady && header.kind == kError &&
             header.length <= (std::uint64_t{1} << 20)) {
    std::string error(header.length, '\0');
    waited = receiveAll(worker->socket, error.data(), header.length, deadline, isCancelled);
    if (waited == Wait::kReady) {
      return decodeStatus(error);
    }
  } else if (waited == Wait::kReady) {
    replace(*worker, file, "malformed answer");
    return internalError(fmt::format("{}: an HDF5 worker answered out of turn", echoed(file)));
  }
  switch (waited) {
    case Wait::kCancelled:
      replace(*worker, file, "caller cancelled");
      return cancelled(fmt::format("{}: cancelled by the caller", echoed(file)));
    case Wait::kTimeout: {
      replace(*worker, file, "time limit");
      return deadlineExceeded(fmt::format(
          "{}: libhdf5 did not finish in time; its worker process was replaced (the file may be "
          "corrupt)",
          echoed(file)));
    }
    default: {
      const std::string ended = replace(*worker, file, "died");
      return failedPrecondition(fmt::format(
          "{}: libhdf5 faulted on this file (its worker process {}) and was replaced; the file "
          "is probably corrupt",
          echoed(file), ended));
    }
  }
}

Result<std::string> Hdf5Workers::describe(const ResolvedPath& file, const DescribeLimits& limits,
                                          const std::function<bool()>& cancelled,
                                          const std::string& user) {
  WireWriter request;
  put(request, file);
  request.u64(static_cast<std::uint64_t>(limits.maxDepth));
  request.u64(limits.maxObjects);
  request.u64(static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::milliseconds>(limits.maxTime).count()));
  std::string answer;
  // The walk bounds itself by limits.maxTime; opening the file comes first.
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(limits.maxTime) +
                        m_settings.pieceTime;
  CRACKVIS_RETURN_IF_ERROR(call(kDescribe, Lane::kWalk, user, request.take(), file.requested,
                                deadline, cancelled, {&answer, nullptr, 0, {}}));
  return answer;
}

Result<ReadPlan> Hdf5Workers::planRead(const ResolvedPath& file,
                                       const std::vector<Hyperslab>& slabs, std::uint64_t maxBytes,
                                       const std::string& user) {
  WireWriter request;
  put(request, file);
  request.u64(slabs.size());
  for (const Hyperslab& slab : slabs) {
    request.text(slab.dataset);
    request.numbers(slab.start);
    request.numbers(slab.count);
  }
  request.u64(maxBytes);
  std::string answer;
  ReadPlan plan;
  // Taken while the worker is still this call's: its buffer holds the first
  // piece.
  Answer into{&answer, nullptr, 0, {}};
  into.shared = [&](const void* shared) {
    WireReader in(answer);
    plan.totalBytes = in.u64();
    const std::uint64_t count = in.u64();
    for (std::uint64_t i = 0; i < count && in.ok(); ++i) {
      plan.slabs.push_back(getSlab(in));
    }
    const std::uint64_t first = in.u64();
    if (in.ok() && first > 0 && first <= kMaxChunkBytes) {
      plan.firstPiece.assign(static_cast<const char*>(shared), first);
    }
    return in.ok();
  };
  CRACKVIS_RETURN_IF_ERROR(call(kPlan, Lane::kRead, user, request.take(), file.requested,
                                Clock::now() + m_settings.pieceTime, {}, into));
  return plan;
}

Status Hdf5Workers::readPiece(const ResolvedPath& file, const SlabPlan& slab, const Piece& piece,
                              void* out, const std::string& user) {
  WireWriter request;
  put(request, file);
  put(request, slab);
  put(request, piece);
  return call(kPiece, Lane::kRead, user, request.take(), file.requested,
              Clock::now() + m_settings.pieceTime, {}, {nullptr, out, piece.bytes, {}});
}

std::vector<pid_t> Hdf5Workers::pids() const {
  std::lock_guard lock(m_mutex);
  std::vector<pid_t> out;
  for (const Worker& worker : m_workers) {
    out.push_back(worker.pid);
  }
  return out;
}

int Hdf5Workers::replaced() const {
  std::lock_guard lock(m_mutex);
  return m_replaced;
}

}  // namespace crackvis::dataservice
