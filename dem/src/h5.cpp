#include <algorithm>
#include <chrono>
#include <cstring>
#include <string_view>
#include <thread>

#include <fmt/format.h>

#include <crackvis/dem/h5.hpp>

namespace crackvis::dem::h5 {
namespace {

herr_t keepInnermost(unsigned position, const H5E_error2_t* entry, void* clientData) {
  auto* text = static_cast<std::string*>(clientData);
  if (position == 0 && entry->desc != nullptr) {
    *text = entry->desc;
  }
  return 0;
}

Result<Handle> openAttribute(hid_t object, const std::string& name) {
  if (H5Aexists(object, name.c_str()) <= 0) {
    lastHdf5Error();
    return notFound(fmt::format("missing attribute '{}'", name));
  }
  Handle attribute = attributeHandle(H5Aopen(object, name.c_str(), H5P_DEFAULT));
  if (!attribute.valid()) {
    return failedPrecondition(
        fmt::format("cannot open attribute '{}' ({})", name, lastHdf5Error()));
  }
  return attribute;
}

Status writeScalarAttribute(hid_t object, const std::string& name, hid_t type, const void* value) {
  if (H5Aexists(object, name.c_str()) > 0) {
    H5Adelete(object, name.c_str());
  }
  Handle space = dataspaceHandle(H5Screate(H5S_SCALAR));
  Handle attribute = attributeHandle(
      H5Acreate2(object, name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (!attribute.valid() || H5Awrite(attribute.get(), type, value) < 0) {
    return internalError(fmt::format("cannot write attribute '{}' ({})", name, lastHdf5Error()));
  }
  return Status::ok();
}

Result<Handle> scalarAttribute(hid_t object, const std::string& name, H5T_class_t expected,
                               const char* expectedName) {
  auto attribute = openAttribute(object, name);
  if (!attribute) {
    return attribute.status();
  }
  Handle type = datatypeHandle(H5Aget_type(attribute->get()));
  Handle space = dataspaceHandle(H5Aget_space(attribute->get()));
  if (H5Tget_class(type.get()) != expected || H5Sget_simple_extent_npoints(space.get()) != 1) {
    return invalidArgument(fmt::format("attribute '{}' is not a scalar {}", name, expectedName));
  }
  return attribute;
}

}  // namespace

void quietHdf5() {
  // libhdf5's own clean-up at exit closes what is still open, and faults
  // (SIGSEGV in H5F__close_cb) on a file whose close failed on a full disk:
  // the writer had reported the error, then the process died of a signal.
  // Every file crackvis opens is closed by its owner, so the clean-up is
  // not needed. Only takes effect before the library's first call.
  static const bool noExitCleanUp = [] {
    (void)H5dont_atexit();
    return true;
  }();
  (void)noExitCleanUp;
  // Debian's HDF5 is built thread-safe, and then its error printing is set
  // per thread: every thread that touches HDF5 silences its own.
  thread_local bool quiet = false;
  if (!quiet) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    quiet = true;
  }
}

std::string lastHdf5Error() {
  std::string text;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, keepInnermost, &text);
  H5Eclear2(H5E_DEFAULT);
  if (text.empty()) {
    return "no detail from HDF5";
  }
  // A failed system call comes with a paragraph of buffers and offsets
  // (over two lines); the system's message is what a user can act on.
  constexpr std::string_view kSystem = "error message = '";
  if (const size_t at = text.find(kSystem); at != std::string::npos) {
    const size_t end = text.find('\'', at + kSystem.size());
    if (end != std::string::npos) {
      return text.substr(at + kSystem.size(), end - at - kSystem.size());
    }
  }
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

hid_t nativeType(ElementType type) {
  switch (type) {
    case ElementType::kInt32:
      return H5T_NATIVE_INT32;
    case ElementType::kInt64:
      return H5T_NATIVE_INT64;
    case ElementType::kUInt8:
      return H5T_NATIVE_UINT8;
    case ElementType::kFloat32:
      return H5T_NATIVE_FLOAT;
    case ElementType::kFloat64:
      return H5T_NATIVE_DOUBLE;
    case ElementType::kOther:
      break;
  }
  return H5I_INVALID_HID;
}

TypeClass typeClass(hid_t datatype) {
  TypeClass type;
  type.bytes = H5Tget_size(datatype);
  switch (H5Tget_class(datatype)) {
    case H5T_INTEGER:
      type.kind = H5Tget_sign(datatype) == H5T_SGN_2 ? TypeClass::kSignedInteger
                                                     : TypeClass::kUnsignedInteger;
      break;
    case H5T_FLOAT:
      type.kind = TypeClass::kFloat;
      break;
    case H5T_STRING:
      type.kind = TypeClass::kString;
      break;
    case H5T_COMPOUND:
      type.kind = TypeClass::kCompound;
      break;
    default:
      break;
  }
  return type;
}

ElementType classify(hid_t datatype) {
  const TypeClass type = typeClass(datatype);
  switch (type.kind) {
    case TypeClass::kSignedInteger:
      return type.bytes == 4   ? ElementType::kInt32
             : type.bytes == 8 ? ElementType::kInt64
                               : ElementType::kOther;
    case TypeClass::kUnsignedInteger:
      return type.bytes == 1 ? ElementType::kUInt8 : ElementType::kOther;
    case TypeClass::kFloat:
      return type.bytes == 8 ? ElementType::kFloat64
                             : (type.bytes == 4 ? ElementType::kFloat32 : ElementType::kOther);
    default:
      return ElementType::kOther;
  }
}

namespace {
std::string typeName(hid_t datatype) {
  const ElementType element = classify(datatype);
  if (element != ElementType::kOther) {
    return elementTypeName(element);
  }
  const TypeClass type = typeClass(datatype);
  const size_t bits = type.bytes * 8;
  switch (type.kind) {
    case TypeClass::kSignedInteger:
      return fmt::format("int{}", bits);
    case TypeClass::kUnsignedInteger:
      return fmt::format("uint{}", bits);
    case TypeClass::kFloat:
      return fmt::format("float{}", bits);
    case TypeClass::kString:
      return "string";
    case TypeClass::kCompound:
      return "compound";
    case TypeClass::kOther:
      break;
  }
  return "unsupported type";
}
}  // namespace

Result<DatasetShape> describeDataset(hid_t dataset) {
  DatasetShape shape;
  Handle type = datatypeHandle(H5Dget_type(dataset));
  Handle space = dataspaceHandle(H5Dget_space(dataset));
  Handle plist = propertyListHandle(H5Dget_create_plist(dataset));
  if (!type.valid() || !space.valid() || !plist.valid()) {
    return failedPrecondition(fmt::format("unreadable dataset header ({})", lastHdf5Error()));
  }
  shape.type = classify(type.get());
  shape.typeName = typeName(type.get());
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) {
    return failedPrecondition(fmt::format("unreadable dataspace ({})", lastHdf5Error()));
  }
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  shape.dims.assign(dims.begin(), dims.end());
  if (H5Pget_layout(plist.get()) == H5D_CHUNKED) {
    std::vector<hsize_t> chunk(static_cast<size_t>(rank));
    H5Pget_chunk(plist.get(), rank, chunk.data());
    shape.chunkDims.assign(chunk.begin(), chunk.end());
  }
  return shape;
}

std::uint64_t storedBytes(hid_t dataset) {
  return H5Dget_storage_size(dataset);
}

namespace {

// The parts of a path inside a file; "." and empty parts name the group
// they are in.
std::vector<std::string> pathParts(const std::string& path) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find('/', start);
    if (end == std::string::npos) {
      end = path.size();
    }
    std::string part = path.substr(start, end - start);
    if (!part.empty() && part != ".") {
      parts.push_back(std::move(part));
    }
    start = end + 1;
  }
  return parts;
}

