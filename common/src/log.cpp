#include <chrono>
#include <ctime>

#include <fmt/format.h>

#include <crackvis/common/log.hpp>

namespace crackvis::log {

std::string utcNow() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto millis =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%S", &utc);
  return fmt::format("{}.{:03d}Z", text, millis);
}

std::string quoted(std::string_view text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20 || c == 0x7f) {
      out += fmt::format("\\x{:02x}", c);
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

void event(std::FILE* out, std::string_view program, std::string_view name,
           std::initializer_list<Field> fields) {
  std::string line = fmt::format("{} {} event={}", utcNow(), program, name);
  for (const auto& [key, value] : fields) {
    line += fmt::format(" {}={}", key, quoted(value));
  }
  line += '\n';
  std::fputs(line.c_str(), out);
  std::fflush(out);
}

}  // namespace crackvis::log
