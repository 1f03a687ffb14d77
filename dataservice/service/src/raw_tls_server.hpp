// The raw TLS baseline: the file bytes over a plain TLS socket with the same
// certificates, path rules, users and limits as the gRPC service, so that
// `crackvis bench transfer` can measure what the link itself delivers. Off
// unless `raw_tls_listen` is set. The wire protocol (docs/protocol.md):
//
//   client: "CRACKVIS-RAW 1\nfile: <path>\noffset: <n>\nlength: <n>\n
//            [authorization: <value>\n]\n"
//   server: "OK <bytes>\n" and the bytes, or "ERROR <STATUS> <message>\n"
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <crackvis/dataservice_config/server_config.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/rpc_server/access_log.hpp>
#include <crackvis/rpc_server/credentials.hpp>
#include <crackvis/tls/tls_material.hpp>

typedef struct ssl_ctx_st SSL_CTX;

namespace crackvis::dataservice {

using rpc::AccessLog;
using rpc::AccessRecord;
using rpc::Authenticator;

class RawTlsServer {
 public:
  static Result<std::unique_ptr<RawTlsServer>> start(const std::string& listen,
                                                     const tls::TlsMaterial& tls,
                                                     const Catalogue& catalogue,
                                                     const Authenticator& authenticator,
                                                     const Limits& limits, AccessLog& log);
  RawTlsServer(const RawTlsServer&) = delete;
  RawTlsServer& operator=(const RawTlsServer&) = delete;
  ~RawTlsServer();

  int port() const { return m_port; }
  void stop();

 private:
  RawTlsServer(const Catalogue& catalogue, const Authenticator& authenticator, const Limits& limits,
               AccessLog& log)
      : m_catalogue(catalogue), m_authenticator(authenticator), m_limits(limits), m_log(log) {}
  void acceptLoop();
  void serve(int fd, std::string peer);
  // Shuts the connections down whose handshake and request did not arrive
  // within handshakeSeconds (an idle TCP connection must not hold a slot).
  void closeStalled();
  void requestReceived(int fd);

  const Catalogue& m_catalogue;
  const Authenticator& m_authenticator;
  Limits m_limits;
  AccessLog& m_log;
  SSL_CTX* m_context = nullptr;
  int m_listenFd = -1;
  int m_wakePipe[2] = {-1, -1};
  int m_port = 0;
  std::atomic<bool> m_stopping{false};
  std::thread m_acceptThread;
  // Connections run on detached threads; stop() waits until none is left.
  std::mutex m_mutex;
  std::condition_variable m_idle;
  int m_active = 0;
  // Open connections and the time by which each must have sent its request
  // (time_point::max() once it has).
  std::map<int, std::chrono::steady_clock::time_point> m_connections;
};

}  // namespace crackvis::dataservice
