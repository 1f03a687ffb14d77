#include <algorithm>
#include <chrono>
#include <limits>
#include <map>

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <crackvis/dataservice/catalogue.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::dataservice {
namespace fs = std::filesystem;
namespace h5 = crackvis::dem::h5;

std::mutex& hdf5Mutex() {
  static std::mutex mutex;
  return mutex;
}

namespace {

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

// Little-endian memory types: what Read sends whatever the host's order.
hid_t littleEndianType(DataType type) {
  switch (type) {
    case DataType::kInt8:
      return H5T_STD_I8LE;
    case DataType::kUInt8:
      return H5T_STD_U8LE;
    case DataType::kInt16:
      return H5T_STD_I16LE;
    case DataType::kUInt16:
      return H5T_STD_U16LE;
    case DataType::kInt32:
      return H5T_STD_I32LE;
    case DataType::kUInt32:
      return H5T_STD_U32LE;
    case DataType::kInt64:
      return H5T_STD_I64LE;
    case DataType::kUInt64:
      return H5T_STD_U64LE;
    case DataType::kFloat32:
      return H5T_IEEE_F32LE;
    case DataType::kFloat64:
      return H5T_IEEE_F64LE;
    case DataType::kUnspecified:
    case DataType::kString:
      break;
  }
  return H5I_INVALID_HID;
}

// Opens a file for reading once it is known to be HDF5; the caller holds
// the HDF5 lock.
Result<h5::Handle> openHdf5(const ResolvedPath& file) {
  if (!hasHdf5Signature(file.absolute)) {
    return failedPrecondition(fmt::format("{}: not an HDF5 file", file.requested));
  }
  h5::Handle handle = h5::fileHandle(H5Fopen(file.absolute.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!handle.valid()) {
    return failedPrecondition(fmt::format("{}: cannot open: file is truncated or corrupt ({})",
                                          file.requested, h5::lastHdf5Error()));
  }
  return handle;
}

// ------------------------------------------------------------- Describe --

Result<AttributeInfo> readAttribute(hid_t object, const char* name) {
  AttributeInfo info;
  info.name = name;
  h5::Handle attribute = h5::attributeHandle(H5Aopen(object, name, H5P_DEFAULT));
  h5::Handle type = h5::datatypeHandle(attribute.valid() ? H5Aget_type(attribute.get()) : -1);
  h5::Handle space = h5::dataspaceHandle(attribute.valid() ? H5Aget_space(attribute.get()) : -1);
  if (!type.valid() || !space.valid()) {
    return failedPrecondition(
        fmt::format("cannot read attribute '{}' ({})", name, h5::lastHdf5Error()));
  }
  info.dtype = classifyType(type.get());
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank > 0) {
    std::vector<hsize_t> dims(static_cast<size_t>(rank));
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    info.shape.assign(dims.begin(), dims.end());
  }
  const hssize_t points = H5Sget_simple_extent_npoints(space.get());
  // Attributes are small by HDF5's design; a huge one is described, not read.
  constexpr hssize_t kMaxPointsRead = 1 << 20;
  if (points <= 0 || points > kMaxPointsRead) {
    info.truncated = points > 0;
    return info;
  }
  const auto count = static_cast<size_t>(points);
  switch (H5Tget_class(type.get())) {
    case H5T_STRING:
      if (count == 1) {
        auto text = h5::readStringAttribute(object, name);
        if (!text) {
          return text.status();
        }
        info.value = *text;
      } else {
        info.truncated = true;
      }
      break;
    case H5T_INTEGER: {
      std::vector<std::int64_t> values(count);
      if (H5Aread(attribute.get(), H5T_NATIVE_INT64, values.data()) < 0) {
        return failedPrecondition(
            fmt::format("cannot read attribute '{}' ({})", name, h5::lastHdf5Error()));
      }
      info.truncated = values.size() > AttributeInfo::kMaxAttributeValues;
      values.resize(std::min(values.size(), AttributeInfo::kMaxAttributeValues));
      info.value = std::move(values);
      break;
    }
    case H5T_FLOAT: {
      std::vector<double> values(count);
      if (H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, values.data()) < 0) {
        return failedPrecondition(
            fmt::format("cannot read attribute '{}' ({})", name, h5::lastHdf5Error()));
      }
      info.truncated = values.size() > AttributeInfo::kMaxAttributeValues;
      values.resize(std::min(values.size(), AttributeInfo::kMaxAttributeValues));
      info.value = std::move(values);
      break;
    }
    default:
      break;
  }
  return info;
}

struct AttributeWalk {
  std::vector<AttributeInfo> attributes;
  Status status;
};

herr_t collectAttribute(hid_t object, const char* name, const H5A_info_t*, void* data) {
  auto* walk = static_cast<AttributeWalk*>(data);
  auto attribute = readAttribute(object, name);
  if (!attribute) {
    walk->status = attribute.status();
    return 1;  // stop
  }
  walk->attributes.push_back(std::move(*attribute));
  return 0;
}

Result<std::vector<AttributeInfo>> readAttributes(hid_t object, const std::string& path) {
  AttributeWalk walk;
  hsize_t index = 0;
  if (H5Aiterate2(object, H5_INDEX_NAME, H5_ITER_INC, &index, collectAttribute, &walk) < 0) {
    return failedPrecondition(
        fmt::format("cannot list the attributes of {} ({})", path, h5::lastHdf5Error()));
  }
  if (!walk.status) {
    return Status(walk.status.code(), fmt::format("{}: {}", path, walk.status.message()));
  }
  return std::move(walk.attributes);
}

struct TreeWalk {
  FileDescription* description = nullptr;
  Status status;
  const DescribeOptions* options = nullptr;
  std::chrono::steady_clock::time_point deadline;
  std::size_t objects = 0;
};

// A path for a message: a hostile one may be thousands of levels long.
std::string shortPath(const std::string& path) {
  constexpr std::size_t kShown = 80;
  return path.size() <= kShown ? path : path.substr(0, kShown) + "...";
}

// Whether the walk may go on: a chain of 1,000 nested groups took 9 s under
// the HDF5 lock (every lookup walks the whole path), so depth, objects and
// time are bounded, and a caller that went away stops it.
bool withinBounds(TreeWalk& walk, const std::string& path) {
  const DescribeLimits& limits = walk.options->limits;
  const auto depth = static_cast<int>(std::count(path.begin(), path.end(), '/'));
  if (depth > limits.maxDepth) {
    walk.status = resourceExhausted(fmt::format("{} lies deeper than {} levels, Describe's limit",
                                                shortPath(path), limits.maxDepth));
  } else if (++walk.objects > limits.maxObjects) {
    walk.status =
        resourceExhausted(fmt::format("more than {} objects, Describe's limit", limits.maxObjects));
  } else if (std::chrono::steady_clock::now() > walk.deadline) {
    walk.status = resourceExhausted(fmt::format(
        "the tree took longer than {} s to walk, Describe's limit", limits.maxTime.count()));
  } else if (walk.options->cancelled && walk.options->cancelled()) {
    walk.status = Status(StatusCode::kUnavailable, "Describe cancelled by the caller");
  }
  return walk.status.isOk();
}

herr_t visitLink(hid_t root, const char* name, const H5L_info_t* link, void* data) {
  auto* walk = static_cast<TreeWalk*>(data);
  if (!withinBounds(*walk, std::string("/") + name)) {
    return 1;  // stop
  }
  // Soft links name objects that are listed under their hard link; external
  // and user-defined links lead out of the file, which the service never
  // follows.
  if (link->type != H5L_TYPE_HARD) {
    return 0;
  }
  const std::string path = std::string("/") + name;
  H5O_info_t object{};
  if (H5Oget_info_by_name2(root, name, &object, H5O_INFO_BASIC, H5P_DEFAULT) < 0) {
    walk->status =
        failedPrecondition(fmt::format("cannot inspect {} ({})", path, h5::lastHdf5Error()));
    return 1;
  }
  if (object.type != H5O_TYPE_GROUP && object.type != H5O_TYPE_DATASET) {
    return 0;  // named datatypes
  }
  h5::Handle handle = {H5Oopen(root, name, H5P_DEFAULT), H5Oclose};
  if (!handle.valid()) {
    walk->status =
        failedPrecondition(fmt::format("cannot open {} ({})", path, h5::lastHdf5Error()));
    return 1;
  }
  auto attributes = readAttributes(handle.get(), path);
  if (!attributes) {
    walk->status = attributes.status();
    return 1;
  }
  if (object.type == H5O_TYPE_GROUP) {
    walk->description->groups.push_back({path, std::move(*attributes)});
    return 0;
  }
  auto shape = h5::describeDataset(handle.get());
  h5::Handle type = h5::datatypeHandle(H5Dget_type(handle.get()));
  if (!shape || !type.valid()) {
    walk->status = failedPrecondition(fmt::format(
        "dataset {}: {}", path, shape ? h5::lastHdf5Error() : shape.status().message()));
    return 1;
  }
  DatasetInfo dataset;
  dataset.path = path;
  dataset.dtype = classifyType(type.get());
  if (dataset.dtype == DataType::kString) {
    dataset.dtype = DataType::kUnspecified;  // Read sends numbers only
  }
  dataset.dtypeName = dataset.dtype != DataType::kUnspecified
                          ? std::string(dataTypeName(dataset.dtype))
                          : shape->typeName;
  dataset.shape = shape->dims;
  dataset.chunkShape = shape->chunkDims;
  dataset.attributes = std::move(*attributes);
  walk->description->datasets.push_back(std::move(dataset));
  return 0;
}

// The format, version and complete steps of a crackvis-dem file, taken from
// the attributes already collected.
void fillDemSummary(FileDescription& description) {
  const GroupInfo* root = description.findGroup("/");
  if (root == nullptr) {
    return;
  }
  const dem::RootAttributes attributes = demRootAttributes(description);
  if (attributes.format) {
    description.format = *attributes.format;
  }
  description.formatVersion = static_cast<int>(attributes.version.isOk() ? *attributes.version : 0);
  if (description.format != dem::kFormatName) {
    return;
  }
  const GroupInfo* steps = description.findGroup("/steps");
  if (steps == nullptr) {
    return;
  }
  const std::int64_t count = steps->integerAttribute("count").value_or(0);
  // A damaged file: the steps before the first problem are reported.
  const dem::StepList list = dem::listSteps(count, [&](int k) -> std::optional<Result<double>> {
    const GroupInfo* group = description.findGroup(dem::stepGroupPath(k));
    if (group == nullptr) {
      return std::nullopt;
    }
    if (auto time = group->floatAttribute("time")) {
      return Result<double>(*time);
    }
    return Result<double>(failedPrecondition("missing attribute 'time'"));
  });
  for (const auto& [index, time] : list.steps) {
    description.steps.push_back({index, time, dem::stepGroupPath(index)});
  }
}

// ----------------------------------------------------------------- Read --

// Opens a dataset named by a client: the path must be absolute in the file,
// and every link on the way (soft links followed to their ends) must exist
// and stay inside the file. The dataset is opened by the path of hard links
// it resolved to, which `resolved` receives.
Result<h5::Handle> openDataset(hid_t file, const std::string& fileName, const std::string& path,
                               std::string& resolved) {
  if (path.empty() || path.front() != '/' || path == "/") {
    return invalidArgument(
        fmt::format("dataset '{}' in {}: name a dataset by its absolute path in the file, like "
                    "/steps/000000/positions",
                    path, fileName));
  }
  if (path.find("//") != std::string::npos) {
    return invalidArgument(
        fmt::format("dataset '{}' in {}: empty part in the path", path, fileName));
  }
  auto target = h5::resolveInFile(file, path);
  if (!target) {
    switch (target.status().code()) {
      case StatusCode::kNotFound:
        return notFound(fmt::format("dataset {} missing in {} ({})", path, fileName,
                                    target.status().message()));
      case StatusCode::kPermissionDenied:
        return permissionDenied(
            fmt::format("dataset {} in {}: {}; the service never follows links out of a file", path,
                        fileName, target.status().message()));
      default:
        return failedPrecondition(
            fmt::format("dataset {} in {}: {}", path, fileName, target.status().message()));
    }
  }
  H5O_info_t object{};
  if (H5Oget_info_by_name2(file, target->c_str(), &object, H5O_INFO_BASIC, H5P_DEFAULT) < 0) {
    return notFound(
        fmt::format("dataset {} missing in {} ({})", path, fileName, h5::lastHdf5Error()));
  }
  if (object.type != H5O_TYPE_DATASET) {
    return invalidArgument(fmt::format("{} in {} is a {}, not a dataset", path, fileName,
                                       object.type == H5O_TYPE_GROUP ? "group" : "named type"));
  }
  h5::Handle access = h5::noExternalLinks();
  h5::Handle dataset = h5::datasetHandle(H5Dopen2(file, target->c_str(), access.get()));
  if (!dataset.valid()) {
    return failedPrecondition(
        fmt::format("dataset {} in {}: cannot open ({})", path, fileName, h5::lastHdf5Error()));
  }
  resolved = std::move(*target);
  return dataset;
}

// Raw data stored outside the file would let a file read beyond the root.
Status checkStorage(hid_t dataset, const std::string& fileName, const std::string& path) {
  h5::Handle plist = h5::propertyListHandle(H5Dget_create_plist(dataset));
  if (!plist.valid()) {
    return failedPrecondition(fmt::format("dataset {} in {}: unreadable header ({})", path,
                                          fileName, h5::lastHdf5Error()));
  }
  if (H5Pget_layout(plist.get()) == H5D_VIRTUAL || H5Pget_external_count(plist.get()) > 0) {
    return permissionDenied(fmt::format(
        "dataset {} in {} keeps its data in other files; the service reads only data stored "
        "in the file itself",
        path, fileName));
  }
  return Status::ok();
}

std::string formatSigned(const std::vector<std::int64_t>& values) {
  return fmt::format("[{}]", fmt::join(values, ","));
}

Result<SlabPlan> planSlab(hid_t file, const std::string& fileName, const Hyperslab& slab,
                          size_t index) {
  SlabPlan plan;
  auto dataset = openDataset(file, fileName, slab.dataset, plan.resolvedDataset);
  if (!dataset) {
    return dataset.status();
  }
  CRACKVIS_RETURN_IF_ERROR(checkStorage(dataset->get(), fileName, slab.dataset));
  auto shape = h5::describeDataset(dataset->get());
  h5::Handle type = h5::datatypeHandle(H5Dget_type(dataset->get()));
  if (!shape || !type.valid()) {
    return failedPrecondition(fmt::format("dataset {} in {}: {}", slab.dataset, fileName,
                                          shape ? h5::lastHdf5Error() : shape.status().message()));
  }
  plan.dataset = slab.dataset;
  plan.dtype = classifyType(type.get());
  plan.datasetShape = shape->dims;
  if (elementSize(plan.dtype) == 0) {
    return invalidArgument(fmt::format("dataset {} in {} has type {}, which Read cannot send",
                                       slab.dataset, fileName, shape->typeName));
  }
  const size_t rank = shape->dims.size();
  const std::string where = fmt::format("hyperslab {} of {} in {}", index, slab.dataset, fileName);
  if (slab.start.empty() && slab.count.empty()) {
    plan.start.assign(rank, 0);
    plan.count = shape->dims;
  } else {
    if (slab.start.size() != rank || slab.count.size() != rank) {
      return invalidArgument(fmt::format(
          "{}: start has {} and count has {} values, the dataset has rank {} (shape {})", where,
          slab.start.size(), slab.count.size(), rank, h5::formatDims(shape->dims)));
    }
    for (size_t d = 0; d < rank; ++d) {
      if (slab.start[d] < 0) {
        return invalidArgument(fmt::format("{}: start[{}] = {} is negative (start {})", where, d,
                                           slab.start[d], formatSigned(slab.start)));
      }
      if (slab.count[d] <= 0) {
        return invalidArgument(fmt::format("{}: count[{}] = {} must be at least 1 (count {})",
                                           where, d, slab.count[d], formatSigned(slab.count)));
      }
      const auto begin = static_cast<std::uint64_t>(slab.start[d]);
      const auto extent = static_cast<std::uint64_t>(slab.count[d]);
      if (begin >= shape->dims[d] || extent > shape->dims[d] - begin) {
        return invalidArgument(fmt::format(
            "{}: start {} count {} lies outside the dataset's shape {} (dimension {})", where,
            formatSigned(slab.start), formatSigned(slab.count), h5::formatDims(shape->dims), d));
      }
      plan.start.push_back(begin);
      plan.count.push_back(extent);
    }
  }
  // The counts lie inside an existing dataset, but a sparse chunked one can
  // still describe more bytes than fit in 64 bits.
  std::uint64_t elements = 1;
  std::uint64_t rowElements = 1;
  for (size_t d = 0; d < rank; ++d) {
    if (__builtin_mul_overflow(elements, plan.count[d], &elements)) {
      return resourceExhausted(fmt::format("{}: too many elements", where));
    }
    if (d > 0 && __builtin_mul_overflow(rowElements, plan.count[d], &rowElements)) {
      return resourceExhausted(fmt::format("{}: too many elements", where));
    }
  }
  const std::uint64_t size = elementSize(plan.dtype);
  if (__builtin_mul_overflow(elements, size, &plan.bytes)) {
    return resourceExhausted(fmt::format("{}: too many bytes", where));
  }
  plan.rowBytes = rowElements * size;
  return plan;
}

}  // namespace

