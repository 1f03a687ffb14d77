// A file descriptor (a socket) that closes itself: the raw sockets of the
// connection probe and of the raw TLS baseline.
#pragma once

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

 private:
  int m_fd;
};

}  // namespace crackvis
