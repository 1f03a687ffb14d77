// Hands the pages a closed session freed back to the system, a little later.
//
// A session's worker frees its scene, step cache, GL context and encoder as
// it ends; glibc keeps those pages in its arenas unless told otherwise, and
// crackvis-render grew by ~150 MB per closed cuboid-A session (issue 17), so
// the heap is trimmed (malloc_trim) after a session. Trimmed at once, though,
// the next session, which the browser page opens as soon as it has closed
// the last one to show another file, faults every page in again (THP's 2 MB
// pages zeroed by the kernel: a quarter of the render server's CPU during an
// open): the warm first picture of cuboid A at 1280x720 took 183-212 ms
// against 125-148 ms untrimmed (docs/benchmarks.md). Deferred, a session
// opened within `quiet` of the last close reuses those pages from the
// arena the ended thread left, and the trim still comes when the server is
// quiet: `quiet` after the last request, and at most `longest` after the
// first one not yet trimmed, so that sessions closing more often than once
// per `quiet` cannot put it off for ever.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

namespace crackvis::service {

class HeapTrimmer {
 public:
  using Clock = std::chrono::steady_clock;
  struct Timing {
    std::chrono::milliseconds quiet{1000};
    std::chrono::milliseconds longest{5000};
  };
  // `trim` defaults to malloc_trim(0). `refill`, if given, runs after each
  // trim but one at destruction: the heap reserve's pages not resident
  // written (common/heap_reserve.hpp), which a server shutting down has no
  // use for.
  explicit HeapTrimmer(Timing timing, std::function<void()> trim = {},
                       std::function<void()> refill = {});
  HeapTrimmer() : HeapTrimmer(Timing{}) {}
  HeapTrimmer(const HeapTrimmer&) = delete;
  HeapTrimmer& operator=(const HeapTrimmer&) = delete;
  ~HeapTrimmer();  // a trim still due runs now

  // A session has ended: trim once the server has been quiet for `quiet`.
  void request();
  std::uint64_t trims() const;

 private:
  void run();

  const Timing m_timing;
  const std::function<void()> m_trim;
  const std::function<void()> m_refill;
  mutable std::mutex m_mutex;
  std::condition_variable m_changed;
  std::optional<Clock::time_point> m_firstPending;  // the oldest request not yet trimmed
  Clock::time_point m_lastRequest;
  bool m_stopping = false;
  std::uint64_t m_trims = 0;
  std::thread m_thread;
};

}  // namespace crackvis::service