// --------------------------------------------------------------- Catalogue

// The HDF5 files describe() and openRead() opened, kept open between calls
// that follow each other within two seconds (a viewer stepping through a
// file). Opening a file HDF5 already has open shares it: no superblock to
// read, and what HDF5 cached of the file's metadata (group B-trees, object
// headers) stays warm. A view's Read of cuboid A opened its file in
// 0.16-0.33 ms and closed it in 0.07-0.2 ms, against 0.03 ms each when kept
// open; stepping through steps, the Read is 7-10% faster.
//
// Every use compares the file with what it was when opened (device, inode,
// size, modification and change times) and opens it afresh on any
// difference; a file changed in the last two seconds is not kept, since a
// second write within one tick of the file system's clock would leave those
// unchanged. The idle limit is short because HDF5's file locking keeps a
// writer from opening a file for writing while any reader has it open (as
// during every call anyway). Everything here runs under hdf5Mutex().
class Catalogue::OpenFiles {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kMaxFiles = 16;
  static constexpr std::chrono::seconds kIdle{2};
  static constexpr std::chrono::seconds kSettled{2};

  OpenFiles() = default;
  OpenFiles(const OpenFiles&) = delete;
  OpenFiles& operator=(const OpenFiles&) = delete;
  ~OpenFiles() {
    std::lock_guard lock(hdf5Mutex());
    h5::quietHdf5();
    m_files.clear();
  }

