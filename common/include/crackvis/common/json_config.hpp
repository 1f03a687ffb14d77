// Reading the services' JSON configuration files: unknown keys are errors (a
// typo must not silently drop a limit) and a value of the wrong type names
// its key and what was there. Header-only; users link nlohmann_json.
#pragma once

#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <crackvis/common/status.hpp>

namespace crackvis::config {

inline Status checkKeys(const nlohmann::json& object, const std::string& where,
                        std::initializer_list<const char*> known) {
  if (!object.is_object()) {
    return invalidArgument(fmt::format("{}: expected an object", where));
  }
  for (const auto& [key, value] : object.items()) {
    bool found = false;
    for (const char* name : known) {
      found = found || key == name;
    }
    if (!found) {
      return invalidArgument(fmt::format("{}: unknown key '{}'", where, key));
    }
  }
  return Status::ok();
}

// The JSON document of a configuration file's text; INVALID_ARGUMENT naming
// `origin` and the byte where parsing stopped.
inline Result<nlohmann::json> parseDocument(const std::string& text, const std::string& origin) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    return invalidArgument(
        fmt::format("{}: not valid JSON (byte {}): {}", origin, e.byte, e.what()));
  }
}

// Reads object[key] into `out` when present; leaves `out` alone otherwise.
template <typename T>
Status read(const nlohmann::json& object, const char* key, const std::string& where, T& out) {
  if (!object.contains(key)) {
    return Status::ok();
  }
  try {
    out = object.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    return invalidArgument(
        fmt::format("{}: '{}' has the wrong type ({})", where, key, object.at(key).dump()));
  }
  return Status::ok();
}

// The text of a configuration file; NOT_FOUND naming it when unreadable.
inline Result<std::string> readFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    return notFound(fmt::format("cannot read configuration file '{}'", path));
  }
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace crackvis::config
