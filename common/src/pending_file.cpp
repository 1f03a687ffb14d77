#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <crackvis/common/pending_file.hpp>

namespace crackvis {
namespace {

// fsync of the written file, so the rename never publishes a name whose
// data is still only in the page cache (a crash would leave it empty).
Status syncFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    return failedPrecondition(
        fmt::format("{}: cannot open to flush: {}", path, std::strerror(errno)));
  }
  const int synced = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (synced != 0) {
    return failedPrecondition(
        fmt::format("{}: cannot flush to disk: {}", path, std::strerror(error)));
  }
  return Status::ok();
}

}  // namespace

PendingFile::PendingFile(std::string target)
    : m_target(std::move(target)), m_partial(m_target + ".partial") {
  std::error_code error;
  std::filesystem::remove(m_partial, error);
}

PendingFile::~PendingFile() {
  if (!m_done && !m_keep) {
    std::error_code error;
    std::filesystem::remove(m_partial, error);
  }
}

Status PendingFile::commit() {
  CRACKVIS_RETURN_IF_ERROR(syncFile(m_partial));
  std::error_code error;
  std::filesystem::rename(m_partial, m_target, error);
  if (error) {
    return failedPrecondition(fmt::format("cannot replace {} with the new file {}: {}", m_target,
                                          m_partial, error.message()));
  }
  m_done = true;
  return Status::ok();
}

Status PendingFile::named(const Status& status) const {
  std::string message = status.message();
  for (std::size_t at = message.find(m_partial); at != std::string::npos;
       at = message.find(m_partial, at + m_target.size())) {
    message.replace(at, m_partial.size(), m_target);
  }
  return {status.code(), std::move(message)};
}

Status replaceFile(const std::string& path, std::string_view bytes) {
  PendingFile output(path);
  std::ofstream out(output.path(), std::ios::binary | std::ios::trunc);
  if (!out) {
    return failedPrecondition(
        fmt::format("{}: cannot open for writing ({})", path, std::strerror(errno)));
  }
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) {
    return failedPrecondition(fmt::format("{}: write failed (disk full?)", path));
  }
  return output.named(output.commit());
}

}  // namespace crackvis
