#include <cstring>

#include <fmt/format.h>

#include <crackvis/common/data_root.hpp>

namespace crackvis {
namespace fs = std::filesystem;

namespace {
// Longer paths are refused before any file system call (PATH_MAX).
constexpr std::size_t kMaxPathBytes = 4096;
}  // namespace

Result<DataRoot> DataRoot::open(const std::string& root) {
  std::error_code error;
  if (root.empty()) {
    return invalidArgument("no data root given");
  }
  const fs::path canonical = fs::canonical(root, error);
  if (error) {
    return crackvis::notFound(fmt::format("data root '{}': {}", root, error.message()));
  }
  if (!fs::is_directory(canonical, error)) {
    return invalidArgument(fmt::format("data root '{}' is not a directory", root));
  }
  return DataRoot(canonical);
}

Result<std::string> DataRoot::normalize(std::string_view path) {
  if (path.find('\0') != std::string_view::npos) {
    return invalidArgument(
        fmt::format("path '{}' contains a NUL character", echoed(path.substr(0, path.find('\0')))));
  }
  if (path.size() > kMaxPathBytes) {
    return invalidArgument(fmt::format("path '{}' is over {} bytes", echoed(path), kMaxPathBytes));
  }
  if (!path.empty() && path.front() == '/') {
    return invalidArgument(
        fmt::format("path '{}' is absolute; paths are relative to the data root", echoed(path)));
  }
  std::string normalized;
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find('/', start);
    if (end == std::string_view::npos) {
      end = path.size();
    }
    const std::string_view part = path.substr(start, end - start);
    if (part == "..") {
      return invalidArgument(fmt::format(
          "path '{}' contains '..'; paths must stay inside the data root", echoed(path)));
    }
    if (!part.empty() && part != ".") {
      if (!normalized.empty()) {
        normalized += '/';
      }
      normalized += part;
    }
    start = end + 1;
  }
  return normalized;
}

bool DataRoot::contains(const fs::path& canonical) const {
  auto rootIt = m_root.begin();
  auto pathIt = canonical.begin();
  for (; rootIt != m_root.end(); ++rootIt, ++pathIt) {
    if (pathIt == canonical.end() || *rootIt != *pathIt) {
      return false;
    }
  }
  return true;
}

Result<ResolvedPath> DataRoot::resolve(std::string_view path, bool wantFolder) const {
  auto normalized = normalize(path);
  if (!normalized) {
    return normalized.status();
  }
  if (normalized->empty() && !wantFolder) {
    return invalidArgument("no file named (empty path)");
  }
  const fs::path joined = normalized->empty() ? m_root : m_root / *normalized;
  std::error_code error;
  // weakly_canonical follows every symlink that exists, so a link that
  // leaves the root is caught even when its target does not exist.
  const fs::path real = fs::weakly_canonical(joined, error);
  if (error) {
    return crackvis::notFound(fmt::format("'{}': {}", echoed(*normalized), error.message()));
  }
  if (!contains(real)) {
    return permissionDenied(fmt::format("'{}' resolves outside the data root (a symlink leaves it)",
                                        echoed(*normalized)));
  }
  const fs::file_status status = fs::status(real, error);
  if (error || !fs::exists(status)) {
    return notFound(*normalized, wantFolder);
  }
  if (wantFolder && !fs::is_directory(status)) {
    return invalidArgument(fmt::format("'{}' is not a folder", echoed(*normalized)));
  }
  if (!wantFolder && !fs::is_regular_file(status)) {
    return invalidArgument(fmt::format("'{}' is not a regular file", echoed(*normalized)));
  }
  ResolvedPath resolved;
  resolved.requested = *normalized;
  resolved.relative = real == m_root ? std::string() : real.lexically_relative(m_root).string();
  resolved.absolute = real;
  return resolved;
}

Status DataRoot::notFound(std::string_view normalized, bool folder) {
  return crackvis::notFound(fmt::format("{} '{}' not found under the data root",
                                        folder ? "folder" : "file", echoed(normalized)));
}

Result<ResolvedPath> DataRoot::resolveFile(std::string_view path) const {
  return resolve(path, false);
}

Result<ResolvedPath> DataRoot::resolveFolder(std::string_view path) const {
  return resolve(path, true);
}

}  // namespace crackvis
