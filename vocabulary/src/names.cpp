#include <algorithm>
#include <cctype>

#include <fmt/format.h>

#include <crackvis/vocabulary/names.hpp>

namespace crackvis::dem {

Status validateName(const std::string& what, const std::string& name) {
  const bool valid =
      !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.' || c == '-';
      });
  if (!valid) {
    return invalidArgument(
        fmt::format("{} name '{}': expected 1 to 64 characters of A-Z a-z 0-9 _ . -", what, name));
  }
  return Status::ok();
}

}  // namespace crackvis::dem
