// The web front door (web_front_door.hpp) on Boost.Beast: one io_context
// (two threads) runs every connection's reads and writes on that
// connection's strand, because an OpenSSL stream may not be read in one
// thread and written in another. What blocks runs elsewhere: unary calls and
// sign-ins (crackvis-data, PBKDF2) on a small worker pool, and each stream's
// writer loop (RenderServiceImpl::pumpStream) on a thread of its own that
// hands each message to the strand and waits for it to be written, the
// back-pressure a blocking gRPC Write gives.
#include "web_front_door.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include <boost/asio/ssl.hpp>
#include <boost/asio/strand.hpp>
#include <boost/asio/thread_pool.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <openssl/ssl.h>
#include <unistd.h>

#include "render_service.hpp"
#include "web_sign_in.hpp"
#include <crackvis/common/log.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/rpc/host_port.hpp>
#include <crackvis/rpc_server/server.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::service {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
namespace ssl = net::ssl;
using tcp = net::ip::tcp;
using Request = http::request<http::string_body>;
using Response = http::response<http::string_body>;

namespace {

// Limits of the front door (docs/security.md's limits table).
constexpr std::size_t kMaxRequestBody = pipeline::kMaxPipelineBytes + 8192;
constexpr std::size_t kMaxStreamMessage = pipeline::kMaxPipelineBytes + 8192;
// A stream message over kMaxStreamMessage is read to its end and dropped, so
// that the client, still sending it, reads the close frame (1009) instead of
// a reset: a socket closed with the message's rest unread resets the
// connection. Beyond this the connection is failed at once (Beast's limit).
constexpr std::size_t kMaxDrainedMessage = std::size_t{64} << 20;
constexpr std::size_t kStreamReadChunk = 64 * 1024;
constexpr std::uint32_t kMaxHeaderBytes = 16 * 1024;
constexpr int kMaxConnections = 1024;
constexpr int kMaxConnectionsPerAddress = 64;
constexpr int kCallWorkers = 8;
// Of the calls waiting for or running on those workers, one caller's: a user
// who floods slow calls (OpenSession of a large file) holds at most half the
// workers, and the others' calls still run.
constexpr int kMaxCallsPerCaller = 4;
constexpr std::size_t kMaxPageBytes = 32 * 1024 * 1024;
constexpr auto kRequestTimeout = std::chrono::seconds(30);
constexpr auto kCallDeadline = std::chrono::seconds(60);
// A WebSocket close code for a stream that ended with a status: 4000 + the
// gRPC code, the message as the reason (the protocol allows 123 bytes).
constexpr int kCloseStatusBase = 4000;
constexpr std::size_t kMaxCloseReason = 120;

// The policy every response carries: only the page's own script, style and
// connections; nothing framed, nothing inline.
constexpr const char* kContentSecurityPolicy =
    "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' blob: data:; "
    "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'";

struct PageFile {
  std::string contentType;
  std::string body;
};
using Page = std::map<std::string, PageFile>;  // by name: "index.html", "app.js", ...

std::string contentTypeOf(const std::filesystem::path& path) {
  static const std::map<std::string, std::string> types = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".png", "image/png"},
      {".svg", "image/svg+xml"},
      {".ico", "image/x-icon"},
      {".json", "application/json"},
      {".map", "application/json"},
      {".txt", "text/plain; charset=utf-8"}};
  const auto found = types.find(path.extension().string());
  return found == types.end() ? std::string() : found->second;
}

// The page's files, read once at start: a request names one of them or
// nothing, so no path from a request ever reaches the file system.
Result<Page> loadPage(const std::string& root) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::is_regular_file(fs::path(root) / "index.html", error)) {
    return notFound(fmt::format(
        "--web-root (web.root): no index.html in '{}' (the page is built with the CMake option "
        "CRACKVIS_WEB=ON and installed to share/crackvis/web)",
        root));
  }
  Page page;
  std::size_t total = 0;
  for (const auto& entry : fs::directory_iterator(root, error)) {
    const std::string type = contentTypeOf(entry.path());
    if (!entry.is_regular_file() || type.empty()) {
      continue;
    }
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream body;
    body << in.rdbuf();
    total += body.str().size();
    if (total > kMaxPageBytes) {
      return failedPrecondition(
          fmt::format("--web-root: the page in '{}' is over {} bytes", root, kMaxPageBytes));
    }
    page[entry.path().filename().string()] = PageFile{type, body.str()};
  }
  return page;
}