  // A handle of its own for the caller, as openHdf5() gives.
  Result<h5::Handle> open(const ResolvedPath& file) {
    const auto now = Clock::now();
    closeIdle(now);
    const std::string path = file.absolute.string();
    struct stat info {};
    const bool found = ::stat(path.c_str(), &info) == 0;
    if (auto kept = m_files.find(path); kept != m_files.end()) {
      if (found && kept->second.identity == identityOf(info)) {
        h5::Handle handle = h5::fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
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
    h5::Handle kept = h5::fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
    if (kept.valid()) {
      m_files.emplace(path, File{std::move(kept), identityOf(info), now, {}});
    }
    return handle;
  }

  // A dataset of a kept file, opened once while the file is unchanged
  // (identity checked as open() does); nothing when the file is not kept.
  struct KeptDataset {
    hid_t dataset;
    DataType dtype;
  };
  std::optional<KeptDataset> keptDataset(const ResolvedPath& file, const std::string& name) {
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

  void closeIdle(Clock::time_point now) {
    std::erase_if(m_files, [&](const auto& file) { return now - file.second.lastUsed > kIdle; });
  }

 private:
  struct Identity {
    dev_t device = 0;
    ino_t inode = 0;
    off_t size = 0;
    std::int64_t modified = 0;  // ns since the epoch
    std::int64_t changed = 0;
    bool operator==(const Identity&) const = default;
  };
  struct File {
    h5::Handle handle;
    Identity identity;
    Clock::time_point lastUsed;
    // Datasets a piece was read from, with the type the piece checked:
    // pieces of one Read come one by one, each its own request.
    std::map<std::string, std::pair<h5::Handle, DataType>> datasets;
  };

  static std::int64_t nanoseconds(const timespec& time) {
    return std::int64_t{time.tv_sec} * 1'000'000'000 + time.tv_nsec;
  }
  static Identity identityOf(const struct stat& info) {
    return {info.st_dev, info.st_ino, info.st_size, nanoseconds(info.st_mtim),
            nanoseconds(info.st_ctim)};
  }
  static bool settled(const struct stat& info) {
    const std::int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                 std::chrono::system_clock::now().time_since_epoch())
                                 .count();
    const std::int64_t last = std::max(nanoseconds(info.st_mtim), nanoseconds(info.st_ctim));
    return now - last >= std::chrono::duration_cast<std::chrono::nanoseconds>(kSettled).count();
  }

  std::map<std::string, File> m_files;
};

Catalogue::Catalogue(DataRoot root)
    : m_root(std::move(root)), m_openFiles(std::make_shared<OpenFiles>()) {}

void Catalogue::closeIdleFiles() const {
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  m_openFiles->closeIdle(OpenFiles::Clock::now());
}

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

Result<FileDescription> Catalogue::describe(const ResolvedPath& file,
                                            const DescribeOptions& options) const {
  FileDescription description;
  description.file = file.requested;
  std::error_code error;
  description.sizeBytes = fs::file_size(file.absolute, error);
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  auto handle = m_openFiles->open(file);
  if (!handle) {
    return handle.status();
  }
  auto rootAttributes = readAttributes(handle->get(), "/");
  if (!rootAttributes) {
    return Status(rootAttributes.status().code(),
                  fmt::format("{}: {}", file.requested, rootAttributes.status().message()));
  }
  description.groups.push_back({"/", std::move(*rootAttributes)});
  TreeWalk walk{
      &description, Status::ok(), &options,
      std::chrono::steady_clock::now() +
          std::chrono::duration_cast<std::chrono::steady_clock::duration>(options.limits.maxTime)};
  const herr_t visited = H5Lvisit(handle->get(), H5_INDEX_NAME, H5_ITER_INC, visitLink, &walk);
  if (!walk.status) {
    return Status(walk.status.code(), fmt::format("{}: {}", file.requested, walk.status.message()));
  }
  if (visited < 0) {
    return failedPrecondition(
        fmt::format("{}: cannot walk the file's tree ({})", file.requested, h5::lastHdf5Error()));
  }
  description.buildIndex();
  fillDemSummary(description);
  return description;
}

// HDF5 handles of an open Read; closed under the lock.
struct SlabReader::Handles {
  h5::Handle file;
  h5::Handle dataset;
  size_t datasetSlab = std::numeric_limits<size_t>::max();
};

SlabReader::SlabReader() : m_handles(std::make_unique<Handles>()) {}

SlabReader::~SlabReader() {
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  m_handles.reset();
}

namespace {

// The first dimension a piece of `slab` runs along: the outermost one whose
// inner block (one index of it, everything after it) fits in a chunk.
std::size_t splitDimension(const SlabPlan& slab) {
  std::uint64_t inner = elementSize(slab.dtype);
  std::size_t dimension = slab.count.size() - 1;
  while (dimension > 0 && inner * slab.count[dimension] <= kMaxChunkBytes) {
    inner *= slab.count[dimension];
    --dimension;
  }
  return dimension;
}

std::uint64_t innerBytes(const SlabPlan& slab, std::size_t dimension) {
  std::uint64_t bytes = elementSize(slab.dtype);
  for (std::size_t d = dimension + 1; d < slab.count.size(); ++d) {
    bytes *= slab.count[d];
  }
  return bytes;
}

}  // namespace

std::optional<Piece> PieceCursor::next(const std::vector<SlabPlan>& slabs) {
  while (m_slab < slabs.size()) {
    const SlabPlan& slab = slabs[m_slab];
    if (slab.bytes == 0 || m_offset >= slab.bytes) {
      ++m_slab;
      m_start.clear();
      m_offset = 0;
      continue;
    }
    Piece piece;
    piece.slab = m_slab;
    piece.offset = m_offset;
    if (slab.count.empty()) {  // a scalar: one piece
      piece.bytes = slab.bytes;
      m_offset = slab.bytes;
      return piece;
    }
    const std::size_t rank = slab.count.size();
    if (m_start.empty()) {
      m_start.assign(rank, 0);
    }
    const std::size_t along = splitDimension(slab);
    const std::uint64_t inner = innerBytes(slab, along);
    const std::uint64_t run = std::min(std::max<std::uint64_t>(1, kMaxChunkBytes / inner),
                                       slab.count[along] - m_start[along]);
    piece.start = m_start;
    piece.count.assign(rank, 1);
    for (std::size_t d = along + 1; d < rank; ++d) {
      piece.count[d] = slab.count[d];
    }
    piece.count[along] = run;
    piece.bytes = run * inner;
    // Advance in row-major order: carry into the dimensions before `along`.
    m_offset += piece.bytes;
    m_start[along] += run;
    for (std::size_t d = along; d > 0 && m_start[d] == slab.count[d]; --d) {
      m_start[d] = 0;
      ++m_start[d - 1];
    }
    return piece;
  }
  return std::nullopt;
}

std::optional<Piece> SlabReader::nextPiece() {
  return m_pieces.next(m_slabs);
}

namespace {

// Reads `piece` of `slab` from an open dataset; the caller holds the lock.
Status readSlabPiece(hid_t dataset, const std::string& file, const SlabPlan& slab,
                     const Piece& piece, void* out) {
  herr_t result = 0;
  if (slab.count.empty()) {  // a scalar, still one value (it may have changed since the plan)
    h5::Handle space = h5::dataspaceHandle(H5Dget_space(dataset));
    if (!space.valid() || H5Sget_simple_extent_npoints(space.get()) != 1) {
      return failedPrecondition(
          fmt::format("dataset {} in {}: no longer a scalar", slab.dataset, file));
    }
    result = H5Dread(dataset, littleEndianType(slab.dtype), H5S_ALL, H5S_ALL, H5P_DEFAULT, out);
  } else {
    if (piece.start.size() != slab.count.size() || piece.count.size() != slab.count.size()) {
      return invalidArgument(
          fmt::format("dataset {} in {}: a piece of rank {} of a slab of rank {}", slab.dataset,
                      file, piece.count.size(), slab.count.size()));
    }
    std::vector<hsize_t> start(slab.start.begin(), slab.start.end());
    std::vector<hsize_t> count(piece.count.begin(), piece.count.end());
    for (std::size_t d = 0; d < start.size(); ++d) {
      start[d] += piece.start[d];
    }
    h5::Handle fileSpace = h5::dataspaceHandle(H5Dget_space(dataset));
    h5::Handle memorySpace = h5::dataspaceHandle(
        H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr));
    if (!fileSpace.valid() || !memorySpace.valid() ||
        H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                            nullptr) < 0 ||
        H5Sselect_valid(fileSpace.get()) <= 0 ||
        static_cast<std::uint64_t>(H5Sget_select_npoints(memorySpace.get())) *
                elementSize(slab.dtype) !=
            piece.bytes) {
      return failedPrecondition(
          fmt::format("dataset {} in {}: cannot select the piece (the file may have changed; {})",
                      slab.dataset, file, h5::lastHdf5Error()));
    }
    result = H5Dread(dataset, littleEndianType(slab.dtype), memorySpace.get(), fileSpace.get(),
                     H5P_DEFAULT, out);
  }
  if (result < 0) {
    return failedPrecondition(
        fmt::format("dataset {} in {}: read failed, the file may be truncated or corrupt ({})",
                    slab.dataset, file, h5::lastHdf5Error()));
  }
  return Status::ok();
}

}  // namespace

