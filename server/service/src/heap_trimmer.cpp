#include <algorithm>

#include <malloc.h>

#include <crackvis/service/heap_trimmer.hpp>

namespace crackvis::service {

HeapTrimmer::HeapTrimmer(Timing timing, std::function<void()> trim, std::function<void()> refill)
    : m_timing(timing),
      m_trim(trim ? std::move(trim) : std::function<void()>([] { malloc_trim(0); })),
      m_refill(std::move(refill)),
      m_thread([this] { run(); }) {}

HeapTrimmer::~HeapTrimmer() {
  {
    std::lock_guard lock(m_mutex);
    m_stopping = true;
  }
  m_changed.notify_all();
  m_thread.join();
}

void HeapTrimmer::request() {
  {
    std::lock_guard lock(m_mutex);
    m_lastRequest = Clock::now();
    if (!m_firstPending) {
      m_firstPending = m_lastRequest;
    }
  }
  m_changed.notify_all();
}

std::uint64_t HeapTrimmer::trims() const {
  std::lock_guard lock(m_mutex);
  return m_trims;
}

void HeapTrimmer::run() {
  std::unique_lock lock(m_mutex);
  for (;;) {
    if (!m_firstPending) {
      if (m_stopping) {
        return;
      }
      m_changed.wait(lock);
      continue;
    }
    const Clock::time_point due =
        std::min(m_lastRequest + m_timing.quiet, *m_firstPending + m_timing.longest);
    if (!m_stopping && Clock::now() < due) {
      m_changed.wait_until(lock, due);  // woken early by a request, which may move `due`
      continue;
    }
    m_firstPending.reset();
    lock.unlock();
    m_trim();  // outside the lock: requests go on arriving while it runs
    lock.lock();
    // A trimmer stopping meanwhile (the server shutting down) has no use for
    // the reserve, and its destructor waits for this thread.
    if (m_refill && !m_stopping) {
      lock.unlock();
      m_refill();
      lock.lock();
    }
    ++m_trims;
  }
}

}  // namespace crackvis::service