int httpStatusOf(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return 200;
    case StatusCode::kInvalidArgument:
    case StatusCode::kOutOfRange:
    case StatusCode::kFailedPrecondition:
      return 400;
    case StatusCode::kUnauthenticated:
      return 401;
    case StatusCode::kPermissionDenied:
      return 403;
    case StatusCode::kNotFound:
      return 404;
    case StatusCode::kResourceExhausted:
      return 429;
    case StatusCode::kUnavailable:
      return 503;
    case StatusCode::kDeadlineExceeded:
      return 504;
    default:
      return 500;
  }
}

// The peer as gRPC names it, so the sign-in throttle keys and the access
// log read the same for both front doors.
std::string peerName(const tcp::endpoint& endpoint) {
  const auto address = endpoint.address();
  return address.is_v4() ? fmt::format("ipv4:{}:{}", address.to_string(), endpoint.port())
                         : fmt::format("ipv6:[{}]:{}", address.to_string(), endpoint.port());
}

std::string closeReason(const std::string& message) {
  if (message.size() <= kMaxCloseReason) {
    return message;
  }
  std::size_t end = kMaxCloseReason;
  while (end > 0 && (static_cast<unsigned char>(message[end]) & 0xC0) == 0x80) {
    --end;  // not inside a UTF-8 sequence
  }
  return message.substr(0, end);
}

// Calls waiting or running on the worker pool, per caller (a user, or an
// address for sign-ins).
class CallSlots {
 public:
  bool take(const std::string& caller) {
    std::lock_guard lock(m_mutex);
    int& held = m_held[caller];
    if (held >= kMaxCallsPerCaller) {
      return false;
    }
    ++held;
    return true;
  }
  void give(const std::string& caller) {
    std::lock_guard lock(m_mutex);
    if (--m_held[caller] <= 0) {
      m_held.erase(caller);
    }
  }

 private:
  std::mutex m_mutex;
  std::map<std::string, int> m_held;
};

// Connections, counted in total and per address: one address cannot hold
// every socket the process may open.
class ConnectionCount {
 public:
  bool take(const std::string& address) {
    std::lock_guard lock(m_mutex);
    if (m_total >= kMaxConnections || m_perAddress[address] >= kMaxConnectionsPerAddress) {
      return false;
    }
    ++m_total;
    ++m_perAddress[address];
    return true;
  }
  void give(const std::string& address) {
    std::lock_guard lock(m_mutex);
    --m_total;
    if (--m_perAddress[address] <= 0) {
      m_perAddress.erase(address);
    }
  }

 private:
  std::mutex m_mutex;
  int m_total = 0;
  std::map<std::string, int> m_perAddress;
};

}  // namespace

struct WebFrontDoor::Impl {
  Impl(const RenderServerConfig& serverConfig, RenderServiceImpl& renderService)
      : config(serverConfig), service(renderService), tls(!serverConfig.insecure) {}

  const RenderServerConfig& config;
  RenderServiceImpl& service;
  bool tls;
  Page page;
  WebSignIns signIns;
  ConnectionCount connections;
  CallSlots callSlots;
  // Before the io_context: its pending handlers, destroyed with it, may
  // still hold TLS streams of this context.
  ssl::context sslContext{ssl::context::tls_server};
  net::io_context io;
  std::optional<tcp::acceptor> acceptor;
  net::thread_pool workers{kCallWorkers};
  std::vector<std::thread> ioThreads;
  std::string address;
  int port = 0;
  std::atomic<bool> stopping{false};
  // Streams' writer loops still running (detached threads).
  std::mutex pumpMutex;
  std::condition_variable pumpsDone;
  int pumps = 0;

  void accept();
  // `caller`: the request's sign-in, looked up once when it arrived.
  Response answer(const Request& request, const std::string& peer,
                  const std::optional<rpc::Caller>& caller);
  Response signIn(const Request& request, const std::string& peer);
  Response signOut(const Request& request);
  Response whoAmI(const Request& request, const std::optional<rpc::Caller>& caller);
  Response call(const Request& request, const std::string& peer, const std::string& method,
                const std::optional<rpc::Caller>& caller);
  std::optional<rpc::Caller> signedIn(const Request& request);
  bool sameOrigin(const Request& request) const;
  Response respond(const Request& request, http::status status, std::string body,
                   const std::string& contentType) const;
  Response error(const Request& request, const Status& status) const;
};

namespace {

template <typename Stream>
class StreamConnection;

// One HTTP connection: requests in turn (keep-alive); an upgrade to the
// stream's path becomes a StreamConnection on the same socket.
template <typename Stream>
class HttpConnection : public std::enable_shared_from_this<HttpConnection<Stream>> {
 public:
  HttpConnection(Stream stream, WebFrontDoor::Impl& door, std::string peer)
      : m_stream(std::move(stream)), m_door(door), m_peer(std::move(peer)) {}
  ~HttpConnection() {
    if (!m_handedOver) {
      m_door.connections.give(address());
    }
  }

