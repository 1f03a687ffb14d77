#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <crackvis/common/json_config.hpp>
#include <crackvis/rpc/connection_advice.hpp>
#include <crackvis/rpc/host_port.hpp>
#include <crackvis/rpc_server/setting_check.hpp>
#include <crackvis/rpc_server/user_list.hpp>
#include <crackvis/service/render_server.hpp>
#include <crackvis/tls/tls_config.hpp>

namespace crackvis::service {
namespace {

using config::checkKeys;
using config::read;
using nlohmann::json;
using tls::readTlsFiles;

Status readDataService(const json& object, const std::string& where,
                       dataservice::ClientOptions& data) {
  CRACKVIS_RETURN_IF_ERROR(checkKeys(
      object, where, {"target", "ca", "cert", "key", "token", "insecure", "server_name"}));
  CRACKVIS_RETURN_IF_ERROR(read(object, "target", where, data.target));
  CRACKVIS_RETURN_IF_ERROR(read(object, "ca", where, data.tls.ca));
  CRACKVIS_RETURN_IF_ERROR(read(object, "cert", where, data.tls.cert));
  CRACKVIS_RETURN_IF_ERROR(read(object, "key", where, data.tls.key));
  CRACKVIS_RETURN_IF_ERROR(read(object, "token", where, data.token));
  CRACKVIS_RETURN_IF_ERROR(read(object, "insecure", where, data.insecure));
  return read(object, "server_name", where, data.serverName);
}

Status readLimits(const json& object, const std::string& where, RenderServerConfig& config) {
  CRACKVIS_RETURN_IF_ERROR(
      checkKeys(object, where,
                {"max_sessions", "max_sessions_per_user", "session_grace_seconds", "attach_seconds",
                 "refine_after_ms", "interactive_frame_ms", "max_reduction", "max_width",
                 "max_height", "max_particles", "max_bonds", "renders_at_once", "kept_renderers",
                 "heap_reserve_mb", "heap_trim_after_ms"}));
  CRACKVIS_RETURN_IF_ERROR(read(object, "renders_at_once", where, config.limits.rendersAtOnce));
  CRACKVIS_RETURN_IF_ERROR(
      read(object, "max_particles", where, config.limits.fileSizes.maxParticles));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_bonds", where, config.limits.fileSizes.maxBonds));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_sessions", where, config.maxSessions));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_sessions_per_user", where, config.maxSessionsPerUser));
  CRACKVIS_RETURN_IF_ERROR(
      read(object, "session_grace_seconds", where, config.sessionGraceSeconds));
  CRACKVIS_RETURN_IF_ERROR(read(object, "attach_seconds", where, config.attachSeconds));
  CRACKVIS_RETURN_IF_ERROR(read(object, "kept_renderers", where, config.keptRenderers));
  CRACKVIS_RETURN_IF_ERROR(read(object, "heap_reserve_mb", where, config.heapReserveMb));
  CRACKVIS_RETURN_IF_ERROR(read(object, "heap_trim_after_ms", where, config.heapTrimAfterMs));
  CRACKVIS_RETURN_IF_ERROR(read(object, "refine_after_ms", where, config.limits.refineAfterMs));
  CRACKVIS_RETURN_IF_ERROR(
      read(object, "interactive_frame_ms", where, config.limits.interactiveFrameMs));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_reduction", where, config.limits.maxReduction));
  CRACKVIS_RETURN_IF_ERROR(read(object, "max_width", where, config.limits.maxWidth));
  return read(object, "max_height", where, config.limits.maxHeight);
}

Status readWeb(const json& object, const std::string& where, WebConfig& web) {
  CRACKVIS_RETURN_IF_ERROR(checkKeys(object, where, {"listen", "root", "origins"}));
  CRACKVIS_RETURN_IF_ERROR(read(object, "listen", where, web.listen));
  CRACKVIS_RETURN_IF_ERROR(read(object, "root", where, web.root));
  return read(object, "origins", where, web.origins);
}

}  // namespace

