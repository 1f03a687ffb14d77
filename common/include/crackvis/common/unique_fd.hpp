// A file descriptor that closes itself: the raw sockets of the connection
// probe and of the raw TLS baseline, an HDF5 worker's socket and buffer
// while it starts.
#pragma once

#include <utility>

#include <unistd.h>

namespace crackvis {

class UniqueFd {
 public:
  explicit UniqueFd(int fd) : m_fd(fd) {}
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd() {
    if (m_fd >= 0) {
      ::close(m_fd);
    }
  }
  int get() const { return m_fd; }
  // Hands the descriptor over; this no longer closes it.
  int release() { return std::exchange(m_fd, -1); }

 private:
  int m_fd;
};

}  // namespace crackvis