// Resolves `path` (absolute, or relative to the hard-link path `base`) to a
// path of hard links only; `hops` counts the soft links followed so far.
Result<std::string> resolveFrom(hid_t file, const std::string& base, const std::string& path,
                                int& hops) {
  std::string resolved = !path.empty() && path.front() == '/' ? "" : base;
  for (const std::string& part : pathParts(path)) {
    const std::string link = resolved + "/" + part;
    if (H5Lexists(file, link.c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return notFound(fmt::format("{} does not exist", link));
    }
    H5L_info_t info{};
    if (H5Lget_info(file, link.c_str(), &info, H5P_DEFAULT) < 0) {
      return failedPrecondition(fmt::format("cannot inspect {} ({})", link, lastHdf5Error()));
    }
    if (info.type == H5L_TYPE_HARD) {
      resolved = link;
      continue;
    }
    if (info.type != H5L_TYPE_SOFT) {
      return Status(StatusCode::kPermissionDenied,
                    fmt::format("{} is {} link", link,
                                info.type == H5L_TYPE_EXTERNAL ? "an external" : "a user-defined"));
    }
    if (++hops > kMaxLinkHops) {
      return failedPrecondition(
          fmt::format("{}: more than {} soft links in a row (a loop?)", link, kMaxLinkHops));
    }
    std::string target(info.u.val_size, '\0');
    if (H5Lget_val(file, link.c_str(), target.data(), target.size(), H5P_DEFAULT) < 0) {
      return failedPrecondition(
          fmt::format("cannot read soft link {} ({})", link, lastHdf5Error()));
    }
    target.resize(target.find('\0') == std::string::npos ? target.size() : target.find('\0'));
    auto followed = resolveFrom(file, resolved, target, hops);
    if (!followed) {
      return Status(followed.status().code(), fmt::format("{} is a soft link to {}: {}", link,
                                                          target, followed.status().message()));
    }
    resolved = std::move(*followed);
  }
  return resolved.empty() ? std::string("/") : resolved;
}

herr_t refuseExternalLink(const char*, const char*, const char*, const char*, unsigned*, hid_t,
                          void*) {
  return -1;
}

}  // namespace

