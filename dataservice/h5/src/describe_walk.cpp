// Describe: the walk of a file's tree, bounded in depth, objects and time.
#include <algorithm>
#include <chrono>

#include <fmt/format.h>

#include "catalogue_internal.hpp"
#include "open_files.hpp"
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::dataservice {
namespace fs = std::filesystem;
namespace h5 = crackvis::dem::h5;

namespace {

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

// Whether the walk may go on: a file can hold millions of objects (40,000
// sibling groups take about 0.6 s), so depth, objects and time are bounded,
// and a caller that went away stops it.
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
  // Opened by the address the link holds, not by its path: a lookup by
  // path walks every group on the way (twice per object: its type, then the
  // open), so a chain of 1,000 nested groups took 6.7 s to walk, against
  // 0.06 s now (tests/dataservice/catalogue.test.cpp).
  h5::Handle handle = {H5Oopen_by_addr(root, link->u.address), H5Oclose};
  if (!handle.valid()) {
    walk->status =
        failedPrecondition(fmt::format("cannot open {} ({})", path, h5::lastHdf5Error()));
    return 1;
  }
  const H5I_type_t kind = H5Iget_type(handle.get());
  if (kind != H5I_GROUP && kind != H5I_DATASET) {
    return 0;  // named datatypes
  }
  auto attributes = readAttributes(handle.get(), path);
  if (!attributes) {
    walk->status = attributes.status();
    return 1;
  }
  if (kind == H5I_GROUP) {
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

// An appendable (live) file's complete steps: the values of /steps/time,
// whose length is the commit mark (docs/data-format.md "Live files").
void fillAppendableSteps(FileDescription& description, hid_t file) {
  const DatasetInfo* time = description.findDataset(dem::kStepTimePath);
  if (time == nullptr || time->dtype != DataType::kFloat64 || time->shape.size() != 1) {
    return;
  }
  constexpr std::uint64_t kMaxSteps = 1'000'000;
  std::uint64_t count = std::min(time->shape[0], kMaxSteps);
  // The walk read the other step-axis datasets' headers before /steps/time
  // (name order): a step committed in between has its time but not, in this
  // description, its rows. Only steps with a row in every one are reported.
  for (const DatasetInfo& dataset : description.datasets) {
    if (dataset.path.starts_with("/steps/") && dataset.path != dem::kStepTimePath &&
        dataset.path != dem::kStepsWritingPath && !dataset.shape.empty()) {
      count = std::min(count, dataset.shape[0]);
    }
  }
  auto resolved = h5::resolveInFile(file, dem::kStepTimePath);
  if (!resolved) {
    return;
  }
  h5::Handle access = h5::noExternalLinks();
  h5::Handle dataset = h5::datasetHandle(H5Dopen2(file, resolved->c_str(), access.get()));
  std::vector<double> times(count);
  if (!dataset.valid() ||
      !h5::readLeading(dataset.get(), h5::ElementType::kFloat64, count, times.data())) {
    h5::lastHdf5Error();
    return;  // a damaged file: no steps reported, the reader says why
  }
  for (std::uint64_t k = 0; k < count; ++k) {
    description.steps.push_back({static_cast<int>(k), times[k], ""});
  }
}

// The format, version and complete steps of a crackvis-dem file, taken from
// the attributes already collected (and an appendable file's step times).
void fillDemSummary(FileDescription& description, hid_t file) {
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
  if (const AttributeInfo* layout = root->findAttribute(dem::kStepLayoutAttribute)) {
    const auto* name = std::get_if<std::string>(&layout->value);
    if (name != nullptr && *name == dem::kAppendableName) {
      fillAppendableSteps(description, file);
    }
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

}  // namespace

Result<FileDescription> describeOpenFile(hid_t file, const std::string& name,
                                         const DescribeOptions& options) {
  FileDescription description;
  description.file = name;
  auto rootAttributes = readAttributes(file, "/");
  if (!rootAttributes) {
    return Status(rootAttributes.status().code(),
                  fmt::format("{}: {}", name, rootAttributes.status().message()));
  }
  description.groups.push_back({"/", std::move(*rootAttributes)});
  TreeWalk walk{
      &description, Status::ok(), &options,
      std::chrono::steady_clock::now() +
          std::chrono::duration_cast<std::chrono::steady_clock::duration>(options.limits.maxTime)};
  const herr_t visited = H5Lvisit(file, H5_INDEX_NAME, H5_ITER_INC, visitLink, &walk);
  if (!walk.status) {
    return Status(walk.status.code(), fmt::format("{}: {}", name, walk.status.message()));
  }
  if (visited < 0) {
    return failedPrecondition(
        fmt::format("{}: cannot walk the file's tree ({})", name, h5::lastHdf5Error()));
  }
  description.buildIndex();
  fillDemSummary(description, file);
  return description;
}

Result<FileDescription> Catalogue::describe(const ResolvedPath& file,
                                            const DescribeOptions& options) const {
  std::error_code error;
  const std::uintmax_t sizeBytes = fs::file_size(file.absolute, error);
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  auto handle = m_openFiles->open(file);
  if (!handle) {
    return handle.status();
  }
  auto description = describeOpenFile(handle->get(), file.requested, options);
  if (description) {
    description->sizeBytes = sizeBytes;
  }
  return description;
}

}  // namespace crackvis::dataservice
