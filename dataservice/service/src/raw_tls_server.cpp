#include "raw_tls_server.hpp"

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <crackvis/rpc/host_port.hpp>
#include <crackvis/rpc_server/call.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::dataservice {
namespace {

constexpr size_t kMaxRequestBytes = 8192;
constexpr int kSocketTimeoutSeconds = 30;

bool loadPemIntoContext(SSL_CTX* context, const tls::TlsMaterial& tls, std::string& error) {
  BIO* certBio = BIO_new_mem_buf(tls.certPem.data(), static_cast<int>(tls.certPem.size()));
  X509* cert = PEM_read_bio_X509(certBio, nullptr, nullptr, nullptr);
  bool ok = cert != nullptr && SSL_CTX_use_certificate(context, cert) == 1;
  // The rest of the chain, if any.
  while (ok) {
    X509* extra = PEM_read_bio_X509(certBio, nullptr, nullptr, nullptr);
    if (extra == nullptr) {
      ERR_clear_error();
      break;
    }
    ok = SSL_CTX_add_extra_chain_cert(context, extra) == 1;
  }
  X509_free(cert);
  BIO_free(certBio);
  BIO* keyBio = BIO_new_mem_buf(tls.keyPem.data(), static_cast<int>(tls.keyPem.size()));
  EVP_PKEY* key = ok ? PEM_read_bio_PrivateKey(keyBio, nullptr, nullptr, nullptr) : nullptr;
  ok = ok && key != nullptr && SSL_CTX_use_PrivateKey(context, key) == 1 &&
       SSL_CTX_check_private_key(context) == 1;
  EVP_PKEY_free(key);
  BIO_free(keyBio);
  X509_STORE* store = SSL_CTX_get_cert_store(context);
  BIO* caBio = BIO_new_mem_buf(tls.caPem.data(), static_cast<int>(tls.caPem.size()));
  int added = 0;
  while (ok) {
    X509* ca = PEM_read_bio_X509(caBio, nullptr, nullptr, nullptr);
    if (ca == nullptr) {
      ERR_clear_error();
      break;
    }
    added += X509_STORE_add_cert(store, ca) == 1 ? 1 : 0;
    X509_free(ca);
  }
  BIO_free(caBio);
  if (!ok || added == 0) {
    error = tls::opensslError();
    return false;
  }
  return true;
}

std::string peerName(const sockaddr_storage& address) {
  char host[INET6_ADDRSTRLEN] = {};
  int port = 0;
  if (address.ss_family == AF_INET) {
    const auto* in = reinterpret_cast<const sockaddr_in*>(&address);
    inet_ntop(AF_INET, &in->sin_addr, host, sizeof(host));
    port = ntohs(in->sin_port);
    return fmt::format("ipv4:{}:{}", host, port);
  }
  const auto* in6 = reinterpret_cast<const sockaddr_in6*>(&address);
  inet_ntop(AF_INET6, &in6->sin6_addr, host, sizeof(host));
  port = ntohs(in6->sin6_port);
  return fmt::format("ipv6:[{}]:{}", host, port);
}

bool sslWriteAll(SSL* ssl, const char* data, size_t size) {
  while (size > 0) {
    size_t written = 0;
    if (SSL_write_ex(ssl, data, size, &written) != 1) {
      return false;
    }
    data += written;
    size -= written;
  }
  return true;
}

struct Request {
  std::string file;
  std::uint64_t offset = 0;
  std::uint64_t length = 0;  // 0: to the end
  std::string authorization;
};

Result<Request> parseRequest(const std::string& text) {
  Request request;
  size_t start = 0;
  bool first = true;
  while (start < text.size()) {
    const size_t end = text.find('\n', start);
    const std::string line = text.substr(start, end - start);
    start = end == std::string::npos ? text.size() : end + 1;
    if (first) {
      if (line != "CRACKVIS-RAW 1") {
        return invalidArgument("expected 'CRACKVIS-RAW 1' as the first line");
      }
      first = false;
      continue;
    }
    if (line.empty()) {
      break;
    }
    const size_t colon = line.find(": ");
    if (colon == std::string::npos) {
      return invalidArgument(fmt::format("malformed request line '{}'", echoed(line)));
    }
    const std::string key = line.substr(0, colon);
    const std::string value = line.substr(colon + 2);
    // Whole unsigned decimals only: std::stoull would take "-1" as 2^64 - 1.
    auto number = [&](std::uint64_t& out) {
      const char* last = value.data() + value.size();
      const auto [stop, error] = std::from_chars(value.data(), last, out);
      return error == std::errc() && stop == last && !value.empty();
    };
    if (key == "file") {
      request.file = value;
    } else if (key == "offset" || key == "length") {
      if (!number(key == "offset" ? request.offset : request.length)) {
        return invalidArgument(fmt::format("{} '{}' is not a whole number", key, echoed(value)));
      }
    } else if (key == "authorization") {
      request.authorization = value;
    } else {
      return invalidArgument(fmt::format("unknown request field '{}'", echoed(key)));
    }
  }
  return request;
}

}  // namespace