Status SlabReader::read(const Piece& piece, void* out) {
  const SlabPlan& slab = m_slabs.at(piece.slab);
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  if (m_handles->datasetSlab != piece.slab) {
    h5::Handle access = h5::noExternalLinks();
    m_handles->dataset = h5::datasetHandle(
        H5Dopen2(m_handles->file.get(), slab.resolvedDataset.c_str(), access.get()));
    m_handles->datasetSlab = piece.slab;
  }
  if (!m_handles->dataset.valid()) {
    return failedPrecondition(fmt::format("dataset {} in {}: cannot open ({})", slab.dataset,
                                          m_file, h5::lastHdf5Error()));
  }
  return readSlabPiece(m_handles->dataset.get(), m_file, slab, piece, out);
}

Status Catalogue::readPiece(const ResolvedPath& file, const SlabPlan& slab, const Piece& piece,
                            void* out) const {
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  // The plan came from an earlier view of the file: the dataset must still
  // have the type the piece's size assumes.
  const auto changedType = [&] {
    return failedPrecondition(fmt::format("dataset {} in {}: its type changed since the Read began",
                                          slab.dataset, file.requested));
  };
  if (auto kept = m_openFiles->keptDataset(file, slab.resolvedDataset)) {
    if (kept->dtype != slab.dtype) {
      return changedType();
    }
    return readSlabPiece(kept->dataset, file.requested, slab, piece, out);
  }
  auto handle = m_openFiles->open(file);
  if (!handle) {
    return handle.status();
  }
  h5::Handle access = h5::noExternalLinks();
  h5::Handle dataset =
      h5::datasetHandle(H5Dopen2(handle->get(), slab.resolvedDataset.c_str(), access.get()));
  if (!dataset.valid()) {
    return failedPrecondition(fmt::format("dataset {} in {}: cannot open ({})", slab.dataset,
                                          file.requested, h5::lastHdf5Error()));
  }
  h5::Handle type = h5::datatypeHandle(H5Dget_type(dataset.get()));
  if (!type.valid() || classifyType(type.get()) != slab.dtype) {
    return changedType();
  }
  return readSlabPiece(dataset.get(), file.requested, slab, piece, out);
}

Result<std::unique_ptr<SlabReader>> Catalogue::openRead(const ResolvedPath& file,
                                                        const std::vector<Hyperslab>& slabs,
                                                        std::uint64_t maxBytes) const {
  if (slabs.empty()) {
    return invalidArgument(fmt::format("Read of {}: no hyperslab requested", file.requested));
  }
  std::unique_ptr<SlabReader> reader(new SlabReader());
  reader->m_file = file.requested;
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  auto handle = m_openFiles->open(file);
  if (!handle) {
    return handle.status();
  }
  for (size_t i = 0; i < slabs.size(); ++i) {
    auto plan = planSlab(handle->get(), file.requested, slabs[i], i);
    if (!plan) {
      return plan.status();
    }
    if (__builtin_add_overflow(reader->m_totalBytes, plan->bytes, &reader->m_totalBytes) ||
        reader->m_totalBytes > maxBytes) {
      return resourceExhausted(fmt::format(
          "Read of {} asks for more than {} (the server's limit per request) at hyperslab {} "
          "({})",
          file.requested, formatBytes(maxBytes), i, plan->dataset));
    }
    reader->m_slabs.push_back(std::move(*plan));
  }
  reader->m_handles->file = std::move(*handle);
  return reader;
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
