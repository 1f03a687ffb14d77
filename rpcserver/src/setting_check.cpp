#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include <fmt/format.h>

#include <crackvis/rpc_server/setting_check.hpp>

namespace crackvis::rpc {

template <typename T>
Status checkSetting(SettingName name, T value, T min, T max) {
  std::string bounds;
  if constexpr (std::is_floating_point_v<T>) {
    if (!std::isfinite(value)) {
      bounds = "must be a finite number";
    }
  }
  if (bounds.empty() && (value < min || value > max)) {
    bounds = max == std::numeric_limits<T>::max()
                 ? fmt::format("must be at least {}", min)
                 : fmt::format("must be between {} and {}", min, max);
  }
  if (bounds.empty()) {
    return Status::ok();
  }
  if (name.flag.empty()) {
    return invalidArgument(
        fmt::format("{} in the configuration file {}, got {}", name.key, bounds, value));
  }
  if (name.key.empty()) {
    return invalidArgument(fmt::format("{} {}, got {}", name.flag, bounds, value));
  }
  return invalidArgument(fmt::format("{} {}, got {} ({} in the configuration file)", name.flag,
                                     bounds, value, name.key));
}

template Status checkSetting<int>(SettingName, int, int, int);
template Status checkSetting<std::int64_t>(SettingName, std::int64_t, std::int64_t, std::int64_t);
template Status checkSetting<std::uint64_t>(SettingName, std::uint64_t, std::uint64_t,
                                            std::uint64_t);
template Status checkSetting<double>(SettingName, double, double, double);

}  // namespace crackvis::rpc
