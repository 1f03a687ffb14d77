// RenderServer: crackvis-render's start-up (the configuration's checks, the
// data client, the access log, the service and the reaper on the shared
// server host) and shut-down.
#include <chrono>
#include <memory>
#include <utility>

#include <fmt/format.h>

#include "render_service.hpp"
#include "web_front_door.hpp"
#include <crackvis/rpc_server/server.hpp>
#include <crackvis/service/render_server.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::service {

dataservice::ClientOptions defaultDataOptions() {
  dataservice::ClientOptions options;
  options.target = "localhost:50051";
  options.tls = tls::defaultTlsFiles("crackvis-render", "--data-", "data_service.");
  return options;
}

struct RenderServer::Impl {
  RenderServerConfig config;
  std::unique_ptr<rpc::AccessLog> log;
  std::unique_ptr<RenderServiceImpl> service;
  std::unique_ptr<WebFrontDoor> web;      // none without web.listen
  std::unique_ptr<rpc::ServerHost> host;  // last: stops before the service goes
};

RenderServer::RenderServer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}

RenderServer::~RenderServer() {
  shutdown(0.5);
}

Result<std::unique_ptr<RenderServer>> RenderServer::start(const RenderServerConfig& config) {
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  auto listener = rpc::prepareListener(config.listen, config.insecure, config.tls);
  if (!listener) {
    return listener.status();
  }
  if (config.data.insecure) {
    // The token would travel in clear: only to this machine.
    CRACKVIS_RETURN_IF_ERROR(rpc::requireLoopback(config.data.target, "--data-insecure"));
  }
  // The same rules as crackvis-render's flags and file: a server started
  // from code (tests, the CLI) cannot bypass them.
  CRACKVIS_RETURN_IF_ERROR(validateRenderServerConfig(config));
  auto data = dataservice::DataClient::connect(impl->config.data);
  if (!data) {
    return Status(data.status().code(),
                  fmt::format("the data service client: {}", data.status().message()));
  }
  // Connected before the first user opens a file: the connection's set-up
  // is not part of anyone's first picture (docs/benchmarks.md).
  data->startConnecting();
  auto log = rpc::AccessLog::open(config.accessLog);
  if (!log) {
    return log.status();
  }
  impl->log = std::move(log).value();
  impl->service =
      std::make_unique<RenderServiceImpl>(impl->config, std::move(data).value(), *impl->log);
  RenderServiceImpl* service = impl->service.get();
  rpc::ServerSettings settings;
  settings.program = kProgram;
  settings.service = v1::RenderService::service_full_name();
  settings.maxReceiveMessageBytes = static_cast<int>(pipeline::kMaxPipelineBytes) + 4096;
  settings.reapPeriod = std::chrono::milliseconds(200);
  settings.reap = [service] {
    service->sessions().reap();
    service->attaching().cancelOverdue();
    service->reapCrackHistories();
  };
  // Each stream holds a handler thread and a reader thread: cap what many
  // clients opening calls can make us create (gRPC refuses calls beyond it
  // with RESOURCE_EXHAUSTED).
  settings.maxThreads = 4 * config.maxSessions + 32;
  // Closing the sessions ends their streams (next() returns kClosed).
  settings.beforeStop = [service] { service->sessions().closeAll(); };
  auto host = rpc::ServerHost::start(*listener, {service}, std::move(settings));
  if (!host) {
    return host.status();
  }
  impl->host = std::move(host).value();
  if (!config.web.listen.empty()) {
    auto web = WebFrontDoor::start(impl->config, *service);
    if (!web) {
      impl->host->shutdown(0.5);
      return web.status();
    }
    impl->web = std::move(web).value();
  }
  return std::unique_ptr<RenderServer>(new RenderServer(std::move(impl)));
}

const std::string& RenderServer::address() const {
  return m_impl->host->address();
}
int RenderServer::port() const {
  return m_impl->host->port();
}
std::string RenderServer::webAddress() const {
  return m_impl->web ? m_impl->web->address() : std::string();
}
int RenderServer::webPort() const {
  return m_impl->web ? m_impl->web->port() : 0;
}
int RenderServer::sessionCount() const {
  return m_impl->service->sessions().count();
}
bool RenderServer::dataServiceConnected() const {
  return m_impl->service->dataConnected();
}

int RenderServer::keptRenderers() const {
  const RendererShelf* shelf = m_impl->service->renderers();
  return shelf ? static_cast<int>(shelf->size()) : 0;
}

std::size_t RenderServer::heapReserveBytes() const {
  return m_impl->service->heapReserve();
}

void RenderServer::shutdown(double graceSeconds) {
  m_impl->host->shutdown(graceSeconds);  // closes the sessions, so the web streams end too
  if (m_impl->web) {
    m_impl->web->shutdown();
  }
}

void RenderServer::wait() {
  m_impl->host->wait();
}

}  // namespace crackvis::service