Result<std::unique_ptr<RawTlsServer>> RawTlsServer::start(const std::string& listen,
                                                          const tls::TlsMaterial& tls,
                                                          const Catalogue& catalogue,
                                                          const Authenticator& authenticator,
                                                          const Limits& limits, AccessLog& log) {
  auto hostPort = rpc::parseHostPort(listen);
  if (!hostPort) {
    return hostPort.status();
  }
  std::unique_ptr<RawTlsServer> server(new RawTlsServer(catalogue, authenticator, limits, log));
  server->m_context = SSL_CTX_new(TLS_server_method());
  if (server->m_context == nullptr) {
    return internalError(fmt::format("raw TLS: SSL_CTX_new failed ({})", tls::opensslError()));
  }
  SSL_CTX_set_min_proto_version(server->m_context, TLS1_2_VERSION);
  std::string error;
  if (!loadPemIntoContext(server->m_context, tls, error)) {
    return failedPrecondition(fmt::format("raw TLS: cannot use the certificates ({})", error));
  }
  SSL_CTX_set_verify(server->m_context, SSL_VERIFY_PEER | SSL_VERIFY_FAIL_IF_NO_PEER_CERT, nullptr);

  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* addresses = nullptr;
  const std::string port = std::to_string(hostPort->port);
  if (const int rc = getaddrinfo(hostPort->host.c_str(), port.c_str(), &hints, &addresses);
      rc != 0) {
    return invalidArgument(
        fmt::format("raw TLS: cannot resolve '{}': {}", hostPort->host, gai_strerror(rc)));
  }
  for (addrinfo* a = addresses; a != nullptr && server->m_listenFd < 0; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    const int one = 1;
    if (fd >= 0 && ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one)) == 0 &&
        ::bind(fd, a->ai_addr, a->ai_addrlen) == 0 && ::listen(fd, 16) == 0) {
      server->m_listenFd = fd;
    } else if (fd >= 0) {
      ::close(fd);
    }
  }
  freeaddrinfo(addresses);
  if (server->m_listenFd < 0) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("raw TLS: cannot listen on {}: {}", listen, std::strerror(errno)));
  }
  sockaddr_storage bound{};
  socklen_t length = sizeof(bound);
  ::getsockname(server->m_listenFd, reinterpret_cast<sockaddr*>(&bound), &length);
  server->m_port =
      ntohs(bound.ss_family == AF_INET ? reinterpret_cast<sockaddr_in*>(&bound)->sin_port
                                       : reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port);
  if (::pipe2(server->m_wakePipe, O_CLOEXEC) != 0) {
    return internalError("raw TLS: pipe2 failed");
  }
  RawTlsServer* self = server.get();
  server->m_acceptThread = std::thread([self] { self->acceptLoop(); });
  return server;
}

RawTlsServer::~RawTlsServer() {
  stop();
  for (int fd : {m_listenFd, m_wakePipe[0], m_wakePipe[1]}) {
    if (fd >= 0) {
      ::close(fd);
    }
  }
  SSL_CTX_free(m_context);
}

void RawTlsServer::stop() {
  if (m_stopping.exchange(true)) {
    return;
  }
  const char byte = 0;
  [[maybe_unused]] const ssize_t written = ::write(m_wakePipe[1], &byte, 1);
  if (m_acceptThread.joinable()) {
    m_acceptThread.join();
  }
  std::unique_lock lock(m_mutex);
  for (const auto& [fd, deadline] : m_connections) {
    ::shutdown(fd, SHUT_RDWR);  // wakes a connection blocked on a slow client
  }
  m_idle.wait(lock, [this] { return m_active == 0; });
}

void RawTlsServer::acceptLoop() {
  while (!m_stopping) {
    pollfd fds[2] = {{m_listenFd, POLLIN, 0}, {m_wakePipe[0], POLLIN, 0}};
    const int ready = ::poll(fds, 2, 200);
    if (ready < 0 || (fds[1].revents & POLLIN) != 0) {
      if (ready < 0 && errno == EINTR) {
        continue;
      }
      return;
    }
    closeStalled();
    if (ready == 0) {
      continue;
    }
    sockaddr_storage address{};
    socklen_t length = sizeof(address);
    const int fd =
        ::accept4(m_listenFd, reinterpret_cast<sockaddr*>(&address), &length, SOCK_CLOEXEC);
    if (fd < 0) {
      continue;
    }
    const timeval timeout{kSocketTimeoutSeconds, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
    ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof(timeout));
    std::lock_guard lock(m_mutex);
    if (m_active >= m_limits.maxConcurrentStreams) {
      ::close(fd);  // over the limit: refuse the connection outright
      continue;
    }
    ++m_active;
    m_connections[fd] = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(m_limits.handshakeSeconds));
    std::thread([this, fd, peer = peerName(address)] { serve(fd, peer); }).detach();
  }
}