Result<std::string> resolveInFile(hid_t file, const std::string& path) {
  int hops = 0;
  return resolveFrom(file, "", path, hops);
}

bool linkExists(hid_t file, const std::string& path) {
  return resolveInFile(file, path).isOk();
}

Handle noExternalLinks() {
  Handle access = propertyListHandle(H5Pcreate(H5P_DATASET_ACCESS));
  if (access.valid()) {
    H5Pset_elink_cb(access.get(), refuseExternalLink, nullptr);
  }
  return access;
}

Result<std::string> readStringAttribute(hid_t object, const std::string& name) {
  auto attribute = scalarAttribute(object, name, H5T_STRING, "string");
  if (!attribute) {
    return attribute.status();
  }
  Handle stored = datatypeHandle(H5Aget_type(attribute->get()));
  if (H5Tis_variable_str(stored.get()) > 0) {
    Handle memType = datatypeHandle(H5Tcopy(H5T_C_S1));
    H5Tset_size(memType.get(), H5T_VARIABLE);
    char* text = nullptr;
    if (H5Aread(attribute->get(), memType.get(), &text) < 0) {
      return failedPrecondition(
          fmt::format("cannot read attribute '{}' ({})", name, lastHdf5Error()));
    }
    std::string value = text != nullptr ? text : "";
    H5free_memory(text);
    return value;
  }
  const size_t size = H5Tget_size(stored.get());
  std::string buffer(size, '\0');
  if (H5Aread(attribute->get(), stored.get(), buffer.data()) < 0) {
    return failedPrecondition(
        fmt::format("cannot read attribute '{}' ({})", name, lastHdf5Error()));
  }
  buffer.resize(buffer.find('\0') == std::string::npos ? size : buffer.find('\0'));
  return buffer;
}

Result<std::int64_t> readIntAttribute(hid_t object, const std::string& name) {
  auto attribute = scalarAttribute(object, name, H5T_INTEGER, "integer");
  if (!attribute) {
    return attribute.status();
  }
  std::int64_t value = 0;
  if (H5Aread(attribute->get(), H5T_NATIVE_INT64, &value) < 0) {
    return failedPrecondition(
        fmt::format("cannot read attribute '{}' ({})", name, lastHdf5Error()));
  }
  return value;
}