  void start() {
    beast::get_lowest_layer(m_stream).expires_after(kRequestTimeout);
    if constexpr (std::is_same_v<Stream, beast::tcp_stream>) {
      read();
    } else {
      m_stream.async_handshake(ssl::stream_base::server,
                               [self = this->shared_from_this()](beast::error_code error) {
                                 if (!error) {
                                   self->read();
                                 }
                               });
    }
  }

 private:
  std::string address() const { return m_peer.substr(0, m_peer.rfind(':')); }

  void read() {
    m_parser.emplace();
    m_parser->body_limit(kMaxRequestBody);
    m_parser->header_limit(kMaxHeaderBytes);
    beast::get_lowest_layer(m_stream).expires_after(kRequestTimeout);
    http::async_read(m_stream, m_buffer, *m_parser,
                     [self = this->shared_from_this()](beast::error_code error, std::size_t) {
                       self->onRead(error);
                     });
  }

  void onRead(beast::error_code error) {
    if (error == http::error::body_limit) {
      Request request;
      request.version(11);
      send(m_door.error(request, invalidArgument(fmt::format("the request body is over {} bytes",
                                                             kMaxRequestBody))),
           /*close=*/true);
      return;
    }
    if (error) {
      return close();
    }
    Request request = m_parser->release();
    if (websocket::is_upgrade(request)) {
      return upgrade(std::move(request));
    }
    if (request.method() == http::verb::get && request.target().rfind("/api/", 0) != 0) {
      return send(m_door.answer(request, m_peer, std::nullopt), false);  // the page, from memory
    }
    // Calls and sign-ins block (crackvis-data, PBKDF2): on the worker pool,
    // the response handed back to this connection's strand.
    auto caller = m_door.signedIn(request);
    std::string slot = caller ? "user " + caller->name : "address " + address();
    if (!m_door.callSlots.take(slot)) {
      return send(m_door.error(request, resourceExhausted(fmt::format(
                                            "{} already has {} calls waiting or running at the "
                                            "web front door, the limit per caller; retry later",
                                            caller ? "user '" + caller->name + "'" : m_peer,
                                            kMaxCallsPerCaller))),
                  false);
    }
    net::post(m_door.workers, [self = this->shared_from_this(), request = std::move(request),
                               slot = std::move(slot), caller = std::move(caller)] {
      Response response = self->m_door.answer(request, self->m_peer, caller);
      self->m_door.callSlots.give(slot);
      net::post(self->m_stream.get_executor(), [self, response = std::move(response)]() mutable {
        self->send(std::move(response), false);
      });
    });
  }

  void upgrade(Request request);

  void send(Response response, bool close) {
    // A fresh time limit: the request's may have run out while a slow call
    // (OpenSession of a large file) was answered on the worker pool.
    beast::get_lowest_layer(m_stream).expires_after(kRequestTimeout);
    auto held = std::make_shared<Response>(std::move(response));
    held->keep_alive(!close && held->keep_alive());
    http::async_write(
        m_stream, *held,
        [self = this->shared_from_this(), held](beast::error_code error, std::size_t) {
          if (error || held->need_eof()) {
            return self->close();
          }
          self->read();
        });
  }

  void close() {
    if constexpr (std::is_same_v<Stream, beast::tcp_stream>) {
      beast::error_code ignored;
      m_stream.socket().shutdown(tcp::socket::shutdown_send, ignored);
    } else {
      beast::get_lowest_layer(m_stream).expires_after(std::chrono::seconds(5));
      m_stream.async_shutdown([self = this->shared_from_this()](beast::error_code) {});
    }
  }

