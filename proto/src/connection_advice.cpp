#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>

#include <fcntl.h>
#include <fmt/format.h>
#include <grpc/support/log.h>
#include <netdb.h>
#include <openssl/bio.h>
#include <openssl/ssl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include "crackvis/v1/data.grpc.pb.h"
#include "crackvis/v1/render.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include <crackvis/common/unique_fd.hpp>
#include <crackvis/rpc/connection_advice.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/rpc/host_port.hpp>

namespace crackvis::rpc {
namespace {

using Clock = std::chrono::steady_clock;

// "host:port", "[v6]:port", with gRPC's "dns:///" or "ipv4:" in front; none
// for other targets (unix sockets), which are not probed.
std::optional<HostPort> splitTarget(std::string target) {
  for (std::string_view scheme : {"dns:///", "dns:", "ipv4:", "ipv6:"}) {
    if (target.starts_with(scheme)) {
      target.erase(0, scheme.size());
      break;
    }
  }
  if (target.starts_with("unix:")) {
    return std::nullopt;
  }
  auto parsed = parseHostPort(target);
  return parsed ? std::optional<HostPort>(std::move(parsed).value()) : std::nullopt;
}

using Socket = UniqueFd;

int millisecondsLeft(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::max<std::int64_t>(0, left.count()));
}

// Connects without blocking past `deadline`; 0 or the errno of the failure
// (ETIMEDOUT when the time ran out).
int connectBefore(const Socket& socket, const addrinfo& address, Clock::time_point deadline) {
  const int flags = ::fcntl(socket.get(), F_GETFL, 0);
  if (flags < 0 || ::fcntl(socket.get(), F_SETFL, flags | O_NONBLOCK) < 0) {
    return errno;
  }
  if (::connect(socket.get(), address.ai_addr, address.ai_addrlen) == 0) {
    return 0;
  }
  if (errno != EINPROGRESS) {
    return errno;
  }
  pollfd wait{socket.get(), POLLOUT, 0};
  const int ready = ::poll(&wait, 1, millisecondsLeft(deadline));
  if (ready <= 0) {
    return ready == 0 ? ETIMEDOUT : errno;
  }
  int error = 0;
  socklen_t size = sizeof(error);
  if (::getsockopt(socket.get(), SOL_SOCKET, SO_ERROR, &error, &size) < 0) {
    return errno;
  }
  return error;
}

// A ClientHello as OpenSSL writes it (ALPN h2, as gRPC asks), taken from a
// memory BIO before any socket is involved.
std::string clientHello() {
  std::unique_ptr<SSL_CTX, decltype(&SSL_CTX_free)> context(SSL_CTX_new(TLS_client_method()),
                                                            &SSL_CTX_free);
  if (!context) {
    return {};
  }
  std::unique_ptr<SSL, decltype(&SSL_free)> ssl(SSL_new(context.get()), &SSL_free);
  if (!ssl) {
    return {};
  }
  BIO* in = BIO_new(BIO_s_mem());
  BIO* out = BIO_new(BIO_s_mem());
  if (in == nullptr || out == nullptr) {
    BIO_free(in);
    BIO_free(out);
    return {};
  }
  SSL_set_bio(ssl.get(), in, out);  // ssl owns both now
  static const unsigned char kAlpn[] = {2, 'h', '2'};
  SSL_set_alpn_protos(ssl.get(), kAlpn, sizeof(kAlpn));
  SSL_set_connect_state(ssl.get());
  (void)SSL_do_handshake(ssl.get());  // wants to read the answer: the hello is written
  char* data = nullptr;
  const long size = BIO_get_mem_data(out, &data);
  return size > 0 ? std::string(data, static_cast<std::size_t>(size)) : std::string();
}

// What the server sends first, after our ClientHello: a TLS record (a
// ServerHello, or an alert), or HTTP/2 frames (a plaintext gRPC server
// sends its SETTINGS at once, and GOAWAY on a bad preface).
Transport classifyAnswer(const Socket& socket, Clock::time_point deadline) {
  const std::string hello = clientHello();
  if (hello.empty() || ::send(socket.get(), hello.data(), hello.size(), MSG_NOSIGNAL) !=
                           static_cast<ssize_t>(hello.size())) {
    return Transport::kUnknown;
  }
  std::array<unsigned char, 9> head{};
  std::size_t received = 0;
  while (received < 4) {
    pollfd wait{socket.get(), POLLIN, 0};
    if (::poll(&wait, 1, millisecondsLeft(deadline)) <= 0) {
      break;
    }
    const ssize_t n = ::recv(socket.get(), head.data() + received, head.size() - received, 0);
    if (n <= 0) {
      break;
    }
    received += static_cast<std::size_t>(n);
    if (head[0] == 0x16 || head[0] == 0x15) {
      return Transport::kTls;  // handshake or alert record
    }
  }
  constexpr unsigned char kSettings = 0x04;
  constexpr unsigned char kGoAway = 0x07;
  if (received >= 4 && (head[3] == kSettings || head[3] == kGoAway)) {
    return Transport::kPlaintext;
  }
  return Transport::kUnknown;
}

std::string flag(const Peer& peer, std::string_view name) {
  return fmt::format("{}{}", peer.flagPrefix, name);
}

Status fromProbe(const grpc::Status& status, const std::string& call, const Peer& peer) {
  const TransportProbe probe = probeTransport(peer.address);
  const std::string_view program = programName(peer.kind);
  switch (probe.transport) {
    case Transport::kRefused:
      return unavailable(
          fmt::format("no {} at {} (connection refused): is it running? see docs/deploy.md",
                      program, peer.address));
    case Transport::kUnresolved:
      return unavailable(fmt::format("no {} at {} ({}): check the host name", program, peer.address,
                                     probe.detail));
    case Transport::kUnreachable:
      return unavailable(fmt::format(
          "no {} at {} ({}): is it running, and does the network let the port through? see "
          "docs/deploy.md",
          program, peer.address, probe.detail));
    case Transport::kTls:
      if (peer.plaintext) {
        return unavailable(fmt::format(
            "{} speaks TLS, but {} asked for plaintext: leave {} out and give the client "
            "certificate ({}, {}, {}; docs/security.md)",
            peer.address, flag(peer, "insecure"), flag(peer, "insecure"), flag(peer, "ca"),
            flag(peer, "cert"), flag(peer, "key")));
      }
      if (const std::string& message = status.error_message();
          message.find("failed to connect") != std::string::npos) {
        // Both speak TLS and no connection came of it: the certificates.
        // Our side's verdict is in gRPC's message; the server's is only a
        // closed socket.
        const bool ours = message.find("andshake") != std::string::npos ||
                          message.find("SSL") != std::string::npos;
        const std::size_t cause = message.rfind(": ");
        return unavailable(fmt::format(
            "TLS handshake with {} failed ({}): check {}, {} and {} against the server's CA "
            "and name (docs/security.md)",
            peer.address,
            ours && cause != std::string::npos
                ? message.substr(cause + 2)
                : std::string("the server closed the connection: did it refuse the client "
                              "certificate?"),
            flag(peer, "ca"), flag(peer, "cert"), flag(peer, "key")));
      }
      break;
    case Transport::kPlaintext:
      if (!peer.plaintext) {
        if (!peer.canPlaintext) {
          return unavailable(fmt::format(
              "{} speaks plaintext (a {} started with --insecure), not TLS, and this client "
              "connects only with TLS: start the server with its certificates "
              "(docs/security.md)",
              peer.address, program));
        }
        return unavailable(fmt::format(
            "{} speaks plaintext (a {} started with --insecure), not TLS: add {} to reach it",
            peer.address, program, flag(peer, "insecure")));
      }
      break;
    case Transport::kUnknown:
      break;
  }
  return fromGrpcStatus(status, call);
}

}  // namespace

