#include <cstdio>

#include <fmt/format.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/resource_quota.h>
#include <grpcpp/security/server_credentials.h>

#include <crackvis/rpc/host_port.hpp>
#include <crackvis/rpc_server/server.hpp>

namespace crackvis::rpc {

std::string formatHostPort(const std::string& host, int port) {
  return fmt::format("{}:{}", host.find(':') != std::string::npos ? "[" + host + "]" : host, port);
}

Status requireLoopback(const std::string& target, const std::string& what) {
  auto hostPort = parseHostPort(target);
  if (!hostPort) {
    return hostPort.status();
  }
  if (!isLoopbackHost(hostPort->host)) {
    return failedPrecondition(
        fmt::format("{} refuses '{}': without TLS only a loopback address (127.0.0.1, ::1, "
                    "localhost) may be used",
                    what, target));
  }
  return Status::ok();
}

Result<Listener> prepareListener(const std::string& listen, bool insecure,
                                 const tls::TlsFiles& tls) {
  Listener listener;
  listener.listen = listen;
  listener.insecure = insecure;
  auto hostPort = parseHostPort(listen);
  if (!hostPort) {
    return hostPort.status();
  }
  listener.hostPort = *hostPort;
  if (insecure) {
    CRACKVIS_RETURN_IF_ERROR(requireLoopback(listen, "--insecure"));
    listener.credentials = grpc::InsecureServerCredentials();
    return listener;
  }
  auto material = tls::loadTlsMaterial(tls);
  if (!material) {
    return material.status();
  }
  grpc::SslServerCredentialsOptions options(
      GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
  options.pem_root_certs = material->caPem;
  options.pem_key_cert_pairs.push_back({material->keyPem, material->certPem});
  listener.credentials = grpc::SslServerCredentials(options);
  return listener;
}

Result<std::unique_ptr<ServerHost>> ServerHost::start(const Listener& listener,
                                                      const std::vector<grpc::Service*>& services,
                                                      ServerSettings settings) {
  std::unique_ptr<ServerHost> host(new ServerHost());
  host->m_settings = std::move(settings);
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  auto gate = ConnectionGate::bind(listener.hostPort, listener.listen, host->m_settings.connections,
                                   host->m_settings.program);
  if (!gate) {
    return gate.status();
  }
  grpc::ServerBuilder builder;
  // The gate accepts; gRPC handshakes with these credentials as on its own port.
  auto acceptor = builder.experimental().AddExternalConnectionAcceptor(
      grpc::ServerBuilder::experimental_type::ExternalConnectionType::FROM_FD,
      listener.credentials);
  for (grpc::Service* service : services) {
    builder.RegisterService(service);
  }
  // Requests are small; a huge one is an attack, not a query.
  builder.SetMaxReceiveMessageSize(host->m_settings.maxReceiveMessageBytes);
  if (host->m_settings.maxConcurrentStreams > 0) {
    builder.AddChannelArgument(GRPC_ARG_MAX_CONCURRENT_STREAMS,
                               host->m_settings.maxConcurrentStreams);
  }
  if (host->m_settings.maxThreads > 0) {
    grpc::ResourceQuota quota(host->m_settings.program);
    quota.SetMaxThreads(host->m_settings.maxThreads);
    builder.SetResourceQuota(quota);
  }
  builder.AddChannelArgument(GRPC_ARG_SERVER_HANDSHAKE_TIMEOUT_MS,
                             static_cast<int>(host->m_settings.handshake.count()));
  builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_IDLE_MS,
                             static_cast<int>(host->m_settings.idleConnection.count()));
  host->m_server = builder.BuildAndStart();
  if (!host->m_server) {
    return unavailable(fmt::format("cannot start the gRPC server for {}", listener.listen));
  }
  host->m_gate = std::move(gate).value();
  host->m_port = host->m_gate->port();
  host->m_gate->start(std::move(acceptor));
  host->m_server->GetHealthCheckService()->SetServingStatus(true);
  if (!host->m_settings.service.empty()) {
    host->m_server->GetHealthCheckService()->SetServingStatus(host->m_settings.service, true);
  }
  host->m_address = formatHostPort(listener.hostPort.host, host->m_port);
  if (listener.insecure) {
    std::fprintf(stderr,
                 "%s: WARNING: --insecure: plaintext gRPC without client certificates on %s "
                 "(loopback only); never use this beyond one machine\n",
                 host->m_settings.program.c_str(), host->m_address.c_str());
  }
  if (host->m_settings.reap) {
    ServerHost* raw = host.get();
    host->m_reaper = std::thread([raw] { raw->reapLoop(); });
  }
  return host;
}

ServerHost::~ServerHost() {
  shutdown(0.5);
}

void ServerHost::reapLoop() {
  std::unique_lock lock(m_mutex);
  while (!m_stopping) {
    m_stopped.wait_for(lock, m_settings.reapPeriod);
    if (m_stopping) {
      break;
    }
    lock.unlock();
    m_settings.reap();
    lock.lock();
  }
}

void ServerHost::shutdown(double graceSeconds) {
  // Concurrent callers (a signal's helper thread and a destructor) both
  // return only once the server has stopped.
  std::call_once(m_shutdownOnce, [&] {
    {
      std::lock_guard lock(m_mutex);
      m_stopping = true;
    }
    m_stopped.notify_all();
    if (m_reaper.joinable()) {
      m_reaper.join();
    }
    if (m_settings.beforeStop) {
      m_settings.beforeStop();
    }
    if (m_gate) {
      m_gate->stop();  // no new connections while the calls finish
    }
    if (!m_server) {
      return;  // it never started
    }
    m_server->GetHealthCheckService()->SetServingStatus(false);
    m_server->Shutdown(std::chrono::system_clock::now() +
                       std::chrono::duration_cast<std::chrono::system_clock::duration>(
                           std::chrono::duration<double>(graceSeconds)));
    m_server->Wait();
  });
}

void ServerHost::wait() {
  std::unique_lock lock(m_mutex);
  m_stopped.wait(lock, [this] { return m_stopping; });
}

bool ServerHost::stopping() const {
  std::lock_guard lock(m_mutex);
  return m_stopping;
}

}  // namespace crackvis::rpc