Result<double> readDoubleAttribute(hid_t object, const std::string& name) {
  auto attribute = scalarAttribute(object, name, H5T_FLOAT, "float");
  if (!attribute) {
    return attribute.status();
  }
  double value = 0;
  if (H5Aread(attribute->get(), H5T_NATIVE_DOUBLE, &value) < 0) {
    return failedPrecondition(
        fmt::format("cannot read attribute '{}' ({})", name, lastHdf5Error()));
  }
  return value;
}

Status writeStringAttribute(hid_t object, const std::string& name, const std::string& value) {
  // Fixed-length, NUL-terminated ASCII: the most portable string for h5py,
  // h5dump and MATLAB alike.
  Handle type = datatypeHandle(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), value.size() + 1);
  H5Tset_strpad(type.get(), H5T_STR_NULLTERM);
  return writeScalarAttribute(object, name, type.get(), value.c_str());
}

Status writeIntAttribute(hid_t object, const std::string& name, std::int64_t value) {
  const auto narrow = static_cast<std::int32_t>(value);
  if (narrow == value) {
    return writeScalarAttribute(object, name, H5T_STD_I32LE, &narrow);
  }
  return writeScalarAttribute(object, name, H5T_STD_I64LE, &value);
}

Status writeDoubleAttribute(hid_t object, const std::string& name, double value) {
  return writeScalarAttribute(object, name, H5T_IEEE_F64LE, &value);
}

namespace {
// A small write waits in the dataset's sieve buffer and reaches the file
// when the dataset is closed: the close is where a full disk shows.
Status closeWritten(Handle& dataset, const std::string& name) {
  if (dataset.reset() < 0) {
    return internalError(fmt::format("cannot write dataset {} ({})", name, lastHdf5Error()));
  }
  return Status::ok();
}

hid_t fileType(ElementType type) {
  // Files are little-endian whatever the writer, so the data service can
  // stream raw bytes in the documented layout.
  switch (type) {
    case ElementType::kInt32:
      return H5T_STD_I32LE;
    case ElementType::kInt64:
      return H5T_STD_I64LE;
    case ElementType::kUInt8:
      return H5T_STD_U8LE;
    case ElementType::kFloat32:
      return H5T_IEEE_F32LE;
    case ElementType::kFloat64:
      return H5T_IEEE_F64LE;
    case ElementType::kOther:
      break;
  }
  return H5I_INVALID_HID;
}

}  // namespace

hsize_t balancedChunkRows(std::uint64_t rows, std::uint64_t rowValues, std::uint64_t chunkValues) {
  if (rows == 0) {
    return 1;
  }
  const std::uint64_t most =
      std::max<std::uint64_t>(1, chunkValues / std::max<std::uint64_t>(1, rowValues));
  const std::uint64_t chunks = (rows + most - 1) / most;
  return (rows + chunks - 1) / chunks;
}

namespace {

// The dataset creation properties of `storage`: contiguous by default, or
// chunked along the first axis with shuffle + deflate.
Result<Handle> creationProperties(const std::vector<hsize_t>& dims, const Storage& storage) {
  Handle properties = propertyListHandle(H5Pcreate(H5P_DATASET_CREATE));
  std::uint64_t count = 1;
  for (auto d : dims) {
    count *= d;
  }
  if (!storage.compressed() || count == 0) {
    return properties;
  }
  std::vector<hsize_t> chunk(dims);
  std::uint64_t rowValues = 1;
  for (size_t i = 1; i < dims.size(); ++i) {
    rowValues *= dims[i];
  }
  chunk[0] = balancedChunkRows(dims[0], rowValues, storage.chunkValues);
  if (H5Pset_chunk(properties.get(), static_cast<int>(chunk.size()), chunk.data()) < 0 ||
      H5Pset_shuffle(properties.get()) < 0 ||
      H5Pset_deflate(properties.get(), static_cast<unsigned>(storage.deflateLevel)) < 0) {
    return internalError(fmt::format("cannot set up compression ({})", lastHdf5Error()));
  }
  return properties;
}
}  // namespace

