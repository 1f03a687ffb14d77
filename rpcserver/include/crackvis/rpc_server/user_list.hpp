// The users both servers know: the "users" array of crackvis-data's
// configuration file, which crackvis-render reads too (its users_from key
// and --users-from flag) so that one list of tokens, passwords and folders
// applies to both. Read strictly: an unknown key, a value of the wrong type,
// a user without a credential or a name given twice is INVALID_ARGUMENT
// naming the file and the entry ("data.json: users[2]: ...").
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include <crackvis/common/status.hpp>
#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::rpc {

// The entries of a parsed "users" array; `origin` names the file.
Result<std::vector<UserEntry>> readUsers(const nlohmann::json& users, const std::string& origin);

// The users of a crackvis-data configuration file; the rest of the file is
// crackvis-data's to check. NOT_FOUND when it cannot be read.
Result<std::vector<UserEntry>> loadUsersFrom(const std::string& path);

}  // namespace crackvis::rpc
