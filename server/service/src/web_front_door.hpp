// The web front door of crackvis-render: the browser page's way in, beside
// the gRPC one (docs/protocol.md, "The browser page"). One port serves, over
// HTTPS (plaintext only on loopback, as gRPC):
//
//   GET  /, /app.js, ...                         the page (a flat folder, held in memory)
//   POST /api/login, /api/logout; GET /api/whoami  sign-in for a session cookie
//   POST /rpc/crackvis.v1.RenderService/<Call>   a unary call: protobuf in, protobuf out
//   GET  /rpc/crackvis.v1.RenderService/Stream   WebSocket: ClientEvent in, ServerMessage out
//
// The calls run RenderServiceImpl's transport-free bodies and its one writer
// loop, so the web page gets the gRPC service's sessions, limits, folder
// rules and access log, with no second copy of them. Private to the service
// library; Boost.Beast stays inside web_front_door.cpp.
#pragma once

#include <memory>
#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/service/render_server.hpp>

namespace crackvis::service {

class RenderServiceImpl;

// The calls the page may make, the path prefix they share, and the stream's path.
inline constexpr const char* kWebCallPrefix = "/rpc/crackvis.v1.RenderService/";
inline constexpr const char* kWebStreamPath = "/rpc/crackvis.v1.RenderService/Stream";

// The page's folder: `configured` when given, else the installed page beside
// the program (../share/crackvis/web), else the build tree's.
std::string webRoot(const std::string& configured);

class WebFrontDoor {
 public:
  // Loads the page, binds `config.web.listen` and starts serving; the
  // service must outlive the front door.
  static Result<std::unique_ptr<WebFrontDoor>> start(const RenderServerConfig& config,
                                                     RenderServiceImpl& service);
  WebFrontDoor(const WebFrontDoor&) = delete;
  WebFrontDoor& operator=(const WebFrontDoor&) = delete;
  ~WebFrontDoor();

  const std::string& address() const;
  int port() const;

  // Stops accepting, waits (bounded) for the streams' writer loops, which
  // end once the sessions close, then stops; idempotent.
  void shutdown();

  struct Impl;

 private:
  explicit WebFrontDoor(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> m_impl;
};

}  // namespace crackvis::service