Status writeDataset(hid_t location, const std::string& name, ElementType type,
                    const std::vector<std::uint64_t>& dims, const void* data,
                    const Storage& storage) {
  std::vector<hsize_t> hdims(dims.begin(), dims.end());
  Handle space =
      dataspaceHandle(H5Screate_simple(static_cast<int>(hdims.size()), hdims.data(), nullptr));
  auto properties = creationProperties(hdims, storage);
  if (!properties) {
    return properties.status();
  }
  Handle dataset = datasetHandle(H5Dcreate2(location, name.c_str(), fileType(type), space.get(),
                                            H5P_DEFAULT, properties->get(), H5P_DEFAULT));
  if (!dataset.valid()) {
    return internalError(fmt::format("cannot create dataset {} ({})", name, lastHdf5Error()));
  }
  std::uint64_t count = 1;
  for (auto d : dims) {
    count *= d;
  }
  if (count > 0 &&
      H5Dwrite(dataset.get(), nativeType(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    return internalError(fmt::format("cannot write dataset {} ({})", name, lastHdf5Error()));
  }
  return closeWritten(dataset, name);
}

Status overwriteDataset(hid_t location, const std::string& name, ElementType type,
                        const void* data) {
  Handle dataset = datasetHandle(H5Dopen2(location, name.c_str(), H5P_DEFAULT));
  if (!dataset.valid() ||
      H5Dwrite(dataset.get(), nativeType(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    return internalError(fmt::format("cannot write dataset {} ({})", name, lastHdf5Error()));
  }
  return closeWritten(dataset, name);
}

Status readDataset(hid_t dataset, ElementType type, void* out) {
  Handle space = dataspaceHandle(H5Dget_space(dataset));
  if (H5Sget_simple_extent_npoints(space.get()) == 0) {
    return Status::ok();
  }
  if (H5Dread(dataset, nativeType(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) {
    return failedPrecondition(
        fmt::format("read failed, the file may be truncated or corrupt ({})", lastHdf5Error()));
  }
  return Status::ok();
}

namespace {

// The selection of row `row` of a dataset whose first axis counts steps,
// and a memory space of the row's shape.
struct RowSelection {
  Handle file;
  Handle memory;
};
Result<RowSelection> selectRow(hid_t dataset, std::uint64_t row) {
  Handle space = dataspaceHandle(H5Dget_space(dataset));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 1) {
    return failedPrecondition("has no step axis");
  }
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  if (row >= dims[0]) {
    return outOfRange(fmt::format("has {} rows, row {} asked for", dims[0], row));
  }
  std::vector<hsize_t> start(dims.size(), 0);
  std::vector<hsize_t> count(dims);
  start[0] = row;
  count[0] = 1;
  if (H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                          nullptr) < 0) {
    return internalError(fmt::format("cannot select row {} ({})", row, lastHdf5Error()));
  }
  Handle memory =
      dataspaceHandle(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr));
  return RowSelection{std::move(space), std::move(memory)};
}

}  // namespace

Result<Handle> createStepAxisDataset(hid_t location, const std::string& name, ElementType type,
                                     const std::vector<std::uint64_t>& rowDims,
                                     const Storage& storage) {
  constexpr hsize_t kScalarStepsPerChunk = 256;
  std::vector<hsize_t> dims{0};
  std::vector<hsize_t> maxDims{H5S_UNLIMITED};
  std::vector<hsize_t> chunk{rowDims.empty() ? kScalarStepsPerChunk : 1};
  std::uint64_t rowValues = 1;
  for (size_t i = 1; i < rowDims.size(); ++i) {
    rowValues *= std::max<std::uint64_t>(1, rowDims[i]);
  }
  for (size_t i = 0; i < rowDims.size(); ++i) {
    dims.push_back(rowDims[i]);
    // HDF5 wants every chunk extent at least 1 and within a fixed axis; an
    // empty axis (a lattice without bonds) is left unlimited instead.
    maxDims.push_back(rowDims[i] == 0 ? H5S_UNLIMITED : rowDims[i]);
    const std::uint64_t along =
        i == 0 ? balancedChunkRows(rowDims[i], rowValues, storage.chunkValues) : rowDims[i];
    chunk.push_back(std::max<hsize_t>(1, along));
  }
  Handle space =
      dataspaceHandle(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxDims.data()));
  Handle properties = propertyListHandle(H5Pcreate(H5P_DATASET_CREATE));
  if (H5Pset_chunk(properties.get(), static_cast<int>(chunk.size()), chunk.data()) < 0 ||
      (storage.compressed() &&
       (H5Pset_shuffle(properties.get()) < 0 ||
        H5Pset_deflate(properties.get(), static_cast<unsigned>(storage.deflateLevel)) < 0))) {
    return internalError(fmt::format("cannot set up the chunks of {} ({})", name, lastHdf5Error()));
  }
  Handle dataset = datasetHandle(H5Dcreate2(location, name.c_str(), fileType(type), space.get(),
                                            H5P_DEFAULT, properties.get(), H5P_DEFAULT));
  if (!dataset.valid()) {
    return internalError(fmt::format("cannot create dataset {} ({})", name, lastHdf5Error()));
  }
  return dataset;
}

Status appendRow(hid_t dataset, ElementType type, std::uint64_t row, const void* data) {
  Handle space = dataspaceHandle(H5Dget_space(dataset));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<size_t>(std::max(rank, 1)));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  dims[0] = std::max<hsize_t>(dims[0], row + 1);
  if (H5Dset_extent(dataset, dims.data()) < 0) {
    return internalError(fmt::format("cannot grow to {} rows ({})", row + 1, lastHdf5Error()));
  }
  auto selection = selectRow(dataset, row);
  if (!selection) {
    return selection.status();
  }
  if (H5Sget_select_npoints(selection->file.get()) > 0 &&
      H5Dwrite(dataset, nativeType(type), selection->memory.get(), selection->file.get(),
               H5P_DEFAULT, data) < 0) {
    return internalError(fmt::format("cannot write row {} ({})", row, lastHdf5Error()));
  }
  if (H5Dflush(dataset) < 0) {
    return internalError(fmt::format("cannot flush row {} ({})", row, lastHdf5Error()));
  }
  return Status::ok();
}

Status readRow(hid_t dataset, ElementType type, std::uint64_t row, void* out) {
  auto selection = selectRow(dataset, row);
  if (!selection) {
    return selection.status();
  }
  if (H5Sget_select_npoints(selection->file.get()) == 0) {
    return Status::ok();
  }
  if (H5Dread(dataset, nativeType(type), selection->memory.get(), selection->file.get(),
              H5P_DEFAULT, out) < 0) {
    return failedPrecondition(
        fmt::format("read failed, the file may be truncated or corrupt ({})", lastHdf5Error()));
  }
  return Status::ok();
}

namespace {

// A run of rows read with one hyperslab: [first, last].
struct RowSpan {
  std::int64_t first = 0;
  std::int64_t last = 0;
};

// The spans readRowsAt reads: rows at most kGapBytes apart share one, and
// none holds more than kSpanBytes (one row at the least).
std::vector<RowSpan> rowSpans(std::span<const std::int32_t> rows, std::uint64_t rowBytes) {
  constexpr std::uint64_t kGapBytes = 64u << 10;
  constexpr std::uint64_t kSpanBytes = 4u << 20;
  const auto gapRows = static_cast<std::int64_t>(std::max<std::uint64_t>(1, kGapBytes / rowBytes));
  const auto spanRows =
      static_cast<std::int64_t>(std::max<std::uint64_t>(1, kSpanBytes / rowBytes));
  std::vector<RowSpan> spans;
  for (std::int32_t row : rows) {
    if (!spans.empty() && row - spans.back().last <= gapRows &&
        row - spans.back().first < spanRows) {
      spans.back().last = row;
    } else {
      spans.push_back({row, row});
    }
  }
  return spans;
}

}  // namespace

Status readRowsAt(hid_t dataset, ElementType type, std::int64_t stepRow,
                  std::span<const std::int32_t> rows, void* out) {
  if (rows.empty()) {
    return Status::ok();
  }
  Handle space = dataspaceHandle(H5Dget_space(dataset));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  const std::size_t axis = stepRow >= 0 ? 1 : 0;
  if (rank < static_cast<int>(axis) + 1) {
    return failedPrecondition(fmt::format("has {} axes, too few for rows", rank));
  }
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  if (stepRow >= 0 && static_cast<hsize_t>(stepRow) >= dims[0]) {
    return outOfRange(fmt::format("has {} rows, row {} asked for", dims[0], stepRow));
  }
  const bool ascending = std::is_sorted(rows.begin(), rows.end()) &&
                         std::adjacent_find(rows.begin(), rows.end()) == rows.end();
  if (!ascending || rows.front() < 0 || static_cast<hsize_t>(rows.back()) >= dims[axis]) {
    return outOfRange(fmt::format("rows {}..{} asked of {} (ascending, each once)", rows.front(),
                                  rows.back(), dims[axis]));
  }
  const hid_t memoryType = nativeType(type);
  std::uint64_t rowValues = 1;
  for (std::size_t d = axis + 1; d < dims.size(); ++d) {
    rowValues *= dims[d];
  }
  const std::uint64_t rowBytes = std::max<std::uint64_t>(1, rowValues * H5Tget_size(memoryType));
  std::vector<unsigned char> buffer;
  auto* target = static_cast<unsigned char*>(out);
  std::size_t next = 0;  // the next row of `rows` to copy out
  for (const RowSpan& span : rowSpans(rows, rowBytes)) {
    const auto length = static_cast<hsize_t>(span.last - span.first + 1);
    std::vector<hsize_t> start(dims.size(), 0);
    std::vector<hsize_t> count(dims);
    if (stepRow >= 0) {
      start[0] = static_cast<hsize_t>(stepRow);
      count[0] = 1;
    }
    start[axis] = static_cast<hsize_t>(span.first);
    count[axis] = length;
    const hsize_t values = length * rowValues;
    // The rows are ascending and each once, so a span holding `length` of
    // them holds every row of it: read straight into place. Otherwise read
    // the span and copy out the rows asked for. (A slab of a z-indexed file
    // is one run: copying it row by row made a rank's read of half the rows
    // slower than one process's read of all of them.)
    const std::size_t end = static_cast<std::size_t>(
        std::upper_bound(rows.begin() + static_cast<std::ptrdiff_t>(next), rows.end(),
                         static_cast<std::int32_t>(span.last)) -
        rows.begin());
    const bool whole = end - next == length;
    unsigned char* into = target + next * rowBytes;
    if (!whole) {
      buffer.resize(static_cast<std::size_t>(length * rowBytes));
      into = buffer.data();
    }
    Handle memory = dataspaceHandle(H5Screate_simple(1, &values, nullptr));
    if (H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                            nullptr) < 0 ||
        H5Dread(dataset, memoryType, memory.get(), space.get(), H5P_DEFAULT, into) < 0) {
      return failedPrecondition(
          fmt::format("read of rows {}..{} failed, the file may be truncated or corrupt ({})",
                      span.first, span.last, lastHdf5Error()));
    }
    for (; !whole && next < end; ++next) {
      std::memcpy(target + next * rowBytes,
                  buffer.data() + static_cast<std::size_t>(rows[next] - span.first) * rowBytes,
                  rowBytes);
    }
    next = end;
  }
  return Status::ok();
}

