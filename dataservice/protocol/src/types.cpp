#include <algorithm>
#include <numeric>

#include <fmt/format.h>

#include <crackvis/dataservice_protocol/types.hpp>

namespace crackvis::dataservice {

std::string_view dataTypeName(DataType type) {
  switch (type) {
    case DataType::kUnspecified:
      return "unspecified";
    case DataType::kInt8:
      return "int8";
    case DataType::kUInt8:
      return "uint8";
    case DataType::kInt16:
      return "int16";
    case DataType::kUInt16:
      return "uint16";
    case DataType::kInt32:
      return "int32";
    case DataType::kUInt32:
      return "uint32";
    case DataType::kInt64:
      return "int64";
    case DataType::kUInt64:
      return "uint64";
    case DataType::kFloat32:
      return "float32";
    case DataType::kFloat64:
      return "float64";
    case DataType::kString:
      return "string";
  }
  return "unspecified";
}

std::size_t elementSize(DataType type) {
  switch (type) {
    case DataType::kInt8:
    case DataType::kUInt8:
      return 1;
    case DataType::kInt16:
    case DataType::kUInt16:
      return 2;
    case DataType::kInt32:
    case DataType::kUInt32:
    case DataType::kFloat32:
      return 4;
    case DataType::kInt64:
    case DataType::kUInt64:
    case DataType::kFloat64:
      return 8;
    case DataType::kUnspecified:
    case DataType::kString:
      break;
  }
  return 0;
}

DataType dataTypeFromInt(int value) {
  if (value < 0 || value > static_cast<int>(DataType::kString)) {
    return DataType::kUnspecified;
  }
  return static_cast<DataType>(value);
}

std::string formatBytes(std::uint64_t bytes) {
  if (bytes < 1024) {
    return fmt::format("{} B", bytes);
  }
  const char* units[] = {"KiB", "MiB", "GiB", "TiB"};
  double value = static_cast<double>(bytes) / 1024.0;
  size_t unit = 0;
  while (value >= 1024.0 && unit + 1 < std::size(units)) {
    value /= 1024.0;
    ++unit;
  }
  return fmt::format("{:.2f} {}", value, units[unit]);
}

namespace {

// Positions of `items` sorted by their paths.
template <typename Item>
std::vector<std::uint32_t> sortedByPath(const std::vector<Item>& items) {
  std::vector<std::uint32_t> order(items.size());
  std::iota(order.begin(), order.end(), std::uint32_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return items[a].path < items[b].path; });
  return order;
}

template <typename Item>
const Item* findByPath(const std::vector<Item>& items, const std::vector<std::uint32_t>& byPath,
                       std::string_view path) {
  if (byPath.size() != items.size()) {
    auto found = std::find_if(items.begin(), items.end(),
                              [&](const Item& item) { return item.path == path; });
    return found == items.end() ? nullptr : &*found;
  }
  auto found =
      std::lower_bound(byPath.begin(), byPath.end(), path,
                       [&](std::uint32_t i, std::string_view p) { return items[i].path < p; });
  return found != byPath.end() && items[*found].path == path ? &items[*found] : nullptr;
}

}  // namespace

const DatasetInfo* FileDescription::findDataset(std::string_view path) const {
  return findByPath(datasets, m_datasetsByPath, path);
}

const GroupInfo* FileDescription::findGroup(std::string_view path) const {
  return findByPath(groups, m_groupsByPath, path);
}

void FileDescription::buildIndex() {
  m_datasetsByPath = sortedByPath(datasets);
  m_groupsByPath = sortedByPath(groups);
}

const AttributeInfo* GroupInfo::findAttribute(std::string_view name) const {
  for (const AttributeInfo& attribute : attributes) {
    if (attribute.name == name) {
      return &attribute;
    }
  }
  return nullptr;
}

