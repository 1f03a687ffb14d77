#include "hdf5_workers.hpp"

#include <algorithm>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string_view>
#include <utility>

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "crackvis/v1/data.pb.h"
#include "describe_proto.hpp"
#include <crackvis/common/child_process.hpp>
#include <crackvis/common/log.hpp>
#include <crackvis/dataservice/hdf5_worker_main.hpp>

namespace crackvis::dataservice {
namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* kProgram = "crackvis-data";
// The two descriptors a worker program is started with: its socket, and the
// memfd of the piece buffer it shares with the service.
constexpr int kWorkerSocket = 3;
constexpr int kWorkerBuffer = 4;

// kOkShared: a piece's bytes are in the worker's shared buffer, not in the
// frame (two copies through the socket cost a view's Read a third more).
enum Kind : std::uint32_t {
  kDescribe = 1,
  kPlan = 2,
  kPiece = 3,
  kOk = 100,
  kError = 101,
  kOkShared = 102
};

// ------------------------------------------------------------------ wire --
// Little-endian fields in a string: what crosses the socket between the
// service and a worker (both the same build of the same program).

class WireWriter {
 public:
  void u64(std::uint64_t value) { m_out.append(reinterpret_cast<const char*>(&value), 8); }
  void text(std::string_view value) {
    u64(value.size());
    m_out.append(value);
  }
  template <typename T>
  void numbers(const std::vector<T>& values) {
    u64(values.size());
    for (T value : values) {
      u64(static_cast<std::uint64_t>(value));
    }
  }
  std::string take() { return std::move(m_out); }

 private:
  std::string m_out;
};

class WireReader {
 public:
  explicit WireReader(std::string_view in) : m_in(in) {}
  std::uint64_t u64() {
    std::uint64_t value = 0;
    if (m_in.size() < 8) {
      m_ok = false;
      return 0;
    }
    std::memcpy(&value, m_in.data(), 8);
    m_in.remove_prefix(8);
    return value;
  }
  std::string text() {
    const std::uint64_t size = u64();
    if (size > m_in.size()) {
      m_ok = false;
      return {};
    }
    std::string value(m_in.substr(0, size));
    m_in.remove_prefix(size);
    return value;
  }
  template <typename T>
  std::vector<T> numbers() {
    const std::uint64_t size = u64();
    if (size > m_in.size() / 8) {
      m_ok = false;
      return {};
    }
    std::vector<T> values(size);
    for (T& value : values) {
      value = static_cast<T>(u64());
    }
    return values;
  }
  bool ok() const { return m_ok; }

 private:
  std::string_view m_in;
  bool m_ok = true;
};

void put(WireWriter& out, const ResolvedPath& file) {
  out.text(file.requested);
  out.text(file.relative);
  out.text(file.absolute.string());
}
ResolvedPath getPath(WireReader& in) {
  ResolvedPath file;
  file.requested = in.text();
  file.relative = in.text();
  file.absolute = in.text();
  return file;
}

void put(WireWriter& out, const SlabPlan& slab) {
  out.text(slab.dataset);
  out.text(slab.resolvedDataset);
  out.u64(static_cast<std::uint64_t>(slab.dtype));
  out.numbers(slab.datasetShape);
  out.numbers(slab.start);
  out.numbers(slab.count);
  out.u64(slab.bytes);
  out.u64(slab.rowBytes);
}
SlabPlan getSlab(WireReader& in) {
  SlabPlan slab;
  slab.dataset = in.text();
  slab.resolvedDataset = in.text();
  slab.dtype = static_cast<DataType>(in.u64());
  slab.datasetShape = in.numbers<std::uint64_t>();
  slab.start = in.numbers<std::uint64_t>();
  slab.count = in.numbers<std::uint64_t>();
  slab.bytes = in.u64();
  slab.rowBytes = in.u64();
  return slab;
}

void put(WireWriter& out, const Piece& piece) {
  out.u64(piece.slab);
  out.u64(piece.offset);
  out.u64(piece.bytes);
  out.numbers(piece.start);
  out.numbers(piece.count);
}
Piece getPiece(WireReader& in) {
  Piece piece;
  piece.slab = in.u64();
  piece.offset = in.u64();
  piece.bytes = in.u64();
  piece.start = in.numbers<std::uint64_t>();
  piece.count = in.numbers<std::uint64_t>();
  return piece;
}

std::string encodeStatus(const Status& status) {
  WireWriter out;
  out.u64(static_cast<std::uint64_t>(status.code()));
  out.text(status.message());
  return out.take();
}
Status decodeStatus(std::string_view payload) {
  WireReader in(payload);
  const auto code = static_cast<StatusCode>(in.u64());
  std::string message = in.text();
  if (!in.ok() || code == StatusCode::kOk) {
    return internalError("an HDF5 worker sent an unreadable error");
  }
  return Status(code, std::move(message));
}

// ---------------------------------------------------------------- frames --
// A frame: kind (4 bytes), 4 bytes of padding, payload length (8 bytes),
// payload.

struct FrameHeader {
  std::uint32_t kind = 0;
  std::uint32_t padding = 0;
  std::uint64_t length = 0;
};

bool sendAll(int socket, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t sent = ::send(socket, bytes, size, MSG_NOSIGNAL);
    if (sent < 0) {
      if (errno == EINTR) {
        continue;
      }
      return false;
    }
    bytes += sent;
    size -= static_cast<std::size_t>(sent);
  }
  return true;
}

