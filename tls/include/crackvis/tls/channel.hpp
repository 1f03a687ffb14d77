// The one way crackvis's clients make a gRPC channel to a crackvis server
// (the data client, crackvis-render towards crackvis-data, the bench
// commands, the thin client): plaintext or mutual TLS, the server name the
// certificate must carry, and the channel arguments a client tunes. The
// channel connects on its first call.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace grpc {
class Channel;
}  // namespace grpc

namespace crackvis::tls {

struct ChannelOptions {
  std::string target;  // host:port
  // Plaintext, for a server started with --insecure: no certificate is read
  // and `serverName` does not apply.
  bool insecure = false;
  // Mutual TLS with `material` when the caller has read it already, else
  // with what loadTlsMaterial reads from `files` (its checks, its messages).
  std::optional<TlsMaterial> material;
  TlsFiles files;
  std::string serverName;  // name the server's certificate must carry; empty: the target's host
  int maxReceiveMessageBytes = 64 << 20;
  // A connection of this channel's own, not shared with other channels of
  // the process to the same server (GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL).
  bool ownConnection = false;
  // Bytes a stream may receive before it must wait for a window update
  // (GRPC_ARG_HTTP2_STREAM_LOOKAHEAD_BYTES); 0: gRPC's default.
  int streamWindowBytes = 0;
  // First and longest wait before reconnecting to a server that went away;
  // 0: gRPC's defaults.
  int initialReconnectBackoffMs = 0;
  int maxReconnectBackoffMs = 0;
};

// FAILED_PRECONDITION from loadTlsMaterial for a missing or bad TLS file;
// INVALID_ARGUMENT when gRPC makes no channel for the target.
Result<std::shared_ptr<grpc::Channel>> createChannel(const ChannelOptions& options);

}  // namespace crackvis::tls