std::optional<std::int64_t> GroupInfo::integerAttribute(std::string_view name) const {
  const AttributeInfo* attribute = findAttribute(name);
  const auto* values =
      attribute != nullptr ? std::get_if<std::vector<std::int64_t>>(&attribute->value) : nullptr;
  if (values == nullptr || values->size() != 1 || !attribute->shape.empty()) {
    return std::nullopt;
  }
  return values->front();
}

std::optional<double> GroupInfo::floatAttribute(std::string_view name) const {
  const AttributeInfo* attribute = findAttribute(name);
  const auto* values =
      attribute != nullptr ? std::get_if<std::vector<double>>(&attribute->value) : nullptr;
  if (values == nullptr || values->size() != 1 || !attribute->shape.empty()) {
    return std::nullopt;
  }
  return values->front();
}

namespace {

// Messages as crackvis::dem::h5's attribute readers word them.
Result<std::int64_t> integerOf(const GroupInfo* group, const char* name) {
  if (group == nullptr || group->findAttribute(name) == nullptr) {
    return notFound(fmt::format("missing attribute '{}'", name));
  }
  if (auto value = group->integerAttribute(name)) {
    return *value;
  }
  return invalidArgument(fmt::format("attribute '{}' is not a scalar integer", name));
}

}  // namespace

dem::RootAttributes demRootAttributes(const FileDescription& description) {
  dem::RootAttributes root;
  const GroupInfo* group = description.findGroup("/");
  const AttributeInfo* format = group != nullptr ? group->findAttribute("format") : nullptr;
  if (format == nullptr) {
    return root;
  }
  if (const auto* text = std::get_if<std::string>(&format->value)) {
    root.format = *text;
  } else {
    root.format = invalidArgument("attribute 'format' is not a scalar string");
  }
  root.version = integerOf(group, "version");
  root.dimension = integerOf(group, "dimension");
  return root;
}

bool isAppendable(const FileDescription& description) {
  const GroupInfo* root = description.findGroup("/");
  const AttributeInfo* layout =
      root != nullptr ? root->findAttribute(dem::kStepLayoutAttribute) : nullptr;
  const auto* name = layout != nullptr ? std::get_if<std::string>(&layout->value) : nullptr;
  return name != nullptr && *name == dem::kAppendableName;
}

std::string demStepDatasetPath(const FileDescription& description, dem::DemDataset id, int step) {
  return isAppendable(description) ? dem::appendablePath(id) : dem::datasetPath(id, step);
}

Status checkDemDataset(const FileDescription& description, dem::DemDataset id, int step,
                       const dem::LayoutSizes& sizes) {
  const bool row = dem::datasetSpec(id).perStep && isAppendable(description);
  const std::string path = demStepDatasetPath(description, id, step);
  const DatasetInfo* dataset = description.findDataset(path);
  if (dataset == nullptr) {
    return dem::missingDataset(path);
  }
  std::vector<std::uint64_t> dims = dataset->shape;
  if (row) {
    // An appendable dataset holds every step along its first axis; the
    // layout's shape is that of one row.
    if (dims.empty() || dims[0] <= static_cast<std::uint64_t>(step)) {
      return failedPrecondition(fmt::format("dataset {} has shape {}, without a row for step {}",
                                            path, dem::formatDims(dims), step));
    }
    dims.erase(dims.begin());
  }
  // The element types the layout uses; any other stays kOther.
  static constexpr std::pair<DataType, dem::ElementType> kLayoutTypes[] = {
      {DataType::kInt32, dem::ElementType::kInt32},
      {DataType::kUInt8, dem::ElementType::kUInt8},
      {DataType::kFloat32, dem::ElementType::kFloat32},
      {DataType::kFloat64, dem::ElementType::kFloat64}};
  dem::DatasetHeader header;
  for (const auto& [stored, element] : kLayoutTypes) {
    if (dataset->dtype == stored) {
      header.type = element;
    }
  }
  header.typeName = dataset->dtypeName;
  header.dims = std::move(dims);
  return dem::checkDatasetHeader(id, row ? fmt::format("{} (step {})", path, step) : path, header,
                                 sizes);
}

}  // namespace crackvis::dataservice
