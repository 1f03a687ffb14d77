#include "support/process.hpp"

#include <chrono>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "support/temp_dir.hpp"

extern char** environ;

namespace crackvis::testing {
std::string fileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

namespace {

// posix_spawn (safe in a threaded test process) with stdin on /dev/null and
// stdout and stderr into the named files ("/dev/null" to drop them).
pid_t spawn(const std::vector<std::string>& argv, const std::string& outPath,
            const std::string& errPath) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, outPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0600);
  posix_spawn_file_actions_addopen(&actions, 2, errPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0600);
  std::vector<char*> args;
  for (const auto& arg : argv) {
    args.push_back(const_cast<char*>(arg.c_str()));
  }
  args.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    throw std::runtime_error("cannot start " + argv.at(0));
  }
  return pid;
}

}  // namespace

ProcessResult runProcess(const std::vector<std::string>& argv) {
  // Files rather than pipes: no deadlock however much the child prints.
  TempDir dir;
  const std::string outPath = dir.file("stdout");
  const std::string errPath = dir.file("stderr");
  ProcessResult result;
  result.exitCode = waitProcess(spawn(argv, outPath, errPath));
  result.out = fileText(outPath);
  result.err = fileText(errPath);
  return result;
}

pid_t startProcess(const std::vector<std::string>& argv, const std::string& errPath) {
  return spawn(argv, "/dev/null", errPath.empty() ? "/dev/null" : errPath);
}

int waitProcess(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> result;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) {
      result.push_back(line);
    }
  }
  return result;
}

std::vector<std::string> programLines(const std::string& text) {
  std::vector<std::string> result;
  for (std::string& line : lines(text)) {
    // "==PID==WARNING: AddressSanitizer failed to allocate ...": the
    // sanitizer's own note when a library asks for more than exists.
    const bool sanitizerNote =
        line.rfind("==", 0) == 0 &&
        line.find("==WARNING: AddressSanitizer failed to allocate") != std::string::npos;
    if (!sanitizerNote) {
      result.push_back(std::move(line));
    }
  }
  return result;
}

std::uint64_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t size = 0;
  std::uint64_t resident = 0;
  statm >> size >> resident;
  return resident * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

int threadCount() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("Threads:", 0) == 0) {
      return std::stoi(line.substr(8));
    }
  }
  return -1;
}

bool waitUntil(const std::function<bool()>& condition, double seconds) {
  const auto end = std::chrono::steady_clock::now() +
                   std::chrono::milliseconds(static_cast<int>(seconds * 1000));
  while (std::chrono::steady_clock::now() < end) {
    if (condition()) {
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return condition();
}

}  // namespace crackvis::testing
