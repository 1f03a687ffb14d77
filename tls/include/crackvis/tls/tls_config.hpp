// The "tls" object of both services' configuration files, read by the rules
// of crackvis/common/json_config.hpp.
#pragma once

#include <string>

#include <nlohmann/json_fwd.hpp>

#include <crackvis/common/status.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::tls {

// Reads {"ca": ..., "cert": ..., "key": ...} into `out`, each member left
// alone when absent (so a built-in default stays). INVALID_ARGUMENT naming
// `where` for anything else in the object or a value that is not a string.
Status readTlsFiles(const nlohmann::json& tls, const std::string& where, TlsFiles& out);

}  // namespace crackvis::tls