  Stream m_stream;
  WebFrontDoor::Impl& m_door;
  std::string m_peer;
  beast::flat_buffer m_buffer;
  std::optional<http::request_parser<http::string_body>> m_parser;
  bool m_handedOver = false;
};

// A session's stream over a WebSocket: the first message attaches, the
// later ones are events; the writer loop runs on its own thread and writes
// through this connection's strand (StreamSink).
template <typename Stream>
class StreamConnection : public std::enable_shared_from_this<StreamConnection<Stream>>,
                         public StreamSink {
 public:
  StreamConnection(Stream stream, WebFrontDoor::Impl& door, std::string peer, rpc::Caller caller)
      : m_ws(std::move(stream)),
        m_door(door),
        m_peer(std::move(peer)),
        m_caller(std::move(caller)),
        m_attachTimer(m_ws.get_executor()) {
    m_record.method = "web/Stream";
    m_record.peer = m_peer;
    m_record.user = m_caller.name;
  }
  ~StreamConnection() override { m_door.connections.give(m_peer.substr(0, m_peer.rfind(':'))); }

  void start(Request request) {
    beast::get_lowest_layer(m_ws).expires_never();  // the WebSocket's own timeouts from here
    m_ws.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    m_ws.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& response) { response.set(http::field::server, kProgram); }));
    m_ws.read_message_max(kMaxDrainedMessage);
    m_ws.binary(true);
    m_ws.async_accept(request, [self = this->shared_from_this()](beast::error_code error) {
      if (error) {
        return self->logOnce(unavailable("the WebSocket handshake failed: " + error.message()));
      }
      self->watchAttach();
      self->read();
    });
  }

  bool write(const v1::ServerMessage& message) override {
    auto bytes = std::make_shared<std::string>(message.SerializeAsString());
    std::unique_lock lock(m_mutex);
    if (!m_open) {
      return false;
    }
    m_writing = true;
    net::post(m_ws.get_executor(), [self = this->shared_from_this(), bytes] {
      self->m_ws.async_write(net::buffer(*bytes),
                             [self, bytes](beast::error_code error, std::size_t) {
                               std::lock_guard written(self->m_mutex);
                               self->m_writing = false;
                               self->m_open = self->m_open && !error;
                               self->m_changed.notify_all();
                             });
    });
    // Slices: a stopping server is noticed even if the handler never runs.
    while (m_writing && m_open && !m_door.stopping) {
      m_changed.wait_for(lock, std::chrono::milliseconds(100));
    }
    return m_open && !m_writing;
  }

  bool open() const override {
    std::lock_guard lock(m_mutex);
    return m_open && !m_door.stopping;
  }

 private:
  void watchAttach() {
    m_attachTimer.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(m_door.config.attachSeconds)));
    m_attachTimer.async_wait([self = this->shared_from_this()](beast::error_code error) {
      if (!error && !self->m_session) {
        self->closeWith(deadlineExceeded(
            fmt::format("the stream sent no attach_session_id within {} s (attach_seconds)",
                        self->m_door.config.attachSeconds)));
      }
    });
  }

  // A message in pieces: one over kMaxStreamMessage is not kept, only read
  // to its end (kMaxDrainedMessage), then refused with 1009.
  void read() {
    m_ws.async_read_some(
        m_buffer.prepare(kStreamReadChunk),
        [self = this->shared_from_this()](beast::error_code error, std::size_t bytes) {
          self->onRead(error, bytes);
        });
  }

  void onRead(beast::error_code error, std::size_t bytes) {
    if (error) {
      return onReadError(error);
    }
    m_buffer.commit(bytes);
    if (m_buffer.size() > kMaxStreamMessage) {
      m_overLimit = true;
      m_buffer.consume(m_buffer.size());
    }
    if (!m_ws.is_message_done()) {
      return read();
    }
    if (m_overLimit) {
      // WebSocket's own code for it, as Beast's limit gives it.
      return closeWith(tooBig(), websocket::close_code::too_big);
    }
    onMessage();
  }

  static Status tooBig() {
    return resourceExhausted(fmt::format("a stream message is over {} bytes", kMaxStreamMessage));
  }

  void onReadError(beast::error_code error) {
    // The client left, or sent more than can be drained (Beast has sent
    // 1009): the writer loop sees the sink closed.
    markClosed();
    m_attachTimer.cancel();
    if (error == websocket::error::message_too_big) {
      m_readEnd = tooBig();
    }
    if (!m_session) {
      logOnce(m_readEnd ? unavailable(
                              fmt::format("the stream ended before attaching: {}", error.message()))
                        : m_readEnd);
    }
  }

  void onMessage() {
    v1::ClientEvent event;
    const bool parsed =
        event.ParseFromArray(m_buffer.data().data(), static_cast<int>(m_buffer.size()));
    m_buffer.consume(m_buffer.size());
    if (!parsed) {
      return closeWith(invalidArgument("a stream message is not a crackvis.v1.ClientEvent"));
    }
    if (!m_session) {
      if (Status attached = attach(event); !attached) {
        return closeWith(attached);
      }
    } else {
      m_door.service.applyEvent(*m_session, event);
    }
    read();
  }

  Status attach(const v1::ClientEvent& first) {
    m_attachTimer.cancel();
    auto session = m_door.service.attachStream(m_caller, first, m_record);
    if (!session) {
      return session.status();
    }
    m_session = std::move(session).value();
    const std::uint64_t attachment = m_session->attach();
    {
      std::lock_guard lock(m_door.pumpMutex);
      ++m_door.pumps;
    }
    std::thread([self = this->shared_from_this(), attachment]() mutable {
      WebFrontDoor::Impl& door = self->m_door;
      self->pump(attachment);
      self.reset();  // before the count: shutdown may end the door once it is 0
      std::lock_guard lock(door.pumpMutex);
      --door.pumps;
      door.pumpsDone.notify_all();
    }).detach();
    return Status::ok();
  }

  // The writer loop, then the stream's end: its close code and access-log line.
  void pump(std::uint64_t attachment) {
    const Status ended = rpc::guarded(kProgram, m_record, [&] {
      return m_door.service.pumpStream(*m_session, attachment, *this, m_record);
    });
    m_session->detach(attachment);
    net::post(m_ws.get_executor(),
              [self = this->shared_from_this(), ended] { self->closeWith(ended); });
  }

  void markClosed() {
    std::lock_guard lock(m_mutex);
    m_open = false;
    m_changed.notify_all();
  }

  // On the strand: a close frame carrying the status, once; its code 4000 +
  // the status's gRPC code unless `code` says otherwise.
  void closeWith(const Status& status, std::optional<websocket::close_code> code = std::nullopt) {
    if (m_closing) {
      return;
    }
    m_closing = true;
    markClosed();
    m_attachTimer.cancel();
    logOnce(status.isOk() ? m_readEnd : status);  // how the client's side ended, if it did
    if (!m_ws.is_open()) {
      return;
    }
    const websocket::close_reason reason =
        status.isOk()
            ? websocket::close_reason(websocket::close_code::normal)
            : websocket::close_reason(
                  code.value_or(static_cast<websocket::close_code>(
                      kCloseStatusBase + static_cast<int>(rpc::toGrpcStatus(status).error_code()))),
                  closeReason(status.message()));
    m_ws.async_close(reason, [self = this->shared_from_this()](beast::error_code) {});
  }

  void logOnce(const Status& status) {
    if (m_logged) {
      return;
    }
    m_logged = true;
    rpc::recordCall(m_door.service.accessLog(), m_record, m_start, status);
  }

  websocket::stream<Stream> m_ws;
  WebFrontDoor::Impl& m_door;
  std::string m_peer;
  rpc::Caller m_caller;
  rpc::AccessRecord m_record;
  rpc::CallClock::time_point m_start = rpc::CallClock::now();
  net::steady_timer m_attachTimer;
  beast::flat_buffer m_buffer;
  std::shared_ptr<Session> m_session;  // set on the strand before the writer loop starts
  Status m_readEnd = Status::ok();     // a limit the client's messages broke
  bool m_overLimit = false;            // the message being read is dropped
  bool m_closing = false;
  bool m_logged = false;
  mutable std::mutex m_mutex;
  std::condition_variable m_changed;
  bool m_open = true;
  bool m_writing = false;
};

