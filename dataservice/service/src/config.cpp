#include <chrono>
#include <cmath>
#include <limits>
#include <type_traits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <crackvis/common/json_config.hpp>
#include <crackvis/dataservice_config/server_config.hpp>
#include <crackvis/rpc/host_port.hpp>
#include <crackvis/rpc_server/setting_check.hpp>
#include <crackvis/rpc_server/user_list.hpp>
#include <crackvis/tls/tls_config.hpp>

namespace crackvis::dataservice {
namespace {

using nlohmann::json;

using config::checkKeys;
using config::read;
using rpc::checkSetting;
using tls::readTlsFiles;

}  // namespace

namespace {

Status readLimits(const json& object, const std::string& where, Limits& limits) {
  CRACKVIS_RETURN_IF_ERROR(checkKeys(
      object, where,
      {"max_read_bytes", "max_fetch_bytes", "max_concurrent_streams", "max_streams_per_user",
       "max_slabs_per_read", "max_call_seconds", "handshake_seconds", "max_memory_bytes",
       "describe_max_depth", "describe_max_objects", "describe_max_seconds", "describe_cache_bytes",
       "hdf5_workers", "hdf5_call_seconds", "idle_connection_seconds", "max_connections",
       "max_connections_per_address"}));
  CRACKVIS_RETURN_IF_ERROR(read(object, "hdf5_call_seconds", where, limits.hdf5CallSeconds));
  CRACKVIS_RETURN_IF_ERROR(read(object, "hdf5_workers", where, limits.hdf5Workers));
  CRACKVIS_RETURN_IF_ERROR(read(object, "describe_max_depth", where, limits.describe.maxDepth));
  std::uint64_t objects = limits.describe.maxObjects;
  CRACKVIS_RETURN_IF_ERROR(read(object, "describe_max_objects", where, objects));
  limits.describe.maxObjects = objects;
  double seconds = limits.describe.maxTime.count();
  CRACKVIS_RETURN_IF_ERROR(read(object, "describe_max_seconds", where, seconds));
  limits.describe.maxTime = std::chrono::duration<double>(seconds);
  CRACKVIS_RETURN_IF_ERROR(read(object, "describe_cache_bytes", where, limits.describeCacheBytes));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_memory_bytes", where, limits.maxMemoryBytes));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_read_bytes", where, limits.maxReadBytes));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_fetch_bytes", where, limits.maxFetchBytes));
  CRACKVIS_RETURN_IF_ERROR(
      read(object, "max_concurrent_streams", where, limits.maxConcurrentStreams));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_streams_per_user", where, limits.maxStreamsPerUser));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_slabs_per_read", where, limits.maxSlabsPerRead));
  CRACKVIS_RETURN_IF_ERROR(read(object, "handshake_seconds", where, limits.handshakeSeconds));
  CRACKVIS_RETURN_IF_ERROR(
      read(object, "idle_connection_seconds", where, limits.idleConnectionSeconds));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_connections", where, limits.maxConnections));
  CRACKVIS_RETURN_IF_ERROR(
      read(object, "max_connections_per_address", where, limits.maxConnectionsPerAddress));
  return read(object, "max_call_seconds", where, limits.maxCallSeconds);
}

}  // namespace

Result<ServerConfig> parseServerConfig(const std::string& text, const std::string& origin) {
  auto document = config::parseDocument(text, origin);
  if (!document) {
    return document.status();
  }
  const json& root = *document;
  ServerConfig config;
  CRACKVIS_RETURN_IF_ERROR(checkKeys(root, origin,
                                     {"listen", "data_root", "tls", "insecure", "limits", "users",
                                      "access_log", "raw_tls_listen", "hdf5_worker_program"}));
  CRACKVIS_RETURN_IF_ERROR(read(root, "listen", origin, config.listen));
  CRACKVIS_RETURN_IF_ERROR(read(root, "data_root", origin, config.dataRoot));
  CRACKVIS_RETURN_IF_ERROR(read(root, "insecure", origin, config.insecure));
  CRACKVIS_RETURN_IF_ERROR(read(root, "access_log", origin, config.accessLog));
  CRACKVIS_RETURN_IF_ERROR(read(root, "raw_tls_listen", origin, config.rawTlsListen));
  CRACKVIS_RETURN_IF_ERROR(read(root, "hdf5_worker_program", origin, config.hdf5WorkerProgram));
  if (root.contains("tls")) {
    CRACKVIS_RETURN_IF_ERROR(readTlsFiles(root.at("tls"), origin + ": tls", config.tls));
  }
  if (root.contains("limits")) {
    CRACKVIS_RETURN_IF_ERROR(readLimits(root.at("limits"), origin + ": limits", config.limits));
  }
  if (root.contains("users")) {
    auto users = rpc::readUsers(root.at("users"), origin);
    if (!users) {
      return users.status();
    }
    config.users = std::move(users).value();
  }
  return config;
}

