#include <nlohmann/json.hpp>

#include <crackvis/common/json_config.hpp>
#include <crackvis/tls/tls_config.hpp>

namespace crackvis::tls {

Status readTlsFiles(const nlohmann::json& tls, const std::string& where, TlsFiles& out) {
  CRACKVIS_RETURN_IF_ERROR(config::checkKeys(tls, where, {"ca", "cert", "key"}));
  CRACKVIS_RETURN_IF_ERROR(config::read(tls, "ca", where, out.ca));
  CRACKVIS_RETURN_IF_ERROR(config::read(tls, "cert", where, out.cert));
  return config::read(tls, "key", where, out.key);
}

}  // namespace crackvis::tls
