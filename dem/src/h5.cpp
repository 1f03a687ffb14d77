
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
  return text.empty() ? "no detail from HDF5" : text;
}

const char* elementTypeName(ElementType type) {
  switch (type) {
    case ElementType::kInt32:
      return "int32";
    case ElementType::kUInt8:
      return "uint8";
    case ElementType::kFloat32:
      return "float32";
    case ElementType::kFloat64:
      return "float64";
    case ElementType::kOther:
      break;
  }
  return "other";
}

hid_t nativeType(ElementType type) {
  switch (type) {
    case ElementType::kInt32:
      return H5T_NATIVE_INT32;
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

ElementType classify(hid_t datatype) {
  const size_t size = H5Tget_size(datatype);
  switch (H5Tget_class(datatype)) {
    case H5T_INTEGER: {
      const bool isSigned = H5Tget_sign(datatype) == H5T_SGN_2;
      if (size == 4 && isSigned) {
        return ElementType::kInt32;
      }
      if (size == 1 && !isSigned) {
        return ElementType::kUInt8;
      }
      return ElementType::kOther;
    }
    case H5T_FLOAT:
      return size == 8 ? ElementType::kFloat64
                       : (size == 4 ? ElementType::kFloat32 : ElementType::kOther);
    default:
      return ElementType::kOther;
  }
}

namespace {
std::string typeName(hid_t datatype) {
  const ElementType type = classify(datatype);
  if (type != ElementType::kOther) {
    return elementTypeName(type);
  }
  const size_t bits = H5Tget_size(datatype) * 8;
  switch (H5Tget_class(datatype)) {
    case H5T_INTEGER:
      return fmt::format("{}int{}", H5Tget_sign(datatype) == H5T_SGN_2 ? "" : "u", bits);
    case H5T_FLOAT:
      return fmt::format("float{}", bits);
    case H5T_STRING:
      return "string";
    case H5T_COMPOUND:
      return "compound";
    default:
      return "unsupported type";
  }
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

std::string formatDims(const std::vector<std::uint64_t>& dims) {
  return fmt::format("[{}]", fmt::join(dims, ","));
}

bool linkExists(hid_t location, const std::string& path) {
  // H5Lexists fails on a missing intermediate group, so walk the path.
  std::string prefix;
  size_t start = path.front() == '/' ? 1 : 0;
  if (start == 1) {
    prefix = "/";
  }
  while (start <= path.size()) {
    const size_t end = path.find('/', start);
    prefix += path.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (H5Lexists(location, prefix.c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
    if (end == std::string::npos) {
      return true;
    }
    prefix += '/';
    start = end + 1;
  }
  return true;
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
hid_t fileType(ElementType type) {
  // Files are little-endian whatever the writer, so the data service can
  // stream raw bytes in the documented layout.
  switch (type) {
    case ElementType::kInt32:
      return H5T_STD_I32LE;
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

Status writeDataset(hid_t location, const std::string& name, ElementType type,
                    const std::vector<std::uint64_t>& dims, const void* data) {
  std::vector<hsize_t> hdims(dims.begin(), dims.end());
  Handle space =
      dataspaceHandle(H5Screate_simple(static_cast<int>(hdims.size()), hdims.data(), nullptr));
  Handle dataset = datasetHandle(H5Dcreate2(location, name.c_str(), fileType(type), space.get(),
                                            H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
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
  return Status::ok();
}

Status overwriteDataset(hid_t location, const std::string& name, ElementType type,
                        const void* data) {
  Handle dataset = datasetHandle(H5Dopen2(location, name.c_str(), H5P_DEFAULT));
  if (!dataset.valid() ||
      H5Dwrite(dataset.get(), nativeType(type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
    return internalError(fmt::format("cannot write dataset {} ({})", name, lastHdf5Error()));
  }
  return Status::ok();
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

}  // namespace crackvis::dem::h5
