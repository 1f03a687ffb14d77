// Runs a program to completion and captures its exit status, stdout and
// stderr: how CLI tests see exactly what a user sees.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <sys/types.h>

namespace crackvis::testing {

struct ProcessResult {
  int exitCode = -1;  // the exit status, or 128 + signal when killed
  std::string out;
  std::string err;
};

ProcessResult runProcess(const std::vector<std::string>& argv);

// Starts a program in the background (posix_spawn: safe in a threaded test
// process), its stdin, stdout and stderr on /dev/null unless `errPath`
// names a file for stderr. The caller ends it (waitProcess, kill).
pid_t startProcess(const std::vector<std::string>& argv, const std::string& errPath = "");
// Waits for a started program: its exit status, or 128 + signal.
int waitProcess(pid_t pid);

// This process's resident memory and thread count (/proc/self), for tests
// that show a hostile input does not make a server grow.
std::uint64_t residentBytes();
int threadCount();

// Polls `condition` every 10 ms until it holds or `seconds` have passed;
// its last answer.
bool waitUntil(const std::function<bool()>& condition, double seconds = 10.0);

// A file's bytes ("" when it cannot be read).
std::string fileText(const std::string& path);

// Non-empty lines of a text.
std::vector<std::string> lines(const std::string& text);
// The same without the notes a sanitizer build's runtime adds of its own
// (an allocation of 2^64 bytes that libhdf5 asks for and is refused).
std::vector<std::string> programLines(const std::string& text);

}  // namespace crackvis::testing