Status readLeading(hid_t dataset, ElementType type, std::uint64_t count, void* out) {
  if (count == 0) {
    return Status::ok();
  }
  Handle space = dataspaceHandle(H5Dget_space(dataset));
  const hsize_t start = 0;
  const hsize_t wanted = count;
  Handle memory = dataspaceHandle(H5Screate_simple(1, &wanted, nullptr));
  if (H5Sget_simple_extent_ndims(space.get()) != 1 ||
      H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, &start, nullptr, &wanted, nullptr) < 0 ||
      H5Dread(dataset, nativeType(type), memory.get(), space.get(), H5P_DEFAULT, out) < 0) {
    return failedPrecondition(
        fmt::format("read failed, the file may be truncated or corrupt ({})", lastHdf5Error()));
  }
  return Status::ok();
}

namespace {

// The plain open's refusal when another process has the file open for
// write: the superblock's write flag, or the writer's flock (EAGAIN, whose
// system message lastHdf5Error() keeps).
bool heldByWriter(const std::string& refusal) {
  return refusal.find("open for write") != std::string::npos ||
         refusal.find("temporarily unavailable") != std::string::npos;
}

// How openReadOnly's reason begins where a writer holds the file.
constexpr std::string_view kHeldByWriter = "another process is writing it";

}  // namespace

