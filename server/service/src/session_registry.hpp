// The render server's bookkeeping that its reaper sweeps: the open sessions
// with their owners (the session limits, fair shares between users, expiry
// of a session whose stream has gone) and the streams that have not yet
// attached to a session. Private to the service library.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/rpc_server/credentials.hpp>
#include <crackvis/service/session.hpp>

namespace grpc {
class ServerContext;
}  // namespace grpc

namespace crackvis::service {

// Streams that have not sent their first (attaching) message yet. Each holds
// one of gRPC's handler threads while it waits, so one past its time is
// cancelled by the reaper: 500 streams that never attach cannot pin 500
// threads for ever.
class AttachWatch {
 public:
  explicit AttachWatch(double seconds) : m_seconds(seconds) {}

  std::uint64_t add(grpc::ServerContext* context);
  // Called before the handler returns, so the reaper never sees a context
  // that has gone. False when the reaper had cancelled the stream.
  bool remove(std::uint64_t id);
  void cancelOverdue();
  double seconds() const { return m_seconds; }

 private:
  struct Waiting {
    grpc::ServerContext* context;
    Clock::time_point deadline;
  };
  const double m_seconds;
  std::mutex m_mutex;
  std::map<std::uint64_t, Waiting> m_waiting;
  std::uint64_t m_next = 0;
};

// The sessions of a server, with their owners; closes those whose stream
// has been gone longer than the grace period.
class SessionRegistry {
 public:
  SessionRegistry(int limit, int perUserLimit, double graceSeconds)
      : m_limit(limit), m_perUserLimit(perUserLimit), m_grace(graceSeconds) {}

  // `perUser`: the owner is a configured user, counted against the
  // per-user limit (without users every client of one certificate name is
  // one owner). A full server lets in an owner below its fair share (the
  // limit divided among the owners with sessions, the newcomer counted) by
  // reclaiming a session of the owner furthest above it: the one whose
  // stream has been gone longest, else the one idle longest. It goes in
  // `reclaimed`, for the caller to close outside the lock.
  Status reserve(const std::string& owner, bool perUser, std::shared_ptr<Session>& reclaimed);
  void add(std::shared_ptr<Session> session, std::string owner);
  Result<std::shared_ptr<Session>> find(const std::string& id, const rpc::Caller& caller) const;
  Status close(const std::string& id, const rpc::Caller& caller);

  // Closes sessions whose stream has been gone longer than the grace.
  void reap();
  void closeAll();
  int count() const;

 private:
  struct Entry {
    std::shared_ptr<Session> session;
    std::string owner;
  };
  using Entries = std::map<std::string, Entry>;

  // The session to reclaim from the owner furthest above `share` (none when
  // every owner is within it): detached the longest, else idle the longest.
  Entries::iterator reclaimable(const std::map<std::string, int>& held, int share);

  const int m_limit;
  const int m_perUserLimit;
  const double m_grace;
  mutable std::mutex m_mutex;
  std::map<std::string, Entry> m_sessions;
  int m_opening = 0;
  std::map<std::string, int> m_openingBy;
};

}  // namespace crackvis::service
