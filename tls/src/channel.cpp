#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include <crackvis/tls/channel.hpp>

namespace crackvis::tls {
namespace {

grpc::ChannelArguments channelArguments(const ChannelOptions& options) {
  grpc::ChannelArguments arguments;
  if (options.ownConnection) {
    arguments.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  }
  arguments.SetMaxReceiveMessageSize(options.maxReceiveMessageBytes);
  if (options.streamWindowBytes > 0) {
    arguments.SetInt(GRPC_ARG_HTTP2_STREAM_LOOKAHEAD_BYTES, options.streamWindowBytes);
  }
  if (options.initialReconnectBackoffMs > 0) {
    arguments.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, options.initialReconnectBackoffMs);
  }
  if (options.maxReconnectBackoffMs > 0) {
    arguments.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, options.maxReconnectBackoffMs);
  }
  return arguments;
}

// Mutual TLS: our certificate and key, the CA the server's must chain to.
Result<std::shared_ptr<grpc::ChannelCredentials>> mutualTls(const ChannelOptions& options) {
  auto material =
      options.material ? Result<TlsMaterial>(*options.material) : loadTlsMaterial(options.files);
  if (!material) {
    return material.status();
  }
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = material->caPem;
  ssl.pem_cert_chain = material->certPem;
  ssl.pem_private_key = material->keyPem;
  return grpc::SslCredentials(ssl);
}

}  // namespace

Result<std::shared_ptr<grpc::Channel>> createChannel(const ChannelOptions& options) {
  grpc::ChannelArguments arguments = channelArguments(options);
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (options.insecure) {
    credentials = grpc::InsecureChannelCredentials();
  } else {
    auto tls = mutualTls(options);
    if (!tls) {
      return tls.status();
    }
    credentials = std::move(tls).value();
    if (!options.serverName.empty()) {
      arguments.SetSslTargetNameOverride(options.serverName);
    }
  }
  auto channel = grpc::CreateCustomChannel(options.target, credentials, arguments);
  if (!channel) {
    return invalidArgument(fmt::format("cannot create a channel to '{}'", options.target));
  }
  return channel;
}

}  // namespace crackvis::tls
