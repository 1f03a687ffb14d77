#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <string>

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <crackvis/common/service_manager.hpp>

namespace crackvis::service_manager {
namespace {

// The socket address of $NOTIFY_SOCKET: a path, or with a leading '@' a name
// in Linux's abstract namespace (what systemd uses inside containers).
bool addressOf(const char* name, sockaddr_un& address, socklen_t& length) {
  const std::size_t size = std::strlen(name);
  if (size < 2 || size >= sizeof(address.sun_path) || (name[0] != '/' && name[0] != '@')) {
    return false;
  }
  address = {};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, name, size);
  if (name[0] == '@') {
    address.sun_path[0] = '\0';
  }
  length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + size);
  return true;
}

}  // namespace

bool notify(std::string_view state) {
  const char* name = std::getenv("NOTIFY_SOCKET");
  sockaddr_un address{};
  socklen_t length = 0;
  if (name == nullptr || !addressOf(name, address, length)) {
    return false;
  }
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    return false;
  }
  const ssize_t sent = sendto(fd, state.data(), state.size(), MSG_NOSIGNAL,
                              reinterpret_cast<const sockaddr*>(&address), length);
  close(fd);
  return sent == static_cast<ssize_t>(state.size());
}

}  // namespace crackvis::service_manager