Result<ServerConfig> loadServerConfig(const std::string& path) {
  auto text = config::readFile(path);
  if (!text) {
    return text.status();
  }
  return parseServerConfig(*text, path);
}

Status validateServerConfig(const ServerConfig& config) {
  if (config.dataRoot.empty()) {
    return invalidArgument("no data root: give --root DIR or data_root in --config");
  }
  if (auto listen = rpc::parseHostPort(config.listen); !listen) {
    return invalidArgument(fmt::format("--listen: {}", listen.status().message()));
  }
  if (!config.rawTlsListen.empty()) {
    if (auto raw = rpc::parseHostPort(config.rawTlsListen); !raw) {
      return invalidArgument(fmt::format("--raw-tls-listen: {}", raw.status().message()));
    }
  }
  const Limits& limits = config.limits;
  constexpr auto kNoMax = std::numeric_limits<std::uint64_t>::max();
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-read-bytes", "limits.max_read_bytes"},
                                        limits.maxReadBytes, std::uint64_t{1}, kNoMax));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-fetch-bytes", "limits.max_fetch_bytes"},
                                        limits.maxFetchBytes, std::uint64_t{1}, kNoMax));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-streams", "limits.max_concurrent_streams"},
                                        limits.maxConcurrentStreams, 1,
                                        std::numeric_limits<int>::max()));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-streams-per-user", "limits.max_streams_per_user"},
                                        limits.maxStreamsPerUser, 1,
                                        std::numeric_limits<int>::max()));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--describe-max-depth", "limits.describe_max_depth"},
                                        limits.describe.maxDepth, 1, 100'000));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--describe-max-objects", "limits.describe_max_objects"},
                                        std::uint64_t{limits.describe.maxObjects}, std::uint64_t{1},
                                        std::uint64_t{100'000'000}));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--describe-max-seconds", "limits.describe_max_seconds"},
                                        limits.describe.maxTime.count(), 0.001, 3600.0));
  // One stream's buffer must fit, or no Read could ever run.
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-memory", "limits.max_memory_bytes"},
                                        limits.maxMemoryBytes, std::uint64_t{kStreamBufferBytes},
                                        kNoMax));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--handshake-seconds", "limits.handshake_seconds"},
                                        limits.handshakeSeconds, 0.1, 3600.0));
  CRACKVIS_RETURN_IF_ERROR(
      checkSetting({"--idle-connection-seconds", "limits.idle_connection_seconds"},
                   limits.idleConnectionSeconds, 0.1, 7 * 86400.0));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-connections", "limits.max_connections"},
                                        limits.maxConnections, 1, 65'536));
  CRACKVIS_RETURN_IF_ERROR(
      checkSetting({"--max-connections-per-address", "limits.max_connections_per_address"},
                   limits.maxConnectionsPerAddress, 1, 65'536));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-slabs-per-read", "limits.max_slabs_per_read"},
                                        limits.maxSlabsPerRead, 1,
                                        std::numeric_limits<int>::max()));
  CRACKVIS_RETURN_IF_ERROR(
      checkSetting({"--hdf5-workers", "limits.hdf5_workers"}, limits.hdf5Workers, 1, 64));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--hdf5-call-seconds", "limits.hdf5_call_seconds"},
                                        limits.hdf5CallSeconds, 0.1, 3600.0));
  // Deadlines are computed from it: a week keeps them far from overflow.
  return checkSetting({"--max-call-seconds", "limits.max_call_seconds"}, limits.maxCallSeconds,
                      0.001, 7 * 86400.0);
}

}  // namespace crackvis::dataservice
