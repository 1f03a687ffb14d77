#include "session_registry.hpp"

#include <algorithm>
#include <chrono>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <grpcpp/server_context.h>

#include <crackvis/common/log.hpp>

namespace crackvis::service {

using rpc::Caller;

std::uint64_t AttachWatch::add(grpc::ServerContext* context) {
  std::lock_guard lock(m_mutex);
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(m_seconds));
  m_waiting.emplace(++m_next, Waiting{context, deadline});
  return m_next;
}

bool AttachWatch::remove(std::uint64_t id) {
  std::lock_guard lock(m_mutex);
  return m_waiting.erase(id) == 1;
}

void AttachWatch::cancelOverdue() {
  std::lock_guard lock(m_mutex);
  const auto now = Clock::now();
  for (auto it = m_waiting.begin(); it != m_waiting.end();) {
    if (now > it->second.deadline) {
      it->second.context->TryCancel();
      it = m_waiting.erase(it);
    } else {
      ++it;
    }
  }
}

Status SessionRegistry::reserve(const std::string& owner, bool perUser,
                                std::shared_ptr<Session>& reclaimed) {
  std::lock_guard lock(m_mutex);
  std::map<std::string, int> held = m_openingBy;
  for (const auto& [id, entry] : m_sessions) {
    ++held[entry.owner];
  }
  const int own = held[owner];
  if (perUser && own >= m_perUserLimit) {
    return resourceExhausted(fmt::format("user '{}' has the maximum of {} sessions per user open",
                                         owner, m_perUserLimit));
  }
  if (static_cast<int>(m_sessions.size()) + m_opening >= m_limit) {
    const int share = std::max(1, m_limit / static_cast<int>(held.size()));
    auto victim = own < share ? reclaimable(held, share) : m_sessions.end();
    if (victim == m_sessions.end()) {
      return resourceExhausted(fmt::format(
          "the server has its maximum of {} sessions open ({} owners; a fair share is {}, "
          "and '{}' holds {})",
          m_limit, held.size(), share, owner, own));
    }
    reclaimed = std::move(victim->second.session);
    m_sessions.erase(victim);
  }
  ++m_opening;
  ++m_openingBy[owner];
  return Status::ok();
}

void SessionRegistry::add(std::shared_ptr<Session> session, std::string owner) {
  std::lock_guard lock(m_mutex);
  --m_opening;
  if (--m_openingBy[owner] <= 0) {
    m_openingBy.erase(owner);
  }
  if (session) {
    const std::string id = session->id();
    m_sessions[id] = {std::move(session), std::move(owner)};
  }
}

Result<std::shared_ptr<Session>> SessionRegistry::find(const std::string& id,
                                                       const Caller& caller) const {
  std::lock_guard lock(m_mutex);
  auto it = m_sessions.find(id);
  if (it == m_sessions.end()) {
    return notFound(fmt::format("no session '{}' (closed, expired or never opened)", echoed(id)));
  }
  if (it->second.owner != caller.name) {
    return permissionDenied(
        fmt::format("session '{}' belongs to another user than '{}'", echoed(id), caller.name));
  }
  return it->second.session;
}

Status SessionRegistry::close(const std::string& id, const Caller& caller) {
  auto session = find(id, caller);
  if (!session) {
    return session.status();
  }
  (*session)->close();
  std::shared_ptr<Session> last;
  {
    std::lock_guard lock(m_mutex);
    auto it = m_sessions.find(id);
    if (it != m_sessions.end()) {
      last = std::move(it->second.session);
      m_sessions.erase(it);
    }
  }
  return Status::ok();  // `last` joins the session's thread here, outside the lock
}

void SessionRegistry::reap() {
  std::vector<std::shared_ptr<Session>> expired;
  {
    std::lock_guard lock(m_mutex);
    const auto now = Clock::now();
    for (auto it = m_sessions.begin(); it != m_sessions.end();) {
      auto since = it->second.session->detachedSince();
      if (it->second.session->closed() ||
          (since && std::chrono::duration<double>(now - *since).count() > m_grace)) {
        it->second.session->close();
        expired.push_back(std::move(it->second.session));
        it = m_sessions.erase(it);
      } else {
        ++it;
      }
    }
  }
  for (auto& session : expired) {
    log::event(stderr, "crackvis-render", "session_expired",
               {{"session", session->id()}, {"no_stream_seconds", fmt::format("{:.1f}", m_grace)}});
  }
}

void SessionRegistry::closeAll() {
  std::map<std::string, Entry> all;
  {
    std::lock_guard lock(m_mutex);
    all.swap(m_sessions);
  }
  for (auto& [id, entry] : all) {
    entry.session->close();
  }
}

int SessionRegistry::count() const {
  std::lock_guard lock(m_mutex);
  return static_cast<int>(m_sessions.size());
}

SessionRegistry::Entries::iterator SessionRegistry::reclaimable(
    const std::map<std::string, int>& held, int share) {
  std::string richest;
  int most = share;
  for (const auto& [owner, count] : held) {
    if (count > most) {
      richest = owner;
      most = count;
    }
  }
  auto victim = m_sessions.end();
  auto rank = [](const Session& session) {
    const auto detached = session.detachedSince();
    // A session without a stream goes before any with one.
    return std::pair{detached ? 0 : 1, detached ? *detached : session.lastActive()};
  };
  for (auto it = m_sessions.begin(); it != m_sessions.end() && !richest.empty(); ++it) {
    if (it->second.owner == richest &&
        (victim == m_sessions.end() || rank(*it->second.session) < rank(*victim->second.session))) {
      victim = it;
    }
  }
  return victim;
}

}  // namespace crackvis::service