// One send for the header and the payload: requests and most answers are
// small, and each system call is a wake-up of the other side.
bool sendFrame(int socket, std::uint32_t kind, std::string_view payload) {
  const FrameHeader header{kind, 0, payload.size()};
  std::string frame(reinterpret_cast<const char*>(&header), sizeof header);
  frame.append(payload);
  return sendAll(socket, frame.data(), frame.size());
}

// Whether an idle worker's socket shows its end closed (it died) or bytes
// nobody asked for; either way it cannot take a request.
bool hungUp(int socket) {
  pollfd entry{socket, POLLIN | POLLRDHUP, 0};
  return ::poll(&entry, 1, 0) > 0;
}

enum class Wait { kReady, kClosed, kTimeout, kCancelled };

// Reads exactly `size` bytes, waiting at most until `deadline` and asking
// `cancelled` every 100 ms.
Wait receiveAll(int socket, void* data, std::size_t size, Clock::time_point deadline,
                const std::function<bool()>& cancelled) {
  auto* bytes = static_cast<char*>(data);
  while (size > 0) {
    // What has arrived already is taken without a poll first.
    const ssize_t got = ::recv(socket, bytes, size, MSG_DONTWAIT);
    if (got > 0) {
      bytes += got;
      size -= static_cast<std::size_t>(got);
      continue;
    }
    if (got == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      return Wait::kClosed;
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) {
      return Wait::kTimeout;
    }
    pollfd ready{socket, POLLIN, 0};
    const int polled =
        ::poll(&ready, 1, static_cast<int>(std::min<std::int64_t>(left.count(), 100)));
    if (polled < 0 && errno != EINTR) {
      return Wait::kClosed;
    }
    if (polled <= 0 && cancelled && cancelled()) {
      return Wait::kCancelled;
    }
  }
  return Wait::kReady;
}

// --------------------------------------------------------------- worker --

