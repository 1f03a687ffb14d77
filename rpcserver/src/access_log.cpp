#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>

#include <fmt/format.h>

#include <crackvis/common/log.hpp>
#include <crackvis/rpc_server/access_log.hpp>

namespace crackvis::rpc {
namespace {

using log::quoted;
using log::utcNow;

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
      quoted(echoed(record.file)), record.bytes, record.seconds, record.status);
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

}  // namespace crackvis::rpc
