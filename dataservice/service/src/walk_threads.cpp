#include "walk_threads.hpp"

#include <thread>

#include <fmt/format.h>

namespace crackvis::dataservice {

WalkThreads::~WalkThreads() {
  std::unique_lock lock(m_mutex);
  m_done.wait(lock, [&] { return m_running == 0; });
}

Status WalkThreads::start(const std::string& user, std::function<void()> work) {
  {
    std::lock_guard lock(m_mutex);
    if (m_running >= m_total) {
      return resourceExhausted(
          fmt::format("the server walks {} files at once, its limit; retry later", m_running));
    }
    if (m_byUser[user] >= m_perUser) {
      return resourceExhausted(fmt::format(
          "user '{}' has {} Describes walking files at once, the limit per user; retry later",
          echoed(user), m_perUser));
    }
    ++m_running;
    ++m_byUser[user];
  }
  try {
    std::thread([this, user, work = std::move(work)] {
      work();
      finished(user);
    }).detach();
  } catch (const std::system_error& error) {
    finished(user);
    return unavailable(fmt::format("cannot start a thread for the walk: {}", error.what()));
  }
  return Status::ok();
}

void WalkThreads::finished(const std::string& user) {
  // Notified under the lock: once the destructor sees no walk running, no
  // thread touches this object again.
  std::lock_guard lock(m_mutex);
  --m_running;
  if (--m_byUser[user] <= 0) {
    m_byUser.erase(user);
  }
  m_done.notify_all();
}

int WalkThreads::running() const {
  std::lock_guard lock(m_mutex);
  return m_running;
}

}  // namespace crackvis::dataservice
