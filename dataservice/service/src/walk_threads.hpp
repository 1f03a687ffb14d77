// Threads for the calls that wait on a whole-file walk (Describe), so that
// they never block gRPC's callback threads. Those threads are few (about
// one per core) and every handler of the service shares them: twelve
// Describes each waiting 0.6 s for an HDF5 worker held all of them, and
// another user's Read could not even start. A walk's handler hands its work
// here and returns; the work finishes the call from its own thread.
//
// Bounded: at most `perUser` walks of one user and `total` in all run at
// once; beyond, start() refuses with RESOURCE_EXHAUSTED at once. The
// destructor waits for every running walk. Private to the service library.
#pragma once

#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <string>

#include <crackvis/common/status.hpp>

namespace crackvis::dataservice {

class WalkThreads {
 public:
  WalkThreads(int perUser, int total) : m_perUser(perUser), m_total(total) {}
  WalkThreads(const WalkThreads&) = delete;
  WalkThreads& operator=(const WalkThreads&) = delete;
  ~WalkThreads();

  // Runs `work` on a thread of its own for `user`.
  Status start(const std::string& user, std::function<void()> work);
  int running() const;

 private:
  void finished(const std::string& user);

  const int m_perUser;
  const int m_total;
  mutable std::mutex m_mutex;
  std::condition_variable m_done;
  std::map<std::string, int> m_byUser;
  int m_running = 0;
};

}  // namespace crackvis::dataservice
