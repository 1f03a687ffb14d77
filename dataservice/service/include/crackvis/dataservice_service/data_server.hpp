// crackvis-data's server: the DataService over gRPC with mutual TLS, the
// standard grpc.health.v1 service, server reflection, and optionally the raw
// TLS baseline for `crackvis bench transfer`. This header has no gRPC types;
// crackvis-data's main and the tests start a server through it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_config/server_config.hpp>

namespace crackvis::dataservice {

class DataServer {
 public:
  // Checks the configuration (data root, TLS files, users, loopback for
  // --insecure), binds and starts serving. Never aborts: a missing
  // certificate or a port in use is a Status.
  static Result<std::unique_ptr<DataServer>> start(const ServerConfig& config);

  DataServer(const DataServer&) = delete;
  DataServer& operator=(const DataServer&) = delete;
  ~DataServer();  // shuts down if still running

  // host:port as bound (the port the OS chose for port 0).
  const std::string& address() const;
  int port() const;
  int rawTlsPort() const;  // 0 when the raw TLS baseline is off
  // Read and Fetch calls in progress (for tests: a cancelled call must end).
  int activeStreams() const;
  // The HDF5 worker processes now, and how many have been replaced (after
  // a fault, a time limit or a cancelled caller) since start.
  std::vector<int> hdf5WorkerPids() const;
  int hdf5WorkersReplaced() const;

  // Stops accepting calls, gives running ones `graceSeconds` to finish and
  // cancels the rest; idempotent.
  void shutdown(double graceSeconds = 2.0);
  // Blocks until shutdown() has been called (from another thread or a signal
  // handler's helper thread).
  void wait();

 private:
  struct Impl;
  explicit DataServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> m_impl;
};

}  // namespace crackvis::dataservice
