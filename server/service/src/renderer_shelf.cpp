#include <algorithm>

#include <crackvis/service/renderer_shelf.hpp>

namespace crackvis::service {

RendererShelf::~RendererShelf() {
  if (m_stocking.joinable()) {
    m_stocking.join();
  }
}

void RendererShelf::stock(int width, int height) {
  std::lock_guard lock(m_mutex);
  if (m_stocking.joinable()) {
    return;
  }
  m_stocking = std::thread([this, width, height] {
    // Nothing stocked, whatever went wrong: the first session makes its own
    // and reports why if it cannot.
    try {
      auto made = render::SceneRenderer::create(width, height);
      if (made) {
        (*made)->releaseContext();
        put(std::move(made).value());
      }
    } catch (...) {
    }
  });
}

std::unique_ptr<render::SceneRenderer> RendererShelf::take(int width, int height,
                                                           std::chrono::milliseconds wait) {
  std::unique_lock lock(m_mutex);
  const auto deadline = std::chrono::steady_clock::now() + wait;
  const std::pair size{width, height};
  for (;;) {
    if (auto renderer = takeLocked(width, height)) {
      return renderer;
    }
    if (!m_incoming.contains(size)) {
      return nullptr;
    }
    ++m_waiting[size];
    const std::cv_status woken = m_changed.wait_until(lock, deadline);
    if (--m_waiting[size] <= 0) {
      m_waiting.erase(size);
    }
    if (woken == std::cv_status::timeout) {
      return takeLocked(width, height);
    }
  }
}

bool RendererShelf::awaited(const render::SceneRenderer& renderer) const {
  return m_waiting.contains({renderer.capacityWidth(), renderer.capacityHeight()});
}

int RendererShelf::waiting(int width, int height) const {
  std::lock_guard lock(m_mutex);
  const auto it = m_waiting.find({width, height});
  return it != m_waiting.end() ? it->second : 0;
}

std::unique_ptr<render::SceneRenderer> RendererShelf::takeLocked(int width, int height) {
  for (auto it = m_kept.begin(); it != m_kept.end(); ++it) {
    if ((*it)->capacityWidth() == width && (*it)->capacityHeight() == height) {
      auto renderer = std::move(*it);
      m_kept.erase(it);
      return renderer;
    }
  }
  return nullptr;
}

void RendererShelf::expect(int width, int height) {
  std::lock_guard lock(m_mutex);
  ++m_incoming[{width, height}];
}

void RendererShelf::arrived(int width, int height) {
  {
    std::lock_guard lock(m_mutex);
    const auto it = m_incoming.find({width, height});
    if (it != m_incoming.end() && --it->second <= 0) {
      m_incoming.erase(it);
    }
  }
  m_changed.notify_all();
}

int RendererShelf::expected(int width, int height) const {
  std::lock_guard lock(m_mutex);
  const auto it = m_incoming.find({width, height});
  return it != m_incoming.end() ? it->second : 0;
}

void RendererShelf::put(std::unique_ptr<render::SceneRenderer> renderer) {
  std::unique_ptr<render::SceneRenderer> dropped;
  {
    std::lock_guard lock(m_mutex);
    if (m_capacity == 0) {
      dropped = std::move(renderer);
    } else if (m_kept.size() < m_capacity) {
      m_kept.push_back(std::move(renderer));
    } else {
      // The oldest no take waits for; else the one put, unless it is awaited.
      auto victim = std::find_if(m_kept.begin(), m_kept.end(),
                                 [&](const auto& kept) { return !awaited(*kept); });
      if (victim == m_kept.end() && !awaited(*renderer)) {
        dropped = std::move(renderer);
      } else {
        if (victim == m_kept.end()) {
          victim = m_kept.begin();
        }
        dropped = std::move(*victim);
        m_kept.erase(victim);
        m_kept.push_back(std::move(renderer));
      }
    }
  }
  m_changed.notify_all();
  dropped.reset();  // outside the lock: it makes its context current to go
}

std::size_t RendererShelf::size() const {
  std::lock_guard lock(m_mutex);
  return m_kept.size();
}

}  // namespace crackvis::service