template <typename Stream>
void HttpConnection<Stream>::upgrade(Request request) {
  // The upgrade is checked as a call: its own page's origin, a signed-in
  // cookie, the stream's path. A refusal is an HTTP answer, before any
  // WebSocket exists.
  Status refused = Status::ok();
  std::optional<rpc::Caller> caller;
  if (request.target() != kWebStreamPath) {
    refused = notFound(fmt::format("no WebSocket at '{}'", std::string(request.target())));
  } else if (!m_door.sameOrigin(request)) {
    refused = permissionDenied("the WebSocket's Origin is not this server's page");
  } else if (caller = m_door.signedIn(request); !caller) {
    refused = unauthenticated("not signed in (POST /api/login first)");
  }
  if (!refused) {
    rpc::AccessRecord record;
    record.method = "web/Stream";
    record.peer = m_peer;
    rpc::recordCall(m_door.service.accessLog(), record, rpc::CallClock::now(), refused);
    return send(m_door.error(request, refused), /*close=*/true);
  }
  m_handedOver = true;  // the stream connection gives the slot back
  auto stream =
      std::make_shared<StreamConnection<Stream>>(std::move(m_stream), m_door, m_peer, *caller);
  stream->start(std::move(request));
}

}  // namespace

// --- requests -------------------------------------------------------------

bool WebFrontDoor::Impl::sameOrigin(const Request& request) const {
  return originAllowed(std::string(request[http::field::origin]), tls ? "https" : "http",
                       std::string(request[http::field::host]), config.web.origins);
}

