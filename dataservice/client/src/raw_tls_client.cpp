#include <cerrno>
#include <chrono>
#include <cstring>
#include <memory>
#include <vector>

#include <fmt/format.h>
#include <netdb.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>
#include <sys/socket.h>
#include <unistd.h>

#include <crackvis/common/unique_fd.hpp>
#include <crackvis/dataservice_client/raw_tls_client.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::dataservice {
namespace {

using Clock = std::chrono::steady_clock;

struct ContextFree {
  void operator()(SSL_CTX* context) const { SSL_CTX_free(context); }
};
struct SslFree {
  void operator()(SSL* ssl) const { SSL_free(ssl); }
};

using Socket = UniqueFd;

Result<int> connectTcp(const std::string& host, const std::string& port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* addresses = nullptr;
  if (const int rc = getaddrinfo(host.c_str(), port.c_str(), &hints, &addresses); rc != 0) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("cannot resolve '{}': {}", host, gai_strerror(rc)));
  }
  int fd = -1;
  int lastError = 0;
  for (addrinfo* a = addresses; a != nullptr && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd >= 0 && ::connect(fd, a->ai_addr, a->ai_addrlen) != 0) {
      lastError = errno;
      ::close(fd);
      fd = -1;
    }
  }
  freeaddrinfo(addresses);
  if (fd < 0) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("cannot connect to {}:{}: {}", host, port, std::strerror(lastError)));
  }
  return fd;
}

bool usePem(SSL_CTX* context, const tls::TlsMaterial& tls) {
  BIO* certBio = BIO_new_mem_buf(tls.certPem.data(), static_cast<int>(tls.certPem.size()));
  X509* cert = PEM_read_bio_X509(certBio, nullptr, nullptr, nullptr);
  BIO_free(certBio);
  BIO* keyBio = BIO_new_mem_buf(tls.keyPem.data(), static_cast<int>(tls.keyPem.size()));
  EVP_PKEY* key = PEM_read_bio_PrivateKey(keyBio, nullptr, nullptr, nullptr);
  BIO_free(keyBio);
  bool ok = cert != nullptr && key != nullptr && SSL_CTX_use_certificate(context, cert) == 1 &&
            SSL_CTX_use_PrivateKey(context, key) == 1;
  X509_free(cert);
  EVP_PKEY_free(key);
  BIO* caBio = BIO_new_mem_buf(tls.caPem.data(), static_cast<int>(tls.caPem.size()));
  X509* ca = PEM_read_bio_X509(caBio, nullptr, nullptr, nullptr);
  BIO_free(caBio);
  ok = ok && ca != nullptr && X509_STORE_add_cert(SSL_CTX_get_cert_store(context), ca) == 1;
  X509_free(ca);
  return ok;
}

}  // namespace

