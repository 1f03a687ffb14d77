#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fstream>

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <crackvis/common/child_process.hpp>
#include <crackvis/common/unique_fd.hpp>

namespace crackvis {
namespace {

using Clock = std::chrono::steady_clock;

void writeAll(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t wrote = ::write(fd, text.data() + done, text.size() - done);
    if (wrote < 0 && errno == EINTR) {
      continue;
    }
    if (wrote <= 0) {
      return;
    }
    done += static_cast<std::size_t>(wrote);
  }
}

// Reads the child's output until it closes its end or the deadline passes.
bool readUntilClosed(int fd, Clock::time_point deadline, std::string& out) {
  char buffer[4096];
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      return false;
    }
    pollfd entry{fd, POLLIN, 0};
    const int ready = ::poll(&entry, 1, static_cast<int>(std::min<long long>(left, 1000)));
    if (ready < 0 && errno != EINTR) {
      return true;  // cannot wait on it; take what the child's exit says
    }
    if (ready <= 0) {
      continue;
    }
    const ssize_t got = ::read(fd, buffer, sizeof buffer);
    if (got == 0) {
      return true;
    }
    if (got > 0) {
      out.append(buffer, static_cast<std::size_t>(got));
    } else if (errno != EINTR) {
      return true;
    }
  }
}

// The address space this process maps now, from /proc/self/statm.
Result<std::uint64_t> mappedBytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t pages = 0;
  if (!(statm >> pages)) {
    return internalError("cannot read /proc/self/statm");
  }
  return pages * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

}  // namespace

#if defined(__SANITIZE_ADDRESS__)
// Under ASan an allocation past capAddressSpace's cap aborts the process,
// where release builds' malloc returns null and libhdf5 reports it. The
// sanitizer builds take the release path; the HDF5 worker starts with an
// empty environment, so ASAN_OPTIONS could not say this for it.
extern "C" const char* __asan_default_options() {
  return "allocator_may_return_null=1";
}
#endif

Status capAddressSpace(std::uint64_t headroomBytes) {
  auto mapped = mappedBytes();
  if (!mapped) {
    return mapped.status();
  }
  rlimit limit{};
  if (::getrlimit(RLIMIT_AS, &limit) != 0) {
    return internalError(fmt::format("getrlimit(RLIMIT_AS): {}", std::strerror(errno)));
  }
  std::uint64_t cap = *mapped + headroomBytes;
  if (limit.rlim_max != RLIM_INFINITY) {
    cap = std::min<std::uint64_t>(cap, limit.rlim_max);
  }
  if (limit.rlim_cur != RLIM_INFINITY && limit.rlim_cur <= cap) {
    return {};  // a lower limit is already set
  }
  limit.rlim_cur = cap;
  limit.rlim_max = cap;
  if (::setrlimit(RLIMIT_AS, &limit) != 0) {
    return internalError(fmt::format("setrlimit(RLIMIT_AS): {}", std::strerror(errno)));
  }
  return {};
}

bool ChildOutcome::finished() const {
  return !timedOut && WIFEXITED(waitStatus) && WEXITSTATUS(waitStatus) == 0;
}

std::string describeExit(int waitStatus) {
  if (WIFSIGNALED(waitStatus)) {
    const int signal = WTERMSIG(waitStatus);
    const char* name = ::sigabbrev_np(signal);
    return fmt::format("killed by SIG{} (signal {})", name != nullptr ? name : "?", signal);
  }
  if (WIFEXITED(waitStatus)) {
    return fmt::format("exited with status {}", WEXITSTATUS(waitStatus));
  }
  return "ended";
}

Result<ChildOutcome> runInChild(const std::function<std::string()>& work,
                                std::chrono::milliseconds limit) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    return internalError(fmt::format("pipe for a child process: {}", std::strerror(errno)));
  }
  UniqueFd readEnd(fds[0]);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[1]);
    return internalError(fmt::format("fork: {}", std::strerror(errno)));
  }
  if (pid == 0) {
    std::string output;
    try {
      output = work();
    } catch (...) {
      ::_exit(2);
    }
    writeAll(fds[1], output);
    ::_exit(0);
  }
  ::close(fds[1]);
  ChildOutcome outcome;
  outcome.timedOut = !readUntilClosed(readEnd.get(), Clock::now() + limit, outcome.output);
  if (outcome.timedOut) {
    ::kill(pid, SIGKILL);
  }
  while (::waitpid(pid, &outcome.waitStatus, 0) < 0 && errno == EINTR) {
  }
  return outcome;
}

}  // namespace crackvis