Handle openReadOnly(const std::string& path, hid_t access) {
  Handle file = fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, access));
  if (file.valid()) {
    return file;
  }
  const std::string refusal = lastHdf5Error();
  // A live writer's file opens for SWMR reading. libhdf5 retries a metadata
  // read whose checksum fails (a block the writer is rewriting) without
  // pausing, so a writer descheduled mid-write on a loaded machine can
  // outlast its retries: a few more tries, spaced, ride that out.
  // Without a writer the file itself is the problem: one try.
  const bool writer = heldByWriter(refusal);
  const int tries = writer ? 4 : 1;
  std::string swmrRefusal;
  for (int attempt = 0; attempt < tries; ++attempt) {
    if (attempt > 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10 * attempt));
    }
    file = fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, access));
    if (file.valid()) {
      return file;
    }
    swmrRefusal = lastHdf5Error();
  }
  // The plain open's reason is the one to give (a truncated file...); where
  // a writer holds the file, the SWMR open's too. Put back on the stack for
  // openRefusal().
  const std::string reason =
      writer ? fmt::format("{}, not as a live file (opened: {}; as a live file: {})", kHeldByWriter,
                           refusal, swmrRefusal)
             : refusal;
  H5Epush2(H5E_DEFAULT, __FILE__, __func__, __LINE__, H5E_ERR_CLS, H5E_FILE, H5E_CANTOPENFILE, "%s",
           reason.c_str());
  return file;
}