Result<RawTransfer> rawTlsRead(const RawTlsOptions& options, const std::string& file,
                               std::uint64_t offset, std::uint64_t length,
                               const std::function<void(const std::byte*, std::size_t)>& sink) {
  const size_t colon = options.target.rfind(':');
  if (colon == std::string::npos) {
    return invalidArgument(fmt::format("raw TLS target '{}': expected host:port", options.target));
  }
  std::string host = options.target.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  const std::string port = options.target.substr(colon + 1);
  auto material = tls::loadTlsMaterial(options.tls);
  if (!material) {
    return material.status();
  }
  std::unique_ptr<SSL_CTX, ContextFree> context(SSL_CTX_new(TLS_client_method()));
  if (!context || !usePem(context.get(), *material)) {
    return failedPrecondition(
        fmt::format("raw TLS: cannot use the certificates ({})", tls::opensslError()));
  }
  SSL_CTX_set_min_proto_version(context.get(), TLS1_2_VERSION);
  SSL_CTX_set_verify(context.get(), SSL_VERIFY_PEER, nullptr);

  RawTransfer transfer;
  const auto connectStart = Clock::now();
  auto fd = connectTcp(host, port);
  if (!fd) {
    return fd.status();
  }
  Socket socket(*fd);
  std::unique_ptr<SSL, SslFree> ssl(SSL_new(context.get()));
  const std::string name = options.serverName.empty() ? host : options.serverName;
  SSL_set_fd(ssl.get(), socket.get());
  SSL_set_tlsext_host_name(ssl.get(), name.c_str());
  // Verify the server's name as gRPC does: DNS or IP SAN.
  X509_VERIFY_PARAM* verify = SSL_get0_param(ssl.get());
  if (X509_VERIFY_PARAM_set1_ip_asc(verify, name.c_str()) != 1) {
    ERR_clear_error();
    X509_VERIFY_PARAM_set1_host(verify, name.c_str(), 0);
  }
  if (SSL_connect(ssl.get()) != 1) {
    return Status(StatusCode::kUnavailable, fmt::format("raw TLS handshake with {} failed ({})",
                                                        options.target, tls::opensslError()));
  }
  transfer.connectSeconds = std::chrono::duration<double>(Clock::now() - connectStart).count();
  transfer.protocol = SSL_get_version(ssl.get());
  transfer.cipher = SSL_get_cipher_name(ssl.get());

  const auto start = Clock::now();
  std::string request =
      fmt::format("CRACKVIS-RAW 1\nfile: {}\noffset: {}\nlength: {}\n", file, offset, length);
  if (!options.authorization.empty()) {
    request += fmt::format("authorization: {}\n", options.authorization);
  }
  request += "\n";
  size_t written = 0;
  if (SSL_write_ex(ssl.get(), request.data(), request.size(), &written) != 1) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("raw TLS: write failed ({})", tls::opensslError()));
  }
  std::vector<char> buffer(1 << 20);
  std::string header;
  std::uint64_t expected = 0;
  bool haveHeader = false;
  for (;;) {
    size_t got = 0;
    if (SSL_read_ex(ssl.get(), buffer.data(), buffer.size(), &got) != 1) {
      break;
    }
    const char* data = buffer.data();
    if (!haveHeader) {
      header.append(data, got);
      const size_t newline = header.find('\n');
      if (newline == std::string::npos) {
        continue;
      }
      const std::string line = header.substr(0, newline);
      if (line.rfind("OK ", 0) != 0) {
        // "ERROR <STATUS> <message>"
        const size_t space = line.find(' ', 6);
        const std::string code = line.substr(6, space == std::string::npos ? 0 : space - 6);
        const std::string message = space == std::string::npos ? line : line.substr(space + 1);
        StatusCode status = StatusCode::kInternal;
        for (StatusCode candidate :
             {StatusCode::kInvalidArgument, StatusCode::kNotFound, StatusCode::kFailedPrecondition,
              StatusCode::kPermissionDenied, StatusCode::kUnauthenticated,
              StatusCode::kResourceExhausted, StatusCode::kUnavailable}) {
          status = toString(candidate) == code ? candidate : status;
        }
        return Status(status, message);
      }
      expected = std::stoull(line.substr(3));
      haveHeader = true;
      const size_t rest = header.size() - newline - 1;
      if (rest > 0 && sink) {
        sink(reinterpret_cast<const std::byte*>(header.data() + newline + 1), rest);
      }
      transfer.bytes += rest;
      continue;
    }
    if (sink) {
      sink(reinterpret_cast<const std::byte*>(data), got);
    }
    transfer.bytes += got;
    if (transfer.bytes >= expected) {
      break;
    }
  }
  transfer.transferSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  SSL_shutdown(ssl.get());
  ERR_clear_error();
  if (!haveHeader || transfer.bytes != expected) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("raw TLS: stream from {} ended after {} of {} bytes", options.target,
                              transfer.bytes, expected));
  }
  return transfer;
}

}  // namespace crackvis::dataservice