Result<RenderServerConfig> parseRenderServerConfig(const std::string& text,
                                                   const std::string& origin) {
  auto document = config::parseDocument(text, origin);
  if (!document) {
    return document.status();
  }
  const json& root = *document;
  RenderServerConfig config;
  CRACKVIS_RETURN_IF_ERROR(checkKeys(
      root, origin,
      {"listen", "tls", "insecure", "users_from", "data_service", "limits", "access_log", "web"}));
  CRACKVIS_RETURN_IF_ERROR(read(root, "listen", origin, config.listen));
  CRACKVIS_RETURN_IF_ERROR(read(root, "insecure", origin, config.insecure));
  CRACKVIS_RETURN_IF_ERROR(read(root, "access_log", origin, config.accessLog));
  if (root.contains("tls")) {
    CRACKVIS_RETURN_IF_ERROR(readTlsFiles(root.at("tls"), origin + ": tls", config.tls));
  }
  if (root.contains("data_service")) {
    CRACKVIS_RETURN_IF_ERROR(
        readDataService(root.at("data_service"), origin + ": data_service", config.data));
  }
  if (root.contains("limits")) {
    CRACKVIS_RETURN_IF_ERROR(readLimits(root.at("limits"), origin + ": limits", config));
  }
  if (root.contains("web")) {
    CRACKVIS_RETURN_IF_ERROR(readWeb(root.at("web"), origin + ": web", config.web));
  }
  std::string usersFrom;
  CRACKVIS_RETURN_IF_ERROR(read(root, "users_from", origin, usersFrom));
  if (!usersFrom.empty()) {
    auto users = rpc::loadUsersFrom(usersFrom);
    if (!users) {
      return Status(users.status().code(),
                    fmt::format("{}: users_from: {}", origin, users.status().message()));
    }
    config.users = std::move(users).value();
  }
  return config;
}

Status validateRenderServerConfig(const RenderServerConfig& config) {
  using rpc::checkSetting;
  if (auto listen = rpc::parseHostPort(config.listen); !listen) {
    return invalidArgument(fmt::format("--listen: {}", listen.status().message()));
  }
  if (!config.web.listen.empty()) {
    if (auto web = rpc::parseHostPort(config.web.listen); !web) {
      return invalidArgument(fmt::format("--web-listen (web.listen): {}", web.status().message()));
    }
    // A browser has no client certificate: without users, anyone who
    // reaches the port would read the whole data root.
    if (config.users.empty()) {
      return invalidArgument(
          "--web-listen (web.listen) needs users (--users-from or users_from): the browser page "
          "signs in with a user's password or token, since browsers bring no client certificate");
    }
    for (const std::string& origin : config.web.origins) {
      if (origin.rfind("https://", 0) != 0 && origin.rfind("http://", 0) != 0) {
        return invalidArgument(fmt::format(
            "--web-origin (web.origins): '{}' is not an origin (https://host[:port])", origin));
      }
    }
  }
  if (config.data.target.empty()) {
    return invalidArgument("--data-server must name crackvis-data's host:port");
  }
  CRACKVIS_RETURN_IF_ERROR(
      rpc::checkHostPort("--data-server (data_service.target)", config.data.target));
  CRACKVIS_RETURN_IF_ERROR(
      checkSetting({"--max-sessions", "limits.max_sessions"}, config.maxSessions, 1, 256));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-sessions-per-user", "limits.max_sessions_per_user"},
                                        config.maxSessionsPerUser, 1, 256));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--session-grace", "limits.session_grace_seconds"},
                                        config.sessionGraceSeconds, 0.1, 86400.0));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--attach-seconds", "limits.attach_seconds"},
                                        config.attachSeconds, 0.1, 3600.0));
  CRACKVIS_RETURN_IF_ERROR(
      checkSetting({"--kept-renderers", "limits.kept_renderers"}, config.keptRenderers, 0, 16));
  CRACKVIS_RETURN_IF_ERROR(
      checkSetting({"--heap-reserve-mb", "limits.heap_reserve_mb"}, config.heapReserveMb, 0, 1023));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--heap-trim-after-ms", "limits.heap_trim_after_ms"},
                                        config.heapTrimAfterMs, 100, 600000));
  const SessionLimits& limits = config.limits;
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--refine-after-ms", "limits.refine_after_ms"},
                                        limits.refineAfterMs, 0.0, 5000.0));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--interactive-frame-ms", "limits.interactive_frame_ms"},
                                        limits.interactiveFrameMs, 1.0, 1000.0));
  CRACKVIS_RETURN_IF_ERROR(
      checkSetting({"--max-reduction", "limits.max_reduction"}, limits.maxReduction, 1, 8));
  CRACKVIS_RETURN_IF_ERROR(
      checkSetting({"--renders-at-once", "limits.renders_at_once"}, limits.rendersAtOnce, 0, 256));
  // The schema's frame sizes: a larger limit could never be used.
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-particles", "limits.max_particles"},
                                        limits.fileSizes.maxParticles, std::int64_t{1},
                                        std::numeric_limits<std::int64_t>::max()));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"--max-bonds", "limits.max_bonds"},
                                        limits.fileSizes.maxBonds, std::int64_t{0},
                                        std::numeric_limits<std::int64_t>::max()));
  CRACKVIS_RETURN_IF_ERROR(checkSetting({"", "limits.max_width"}, limits.maxWidth, 16, 7680));
  return checkSetting({"", "limits.max_height"}, limits.maxHeight, 16, 7680);
}

Result<RenderServerConfig> loadRenderServerConfig(const std::string& path) {
  auto text = config::readFile(path);
  if (!text) {
    return text.status();
  }
  return parseRenderServerConfig(*text, path);
}

}  // namespace crackvis::service