// What a worker answers to one request: kOk and its payload, or kError and
// an encoded Status.
std::pair<std::uint32_t, std::string> serve(const Catalogue& catalogue, std::uint32_t kind,
                                            std::string_view payload, void* shared) {
  WireReader in(payload);
  const ResolvedPath file = getPath(in);
  auto failed = [](const Status& status) { return std::pair{kError, encodeStatus(status)}; };
  switch (kind) {
    case kDescribe: {
      DescribeOptions options;
      options.limits.maxDepth = static_cast<int>(in.u64());
      options.limits.maxObjects = in.u64();
      options.limits.maxTime = std::chrono::milliseconds(in.u64());
      if (!in.ok()) {
        break;
      }
      auto description = catalogue.describe(file, options);
      if (!description) {
        return failed(description.status());
      }
      crackvis::v1::DescribeResponse response;
      toProto(*description, response);
      return {kOk, response.SerializeAsString()};
    }
    case kPlan: {
      const std::uint64_t count = in.u64();
      if (count > payload.size()) {
        break;
      }
      std::vector<Hyperslab> slabs(count);
      for (Hyperslab& slab : slabs) {
        slab.dataset = in.text();
        slab.start = in.numbers<std::int64_t>();
        slab.count = in.numbers<std::int64_t>();
      }
      const std::uint64_t maxBytes = in.u64();
      if (!in.ok()) {
        break;
      }
      auto reader = catalogue.openRead(file, slabs, maxBytes);
      if (!reader) {
        return failed(reader.status());
      }
      WireWriter out;
      out.u64((*reader)->totalBytes());
      out.u64((*reader)->slabs().size());
      for (const SlabPlan& slab : (*reader)->slabs()) {
        put(out, slab);
      }
      // The first piece comes with the plan, in the shared buffer: one
      // round trip fewer for every Read (a view's has seven). If it cannot
      // be read now, the service asks for it again and gets the error then.
      PieceCursor cursor;
      const auto first = cursor.next((*reader)->slabs());
      const bool read = first && (*reader)->read(*first, shared).isOk();
      out.u64(read ? first->bytes : 0);
      return {kOk, out.take()};
    }
    case kPiece: {
      const SlabPlan slab = getSlab(in);
      const Piece piece = getPiece(in);
      if (!in.ok() || piece.bytes > kMaxChunkBytes) {
        break;
      }
      if (Status read = catalogue.readPiece(file, slab, piece, shared); !read) {
        return failed(read);
      }
      return {kOkShared, {}};
    }
    default:
      break;
  }
  return failed(internalError("an HDF5 worker got a request it cannot read"));
}

[[noreturn]] void runWorker(const DataRoot& root, void* shared) {
  const Catalogue catalogue(root);
  for (;;) {
    pollfd ready{kWorkerSocket, POLLIN, 0};
    const int polled = ::poll(&ready, 1, 1000);
    if (polled == 0) {
      catalogue.closeIdleFiles();  // a writer is not kept out by an idle worker
      continue;
    }
    if (polled < 0) {
      if (errno == EINTR) {
        continue;
      }
      ::_exit(1);
    }
    FrameHeader header;
    const auto forever = Clock::now() + std::chrono::hours(24 * 365);
    if (receiveAll(kWorkerSocket, &header, sizeof header, forever, {}) != Wait::kReady ||
        header.length > (std::uint64_t{64} << 20)) {
      ::_exit(0);  // the service closed the socket (or speaks nonsense): done
    }
    std::string payload(header.length, '\0');
    if (receiveAll(kWorkerSocket, payload.data(), payload.size(), forever, {}) != Wait::kReady) {
      ::_exit(0);
    }
    const auto [kind, answer] = serve(catalogue, header.kind, payload, shared);
    if (!sendFrame(kWorkerSocket, kind, answer)) {
      ::_exit(0);
    }
  }
}

// Whether `fd` is a Unix stream socket: the one a worker is given.
bool isWorkerSocket(int fd) {
  int type = 0;
  socklen_t length = sizeof type;
  return ::getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &length) == 0 && type == SOCK_STREAM;
}

// The worker program's arguments: the data root and the service's pid.
std::optional<pid_t> servicePid(std::string_view text) {
  pid_t pid = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), pid);
  if (error != std::errc() || end != text.data() + text.size() || pid <= 1) {
    return std::nullopt;
  }
  return pid;
}

}  // namespace

// ------------------------------------------------------------ supervisor --

Hdf5Workers::Hdf5Workers(DataRoot root, Settings settings)
    : m_root(std::move(root)), m_settings(settings) {}

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
      ::kill(worker.pid, SIGKILL);
      int status = 0;
      while (::waitpid(worker.pid, &status, 0) < 0 && errno == EINTR) {
      }
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