std::string_view programName(ServerKind kind) {
  switch (kind) {
    case ServerKind::kData:
      return "crackvis-data";
    case ServerKind::kRender:
      return "crackvis-render";
    case ServerKind::kAny:
      break;
  }
  return "crackvis-data or crackvis-render";
}

std::string_view serviceName(ServerKind kind) {
  switch (kind) {
    case ServerKind::kData:
      return crackvis::v1::DataService::service_full_name();
    case ServerKind::kRender:
      return crackvis::v1::RenderService::service_full_name();
    case ServerKind::kAny:
      break;
  }
  return {};
}

Status checkHostPort(const std::string& what, const std::string& address) {
  const auto parsed = parseHostPort(address);
  if (!parsed || parsed->port < 1) {  // a server to reach has a port; 0 only listens
    return invalidArgument(
        fmt::format("{} '{}': expected HOST:PORT with the port (crackvis-data listens on 50051 and "
                    "crackvis-render on 50052 unless configured otherwise)",
                    what, address));
  }
  return Status::ok();
}

TransportProbe probeTransport(const std::string& address, std::chrono::milliseconds timeout) {
  const auto target = splitTarget(address);
  if (!target) {
    return {};
  }
  const auto deadline = Clock::now() + timeout;
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int error =
          ::getaddrinfo(target->host.c_str(), std::to_string(target->port).c_str(), &hints, &found);
      error != 0) {
    if (error == EAI_NONAME || error == EAI_FAIL || error == EAI_NODATA) {
      return {Transport::kUnresolved,
              fmt::format("cannot resolve '{}': {}", target->host, ::gai_strerror(error))};
    }
    return {Transport::kUnknown, ::gai_strerror(error)};
  }
  std::unique_ptr<addrinfo, decltype(&::freeaddrinfo)> addresses(found, &::freeaddrinfo);
  // "localhost" may be ::1 and 127.0.0.1: a server on either counts.
  bool refused = false;
  int otherError = 0;
  for (const addrinfo* a = addresses.get(); a != nullptr; a = a->ai_next) {
    const Socket socket(::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol));
    if (socket.get() < 0) {
      otherError = errno;
      continue;
    }
    const int error = connectBefore(socket, *a, deadline);
    if (error == 0) {
      return {classifyAnswer(socket, deadline), {}};
    }
    if (error == ECONNREFUSED) {
      refused = true;
    } else {
      otherError = error;
    }
  }
  if (refused) {
    return {Transport::kRefused, {}};
  }
  if (otherError == ETIMEDOUT) {
    return {Transport::kUnreachable, fmt::format("no answer within {} ms", timeout.count())};
  }
  return {Transport::kUnreachable, std::strerror(otherError)};
}

