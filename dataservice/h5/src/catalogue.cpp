#include <algorithm>
#include <chrono>

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include "catalogue_internal.hpp"
#include "open_files.hpp"
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::dataservice {
namespace fs = std::filesystem;
namespace h5 = crackvis::dem::h5;

std::mutex& hdf5Mutex() {
  static std::mutex mutex;
  return mutex;
}

// The element type of a stored datatype, as the service names it.
DataType classifyType(hid_t type) {
  const h5::TypeClass stored = h5::typeClass(type);
  const auto sized = [&](DataType one, DataType two, DataType four, DataType eight) {
    switch (stored.bytes) {
      case 1:
        return one;
      case 2:
        return two;
      case 4:
        return four;
      case 8:
        return eight;
      default:
        return DataType::kUnspecified;
    }
  };
  switch (stored.kind) {
    case h5::TypeClass::kSignedInteger:
      return sized(DataType::kInt8, DataType::kInt16, DataType::kInt32, DataType::kInt64);
    case h5::TypeClass::kUnsignedInteger:
      return sized(DataType::kUInt8, DataType::kUInt16, DataType::kUInt32, DataType::kUInt64);
    case h5::TypeClass::kFloat:
      return sized(DataType::kUnspecified, DataType::kUnspecified, DataType::kFloat32,
                   DataType::kFloat64);
    case h5::TypeClass::kString:
      return DataType::kString;
    default:
      return DataType::kUnspecified;
  }
}

// --------------------------------------------------------------- Catalogue

Catalogue::Catalogue(DataRoot root)
    : m_root(std::move(root)), m_openFiles(std::make_shared<OpenFiles>()) {}

Result<std::vector<FileEntry>> Catalogue::listFiles(std::string_view folder, bool recursive,
                                                    const AccessFilter& mayRead) const {
  auto base = m_root.resolveFolder(folder);
  if (!base) {
    return base.status();
  }
  std::vector<FileEntry> entries;
  std::error_code error;
  auto consider = [&](const fs::directory_entry& entry) {
    std::error_code entryError;
    const fs::path real = fs::canonical(entry.path(), entryError);
    if (entryError || !m_root.contains(real) || !fs::is_regular_file(real, entryError)) {
      return;
    }
    const std::string relative = real.lexically_relative(m_root.path()).string();
    if (mayRead && !mayRead(relative)) {
      return;
    }
    FileEntry file;
    file.path = entry.path().lexically_relative(m_root.path()).string();
    file.sizeBytes = fs::file_size(real, entryError);
    const auto modified = fs::last_write_time(real, entryError);
    file.modifiedUnixSeconds = std::chrono::duration_cast<std::chrono::seconds>(
                                   std::chrono::file_clock::to_sys(modified).time_since_epoch())
                                   .count();
    file.isHdf5 = hasHdf5Signature(real);
    entries.push_back(std::move(file));
  };
  // Symlinked folders are not descended into: a link may not widen a listing.
  if (recursive) {
    for (fs::recursive_directory_iterator
             it(base->absolute, fs::directory_options::skip_permission_denied, error),
         end;
         !error && it != end; it.increment(error)) {
      consider(*it);
    }
  } else {
    for (fs::directory_iterator
             it(base->absolute, fs::directory_options::skip_permission_denied, error),
         end;
         !error && it != end; it.increment(error)) {
      consider(*it);
    }
  }
  if (error) {
    return internalError(fmt::format("cannot list '{}': {}", base->requested, error.message()));
  }
  std::sort(entries.begin(), entries.end(),
            [](const FileEntry& a, const FileEntry& b) { return a.path < b.path; });
  return entries;
}

FileReader::~FileReader() {
  if (m_fd >= 0) {
    ::close(m_fd);
  }
}

Result<std::size_t> FileReader::readAt(std::uint64_t offset, void* out, std::size_t bytes) {
  for (;;) {
    const ssize_t got = ::pread(m_fd, out, bytes, static_cast<off_t>(offset));
    if (got >= 0) {
      return static_cast<std::size_t>(got);
    }
    if (errno != EINTR) {
      return internalError(
          fmt::format("{}: read failed at offset {}: {}", m_name, offset, std::strerror(errno)));
    }
  }
}

Result<std::unique_ptr<FileReader>> Catalogue::openFetch(const ResolvedPath& file,
                                                         std::uint64_t maxBytes) const {
  if (!hasHdf5Signature(file.absolute)) {
    return failedPrecondition(fmt::format("{}: not an HDF5 file", file.requested));
  }
  // The path is canonical, so O_NOFOLLOW only refuses a symlink swapped in
  // since it was resolved.
  const int fd = ::open(file.absolute.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    return notFound(fmt::format("{}: cannot open: {}", file.requested, std::strerror(errno)));
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    return invalidArgument(fmt::format("'{}' is not a regular file", file.requested));
  }
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (size > maxBytes) {
    ::close(fd);
    return resourceExhausted(
        fmt::format("Fetch of {} ({}) exceeds the server's limit of {} per request", file.requested,
                    formatBytes(size), formatBytes(maxBytes)));
  }
  return std::unique_ptr<FileReader>(new FileReader(fd, size, file.requested));
}

}  // namespace crackvis::dataservice