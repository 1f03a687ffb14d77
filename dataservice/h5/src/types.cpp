#include <fmt/format.h>

#include <crackvis/dataservice/types.hpp>

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

const DatasetInfo* FileDescription::findDataset(std::string_view path) const {
  for (const DatasetInfo& dataset : datasets) {
    if (dataset.path == path) {
      return &dataset;
    }
  }
  return nullptr;
}

const GroupInfo* FileDescription::findGroup(std::string_view path) const {
  for (const GroupInfo& group : groups) {
    if (group.path == path) {
      return &group;
    }
  }
  return nullptr;
}

}  // namespace crackvis::dataservice
