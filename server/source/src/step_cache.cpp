#include <algorithm>
#include <chrono>

#include <crackvis/common/elapsed.hpp>
#include <crackvis/source/step_source.hpp>

namespace crackvis::source {

StepCache::StepCache(std::unique_ptr<StepSource> source, std::size_t capacity)
    : m_source(std::move(source)),
      m_capacity(capacity < 1 ? 1 : capacity),
      m_prefetcher([this] { prefetchLoop(); }) {}

StepCache::~StepCache() {
  {
    std::lock_guard lock(m_mutex);
    m_stopping = true;
  }
  m_changed.notify_all();
  m_prefetcher.join();
}

namespace {

auto holding(int step) {
  return [step](const std::shared_ptr<const SourceStep>& held) { return held->index == step; };
}

}  // namespace

std::shared_ptr<const SourceStep> StepCache::lookup(int step) {
  const auto it = std::find_if(m_steps.begin(), m_steps.end(), holding(step));
  if (it == m_steps.end()) {
    return nullptr;
  }
  auto found = *it;
  m_steps.splice(m_steps.begin(), m_steps, it);  // most recently used first
  return found;
}

void StepCache::insert(std::shared_ptr<const SourceStep> step) {
  if (lookup(step->index) != nullptr) {
    return;
  }
  m_steps.push_front(std::move(step));
  while (m_steps.size() > m_capacity) {
    m_steps.pop_back();
  }
}

bool StepCache::cached(int step) const {
  return std::any_of(m_steps.begin(), m_steps.end(), holding(step));
}

Result<CachedStep> StepCache::get(int step) {
  double waitedMs = 0.0;
  {
    std::unique_lock lock(m_mutex);
    // A prefetch of this very step is asked for or under way: wait for it
    // instead of reading the same bytes twice. A step the cache holds is
    // never waited for, whatever the prefetch thread is reading. The wait
    // is the part of the read that the caller's other work did not hide,
    // counted as the step's load time.
    const auto inFlight = [&] {
      return !m_stopping && (m_reading == step || m_wanted == step) && !cached(step);
    };
    if (inFlight()) {
      const auto start = std::chrono::steady_clock::now();
      m_changed.wait(lock, [&] { return !inFlight(); });
      waitedMs = millisecondsSince(start);
    }
    if (auto found = lookup(step)) {
      ++m_stats.hits;
      return CachedStep{std::move(found), waitedMs};
    }
    ++m_stats.misses;
  }
  std::lock_guard reading(m_readMutex);
  auto loaded = m_source->read(step);
  if (!loaded) {
    return loaded.status();
  }
  auto shared = std::make_shared<const SourceStep>(std::move(loaded).value());
  std::lock_guard lock(m_mutex);
  insert(shared);
  // A prefetch that failed or was replaced by another: its wait counts too.
  return CachedStep{shared, waitedMs + shared->loadMs};
}

Result<SourceStep> StepCache::readAside(int step) {
  std::lock_guard reading(m_readMutex);
  return m_source->read(step);
}

Result<bool> StepCache::refresh() {
  // Between reads, and with prefetch()'s range check held off: the source's
  // list of steps changes.
  std::lock_guard reading(m_readMutex);
  std::lock_guard lock(m_mutex);
  return m_source->refresh();
}

void StepCache::prefetch(int step) {
  {
    std::lock_guard lock(m_mutex);
    if (step < 0 || step >= m_source->stepCount() || cached(step)) {
      return;
    }
    m_wanted = step;
  }
  m_changed.notify_all();
}

StepCache::Stats StepCache::stats() const {
  std::lock_guard lock(m_mutex);
  return m_stats;
}

void StepCache::prefetchLoop() {
  std::unique_lock lock(m_mutex);
  while (true) {
    m_changed.wait(lock, [&] { return m_stopping || m_wanted >= 0; });
    if (m_stopping) {
      return;
    }
    const int step = m_wanted;
    m_wanted = -1;
    if (lookup(step) != nullptr) {
      m_changed.notify_all();  // a get() may wait for this step
      continue;
    }
    m_reading = step;
    lock.unlock();
    Result<SourceStep> loaded = [&] {
      std::lock_guard reading(m_readMutex);
      return m_source->read(step);
    }();
    lock.lock();
    m_reading = -1;
    // A failed prefetch is not an error: get() reads again and reports it.
    if (loaded) {
      insert(std::make_shared<const SourceStep>(std::move(loaded).value()));
      ++m_stats.prefetched;
    }
    m_changed.notify_all();
  }
}

}  // namespace crackvis::source