std::optional<rpc::Caller> WebFrontDoor::Impl::signedIn(const Request& request) {
  const auto cookie = cookieValue(std::string(request[http::field::cookie]), kSignInCookie);
  return cookie ? signIns.find(*cookie) : std::nullopt;
}

Response WebFrontDoor::Impl::respond(const Request& request, http::status status, std::string body,
                                     const std::string& contentType) const {
  Response response{status, request.version()};
  response.set(http::field::server, kProgram);
  response.set(http::field::content_type, contentType);
  response.set("Content-Security-Policy", kContentSecurityPolicy);
  response.set("X-Content-Type-Options", "nosniff");
  response.set("X-Frame-Options", "DENY");
  response.set("Referrer-Policy", "no-referrer");
  response.set("Cross-Origin-Opener-Policy", "same-origin");
  if (tls) {
    response.set("Strict-Transport-Security", "max-age=31536000");
  }
  response.set(http::field::cache_control, "no-store");
  response.keep_alive(request.keep_alive());
  response.body() = std::move(body);
  response.prepare_payload();
  return response;
}

Response WebFrontDoor::Impl::error(const Request& request, const Status& status) const {
  const nlohmann::json body = {{"code", std::string(toString(status.code()))},
                               {"message", status.message()}};
  return respond(request, static_cast<http::status>(httpStatusOf(status.code())),
                 body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
                 "application/json");
}

Response WebFrontDoor::Impl::answer(const Request& request, const std::string& peer,
                                    const std::optional<rpc::Caller>& caller) {
  const std::string target(request.target());
  if (request.method() == http::verb::get) {
    if (target == "/api/whoami") {
      return whoAmI(request, caller);
    }
    const std::string name = target == "/" ? "index.html" : target.substr(1);
    const auto file = page.find(name);
    if (file == page.end()) {
      return error(request, notFound(fmt::format("no page at '{}'", echoed(target))));
    }
    return respond(request, http::status::ok, file->second.body, file->second.contentType);
  }
  if (request.method() != http::verb::post) {
    return error(request, invalidArgument("only GET and POST are served"));
  }
  // A call from another site's page is refused before anything else: the
  // cookie is SameSite=Strict, and the Origin check holds even without it.
  if (!sameOrigin(request)) {
    return error(request, permissionDenied("the request's Origin is not this server's page"));
  }
  if (target == "/api/login") {
    return signIn(request, peer);
  }
  if (target == "/api/logout") {
    return signOut(request);
  }
  if (target.rfind(kWebCallPrefix, 0) == 0) {
    return call(request, peer, target.substr(std::string_view(kWebCallPrefix).size()), caller);
  }
  return error(request, notFound(fmt::format("no call at '{}'", echoed(target))));
}

Response WebFrontDoor::Impl::signIn(const Request& request, const std::string& peer) {
  rpc::AccessRecord record;
  record.method = "web/SignIn";
  record.peer = peer;
  const auto start = rpc::CallClock::now();
  auto caller = service.authenticator().authenticate(
      std::string(request[http::field::authorization]), "", peer);
  Result<std::string> cookie = caller ? signIns.add(*caller) : Result<std::string>(caller.status());
  if (caller) {
    record.user = caller->name;
  }
  rpc::recordCall(service.accessLog(), record, start, cookie.status());
  if (!cookie) {
    return error(request, cookie.status());
  }
  Response response = respond(request, http::status::ok,
                              nlohmann::json{{"user", caller->name}}.dump(
                                  -1, ' ', false, nlohmann::json::error_handler_t::replace),
                              "application/json");
  response.set(http::field::set_cookie,
               signInCookieHeader(*cookie, signIns.limits().lifetimeSeconds, tls));
  return response;
}

Response WebFrontDoor::Impl::signOut(const Request& request) {
  if (auto cookie = cookieValue(std::string(request[http::field::cookie]), kSignInCookie)) {
    signIns.remove(*cookie);
  }
  Response response = respond(request, http::status::ok, "{}", "application/json");
  response.set(http::field::set_cookie, signInCookieHeader("", 0, tls));
  return response;
}

Response WebFrontDoor::Impl::whoAmI(const Request& request,
                                    const std::optional<rpc::Caller>& caller) {
  if (!caller) {
    return error(request, unauthenticated("not signed in"));
  }
  return respond(request, http::status::ok,
                 nlohmann::json{{"user", caller->name}}.dump(
                     -1, ' ', false, nlohmann::json::error_handler_t::replace),
                 "application/json");
}