std::string openRefusal() {
  const std::string reason = lastHdf5Error();
  if (reason.starts_with(kHeldByWriter)) {
    return reason;
  }
  return fmt::format("file is truncated or corrupt ({})", reason);
}

Status refreshDataset(hid_t dataset) {
  if (H5Drefresh(dataset) < 0) {
    return failedPrecondition(
        fmt::format("cannot reload the dataset's metadata ({})", lastHdf5Error()));
  }
  return Status::ok();
}

namespace {
herr_t collectAttributeName(hid_t, const char* name, const H5A_info_t*, void* data) {
  static_cast<std::vector<std::string>*>(data)->emplace_back(name);
  return 0;
}
herr_t collectMemberName(hid_t, const char* name, const H5L_info_t*, void* data) {
  static_cast<std::vector<std::string>*>(data)->emplace_back(name);
  return 0;
}
}  // namespace

Result<std::vector<std::string>> attributeNames(hid_t object) {
  std::vector<std::string> names;
  hsize_t index = 0;
  if (H5Aiterate2(object, H5_INDEX_NAME, H5_ITER_INC, &index, collectAttributeName, &names) < 0) {
    return failedPrecondition(
        fmt::format("cannot list attributes: file is truncated or corrupt ({})", lastHdf5Error()));
  }
  return names;
}

Result<std::vector<std::string>> memberNames(hid_t group) {
  std::vector<std::string> names;
  if (H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, nullptr, collectMemberName, &names) < 0) {
    return failedPrecondition(
        fmt::format("cannot list a group: file is truncated or corrupt ({})", lastHdf5Error()));
  }
  return names;
}

}  // namespace crackvis::dem::h5
