// Everything crackvis-data is configured with: where to listen, the data
// root, TLS files, limits, users and logs. Read from a JSON file
// (docs/security.md shows one) and overridden by command-line flags.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/rpc_server/credentials.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::dataservice {

// What one Read or Fetch stream buffers at most: one chunk of data (1 MiB,
// kMaxChunkBytes) and its message header.
inline constexpr std::uint64_t kStreamBufferBytes = (std::uint64_t{1} << 20) + 4096;

struct Limits {
  std::uint64_t maxReadBytes = std::uint64_t{1} << 30;   // per Read call (all slabs)
  std::uint64_t maxFetchBytes = std::uint64_t{1} << 40;  // per Fetch call (the whole file)
  int maxConcurrentStreams = 64;                         // Read and Fetch calls at once
  int maxStreamsPerUser = 16;  // ... of them for one configured user (not applied without users)
  int maxSlabsPerRead = 4096;
  double maxCallSeconds = 600.0;  // a stream running longer is cancelled
  // A raw TLS connection must finish its handshake and send its request
  // within this time, and a gRPC connection its TLS and HTTP/2 handshake,
  // so idle TCP connections cannot hold the slots.
  double handshakeSeconds = 10.0;
  // A gRPC connection without a call for this long is closed (GOAWAY).
  double idleConnectionSeconds = 300.0;
  // gRPC connections open at once, in all and from one address; one past
  // either is closed before its handshake (rpc::ConnectionGate).
  int maxConnections = 1024;
  int maxConnectionsPerAddress = 64;
  // Bytes of data buffered by all Read and Fetch streams together. A stream
  // holds at most one chunk (about 1 MiB) whatever it reads, and reserves it
  // from this budget when it starts; past it, RESOURCE_EXHAUSTED.
  std::uint64_t maxMemoryBytes = std::uint64_t{256} << 20;
  // One Describe holds the HDF5 lock while it walks a file's tree: bounded
  // in depth, objects and time (limits.describe_max_depth, _max_objects,
  // _max_seconds).
  DescribeLimits describe;
  // Describe's answers kept for files that have not changed since (size,
  // modification time, inode), so that a file is walked once per change
  // rather than once per view (limits.describe_cache_bytes; 0: none).
  std::uint64_t describeCacheBytes = std::uint64_t{64} << 20;
  // Processes that make every HDF5 call (Describe, Read), so that a libhdf5
  // fault on a corrupt file ends only the call on it (limits.hdf5_workers,
  // --hdf5-workers). Also how many HDF5 calls run at once.
  int hdf5Workers = 4;
  // A worker that has not answered a plan or a piece (at most 1 MiB) in this
  // time is stuck in libhdf5 on a corrupt file: it is killed and replaced
  // (limits.hdf5_call_seconds). Describe gets describe.maxTime on top.
  double hdf5CallSeconds = 30.0;
};

using rpc::UserEntry;

struct ServerConfig {
  std::string listen = "127.0.0.1:50051";  // host:port; port 0 lets the OS choose
  std::string dataRoot;
  tls::TlsFiles tls = tls::defaultTlsFiles("server", "--", "tls.");
  bool insecure = false;  // plaintext, loopback only
  Limits limits;
  std::vector<UserEntry> users;  // empty: every certified client reads the whole root
  std::string accessLog = "-";   // file to append access lines to; "-": stderr; "": none
  std::string rawTlsListen;      // host:port of the raw TLS baseline for benchmarks; "": off
  // The program that runs the HDF5 workers; "": crackvis-hdf5-worker beside
  // the running program, else the one this build made.
  std::string hdf5WorkerProgram;
};

// Reads a JSON configuration; unknown keys are errors (a typo must not
// silently drop a limit). Relative paths are kept as written. Values are not
// range-checked here: flags may still override them (validateServerConfig).
Result<ServerConfig> loadServerConfig(const std::string& path);
Result<ServerConfig> parseServerConfig(const std::string& json, const std::string& origin);

// The merged configuration (file, then flags), checked once before the
// server starts: a data root, well-formed addresses, every limit in range.
// INVALID_ARGUMENT naming the flag and the file's key, e.g. "--max-streams
// must be at least 1, got 0 (limits.max_concurrent_streams in the
// configuration file)".
Status validateServerConfig(const ServerConfig& config);

}  // namespace crackvis::dataservice