namespace {

// Parses the request message, runs the body, serializes the response.
template <typename RequestMessage, typename ResponseMessage, typename Body>
Result<std::string> unaryCall(const std::string& bytes, Body&& body) {
  RequestMessage request;
  if (!request.ParseFromString(bytes)) {
    return invalidArgument(
        fmt::format("the request body is not a {}", RequestMessage::descriptor()->full_name()));
  }
  ResponseMessage response;
  CRACKVIS_RETURN_IF_ERROR(body(request, response));
  return response.SerializeAsString();
}

}  // namespace

Response WebFrontDoor::Impl::call(const Request& request, const std::string& peer,
                                  const std::string& method,
                                  const std::optional<rpc::Caller>& caller) {
  rpc::AccessRecord record;
  record.method = "web/" + echoed(method);
  record.peer = peer;
  const auto start = rpc::CallClock::now();
  const auto deadline = std::chrono::system_clock::now() + kCallDeadline;
  Result<std::string> answered = unauthenticated("not signed in (POST /api/login first)");
  const Status status = rpc::guarded(kProgram, record, [&]() -> Status {
    if (!caller) {
      return answered.status();
    }
    record.user = caller->name;
    const std::string& body = request.body();
    RenderServiceImpl& s = service;
    if (method == "ListFiles") {
      answered = unaryCall<v1::ListFilesRequest, v1::ListFilesResponse>(
          body, [&](const auto& in, auto& out) {
            return s.listFiles(*caller, in, out, record, deadline);
          });
    } else if (method == "Describe") {
      answered = unaryCall<v1::DescribeRequest, v1::DescribeResponse>(
          body, [&](const auto& in, auto& out) {
            return s.describe(*caller, in, out, record, deadline);
          });
    } else if (method == "StepHistory") {
      answered = unaryCall<v1::StepHistoryRequest, v1::StepHistoryResponse>(
          body, [&](const auto& in, auto& out) {
            return s.stepHistory(*caller, in, out, record, deadline);
          });
    } else if (method == "OpenSession") {
      answered = unaryCall<v1::OpenSessionRequest, v1::OpenSessionResponse>(
          body, [&](const auto& in, auto& out) { return s.openSession(*caller, in, out, record); });
    } else if (method == "Snapshot") {
      answered = unaryCall<v1::SnapshotRequest, v1::SnapshotResponse>(
          body, [&](const auto& in, auto& out) {
            return s.snapshot(*caller, in, out, record, deadline);
          });
    } else if (method == "CloseSession") {
      answered = unaryCall<v1::CloseSessionRequest, v1::CloseSessionResponse>(
          body, [&](const auto& in, auto&) { return s.closeSession(*caller, in); });
    } else {
      answered =
          notFound(fmt::format("no call '{}' (ListFiles, Describe, StepHistory, "
                               "OpenSession, Snapshot, CloseSession)",
                               echoed(method)));
    }
    return answered.status();
  });
  rpc::recordCall(service.accessLog(), record, start, status);
  if (!status) {
    return error(request, status);
  }
  return respond(request, http::status::ok, std::move(answered).value(), "application/x-protobuf");
}

// --- start and stop --------------------------------------------------------

void WebFrontDoor::Impl::accept() {
  acceptor->async_accept(net::make_strand(io), [this](beast::error_code error, tcp::socket socket) {
    if (error) {
      if (!stopping) {
        accept();
      }
      return;
    }
    beast::error_code ignored;
    // Frames go out as soon as they are written: with Nagle's algorithm a
    // frame's last segment would wait for the browser's delayed ACK (up to
    // 40 ms), as gRPC avoids by setting the same option.
    socket.set_option(tcp::no_delay(true), ignored);
    const tcp::endpoint remote = socket.remote_endpoint(ignored);
    const std::string peer = peerName(remote);
    if (!connections.take(peer.substr(0, peer.rfind(':')))) {
      socket.close(ignored);  // over the connection caps: refused at once
    } else if (tls) {
      std::make_shared<HttpConnection<beast::ssl_stream<beast::tcp_stream>>>(
          beast::ssl_stream<beast::tcp_stream>(std::move(socket), sslContext), *this, peer)
          ->start();
    } else {
      std::make_shared<HttpConnection<beast::tcp_stream>>(beast::tcp_stream(std::move(socket)),
                                                          *this, peer)
          ->start();
    }
    accept();
  });
}

std::string webRoot(const std::string& configured) {
  namespace fs = std::filesystem;
  if (!configured.empty()) {
    return configured;
  }
  std::error_code error;
  const fs::path program = fs::read_symlink("/proc/self/exe", error);
  if (!error) {
    const fs::path installed = program.parent_path().parent_path() / "share/crackvis/web";
    if (fs::is_regular_file(installed / "index.html", error)) {
      return installed.string();
    }
  }
#ifdef CRACKVIS_WEB_BUILD_DIST
  return CRACKVIS_WEB_BUILD_DIST;
#else
  return "share/crackvis/web";
#endif
}

