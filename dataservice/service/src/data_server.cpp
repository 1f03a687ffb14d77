#include <filesystem>
#include <system_error>
#include <vector>

#include <fmt/format.h>
#include <unistd.h>

#include "data_service.hpp"
#include "raw_tls_server.hpp"
#include <crackvis/dataservice_service/data_server.hpp>
#include <crackvis/rpc_server/server.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::dataservice {

struct DataServer::Impl {
  ServerConfig config;
  std::unique_ptr<rpc::AccessLog> log;
  std::unique_ptr<rpc::Authenticator> authenticator;
  std::unique_ptr<Hdf5Workers> workers;  // outlives the service that calls it
  std::unique_ptr<DataServiceImpl> service;
  std::unique_ptr<RawTlsServer> raw;
  std::unique_ptr<rpc::ServerHost> host;
  int round = 0;

  void reap() {
    service->streams().cancelOverdue(StreamRegistry::Clock::now());
    if (++round % 10 == 0) {
      // Once a second: files no call needs any more are not held open
      // (nor, if deleted, their disk space).
      service->catalogue().closeIdleFiles();  // the workers close theirs themselves
    }
  }
};

namespace {

// The HDF5 worker program: the configured one, else crackvis-hdf5-worker
// beside the running program (an installation), else the one this build
// made (a test or the CLI's benchmark, run from the build tree).
Result<std::string> workerProgram(const std::string& configured) {
  namespace fs = std::filesystem;
  std::vector<fs::path> candidates;
  if (!configured.empty()) {
    candidates.emplace_back(configured);
  } else {
    std::error_code error;
    const fs::path self = fs::read_symlink("/proc/self/exe", error);
    if (!error) {
      candidates.push_back(self.parent_path() / "crackvis-hdf5-worker");
    }
    candidates.emplace_back(CRACKVIS_HDF5_WORKER_BUILT);
  }
  for (const fs::path& candidate : candidates) {
    if (::access(candidate.c_str(), X_OK) == 0) {
      return candidate.string();
    }
  }
  return failedPrecondition(fmt::format(
      "crackvis-data runs libhdf5 in worker processes of the program crackvis-hdf5-worker, and "
      "{} is not an executable file: install it beside crackvis-data or give "
      "--hdf5-worker-program (hdf5_worker_program in --config)",
      candidates.front().string()));
}

}  // namespace

Result<std::unique_ptr<DataServer>> DataServer::start(const ServerConfig& config) {
  // The same rules as crackvis-data's flags and file: a server started from
  // code (tests, the CLI's benchmark) cannot bypass them.
  CRACKVIS_RETURN_IF_ERROR(validateServerConfig(config));
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  if (!config.rawTlsListen.empty() && config.insecure) {
    return failedPrecondition("the raw TLS baseline needs TLS; it cannot run with --insecure");
  }
  auto listener = rpc::prepareListener(config.listen, config.insecure, config.tls);
  if (!listener) {
    return listener.status();
  }
  auto root = DataRoot::open(config.dataRoot);
  if (!root) {
    return root.status();
  }
  auto log = rpc::AccessLog::open(config.accessLog);
  if (!log) {
    return log.status();
  }
  impl->log = std::move(*log);
  impl->authenticator = std::make_unique<rpc::Authenticator>(config.users);
  auto program = workerProgram(config.hdf5WorkerProgram);
  if (!program) {
    return program.status();
  }
  Hdf5Workers::Settings workerSettings;
  workerSettings.program = std::move(*program);
  workerSettings.workers = config.limits.hdf5Workers;
  workerSettings.pieceTime =
      std::chrono::milliseconds(static_cast<std::int64_t>(config.limits.hdf5CallSeconds * 1000));
  auto workers = Hdf5Workers::start(*root, workerSettings);
  if (!workers) {
    return workers.status();
  }
  impl->workers = std::move(*workers);
  impl->service = std::make_unique<DataServiceImpl>(
      Catalogue(std::move(*root)), *impl->workers, *impl->authenticator, config.limits, *impl->log);
  if (!config.rawTlsListen.empty()) {
    auto material = tls::loadTlsMaterial(config.tls);
    if (!material) {
      return material.status();
    }
    auto raw = RawTlsServer::start(config.rawTlsListen, *material, impl->service->catalogue(),
                                   *impl->authenticator, config.limits, *impl->log);
    if (!raw) {
      return raw.status();
    }
    impl->raw = std::move(*raw);
  }
  Impl* self = impl.get();
  rpc::ServerSettings settings;
  settings.program = "crackvis-data";
  settings.service = crackvis::v1::DataService::service_full_name();
  settings.maxReceiveMessageBytes = 4 << 20;
  settings.maxConcurrentStreams = config.limits.maxConcurrentStreams;
  settings.handshake =
      std::chrono::milliseconds(static_cast<std::int64_t>(config.limits.handshakeSeconds * 1000.0));
  settings.idleConnection = std::chrono::milliseconds(
      static_cast<std::int64_t>(config.limits.idleConnectionSeconds * 1000.0));
  settings.connections.total = config.limits.maxConnections;
  settings.connections.perAddress = config.limits.maxConnectionsPerAddress;
  settings.reapPeriod = std::chrono::milliseconds(100);
  settings.reap = [self] { self->reap(); };
  settings.beforeStop = [self] {
    if (self->raw) {
      self->raw->stop();
    }
  };
  auto host = rpc::ServerHost::start(*listener, {impl->service.get()}, std::move(settings));
  if (!host) {
    return host.status();
  }
  impl->host = std::move(*host);
  return std::unique_ptr<DataServer>(new DataServer(std::move(impl)));
}

DataServer::DataServer(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}

DataServer::~DataServer() {
  shutdown();
}

const std::string& DataServer::address() const {
  return m_impl->host->address();
}

int DataServer::port() const {
  return m_impl->host->port();
}

int DataServer::rawTlsPort() const {
  return m_impl->raw ? m_impl->raw->port() : 0;
}

int DataServer::activeStreams() const {
  return m_impl->service->streams().active();
}

std::vector<int> DataServer::hdf5WorkerPids() const {
  const auto pids = m_impl->workers->pids();
  return {pids.begin(), pids.end()};
}

int DataServer::hdf5WorkersReplaced() const {
  return m_impl->workers->replaced();
}

void DataServer::shutdown(double graceSeconds) {
  m_impl->host->shutdown(graceSeconds);
}

void DataServer::wait() {
  m_impl->host->wait();
}

}  // namespace crackvis::dataservice
