// The TCP front of both gRPC servers: it binds the listen address, accepts
// every connection itself and hands the admitted ones to gRPC (ServerBuilder's
// external connection acceptor, which does the TLS and HTTP/2 handshakes with
// the server's credentials as for a port gRPC bound itself).
//
// Why not gRPC's own port: gRPC 1.51 has no limit on connections per address
// or in all, and no accept hook, so one address could hold every file
// descriptor of the process with idle connections (each closed only after
// its handshake time, and reopened at once). Here a connection past a limit
// is closed before any handshake, and the server's other users keep theirs.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/server_builder.h>
#include <sys/types.h>

#include <crackvis/common/status.hpp>
#include <crackvis/rpc/host_port.hpp>

namespace crackvis::rpc {

struct ConnectionLimits {
  // Behind a NAT or a proxy many users share one address: the cap bounds one
  // address's share of the descriptors, not one user's.
  int perAddress = 64;
  int total = 1024;
};

class ConnectionGate {
 public:
  // Binds every address `listen` names ("localhost": 127.0.0.1 and ::1;
  // "::": both families), all on one port; port 0 lets the OS choose it.
  // UNAVAILABLE naming the address when it is in use or not this machine's.
  static Result<std::unique_ptr<ConnectionGate>> bind(const HostPort& listen,
                                                      const std::string& what,
                                                      ConnectionLimits limits, std::string program);
  ConnectionGate(const ConnectionGate&) = delete;
  ConnectionGate& operator=(const ConnectionGate&) = delete;
  ~ConnectionGate();  // stops

  int port() const { return m_port; }

  // Starts accepting on a thread of its own; admitted connections go to
  // `acceptor`, which must belong to a started server.
  void start(std::unique_ptr<grpc::experimental::ExternalConnectionAcceptor> acceptor);
  // Stops accepting and closes the listening sockets; connections already
  // handed to gRPC stay with it. Idempotent.
  void stop();

  // Connections closed at once because a limit was reached, since bind().
  std::uint64_t refused() const { return m_refused.load(); }

 private:
  // A connection handed to gRPC, recognised by its socket's inode: gRPC
  // closes it without telling us, and may reuse the descriptor's number.
  struct Handed {
    int fd;
    dev_t device;
    ino_t inode;
    std::string address;
  };

  ConnectionGate() = default;
  void acceptLoop();
  void acceptFrom(int listener);
  // Drops the connections gRPC has closed, then says whether one more from
  // `address` fits both limits.
  bool admits(const std::string& address);
  void reportRefusal(const std::string& address, int limit, const char* which);

  ConnectionLimits m_limits;
  std::string m_program;
  std::vector<int> m_listeners;
  int m_wake = -1;  // eventfd: stop() wakes the accept loop
  int m_port = 0;
  std::unique_ptr<grpc::experimental::ExternalConnectionAcceptor> m_acceptor;
  std::thread m_thread;
  std::once_flag m_stopOnce;

  std::vector<Handed> m_handed;                      // only the accept thread touches it
  std::map<std::string, std::int64_t> m_lastReport;  // address -> steady seconds
  std::atomic<std::uint64_t> m_refused{0};
};

// The peer's address without its port ("127.0.0.1", "::1"); an IPv4 peer on a
// dual-stack socket is given as IPv4. "" when the socket has no peer.
std::string peerAddress(int fd);

}  // namespace crackvis::rpc
