#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <crackvis/rpc_server/connection_gate.hpp>

namespace crackvis::rpc {
namespace {

void closeAll(std::vector<int>& fds) {
  for (int fd : fds) {
    ::close(fd);
  }
  fds.clear();
}

struct AddressList {
  addrinfo* head = nullptr;
  ~AddressList() {
    if (head != nullptr) {
      freeaddrinfo(head);
    }
  }
};

int boundPort(int fd) {
  sockaddr_storage address{};
  socklen_t length = sizeof(address);
  if (getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    return 0;
  }
  if (address.ss_family == AF_INET6) {
    return ntohs(reinterpret_cast<sockaddr_in6*>(&address)->sin6_port);
  }
  return ntohs(reinterpret_cast<sockaddr_in*>(&address)->sin_port);
}

void setPort(addrinfo& entry, int port) {
  if (entry.ai_family == AF_INET6) {
    reinterpret_cast<sockaddr_in6*>(entry.ai_addr)->sin6_port = htons(static_cast<uint16_t>(port));
  } else {
    reinterpret_cast<sockaddr_in*>(entry.ai_addr)->sin_port = htons(static_cast<uint16_t>(port));
  }
}

bool isWildcard6(const addrinfo& entry) {
  const auto* address = reinterpret_cast<const sockaddr_in6*>(entry.ai_addr);
  return entry.ai_family == AF_INET6 && IN6_IS_ADDR_UNSPECIFIED(&address->sin6_addr);
}

// One listening socket, non-blocking; -1 with errno set when it cannot bind.
int listenOn(const addrinfo& entry) {
  const int fd = ::socket(entry.ai_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    return -1;
  }
  const int one = 1;
  // SO_REUSEADDR (not SO_REUSEPORT): a restart may bind over TIME_WAIT, but
  // a second server on a busy port fails instead of taking half the
  // connections.
  (void)setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (entry.ai_family == AF_INET6) {
    // "::" serves both families, as gRPC's own wildcard port does.
    const int v6only = isWildcard6(entry) ? 0 : 1;
    (void)setsockopt(fd, IPPROTO_IPV6, IPV6_V6ONLY, &v6only, sizeof(v6only));
  }
  // Accepted sockets inherit it: small messages (input events) go at once.
  (void)setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  if (::bind(fd, entry.ai_addr, entry.ai_addrlen) != 0 || ::listen(fd, SOMAXCONN) != 0) {
    const int error = errno;
    ::close(fd);
    errno = error;
    return -1;
  }
  return fd;
}

std::int64_t steadySeconds() {
  return std::chrono::duration_cast<std::chrono::seconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

std::string peerAddress(int fd) {
  sockaddr_storage address{};
  socklen_t length = sizeof(address);
  if (getpeername(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    return "";
  }
  char text[INET6_ADDRSTRLEN] = {};
  if (address.ss_family == AF_INET6) {
    const auto* v6 = reinterpret_cast<const sockaddr_in6*>(&address);
    if (IN6_IS_ADDR_V4MAPPED(&v6->sin6_addr)) {
      // The last four bytes are the IPv4 address.
      (void)inet_ntop(AF_INET, &v6->sin6_addr.s6_addr[12], text, sizeof(text));
    } else {
      (void)inet_ntop(AF_INET6, &v6->sin6_addr, text, sizeof(text));
    }
  } else if (address.ss_family == AF_INET) {
    (void)inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(&address)->sin_addr, text,
                    sizeof(text));
  }
  return text;
}

Result<std::unique_ptr<ConnectionGate>> ConnectionGate::bind(const HostPort& listen,
                                                             const std::string& what,
                                                             ConnectionLimits limits,
                                                             std::string program) {
  std::unique_ptr<ConnectionGate> gate(new ConnectionGate());
  gate->m_limits = limits;
  gate->m_program = std::move(program);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  AddressList addresses;
  const std::string port = std::to_string(listen.port);
  const int resolved = getaddrinfo(listen.host.empty() ? nullptr : listen.host.c_str(),
                                   port.c_str(), &hints, &addresses.head);
  if (resolved != 0) {
    return unavailable(fmt::format("cannot listen on {}: {}", what, gai_strerror(resolved)));
  }
  // A dual-stack "::" socket already takes IPv4: a second socket on
  // 0.0.0.0 would collide with it.
  bool dualStack = false;
  for (addrinfo* entry = addresses.head; entry != nullptr; entry = entry->ai_next) {
    dualStack = dualStack || isWildcard6(*entry);
  }
  int firstError = 0;
  for (addrinfo* entry = addresses.head; entry != nullptr; entry = entry->ai_next) {
    if (dualStack && entry->ai_family == AF_INET) {
      continue;
    }
    if (gate->m_port != 0) {
      setPort(*entry, gate->m_port);  // every address on the port the first one got
    }
    const int fd = listenOn(*entry);
    if (fd < 0) {
      firstError = firstError != 0 ? firstError : errno;
      continue;
    }
    gate->m_listeners.push_back(fd);
    gate->m_port = boundPort(fd);
  }
  // As gRPC's own port: bound if any of the addresses could be.
  if (gate->m_listeners.empty()) {
    return unavailable(fmt::format(
        "cannot listen on {}: {} (the address is in use, or not an address of this machine)", what,
        std::strerror(firstError)));
  }
  gate->m_wake = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (gate->m_wake < 0) {
    closeAll(gate->m_listeners);
    return unavailable(fmt::format("cannot listen on {}: eventfd: {}", what, std::strerror(errno)));
  }
  return gate;
}

ConnectionGate::~ConnectionGate() {
  stop();
}

void ConnectionGate::start(
    std::unique_ptr<grpc::experimental::ExternalConnectionAcceptor> acceptor) {
  m_acceptor = std::move(acceptor);
  m_thread = std::thread([this] { acceptLoop(); });
}

void ConnectionGate::stop() {
  std::call_once(m_stopOnce, [this] {
    if (m_wake >= 0) {
      const std::uint64_t one = 1;
      (void)!::write(m_wake, &one, sizeof(one));
    }
    if (m_thread.joinable()) {
      m_thread.join();
    }
    closeAll(m_listeners);
    if (m_wake >= 0) {
      ::close(m_wake);
      m_wake = -1;
    }
  });
}

void ConnectionGate::acceptLoop() {
  std::vector<pollfd> waits;
  for (int fd : m_listeners) {
    waits.push_back({fd, POLLIN, 0});
  }
  waits.push_back({m_wake, POLLIN, 0});
  for (;;) {
    if (::poll(waits.data(), waits.size(), -1) < 0) {
      if (errno == EINTR) {
        continue;
      }
      std::fprintf(stderr, "%s: the connection gate stopped: poll: %s\n", m_program.c_str(),
                   std::strerror(errno));
      return;
    }
    if (waits.back().revents != 0) {
      return;  // stop()
    }
    for (std::size_t i = 0; i + 1 < waits.size(); ++i) {
      if (waits[i].revents != 0) {
        acceptFrom(waits[i].fd);
      }
    }
  }
}

void ConnectionGate::acceptFrom(int listener) {
  for (;;) {
    const int fd = ::accept4(listener, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        // Out of descriptors: the pending connection waits in the backlog;
        // do not spin on it.
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      return;  // EAGAIN: drained; ECONNABORTED and the like: gone already
    }
    const std::string address = peerAddress(fd);
    if (!admits(address)) {
      ::close(fd);
      continue;
    }
    struct stat status {};
    if (::fstat(fd, &status) != 0) {
      ::close(fd);
      continue;
    }
    m_handed.push_back({fd, status.st_dev, status.st_ino, address});
    grpc::experimental::ExternalConnectionAcceptor::NewConnectionParameters connection;
    connection.listener_fd = listener;
    connection.fd = fd;
    m_acceptor->HandleNewConnection(&connection);  // gRPC owns fd from here
  }
}

bool ConnectionGate::admits(const std::string& address) {
  // A connection gRPC has closed no longer has its socket behind the number
  // (or another one does): at most `total` fstat calls per accept.
  m_handed.erase(std::remove_if(m_handed.begin(), m_handed.end(),
                                [](const Handed& handed) {
                                  struct stat status {};
                                  return ::fstat(handed.fd, &status) != 0 ||
                                         status.st_ino != handed.inode ||
                                         status.st_dev != handed.device;
                                }),
                 m_handed.end());
  if (static_cast<int>(m_handed.size()) >= m_limits.total) {
    reportRefusal(address, m_limits.total, "connections are open in all");
    return false;
  }
  const auto fromAddress =
      std::count_if(m_handed.begin(), m_handed.end(),
                    [&](const Handed& handed) { return handed.address == address; });
  if (fromAddress >= m_limits.perAddress) {
    reportRefusal(address, m_limits.perAddress, "connections from that address are open");
    return false;
  }
  return true;
}

void ConnectionGate::reportRefusal(const std::string& address, int limit, const char* which) {
  ++m_refused;
  // One line per address a minute: a flood must not flood the log too.
  const std::int64_t now = steadySeconds();
  if (m_lastReport.size() > 4096) {
    m_lastReport.clear();
  }
  auto [entry, inserted] = m_lastReport.try_emplace(address, now);
  if (!inserted && now - entry->second < 60) {
    return;
  }
  entry->second = now;
  std::fprintf(stderr,
               "%s: refused connections from %s: %d %s (further refusals from it are not "
               "logged for a minute)\n",
               m_program.c_str(), address.c_str(), limit, which);
}

}  // namespace crackvis::rpc