ServerKind identifyServer(const std::shared_ptr<grpc::ChannelInterface>& channel,
                          std::chrono::milliseconds timeout) {
  if (!channel) {
    return ServerKind::kAny;
  }
  auto health = grpc::health::v1::Health::NewStub(channel);
  for (ServerKind kind : {ServerKind::kData, ServerKind::kRender}) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + timeout);
    grpc::health::v1::HealthCheckRequest request;
    request.set_service(std::string(serviceName(kind)));
    grpc::health::v1::HealthCheckResponse response;
    if (health->Check(&context, request, &response).ok()) {
      return kind;  // SERVING or not, the server knows the name
    }
  }
  return ServerKind::kAny;
}

Status fromGrpcStatus(const grpc::Status& status, const std::string& call, const Peer& peer,
                      const std::shared_ptr<grpc::ChannelInterface>& channel) {
  if (status.ok()) {
    return Status::ok();
  }
  const grpc::StatusCode code = status.error_code();
  if (code == grpc::StatusCode::UNIMPLEMENTED && peer.kind != ServerKind::kAny) {
    // The method is not there: a server of the other kind, most likely.
    const ServerKind actual = identifyServer(channel);
    if (actual != ServerKind::kAny && actual != peer.kind) {
      return failedPrecondition(fmt::format("{} is a {}, not a {}", peer.address,
                                            programName(actual), programName(peer.kind)));
    }
    if (actual == ServerKind::kAny) {
      return failedPrecondition(fmt::format("{} does not serve {} ({}: UNIMPLEMENTED): is it a {}?",
                                            peer.address, serviceName(peer.kind), call,
                                            programName(peer.kind)));
    }
    return fromGrpcStatus(status, call);
  }
  // A server's own UNAVAILABLE comes over a connection that works.
  const bool connected = channel && channel->GetState(false) == GRPC_CHANNEL_READY;
  if (connected ||
      (code != grpc::StatusCode::UNAVAILABLE && code != grpc::StatusCode::DEADLINE_EXCEEDED)) {
    return fromGrpcStatus(status, call);
  }
  return fromProbe(status, call, peer);
}

void awaitConnection(grpc::Channel& channel, const std::string& address,
                     std::chrono::system_clock::time_point deadline) {
  grpc_connectivity_state state = channel.GetState(/*try_to_connect=*/true);
  if (state == GRPC_CHANNEL_READY) {
    return;
  }
  // The first attempt (a TCP connection and the TLS handshake), and the
  // next one, made at once: a handshake on loopback takes milliseconds.
  constexpr auto kFirstAttempt = std::chrono::seconds(5);
  constexpr auto kNextAttempt = std::chrono::seconds(1);
  auto limit = std::min(deadline, std::chrono::system_clock::now() + kFirstAttempt);
  bool failedOnce = false;
  while (state != GRPC_CHANNEL_READY && state != GRPC_CHANNEL_SHUTDOWN) {
    if (state == GRPC_CHANNEL_TRANSIENT_FAILURE) {
      if (failedOnce ||
          probeTransport(address, std::chrono::milliseconds(1000)).transport != Transport::kTls) {
        return;  // the call's own failure says why
      }
      failedOnce = true;
      // pick_first stays in TRANSIENT_FAILURE until it connects: the wait
      // below ends with a connection or at its limit.
      grpc::experimental::ChannelResetConnectionBackoff(&channel);
      limit = std::min(deadline, std::chrono::system_clock::now() + kNextAttempt);
    }
    if (!channel.WaitForStateChange(state, limit)) {
      return;
    }
    state = channel.GetState(/*try_to_connect=*/true);
  }
}

void quietGrpcLogs() {
  if (std::getenv("GRPC_VERBOSITY") == nullptr) {
    gpr_set_log_function([](gpr_log_func_args*) {});
  }
}

}  // namespace crackvis::rpc
