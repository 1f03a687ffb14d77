// What a client says when it cannot reach the server it meant: the one
// place that turns a failed call's gRPC status into a line naming the
// address and what to do, shared by the crackvis CLI, crackvis-client and
// crackvis-render's connection to crackvis-data.
//
//   no crackvis-render at localhost:50052 (connection refused): is it running? see docs/deploy.md
//   localhost:50051 is a crackvis-data, not a crackvis-render
//   localhost:50051 speaks TLS, but --insecure asked for plaintext: ...
//
// gRPC's own messages ("failed to connect to all addresses", "Socket
// closed") do not say which of these happened, so on a failure that may be
// the connection's the address is probed: a TCP connection that sends a TLS
// ClientHello tells refused, unresolved, TLS and plaintext HTTP/2 apart, and
// the standard health service (each crackvis server reports its own
// service's name as SERVING) tells crackvis-data from crackvis-render.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <string_view>

#include <grpcpp/grpcpp.h>

#include <crackvis/common/status.hpp>

namespace crackvis::rpc {

enum class ServerKind {
  kData,    // crackvis-data (crackvis.v1.DataService)
  kRender,  // crackvis-render (crackvis.v1.RenderService)
  kAny,     // either (a health check)
};

// "crackvis-data", "crackvis-render", "crackvis-data or crackvis-render".
std::string_view programName(ServerKind kind);
// The gRPC service a server of `kind` serves ("crackvis.v1.DataService");
// empty for kAny.
std::string_view serviceName(ServerKind kind);

// The server a client means to reach, and how its user chose the
// connection, for the advice.
struct Peer {
  ServerKind kind = ServerKind::kRender;
  std::string address;     // host:port as the user gave it
  bool plaintext = false;  // this client connects without TLS
  // The client's flags: "--" gives --insecure, --ca, --cert and --key;
  // "--data-" gives --data-insecure, --data-ca, ...
  std::string flagPrefix = "--";
  bool canPlaintext = true;  // false: this client has no plaintext mode
};

// Host:port must have the port: gRPC would otherwise try 443 without a
// word. INVALID_ARGUMENT naming `what` (the flag or argument) otherwise.
Status checkHostPort(const std::string& what, const std::string& address);

// What answers at an address, as one TCP connection sees it.
enum class Transport {
  kUnknown,      // no answer we recognise (or an address we do not probe)
  kUnresolved,   // the host name does not resolve
  kRefused,      // nothing listens on the port
  kUnreachable,  // no answer in time, or no route
  kTls,          // answers a ClientHello with TLS
  kPlaintext,    // speaks HTTP/2 without TLS (a server on --insecure)
};
struct TransportProbe {
  Transport transport = Transport::kUnknown;
  std::string detail;  // for kUnresolved and kUnreachable: why
};
TransportProbe probeTransport(const std::string& address,
                              std::chrono::milliseconds timeout = std::chrono::milliseconds(2000));

// Which crackvis server answers on `channel` (its health service names
// crackvis.v1.DataService or crackvis.v1.RenderService as SERVING); kAny
// when it tells neither. One or two calls of at most `timeout` each.
ServerKind identifyServer(const std::shared_ptr<grpc::ChannelInterface>& channel,
                          std::chrono::milliseconds timeout = std::chrono::milliseconds(2000));

// fromGrpcStatus (grpc_status.hpp) for a call to `peer`: a failure to reach
// it, a server of the other kind, or TLS against plaintext (either way)
// becomes one line of advice, in place of the call's message; any other
// failure is fromGrpcStatus's. `channel` is the call's (for the health
// probe; may be null). Probes only after a failure whose cause it cannot
// see, so a healthy connection costs nothing.
Status fromGrpcStatus(const grpc::Status& status, const std::string& call, const Peer& peer,
                      const std::shared_ptr<grpc::ChannelInterface>& channel);

// Before a call on `channel` to `address`: when the channel is not
// connected, waits (until `deadline`, at most a few seconds) for it to
// connect, allowing one failed attempt when a TLS server answers there.
// gRPC 1.51 (Debian 12's) can fail a connection attempt that is merely in
// progress: between connect(2) and its errno check it makes calls that may
// overwrite errno (fixed upstream by grpc/grpc#35064), so EINPROGRESS reads
// as "connect: No such file or directory". A call that is not
// wait-for-ready then fails at once ("failed to connect to all addresses",
// which fromGrpcStatus would blame on the certificates), although the
// channel's next attempt connects. That attempt is made at once (the
// channel's backoff reset) and waited for at most a second. Returns at once
// when connected, and after the first failed attempt when nothing listens
// there or it is not TLS, so that the call fails fast with its advice.
void awaitConnection(grpc::Channel& channel, const std::string& address,
                     std::chrono::system_clock::time_point deadline);

// gRPC's own log lines (a failed TLS handshake prints one to stderr) are
// dropped unless GRPC_VERBOSITY is set: a command-line tool's failure is
// the one line it prints itself.
void quietGrpcLogs();

}  // namespace crackvis::rpc