// A descriptor that closes itself.
class OwnedFd {
 public:
  explicit OwnedFd(int fd = -1) : m_fd(fd) {}
  OwnedFd(const OwnedFd&) = delete;
  OwnedFd& operator=(const OwnedFd&) = delete;
  ~OwnedFd() {
    if (m_fd >= 0) {
      ::close(m_fd);
    }
  }
  int get() const { return m_fd; }
  int release() { return std::exchange(m_fd, -1); }

 private:
  int m_fd;
};

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
  OwnedFd ours(sockets[0]);
  OwnedFd theirs(sockets[1]);
  // The piece buffer both map: a memfd, as an anonymous mapping does not
  // outlive exec.
  OwnedFd buffer(::memfd_create("crackvis-hdf5-pieces", MFD_CLOEXEC));
  if (buffer.get() < 0 || ::ftruncate(buffer.get(), kMaxChunkBytes) != 0) {
    return failed("memfd");
  }
  void* shared =
      ::mmap(nullptr, kMaxChunkBytes, PROT_READ | PROT_WRITE, MAP_SHARED, buffer.get(), 0);
  if (shared == MAP_FAILED) {
    return failed("mmap");
  }
  const OwnedFd socketCopy(::fcntl(theirs.get(), F_DUPFD_CLOEXEC, kAboveWorkerFds));
  const OwnedFd bufferCopy(::fcntl(buffer.get(), F_DUPFD_CLOEXEC, kAboveWorkerFds));
  const std::string service = std::to_string(::getpid());
  const std::string root = m_root.path().string();
  char* argv[] = {const_cast<char*>(m_settings.program.c_str()), const_cast<char*>(root.c_str()),
                  const_cast<char*>(service.c_str()), nullptr};
  char* envp[] = {nullptr};  // the service's environment is none of a worker's business
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
    const bool anyAlive = std::any_of(m_workers.begin(), m_workers.end(),
                                      [](const Worker& worker) { return worker.pid > 0; });
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
  ::kill(worker.pid, SIGKILL);  // a no-op for one that has died already
  int status = 0;
  while (::waitpid(worker.pid, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string ended = describeExit(status);
  ::close(worker.socket);
  ::munmap(worker.shared, kMaxChunkBytes);
  const pid_t old = worker.pid;
  {
    std::lock_guard lock(m_mutex);
    worker.pid = -1;
    worker.socket = -1;
    worker.shared = nullptr;
    ++m_replaced;
  }
  const Status spawned = spawn(worker);
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
  request.u64(static_cast<std::uint64_t>(limits.maxTime.count()));
  std::string answer;
  // The walk bounds itself by limits.maxTime; opening the file comes first.
  const auto deadline = Clock::now() + limits.maxTime + m_settings.pieceTime;
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

// ---------------------------------------------------------------- worker --

int hdf5WorkerMain(int argc, char** argv) {
  const std::optional<pid_t> service = argc == 3 ? servicePid(argv[2]) : std::nullopt;
  if (!service || !isWorkerSocket(kWorkerSocket)) {
    std::fprintf(stderr,
                 "crackvis-hdf5-worker: crackvis-data starts this program for its HDF5 work "
                 "(docs/security.md); it is not run by hand\n");
    return 2;
  }
  // Dies with the service's thread that started it; the check after closes
  // the gap in which the service could have died first.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != *service) {
    return 0;
  }
  ::prctl(PR_SET_DUMPABLE, 0);  // no core files of users' data when libhdf5 faults
  // A fault ends the worker by its signal, which the service reports: no
  // handler a sanitizer installed may turn it into an exit status.
  for (const int signal : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) {
    ::signal(signal, SIG_DFL);
  }
  ::signal(SIGPIPE, SIG_IGN);
  void* shared =
      ::mmap(nullptr, kMaxChunkBytes, PROT_READ | PROT_WRITE, MAP_SHARED, kWorkerBuffer, 0);
  ::close(kWorkerBuffer);
  auto root = DataRoot::open(argv[1]);
  if (shared == MAP_FAILED || !root) {
    return 1;  // the service sees the socket close and replaces the worker
  }
  runWorker(*root, shared);
}

}  // namespace crackvis::dataservice
