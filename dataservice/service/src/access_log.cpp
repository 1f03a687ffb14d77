#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>

#include <fmt/format.h>

#include <crackvis/dataservice/access_log.hpp>

namespace crackvis::dataservice {
namespace {

// Quotes a value; control characters, quotes and backslashes are escaped,
// so a hostile file name cannot forge a log line.
std::string quoted(const std::string& text) {
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

}  // namespace

Result<std::unique_ptr<AccessLog>> AccessLog::open(const std::string& path) {
  if (path.empty()) {
    return std::unique_ptr<AccessLog>(new AccessLog(nullptr, false));
  }
  if (path == "-") {
    return std::unique_ptr<AccessLog>(new AccessLog(stderr, false));
  }
  std::FILE* file = std::fopen(path.c_str(), "ae");
  if (file == nullptr) {
    return failedPrecondition(
        fmt::format("cannot open access log '{}': {}", path, std::strerror(errno)));
  }
  return std::unique_ptr<AccessLog>(new AccessLog(file, true));
}

AccessLog::~AccessLog() {
  if (m_owned && m_file != nullptr) {
    std::fclose(m_file);
  }
}

std::string AccessLog::format(const AccessRecord& record) {
  std::string line = fmt::format(
      "{} method={} user={} cert={} peer={} file={} bytes={} seconds={:.6f} status={}", utcNow(),
      record.method, quoted(record.user), quoted(record.certificateName), quoted(record.peer),
      quoted(record.file), record.bytes, record.seconds, record.status);
  if (!record.detail.empty()) {
    line += " detail=" + quoted(record.detail);
  }
  return line;
}

void AccessLog::record(const AccessRecord& record) {
  if (m_file == nullptr) {
    return;
  }
  const std::string line = format(record) + "\n";
  std::lock_guard lock(m_mutex);
  std::fwrite(line.data(), 1, line.size(), m_file);
  std::fflush(m_file);
}

}  // namespace crackvis::dataservice
