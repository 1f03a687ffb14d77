// crackvis-render's server: the RenderService over gRPC with mutual TLS (the
// same per-user credentials as crackvis-data), the standard grpc.health.v1
// service and server reflection. Sessions read their data through
// crackvis-data, the render server being a TLS client of it with its own
// certificate. This header has no gRPC types; crackvis-render's main and the
// tests start a server through it.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_client/data_client.hpp>
#include <crackvis/rpc_server/credentials.hpp>
#include <crackvis/service/session.hpp>

namespace crackvis::service {

// localhost:50051 with certs/generated/crackvis-render.pem and .key.
dataservice::ClientOptions defaultDataOptions();

// The web front door (docs/protocol.md, "The browser page"): one HTTPS port
// that serves the page and its calls, and a WebSocket per session stream,
// onto the same sessions, limits, users and access log as the gRPC service.
struct WebConfig {
  std::string listen;  // host:port; empty: no web front door
  // The page's folder (index.html, app.js, app.css); empty: the installed
  // page (share/crackvis/web beside the program), else the build tree's.
  std::string root;
  // Origins besides the page's own whose pages may call (a reverse proxy's
  // public name: "https://viz.example.org").
  std::vector<std::string> origins;
};

struct RenderServerConfig {
  std::string listen = "127.0.0.1:50052";  // host:port; port 0 lets the OS choose
  tls::TlsFiles tls = tls::defaultTlsFiles("server", "--", "tls.");
  bool insecure = false;              // plaintext, loopback only
  std::vector<rpc::UserEntry> users;  // empty: every certified client
  // crackvis-data, reached with the render server's own client certificate.
  dataservice::ClientOptions data = defaultDataOptions();
  int maxSessions = 8;
  int maxSessionsPerUser = 4;  // of maxSessions, for one configured user (none without users)
  double sessionGraceSeconds = 30.0;  // a session without a stream lives this long
  double attachSeconds = 10.0;        // a stream must attach to a session within this time
  // Renderers of ended sessions kept for the next session of their view
  // size, one stocked at start (RendererShelf; 0: every session makes its own).
  int keptRenderers = 1;
  // MiB of heap kept touched while idle (common/heap_reserve.hpp), written
  // at start and kept back from each trim of the heap, so that a first
  // picture finds resident pages (0: none).
  int heapReserveMb = 160;
  // What ended sessions freed beyond the reserve goes back to the system
  // once no session has ended for this long (HeapTrimmer). A trim between
  // one session's close and the next open makes that open fault the pages
  // in again (cuboid A: 147-163 ms against 128-137 untrimmed, a second
  // after the close), so it waits out a user choosing the next file.
  int heapTrimAfterMs = 10000;
  SessionLimits limits;
  std::string accessLog = "-";  // "-": stderr; "": none
  WebConfig web;
};

// Reads a JSON configuration (deploy/config/render.json shows one): listen,
// tls {ca, cert, key}, insecure, users_from (a crackvis-data configuration
// whose users apply here too), data_service {target, ca, cert, key, token,
// insecure, server_name}, limits {max_sessions, max_sessions_per_user,
// session_grace_seconds, attach_seconds, kept_renderers, heap_reserve_mb, refine_after_ms,
// interactive_frame_ms, max_width, max_height, max_particles, max_bonds},
// access_log, web {listen, root, origins}.
// Unknown keys are errors; values are range-checked by
// validateRenderServerConfig once flags are applied.
Result<RenderServerConfig> loadRenderServerConfig(const std::string& path);
Result<RenderServerConfig> parseRenderServerConfig(const std::string& json,
                                                   const std::string& origin);

// The merged configuration (file, then flags), checked once before the
// server starts; INVALID_ARGUMENT naming the flag and the file's key.
Status validateRenderServerConfig(const RenderServerConfig& config);

class RenderServer {
 public:
  // Checks the configuration (TLS files, loopback for --insecure and for
  // --data-insecure, the data service's TLS files), binds and starts serving
  // (health status SERVING); "address in use" when the port is taken. A data service that is
  // down is not an error here: sessions report it when they open.
  static Result<std::unique_ptr<RenderServer>> start(const RenderServerConfig& config);
  RenderServer(const RenderServer&) = delete;
  RenderServer& operator=(const RenderServer&) = delete;
  ~RenderServer();

  const std::string& address() const;
  int port() const;
  // The web front door's address and port ("" and 0 without one).
  std::string webAddress() const;
  int webPort() const;
  int sessionCount() const;
  // Renderers of ended sessions (or stocked at start) waiting for the next
  // session: each holds a GL context (RendererShelf).
  int keptRenderers() const;
  // The heap kept touched while idle (RenderServerConfig::heapReserveMb):
  // 0 when none was asked for, or when threads do not share the main heap.
  std::size_t heapReserveBytes() const;
  // Whether the connection to crackvis-data is made (it is started as the
  // server starts, and retried while crackvis-data is unreachable).
  bool dataServiceConnected() const;

  // Closes every session, ends the streams, stops serving (NOT_SERVING
  // first) and waits for the calls to end; idempotent.
  void shutdown(double graceSeconds = 2.0);
  // Blocks until shutdown() has been called.
  void wait();

 private:
  struct Impl;
  explicit RenderServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> m_impl;
};

}  // namespace crackvis::service
