#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <crackvis/common/json_config.hpp>
#include <crackvis/rpc_server/user_list.hpp>

namespace crackvis::rpc {
namespace {

using config::checkKeys;
using config::read;
using nlohmann::json;

Status readUser(const json& object, const std::string& where, UserEntry& user) {
  CRACKVIS_RETURN_IF_ERROR(checkKeys(
      object, where, {"name", "token_hash", "password_hash", "certificate_name", "folders"}));
  CRACKVIS_RETURN_IF_ERROR(read(object, "name", where, user.name));
  CRACKVIS_RETURN_IF_ERROR(read(object, "token_hash", where, user.tokenHash));
  CRACKVIS_RETURN_IF_ERROR(read(object, "password_hash", where, user.passwordHash));
  CRACKVIS_RETURN_IF_ERROR(read(object, "certificate_name", where, user.certificateName));
  CRACKVIS_RETURN_IF_ERROR(read(object, "folders", where, user.folders));
  if (user.name.empty() || user.name.find_first_of(": \t\n") != std::string::npos) {
    return invalidArgument(
        fmt::format("{}: 'name' must be non-empty, without spaces or ':'", where));
  }
  if (user.tokenHash.empty() && user.passwordHash.empty() && user.certificateName.empty()) {
    return invalidArgument(fmt::format(
        "{}: user '{}' needs token_hash, password_hash or certificate_name", where, user.name));
  }
  return Status::ok();
}

}  // namespace

Result<std::vector<UserEntry>> readUsers(const json& users, const std::string& origin) {
  if (!users.is_array()) {
    return invalidArgument(fmt::format("{}: 'users' must be an array", origin));
  }
  std::vector<UserEntry> entries;
  for (size_t i = 0; i < users.size(); ++i) {
    UserEntry user;
    CRACKVIS_RETURN_IF_ERROR(readUser(users[i], fmt::format("{}: users[{}]", origin, i), user));
    for (const UserEntry& other : entries) {
      if (other.name == user.name) {
        return invalidArgument(
            fmt::format("{}: users[{}]: user '{}' appears twice", origin, i, user.name));
      }
    }
    entries.push_back(std::move(user));
  }
  return entries;
}

Result<std::vector<UserEntry>> loadUsersFrom(const std::string& path) {
  auto text = config::readFile(path);
  if (!text) {
    return text.status();
  }
  auto document = config::parseDocument(*text, path);
  if (!document) {
    return document.status();
  }
  const json& root = *document;
  if (!root.is_object()) {
    return invalidArgument(fmt::format("{}: expected an object", path));
  }
  if (!root.contains("users")) {
    return std::vector<UserEntry>{};
  }
  return readUsers(root.at("users"), path);
}

}  // namespace crackvis::rpc
