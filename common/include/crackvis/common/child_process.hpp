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
#include <cstdint>
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

// Caps this process's address space (RLIMIT_AS, soft and hard) at what it
// maps now plus `headroomBytes`, so that an allocation past that fails
// instead of taking the host's memory. For processes that run libhdf5 on
// files users name: a corrupt size makes libhdf5 allocate what the size says
// and then fill it (tests/fuzz/crashes/dem_reader-hdf5-20gb-metadata-read.h5:
// 20 GB, which ran a 24 GiB node into the OOM killer in 45 s). Never raises
// a lower limit already set.
Status capAddressSpace(std::uint64_t headroomBytes);

}  // namespace crackvis
