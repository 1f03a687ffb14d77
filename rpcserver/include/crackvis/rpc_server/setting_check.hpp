// How both services check a setting's range: one message naming the flag,
// the configuration key, the bounds and the value given.
#pragma once

#include <string_view>

#include <crackvis/common/status.hpp>

namespace crackvis::rpc {

// A setting as a user may give it: its command-line flag and its key in the
// configuration file (either may be empty).
struct SettingName {
  std::string_view flag;
  std::string_view key;
};

// OK when min <= value <= max (and a real is finite), otherwise
// INVALID_ARGUMENT naming the setting, its bounds and the value. The
// services' configuration checks are made of these (T: int, std::int64_t,
// std::uint64_t, double).
template <typename T>
Status checkSetting(SettingName name, T value, T min, T max);

}  // namespace crackvis::rpc