namespace {

Status prepareTls(const RenderServerConfig& config, ssl::context& context) {
  auto material = tls::loadTlsMaterial(config.tls);
  if (!material) {
    return material.status();
  }
  beast::error_code error;
  context.set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 |
                      ssl::context::no_sslv3 | ssl::context::single_dh_use);
  SSL_CTX_set_min_proto_version(context.native_handle(), TLS1_2_VERSION);
  context.use_certificate_chain(net::buffer(material->certPem), error);
  if (!error) {
    context.use_private_key(net::buffer(material->keyPem), ssl::context::pem, error);
  }
  if (error) {
    return failedPrecondition(
        fmt::format("--web-listen: the server certificate or key: {}", error.message()));
  }
  return Status::ok();
}

Status bind(tcp::acceptor& acceptor, net::io_context& io, const std::string& listen) {
  auto hostPort = rpc::parseHostPort(listen);
  if (!hostPort) {
    return invalidArgument(fmt::format("--web-listen: {}", hostPort.status().message()));
  }
  beast::error_code error;
  tcp::resolver resolver(io);
  const auto endpoints = resolver.resolve(hostPort->host, std::to_string(hostPort->port),
                                          tcp::resolver::passive, error);
  if (error || endpoints.empty()) {
    return invalidArgument(
        fmt::format("--web-listen: cannot resolve '{}': {}", hostPort->host, error.message()));
  }
  const tcp::endpoint endpoint = endpoints.begin()->endpoint();
  acceptor.open(endpoint.protocol(), error);
  if (!error) {
    acceptor.set_option(net::socket_base::reuse_address(true), error);
  }
  if (!error) {
    acceptor.bind(endpoint, error);
  }
  if (!error) {
    acceptor.listen(net::socket_base::max_listen_connections, error);
  }
  if (error) {
    return unavailable(
        fmt::format("--web-listen {}: {}", listen,
                    error == net::error::address_in_use ? "address in use" : error.message()));
  }
  return Status::ok();
}

}  // namespace

Result<std::unique_ptr<WebFrontDoor>> WebFrontDoor::start(const RenderServerConfig& config,
                                                          RenderServiceImpl& service) {
  auto impl = std::make_unique<Impl>(config, service);
  if (config.insecure) {
    // The cookie and passwords would travel in clear: only to this machine.
    CRACKVIS_RETURN_IF_ERROR(rpc::requireLoopback(config.web.listen, "--insecure (web)"));
  } else {
    CRACKVIS_RETURN_IF_ERROR(prepareTls(config, impl->sslContext));
  }
  auto page = loadPage(webRoot(config.web.root));
  if (!page) {
    return page.status();
  }
  impl->page = std::move(page).value();
  impl->acceptor.emplace(impl->io);
  CRACKVIS_RETURN_IF_ERROR(bind(*impl->acceptor, impl->io, config.web.listen));
  const tcp::endpoint bound = impl->acceptor->local_endpoint();
  impl->port = bound.port();
  impl->address = rpc::formatHostPort(rpc::parseHostPort(config.web.listen)->host, impl->port);
  impl->accept();
  for (int i = 0; i < 2; ++i) {
    impl->ioThreads.emplace_back([io = &impl->io] { io->run(); });
  }
  return std::unique_ptr<WebFrontDoor>(new WebFrontDoor(std::move(impl)));
}

WebFrontDoor::WebFrontDoor(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}

WebFrontDoor::~WebFrontDoor() {
  shutdown();
}

const std::string& WebFrontDoor::address() const {
  return m_impl->address;
}

int WebFrontDoor::port() const {
  return m_impl->port;
}

void WebFrontDoor::shutdown() {
  Impl& door = *m_impl;
  if (door.stopping.exchange(true)) {
    return;
  }
  net::post(door.io, [&door] {
    beast::error_code ignored;
    door.acceptor->close(ignored);
  });
  {
    // The sessions are closed by now (RenderServer::shutdown): each writer
    // loop ends within its next 100 ms wait.
    std::unique_lock lock(door.pumpMutex);
    door.pumpsDone.wait_for(lock, std::chrono::seconds(5), [&door] { return door.pumps == 0; });
  }
  door.workers.join();
  door.io.stop();
  for (std::thread& thread : door.ioThreads) {
    thread.join();
  }
}

}  // namespace crackvis::service
