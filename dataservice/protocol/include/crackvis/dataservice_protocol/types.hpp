// The vocabulary of the data service, shared by the catalogue (server side)
// and the client library, free of gRPC and HDF5 types: element types, file
// entries, the description of a file's tree, and hyperslabs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::dataservice {

// Element types a dataset or attribute can have; numeric values match the
// DataType enum of proto/crackvis/v1/data.proto. Arrays are little-endian.
enum class DataType : int {
  kUnspecified = 0,  // not readable through Read (compounds, enums, ...)
  kInt8 = 1,
  kUInt8 = 2,
  kInt16 = 3,
  kUInt16 = 4,
  kInt32 = 5,
  kUInt32 = 6,
  kInt64 = 7,
  kUInt64 = 8,
  kFloat32 = 9,
  kFloat64 = 10,
  kString = 11,  // attributes only
};

std::string_view dataTypeName(DataType type);
// Bytes per element; 0 for types Read cannot send.
std::size_t elementSize(DataType type);
DataType dataTypeFromInt(int value);

// The DataType that stores a C++ type.
template <typename T>
constexpr DataType dataTypeOf();
template <>
constexpr DataType dataTypeOf<std::int8_t>() {
  return DataType::kInt8;
}
template <>
constexpr DataType dataTypeOf<std::uint8_t>() {
  return DataType::kUInt8;
}
template <>
constexpr DataType dataTypeOf<std::int16_t>() {
  return DataType::kInt16;
}
template <>
constexpr DataType dataTypeOf<std::uint16_t>() {
  return DataType::kUInt16;
}
template <>
constexpr DataType dataTypeOf<std::int32_t>() {
  return DataType::kInt32;
}
template <>
constexpr DataType dataTypeOf<std::uint32_t>() {
  return DataType::kUInt32;
}
template <>
constexpr DataType dataTypeOf<std::int64_t>() {
  return DataType::kInt64;
}
template <>
constexpr DataType dataTypeOf<std::uint64_t>() {
  return DataType::kUInt64;
}
template <>
constexpr DataType dataTypeOf<float>() {
  return DataType::kFloat32;
}
template <>
constexpr DataType dataTypeOf<double>() {
  return DataType::kFloat64;
}

// One file under the data root, as ListFiles reports it.
struct FileEntry {
  std::string path;  // relative to the data root, '/'-separated
  std::uint64_t sizeBytes = 0;
  std::int64_t modifiedUnixSeconds = 0;
  bool isHdf5 = false;

  friend bool operator==(const FileEntry&, const FileEntry&) = default;
};

// An attribute with its values (numbers widened to int64 or double; at most
// kMaxAttributeValues of them, `truncated` says if there were more).
struct AttributeInfo {
  static constexpr std::size_t kMaxAttributeValues = 64;
  using Value =
      std::variant<std::monostate, std::string, std::vector<std::int64_t>, std::vector<double>>;

  std::string name;
  DataType dtype = DataType::kUnspecified;
  std::vector<std::uint64_t> shape;  // empty for a scalar
  Value value;
  bool truncated = false;

  friend bool operator==(const AttributeInfo&, const AttributeInfo&) = default;
};

struct GroupInfo {
  std::string path;  // "/", "/steps", ...
  std::vector<AttributeInfo> attributes;

  const AttributeInfo* findAttribute(std::string_view name) const;
  // A scalar integer or float attribute's value, if the group has one.
  std::optional<std::int64_t> integerAttribute(std::string_view name) const;
  std::optional<double> floatAttribute(std::string_view name) const;

  friend bool operator==(const GroupInfo&, const GroupInfo&) = default;
};

struct DatasetInfo {
  std::string path;  // "/steps/000000/positions"
  DataType dtype = DataType::kUnspecified;
  std::string dtypeName;  // "float64", or what HDF5 calls a type Read cannot send
  std::vector<std::uint64_t> shape;
  std::vector<std::uint64_t> chunkShape;  // empty when contiguous
  std::vector<AttributeInfo> attributes;

  friend bool operator==(const DatasetInfo&, const DatasetInfo&) = default;
};

struct StepEntry {
  int index = 0;
  double time = 0.0;
  std::string group;  // "/steps/000042"

  friend bool operator==(const StepEntry&, const StepEntry&) = default;
};

// The whole tree of one file, as Describe returns it.
struct FileDescription {
  std::string file;  // as the caller named it, normalized
  std::uint64_t sizeBytes = 0;
  std::vector<GroupInfo> groups;      // depth-first, by name
  std::vector<DatasetInfo> datasets;  // depth-first, by name
  std::string format;                 // root attribute 'format', if any
  int formatVersion = 0;              // root attribute 'version', if any
  std::vector<StepEntry> steps;       // crackvis-dem: the complete steps, in order

  // By path: a binary search once buildIndex() has run on the final lists
  // (a file's first view looked up 400 step datasets one by one, each a
  // scan of 804), a scan otherwise.
  const DatasetInfo* findDataset(std::string_view path) const;
  const GroupInfo* findGroup(std::string_view path) const;
  // Sorts an index of both lists by path; call it after the last change to
  // them (an index of another length is ignored).
  void buildIndex();

  // The described tree only; the index follows from it.
  friend bool operator==(const FileDescription& a, const FileDescription& b) {
    return a.file == b.file && a.sizeBytes == b.sizeBytes && a.groups == b.groups &&
           a.datasets == b.datasets && a.format == b.format && a.formatVersion == b.formatVersion &&
           a.steps == b.steps;
  }

 private:
  std::vector<std::uint32_t> m_datasetsByPath;  // positions in `datasets`, by path
  std::vector<std::uint32_t> m_groupsByPath;
};

// A box [start, start + count) of a dataset. Both empty: the whole dataset.
// Signed on purpose: a negative value from a client is an error to report,
// not a huge unsigned number.
struct Hyperslab {
  std::string dataset;
  std::vector<std::int64_t> start;
  std::vector<std::int64_t> count;

  static Hyperslab whole(std::string dataset) { return {std::move(dataset), {}, {}}; }
};

// The crackvis-dem layout (crackvis/dem_layout/layout.hpp) checked on a Describe's
// answer, by the catalogue's step summary and the remote reader alike: the
// root attributes as the layout check takes them, and one dataset's header
// against the layout table (FAILED_PRECONDITION "missing dataset P" or the
// dtype/shape message).
dem::RootAttributes demRootAttributes(const FileDescription& description);
// Whether the file stores its steps along an extendible axis (a live file,
// crackvis-dem v1.2's appendable layout) rather than a group per step.
bool isAppendable(const FileDescription& description);
// Where step `step` of a per-step dataset lives: "/steps/000042/positions",
// or "/steps/positions" (row 42) in an appendable file.
std::string demStepDatasetPath(const FileDescription& description, dem::DemDataset id, int step);
Status checkDemDataset(const FileDescription& description, dem::DemDataset id, int step,
                       const dem::LayoutSizes& sizes);

// "1.50 MiB": sizes in messages and logs.
std::string formatBytes(std::uint64_t bytes);

// A Read's pieces travel in chunks of at most this many bytes of data.
inline constexpr std::size_t kMaxChunkBytes = std::size_t{1} << 20;

}  // namespace crackvis::dataservice
