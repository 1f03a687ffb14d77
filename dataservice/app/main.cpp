// crackvis-data: serves HDF5 DEM results from beside the storage over gRPC
// with mutual TLS. Parses options, wires a DataServer, waits for SIGINT or
// SIGTERM. docs/security.md and docs/protocol.md describe what it does.
#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <hdf5.h>

#include <crackvis/common/huge_pages.hpp>
#include <crackvis/common/log.hpp>
#include <crackvis/common/service_manager.hpp>
#include <crackvis/common/termination.hpp>
#include <crackvis/dataservice_service/data_server.hpp>
#include <crackvis/rpc_server/credentials.hpp>

namespace {

using crackvis::dataservice::ServerConfig;

enum ExitCode : int { kExitOk = 0, kExitFailure = 1, kExitUsage = 2 };

int fail(const std::string& message) {
  std::fprintf(stderr, "crackvis-data: %s\n", message.c_str());
  return kExitFailure;
}

struct Flags {
  std::string config;
  std::string listen;
  std::string root;
  std::string ca;
  std::string cert;
  std::string key;
  bool insecure = false;
  std::string accessLog;
  std::string rawTlsListen;
  std::string hdf5WorkerProgram;
  std::optional<std::uint64_t> maxReadBytes;
  std::optional<std::uint64_t> maxFetchBytes;
  std::optional<std::uint64_t> maxMemoryBytes;
  std::optional<int> hdf5Workers;
  std::optional<int> maxStreams;
  std::optional<int> maxStreamsPerUser;
  std::optional<double> handshakeSeconds;
  std::optional<double> idleConnectionSeconds;
  std::optional<int> maxConnections;
  std::optional<int> maxConnectionsPerAddress;
  std::optional<double> maxCallSeconds;
  std::optional<int> maxSlabsPerRead;
  std::optional<int> describeMaxDepth;
  std::optional<std::uint64_t> describeMaxObjects;
  std::optional<double> describeMaxSeconds;
  std::optional<double> hdf5CallSeconds;
};

// The configuration file first, then every flag given on top of it, then
// the checks.
crackvis::Result<ServerConfig> configure(const Flags& flags, const CLI::App& app) {
  ServerConfig config;
  if (!flags.config.empty()) {
    auto loaded = crackvis::dataservice::loadServerConfig(flags.config);
    if (!loaded) {
      return loaded.status();
    }
    config = std::move(*loaded);
  }
  auto given = [&](const char* name) { return app.count(name) > 0; };
  if (given("--listen")) {
    config.listen = flags.listen;
  }
  if (given("--root")) {
    config.dataRoot = flags.root;
  }
  if (given("--ca")) {
    config.tls.ca = flags.ca;
  }
  if (given("--cert")) {
    config.tls.cert = flags.cert;
  }
  if (given("--key")) {
    config.tls.key = flags.key;
  }
  if (flags.insecure) {
    config.insecure = true;
  }
  if (given("--access-log")) {
    config.accessLog = flags.accessLog;
  }
  if (given("--raw-tls-listen")) {
    config.rawTlsListen = flags.rawTlsListen;
  }
  if (given("--hdf5-worker-program")) {
    config.hdf5WorkerProgram = flags.hdf5WorkerProgram;
  }
  if (flags.maxReadBytes) {
    config.limits.maxReadBytes = *flags.maxReadBytes;
  }
  if (flags.maxFetchBytes) {
    config.limits.maxFetchBytes = *flags.maxFetchBytes;
  }
  if (flags.maxMemoryBytes) {
    config.limits.maxMemoryBytes = *flags.maxMemoryBytes;
  }
  if (flags.hdf5Workers) {
    config.limits.hdf5Workers = *flags.hdf5Workers;
  }
  if (flags.maxStreams) {
    config.limits.maxConcurrentStreams = *flags.maxStreams;
  }
  if (flags.maxStreamsPerUser) {
    config.limits.maxStreamsPerUser = *flags.maxStreamsPerUser;
  }
  if (flags.idleConnectionSeconds) {
    config.limits.idleConnectionSeconds = *flags.idleConnectionSeconds;
  }
  if (flags.handshakeSeconds) {
    config.limits.handshakeSeconds = *flags.handshakeSeconds;
  }
  if (flags.maxConnections) {
    config.limits.maxConnections = *flags.maxConnections;
  }
  if (flags.maxConnectionsPerAddress) {
    config.limits.maxConnectionsPerAddress = *flags.maxConnectionsPerAddress;
  }
  if (flags.maxCallSeconds) {
    config.limits.maxCallSeconds = *flags.maxCallSeconds;
  }
  if (flags.maxSlabsPerRead) {
    config.limits.maxSlabsPerRead = *flags.maxSlabsPerRead;
  }
  if (flags.describeMaxDepth) {
    config.limits.describe.maxDepth = *flags.describeMaxDepth;
  }
  if (flags.describeMaxObjects) {
    config.limits.describe.maxObjects = *flags.describeMaxObjects;
  }
  if (flags.describeMaxSeconds) {
    config.limits.describe.maxTime = std::chrono::duration<double>(*flags.describeMaxSeconds);
  }
  if (flags.hdf5CallSeconds) {
    config.limits.hdf5CallSeconds = *flags.hdf5CallSeconds;
  }
  // Checked once merged, so a flag and a file value meet the same rules.
  CRACKVIS_RETURN_IF_ERROR(crackvis::dataservice::validateServerConfig(config));
  return config;
}

int hashSecretFromStdin() {
  std::string secret;
  std::getline(std::cin, secret);
  auto hash = crackvis::rpc::hashSecret(secret);
  if (!hash) {
    return fail(hash.status().message());
  }
  std::printf("%s\n", hash->c_str());
  return kExitOk;
}

int newToken() {
  auto token = crackvis::rpc::generateToken();
  auto hash = token ? crackvis::rpc::hashToken(*token) : token.status();
  if (!hash) {
    return fail(hash.status().message());
  }
  std::printf("token       %s\ntoken_hash  %s\n", token->c_str(), hash->c_str());
  return kExitOk;
}

std::string hdf5Version() {
  unsigned major = 0;
  unsigned minor = 0;
  unsigned release = 0;
  H5get_libversion(&major, &minor, &release);
  return fmt::format("{}.{}.{}", major, minor, release);
}

int serve(const ServerConfig& config) {
  const crackvis::TerminationSignals signals;

  auto server = crackvis::dataservice::DataServer::start(config);
  if (!server) {
    return fail(server.status().message());
  }
  crackvis::log::event(
      stdout, "crackvis-data", "start",
      {{"version", CRACKVIS_VERSION}, {"grpc", grpc::Version()}, {"hdf5", hdf5Version()}});
  crackvis::log::event(stdout, "crackvis-data", "serving",
                       {{"address", (*server)->address()},
                        {"root", config.dataRoot},
                        {"tls", config.insecure ? "none (INSECURE, loopback only)" : "mutual"},
                        {"raw_tls_port", std::to_string((*server)->rawTlsPort())}});
  std::fflush(stdout);
  crackvis::service_manager::notify("READY=1\nSTATUS=serving " + (*server)->address());
  const int signal = signals.wait();
  crackvis::service_manager::notify("STOPPING=1");
  crackvis::log::event(stderr, "crackvis-data", "stop", {{"signal", std::to_string(signal)}});
  (*server)->shutdown();
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  // Before anything else: tunables are read when a process starts.
  crackvis::reexecWithHugePages(argv);
  CLI::App app{
      "crackvis-data: partial reads of HDF5 DEM results over gRPC with mutual TLS.\n"
      "Serves the files under a data root: ListFiles, Describe (a file's whole tree in one\n"
      "call), Read (hyperslabs, streamed in chunks of at most 1 MiB), Fetch (the whole file),\n"
      "plus grpc.health.v1 and server reflection. Flags override the --config file.\n"
      "Certificates: certs/make-dev-certs.sh; see docs/security.md and docs/protocol.md.",
      "crackvis-data"};
  app.set_version_flag("--version", fmt::format("crackvis-data {} (gRPC {}, HDF5 {})",
                                                CRACKVIS_VERSION, grpc::Version(), hdf5Version()));
  Flags flags;
  app.add_option("-c,--config", flags.config,
                 "JSON configuration file (listen, data_root, tls, limits, users, access_log, "
                 "raw_tls_listen; docs/security.md)");
  app.add_option("--listen", flags.listen,
                 "host:port to listen on (default 127.0.0.1:50051; port 0 lets the OS choose)");
  app.add_option("--root", flags.root, "data root: the folder whose files are served");
  app.add_option("--ca", flags.ca,
                 "CA certificate (PEM) that client certificates must be signed by "
                 "(default certs/generated/ca.pem, where missing /etc/crackvis/certs/ca.pem)");
  app.add_option("--cert", flags.cert,
                 "server certificate (PEM; default certs/generated/server.pem)");
  app.add_option("--key", flags.key,
                 "server private key (PEM; default certs/generated/server.key)");
  app.add_flag("--insecure", flags.insecure,
               "plaintext without client certificates, for development: refuses any address "
               "but loopback and logs a warning");
  app.add_option("--access-log", flags.accessLog,
                 "file to append one line per call to; '-' for stderr (the default), '' for none");
  app.add_option("--raw-tls-listen", flags.rawTlsListen,
                 "host:port of the raw TLS baseline for 'crackvis bench transfer' (off unless "
                 "given)");
  app.add_option("--max-read-bytes", flags.maxReadBytes, "limit on the bytes of one Read call");
  app.add_option("--max-fetch-bytes", flags.maxFetchBytes, "limit on the size of a fetched file");
  app.add_option("--hdf5-workers", flags.hdf5Workers,
                 "processes that make the HDF5 calls, so that a libhdf5 fault on a corrupt file "
                 "ends only the call on it (default 4)");
  app.add_option("--hdf5-worker-program", flags.hdf5WorkerProgram,
                 "the program those processes run (default: crackvis-hdf5-worker beside "
                 "crackvis-data)");
  app.add_option("--max-memory", flags.maxMemoryBytes,
                 "bytes all Read and Fetch streams may buffer together; each stream holds one "
                 "chunk (about 1 MiB), so this caps the streams' memory (default 256 MiB)");
  app.add_option("--max-streams", flags.maxStreams, "limit on Read/Fetch calls at once");
  app.add_option("--max-streams-per-user", flags.maxStreamsPerUser,
                 "limit on one configured user's Read/Fetch calls at once (default 16)");
  app.add_option("--handshake-seconds", flags.handshakeSeconds,
                 "time a connection has for its TLS handshake (and a raw TLS one for its "
                 "request); an idle TCP connection is closed then (default 10)");
  app.add_option("--idle-connection-seconds", flags.idleConnectionSeconds,
                 "a gRPC connection without a call for this long is closed; clients reconnect "
                 "when they next call (default 300)");
  app.add_option("--max-connections", flags.maxConnections,
                 "gRPC connections open at once; more are closed before their handshake "
                 "(default 1024)");
  app.add_option("--max-connections-per-address", flags.maxConnectionsPerAddress,
                 "gRPC connections open at once from one address; behind a NAT or proxy many "
                 "users share one (default 64)");
  app.add_option("--max-call-seconds", flags.maxCallSeconds,
                 "a Read or Fetch running longer is cancelled");
  app.add_option("--max-slabs-per-read", flags.maxSlabsPerRead,
                 "limit on the hyperslabs of one Read (default 4096)");
  app.add_option("--describe-max-depth", flags.describeMaxDepth,
                 "levels of nested groups one Describe walks (default 64)");
  app.add_option("--describe-max-objects", flags.describeMaxObjects,
                 "objects one Describe lists (default 100000)");
  app.add_option("--describe-max-seconds", flags.describeMaxSeconds,
                 "time one Describe may walk a file's tree (default 10)");
  app.add_option("--hdf5-call-seconds", flags.hdf5CallSeconds,
                 "time an HDF5 worker may take for a Read's plan or one piece before it is "
                 "killed and replaced (0.1..3600, default 30)");
  auto* hash = app.add_subcommand(
      "hash-secret", "Read a password or token from stdin and print its hash for the config");
  auto* token = app.add_subcommand("new-token", "Print a random bearer token and its hash");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {
      return app.exit(e);
    }
    std::fprintf(stderr, "crackvis-data: %s\nRun 'crackvis-data --help' for usage.\n", e.what());
    return kExitUsage;
  }
  if (hash->parsed()) {
    return hashSecretFromStdin();
  }
  if (token->parsed()) {
    return newToken();
  }
  auto config = configure(flags, app);
  if (!config) {
    return fail(config.status().message());
  }
  return serve(*config);
}
