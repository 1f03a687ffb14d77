// The start-up and shut-down both gRPC servers share (crackvis-data and
// crackvis-render): the loopback rule for plaintext, mutual-TLS server
// credentials, the grpc.health.v1 service with its serving status, server
// reflection, binding through the connection gate (limits per address and in
// all; "address in use" is an error, SO_REUSEPORT off, so a second server on
// a busy port fails instead of taking half the connections), a reaper
// thread, and a shutdown that waits for the calls.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include <crackvis/common/status.hpp>
#include <crackvis/rpc/host_port.hpp>
#include <crackvis/rpc_server/connection_gate.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::rpc {

// "host:port", with IPv6 hosts bracketed ("[::1]:50051").
std::string formatHostPort(const std::string& host, int port);

// FAILED_PRECONDITION unless `target`'s host is a loopback address; `what`
// names the option that asked for plaintext ("--insecure").
Status requireLoopback(const std::string& target, const std::string& what);

// Where and how a server listens, checked before anything else is set up.
struct Listener {
  std::string listen;  // as configured
  HostPort hostPort;
  bool insecure = false;
  std::shared_ptr<grpc::ServerCredentials> credentials;
};
// Parses the address, applies the loopback rule for `insecure` and loads the
// TLS files (client certificates required and verified against the CA).
Result<Listener> prepareListener(const std::string& listen, bool insecure,
                                 const tls::TlsFiles& tls);

struct ServerSettings {
  std::string program;  // "crackvis-data", for messages and the plaintext warning
  // The program's own gRPC service ("crackvis.v1.DataService"): the health
  // service reports it by name too, so a client that reached the wrong kind
  // of server can say which it reached (connection_advice.hpp).
  std::string service;
  int maxReceiveMessageBytes = 4 << 20;
  int maxConcurrentStreams = 0;  // per connection; 0: gRPC's default
  int maxThreads = 0;            // gRPC's handler threads (sync services); 0: unbounded
  // A connection must finish its TLS and HTTP/2 handshake within this time
  // (an idle TCP connection is closed then), and one with no call for
  // `idleConnection` is sent GOAWAY and closed; a client reconnects when it
  // next calls. Idle connections must not pile up for ever.
  std::chrono::milliseconds handshake{10'000};
  std::chrono::milliseconds idleConnection{300'000};
  // Connections past these are closed before any handshake (connection_gate.hpp).
  ConnectionLimits connections;
  std::chrono::milliseconds reapPeriod{100};
  std::function<void()> reap;        // run every reapPeriod on the reaper thread; may be empty
  std::function<void()> beforeStop;  // run by shutdown() before gRPC stops; may be empty
};

class ServerHost {
 public:
  // Registers the services, binds, starts serving and sets the health
  // status to SERVING. UNAVAILABLE naming the address when it is in use.
  static Result<std::unique_ptr<ServerHost>> start(const Listener& listener,
                                                   const std::vector<grpc::Service*>& services,
                                                   ServerSettings settings);
  ServerHost(const ServerHost&) = delete;
  ServerHost& operator=(const ServerHost&) = delete;
  ~ServerHost();  // shuts down if still running

  const std::string& address() const { return m_address; }  // host:port as bound
  int port() const { return m_port; }

  // NOT_SERVING, stops the reaper, runs beforeStop, stops accepting calls,
  // gives running ones `graceSeconds` and cancels the rest, then waits for
  // every handler to return; idempotent.
  void shutdown(double graceSeconds);
  // Blocks until shutdown() has been called.
  void wait();
  bool stopping() const;

 private:
  ServerHost() = default;
  void reapLoop();

  ServerSettings m_settings;
  std::unique_ptr<ConnectionGate> m_gate;
  std::unique_ptr<grpc::Server> m_server;
  std::string m_address;
  int m_port = 0;

  mutable std::mutex m_mutex;
  std::condition_variable m_stopped;
  bool m_stopping = false;
  std::once_flag m_shutdownOnce;
  std::thread m_reaper;
};

}  // namespace crackvis::rpc
