#include "open_files.hpp"

#include <algorithm>
#include <chrono>
#include <mutex>

#include <fmt/format.h>

#include "catalogue_internal.hpp"

namespace crackvis::dataservice {
namespace h5 = crackvis::dem::h5;

namespace {

// Opens a file for reading once it is known to be HDF5; the caller holds
// the HDF5 lock.
Result<h5::Handle> openHdf5(const ResolvedPath& file) {
  if (!hasHdf5Signature(file.absolute)) {
    return failedPrecondition(fmt::format("{}: not an HDF5 file", file.requested));
  }
  h5::Handle handle = h5::openReadOnly(file.absolute.string());
  if (!handle.valid()) {
    return failedPrecondition(
        fmt::format("{}: cannot open: {}", file.requested, h5::openRefusal()));
  }
  return handle;
}

}  // namespace

Catalogue::OpenFiles::~OpenFiles() {
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  m_files.clear();
}

Result<h5::Handle> Catalogue::OpenFiles::open(const ResolvedPath& file) {
  const auto now = Clock::now();
  closeIdle(now);
  const std::string path = file.absolute.string();
  struct stat info {};
  const bool found = ::stat(path.c_str(), &info) == 0;
  if (auto kept = m_files.find(path); kept != m_files.end()) {
    if (found && kept->second.identity == identityOf(info)) {
      h5::Handle handle = h5::openReadOnly(path);
      if (handle.valid()) {
        kept->second.lastUsed = now;
        return handle;
      }
    }
    m_files.erase(kept);  // changed, gone or unreadable: opened afresh below
  }
  auto handle = openHdf5(file);
  if (!handle || !found || !settled(info)) {
    return handle;
  }
  if (m_files.size() >= kMaxFiles) {
    m_files.erase(std::min_element(
        m_files.begin(), m_files.end(),
        [](const auto& a, const auto& b) { return a.second.lastUsed < b.second.lastUsed; }));
  }
  // A second handle, kept: it shares the file the caller's handle opened.
  h5::Handle kept = h5::openReadOnly(path);
  if (kept.valid()) {
    m_files.emplace(path, File{std::move(kept), identityOf(info), now, {}});
  }
  return handle;
}

std::optional<Catalogue::OpenFiles::KeptDataset> Catalogue::OpenFiles::keptDataset(
    const ResolvedPath& file, const std::string& name) {
  const auto now = Clock::now();
  struct stat info {};
  auto kept = m_files.find(file.absolute.string());
  if (kept == m_files.end() || ::stat(file.absolute.c_str(), &info) != 0 ||
      !(kept->second.identity == identityOf(info))) {
    return std::nullopt;
  }
  kept->second.lastUsed = now;
  auto& datasets = kept->second.datasets;
  if (auto found = datasets.find(name); found != datasets.end()) {
    return KeptDataset{found->second.first.get(), found->second.second};
  }
  h5::Handle access = h5::noExternalLinks();
  h5::Handle dataset =
      h5::datasetHandle(H5Dopen2(kept->second.handle.get(), name.c_str(), access.get()));
  if (!dataset.valid()) {
    return std::nullopt;  // the caller opens it the slow way and reports why
  }
  h5::Handle type = h5::datatypeHandle(H5Dget_type(dataset.get()));
  const DataType dtype = type.valid() ? classifyType(type.get()) : DataType::kUnspecified;
  const hid_t id = dataset.get();
  datasets.emplace(name, std::pair{std::move(dataset), dtype});
  return KeptDataset{id, dtype};
}

void Catalogue::OpenFiles::closeIdle(Clock::time_point now) {
  std::erase_if(m_files, [&](const auto& file) { return now - file.second.lastUsed > kIdle; });
}

std::int64_t Catalogue::OpenFiles::nanoseconds(const timespec& time) {
  return std::int64_t{time.tv_sec} * 1'000'000'000 + time.tv_nsec;
}

Catalogue::OpenFiles::Identity Catalogue::OpenFiles::identityOf(const struct stat& info) {
  return {info.st_dev, info.st_ino, info.st_size, nanoseconds(info.st_mtim),
          nanoseconds(info.st_ctim)};
}

bool Catalogue::OpenFiles::settled(const struct stat& info) {
  const std::int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::system_clock::now().time_since_epoch())
                               .count();
  const std::int64_t last = std::max(nanoseconds(info.st_mtim), nanoseconds(info.st_ctim));
  return now - last >= std::chrono::duration_cast<std::chrono::nanoseconds>(kSettled).count();
}

void Catalogue::closeIdleFiles() const {
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  m_openFiles->closeIdle(OpenFiles::Clock::now());
}

}  // namespace crackvis::dataservice
