// Work that may crash the process it runs in (libhdf5 on a corrupt file),
// run in a forked child instead: the caller learns how the child ended and
// what it wrote, and survives a fault. Used where a process cannot hand the
// work to a supervised worker (the CLI's readers, an offline render).
//
// The child runs only `work` and then _exit()s: no atexit handlers, no
// destructors of the parent's objects. Fork from a thread that no other
// thread shares the library's state with (libhdf5 is not thread-safe here).
#pragma once

#include <chrono>
#include <functional>
#include <string>

#include <crackvis/common/status.hpp>

namespace crackvis {

struct ChildOutcome {
  bool timedOut = false;  // killed at the time limit
  int waitStatus = 0;     // as waitpid reports it
  std::string output;     // what `work` returned, when it returned
  bool finished() const;  // `work` returned and the child exited normally
};

// Runs `work` in a forked child and waits at most `limit` for it.
Result<ChildOutcome> runInChild(const std::function<std::string()>& work,
                                std::chrono::milliseconds limit);

// How a child ended, for messages: "killed by SIGSEGV (signal 11)",
// "exited with status 3".
std::string describeExit(int waitStatus);

}  // namespace crackvis