void RawTlsServer::closeStalled() {
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard lock(m_mutex);
  for (auto& [fd, deadline] : m_connections) {
    if (now > deadline) {
      ::shutdown(fd, SHUT_RD);  // its blocked SSL_accept or SSL_read sees the end
      deadline = std::chrono::steady_clock::time_point::max();
    }
  }
}

void RawTlsServer::requestReceived(int fd) {
  std::lock_guard lock(m_mutex);
  m_connections[fd] = std::chrono::steady_clock::time_point::max();
}

void RawTlsServer::serve(int fd, std::string peer) {
  const auto start = std::chrono::steady_clock::now();
  AccessRecord record;
  record.method = "RawTls";
  record.peer = std::move(peer);
  SSL* ssl = SSL_new(m_context);
  SSL_set_fd(ssl, fd);
  Status status = rpc::guarded("crackvis-data", record, [&]() -> Status {
    if (SSL_accept(ssl) != 1) {
      return Status(StatusCode::kUnauthenticated,
                    fmt::format("TLS handshake failed ({})", tls::opensslError()));
    }
    if (X509* cert = SSL_get1_peer_certificate(ssl); cert != nullptr) {
      char name[256] = {};
      X509_NAME_get_text_by_NID(X509_get_subject_name(cert), NID_commonName, name, sizeof(name));
      record.certificateName = name;
      X509_free(cert);
    }
    std::string text;
    char buffer[1024];
    while (text.find("\n\n") == std::string::npos) {
      size_t got = 0;
      if (text.size() > kMaxRequestBytes || SSL_read_ex(ssl, buffer, sizeof(buffer), &got) != 1) {
        return invalidArgument("incomplete or oversized request");
      }
      text.append(buffer, got);
    }
    requestReceived(fd);
    auto request = parseRequest(text);
    if (!request) {
      return request.status();
    }
    record.file = request->file;
    auto caller =
        m_authenticator.authenticate(request->authorization, record.certificateName, record.peer);
    if (!caller) {
      return caller.status();
    }
    record.user = caller->name;
    auto normalized = DataRoot::normalize(request->file);
    if (!normalized) {
      return normalized.status();
    }
    CRACKVIS_RETURN_IF_ERROR(rpc::checkNamedPath(*caller, *normalized));
    auto resolved = m_catalogue.root().resolveFile(*normalized);
    if (!resolved) {
      return resolved.status();
    }
    CRACKVIS_RETURN_IF_ERROR(rpc::checkResolvedPath(*caller, *normalized, resolved->relative));
    auto reader = m_catalogue.openFetch(*resolved, m_limits.maxFetchBytes);
    if (!reader) {
      return reader.status();
    }
    const std::uint64_t size = (*reader)->size();
    if (request->offset > size) {
      return invalidArgument(fmt::format("offset {} lies beyond the end of {} ({} bytes)",
                                         request->offset, echoed(*normalized), size));
    }
    const std::uint64_t length = request->length == 0
                                     ? size - request->offset
                                     : std::min(request->length, size - request->offset);
    const std::string header = fmt::format("OK {}\n", length);
    if (!sslWriteAll(ssl, header.data(), header.size())) {
      return Status(StatusCode::kUnavailable, "client went away");
    }
    std::string chunk(kMaxChunkBytes, '\0');
    std::uint64_t sent = 0;
    while (sent < length) {
      const auto want = static_cast<size_t>(std::min<std::uint64_t>(chunk.size(), length - sent));
      auto got = (*reader)->readAt(request->offset + sent, chunk.data(), want);
      if (!got) {
        return got.status();
      }
      if (*got == 0 || !sslWriteAll(ssl, chunk.data(), *got)) {
        return Status(StatusCode::kUnavailable, "client went away or the file shrank");
      }
      sent += *got;
      record.bytes = sent;
    }
    return Status::ok();
  });
  if (!status && SSL_is_init_finished(ssl)) {
    const std::string line =
        fmt::format("ERROR {} {}\n", toString(status.code()), status.message());
    sslWriteAll(ssl, line.data(), line.size());
  }
  if (SSL_is_init_finished(ssl)) {
    SSL_shutdown(ssl);
  }
  SSL_free(ssl);
  ERR_clear_error();
  rpc::finishCall(m_log, record, start, status);
  {
    std::lock_guard lock(m_mutex);
    m_connections.erase(fd);
  }
  ::close(fd);
  std::lock_guard lock(m_mutex);
  --m_active;
  m_idle.notify_all();  // under the lock: stop() cannot return before this thread lets go
}

}  // namespace crackvis::dataservice
