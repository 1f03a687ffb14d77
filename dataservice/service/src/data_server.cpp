#include <condition_variable>
#include <cstdio>
#include <thread>

#include <fmt/format.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>

#include "data_service.hpp"
#include "raw_tls_server.hpp"
#include <crackvis/dataservice/data_server.hpp>

namespace crackvis::dataservice {

struct DataServer::Impl {
  ServerConfig config;
  std::unique_ptr<AccessLog> log;
  std::unique_ptr<Authenticator> authenticator;
  std::unique_ptr<DataServiceImpl> service;
  std::unique_ptr<grpc::Server> server;
  std::unique_ptr<RawTlsServer> raw;
  std::string address;
  int port = 0;

  std::mutex mutex;
  std::condition_variable stopped;
  bool stopping = false;
  std::thread reaper;

  void reap() {
    std::unique_lock lock(mutex);
    for (int round = 1; !stopping; ++round) {
      stopped.wait_for(lock, std::chrono::milliseconds(100));
      service->streams().cancelOverdue(StreamRegistry::Clock::now());
      if (round % 10 == 0) {
        // Once a second: files no call needs any more are not held open
        // (nor, if deleted, their disk space).
        service->catalogue().closeIdleFiles();
      }
    }
  }
};

namespace {

Status checkConfig(const ServerConfig& config, const HostPort& listen) {
  if (config.insecure && !isLoopbackHost(listen.host)) {
    return failedPrecondition(fmt::format(
        "--insecure refuses to listen on '{}': without TLS only a loopback address (127.0.0.1, "
        "::1, localhost) may be bound",
        config.listen));
  }
  if (!config.rawTlsListen.empty() && config.insecure) {
    return failedPrecondition("the raw TLS baseline needs TLS; it cannot run with --insecure");
  }
  return Status::ok();
}

std::shared_ptr<grpc::ServerCredentials> serverCredentials(const TlsMaterial& material) {
  grpc::SslServerCredentialsOptions options(
      GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
  options.pem_root_certs = material.caPem;
  options.pem_key_cert_pairs.push_back({material.keyPem, material.certPem});
  return grpc::SslServerCredentials(options);
}

}  // namespace

Result<std::unique_ptr<DataServer>> DataServer::start(const ServerConfig& config) {
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  auto listen = parseHostPort(config.listen);
  if (!listen) {
    return listen.status();
  }
  CRACKVIS_RETURN_IF_ERROR(checkConfig(config, *listen));
  auto root = DataRoot::open(config.dataRoot);
  if (!root) {
    return root.status();
  }
  std::optional<TlsMaterial> tls;
  if (!config.insecure) {
    auto material = loadTlsMaterial(config.tls);
    if (!material) {
      return material.status();
    }
    tls = std::move(*material);
  }
  auto log = AccessLog::open(config.accessLog);
  if (!log) {
    return log.status();
  }
  impl->log = std::move(*log);
  impl->authenticator = std::make_unique<Authenticator>(config.users);
  impl->service = std::make_unique<DataServiceImpl>(
      Catalogue(std::move(*root)), *impl->authenticator, config.limits, *impl->log);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(config.listen,
                           tls ? serverCredentials(*tls) : grpc::InsecureServerCredentials(),
                           &impl->port);
  builder.RegisterService(impl->service.get());
  // Requests are small; a huge one is an attack, not a query.
  builder.SetMaxReceiveMessageSize(4 << 20);
  builder.AddChannelArgument(GRPC_ARG_MAX_CONCURRENT_STREAMS, config.limits.maxConcurrentStreams);
  impl->server = builder.BuildAndStart();
  if (!impl->server || impl->port == 0) {
    return Status(
        StatusCode::kUnavailable,
        fmt::format("cannot listen on {}: the address is in use or not local", config.listen));
  }
  impl->server->GetHealthCheckService()->SetServingStatus(true);
  impl->address = fmt::format(
      "{}:{}",
      listen->host.find(':') != std::string::npos ? "[" + listen->host + "]" : listen->host,
      impl->port);
  if (config.insecure) {
    std::fprintf(stderr,
                 "crackvis-data: WARNING: --insecure: plaintext gRPC without client "
                 "certificates on %s (loopback only); never use this beyond one machine\n",
                 impl->address.c_str());
  }
  if (!config.rawTlsListen.empty()) {
    auto raw = RawTlsServer::start(config.rawTlsListen, *tls, impl->service->catalogue(),
                                   *impl->authenticator, config.limits, *impl->log);
    if (!raw) {
      impl->server->Shutdown();
      return raw.status();
    }
    impl->raw = std::move(*raw);
  }
  Impl* raw = impl.get();
  impl->reaper = std::thread([raw] { raw->reap(); });
  return std::unique_ptr<DataServer>(new DataServer(std::move(impl)));
}

DataServer::DataServer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}

DataServer::~DataServer() {
  shutdown();
}

const std::string& DataServer::address() const {
  return m_impl->address;
}

int DataServer::port() const {
  return m_impl->port;
}

int DataServer::rawTlsPort() const {
  return m_impl->raw ? m_impl->raw->port() : 0;
}

int DataServer::activeStreams() const {
  return m_impl->service->streams().active();
}

void DataServer::shutdown(double graceSeconds) {
  {
    std::lock_guard lock(m_impl->mutex);
    if (m_impl->stopping) {
      return;
    }
    m_impl->stopping = true;
  }
  m_impl->stopped.notify_all();
  if (m_impl->reaper.joinable()) {
    m_impl->reaper.join();
  }
  if (m_impl->raw) {
    m_impl->raw->stop();
  }
  m_impl->server->GetHealthCheckService()->SetServingStatus(false);
  m_impl->server->Shutdown(std::chrono::system_clock::now() +
                           std::chrono::duration_cast<std::chrono::system_clock::duration>(
                               std::chrono::duration<double>(graceSeconds)));
  m_impl->server->Wait();
}

void DataServer::wait() {
  std::unique_lock lock(m_impl->mutex);
  m_impl->stopped.wait(lock, [this] { return m_impl->stopping; });
}

}  // namespace crackvis::dataservice
