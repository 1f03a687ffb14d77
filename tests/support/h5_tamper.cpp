#include "support/h5_tamper.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace crackvis::testing {
namespace h5 = dem::h5;
namespace {

h5::Handle openForWrite(const std::string& file) {
  h5::quietHdf5();
  h5::Handle handle = h5::fileHandle(H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
  if (!handle.valid()) {
    throw std::runtime_error("tamper: cannot open " + file + ": " + h5::lastHdf5Error());
  }
  return handle;
}

h5::Handle openObject(const h5::Handle& file, const std::string& object) {
  h5::Handle handle{H5Oopen(file.get(), object.c_str(), H5P_DEFAULT), H5Oclose};
  if (!handle.valid()) {
    throw std::runtime_error("tamper: cannot open object " + object);
  }
  return handle;
}

void check(crackvis::Status status) {
  if (!status) {
    throw std::runtime_error("tamper: " + status.message());
  }
}

}  // namespace

void setStringAttribute(const std::string& file, const std::string& object, const std::string& name,
                        const std::string& value) {
  auto handle = openForWrite(file);
  auto target = openObject(handle, object);
  check(h5::writeStringAttribute(target.get(), name, value));
}

void setIntAttribute(const std::string& file, const std::string& object, const std::string& name,
                     std::int64_t value) {
  auto handle = openForWrite(file);
  auto target = openObject(handle, object);
  check(h5::writeIntAttribute(target.get(), name, value));
}

void deleteLink(const std::string& file, const std::string& path) {
  auto handle = openForWrite(file);
  if (H5Ldelete(handle.get(), path.c_str(), H5P_DEFAULT) < 0) {
    throw std::runtime_error("tamper: cannot delete " + path);
  }
}

void replaceDataset(const std::string& file, const std::string& path, h5::ElementType type,
                    const std::vector<std::uint64_t>& dims) {
  auto handle = openForWrite(file);
  if (h5::linkExists(handle.get(), path) &&
      H5Ldelete(handle.get(), path.c_str(), H5P_DEFAULT) < 0) {
    throw std::runtime_error("tamper: cannot delete " + path);
  }
  std::uint64_t count = 1;
  for (auto d : dims) {
    count *= d;
  }
  std::vector<double> zeros(count + 1, 0.0);  // large enough for any element type
  check(h5::writeDataset(handle.get(), path, type, dims, zeros.data()));
}

void replaceWithSparseDataset(const std::string& file, const std::string& path,
                              h5::ElementType type, const std::vector<std::uint64_t>& dims) {
  auto handle = openForWrite(file);
  if (h5::linkExists(handle.get(), path) &&
      H5Ldelete(handle.get(), path.c_str(), H5P_DEFAULT) < 0) {
    throw std::runtime_error("tamper: cannot delete " + path);
  }
  std::vector<hsize_t> shape(dims.begin(), dims.end());
  std::vector<hsize_t> chunk(shape.size(), 1);
  chunk[0] = std::min<hsize_t>(shape[0], 4096);
  h5::Handle space =
      h5::dataspaceHandle(H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr));
  h5::Handle create = h5::propertyListHandle(H5Pcreate(H5P_DATASET_CREATE));
  if (H5Pset_chunk(create.get(), static_cast<int>(chunk.size()), chunk.data()) < 0) {
    throw std::runtime_error("tamper: cannot set chunks for " + path);
  }
  h5::Handle dataset =
      h5::datasetHandle(H5Dcreate2(handle.get(), path.c_str(), h5::nativeType(type), space.get(),
                                   H5P_DEFAULT, create.get(), H5P_DEFAULT));
  if (!dataset.valid()) {
    throw std::runtime_error("tamper: cannot create " + path);
  }
}

void setElement(const std::string& file, const std::string& path, std::uint64_t index,
                double value) {
  auto handle = openForWrite(file);
  h5::Handle dataset = h5::datasetHandle(H5Dopen2(handle.get(), path.c_str(), H5P_DEFAULT));
  h5::Handle space = h5::dataspaceHandle(H5Dget_space(dataset.get()));
  const hsize_t one[1] = {1};
  // Flat index into a dataset of any rank.
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  std::vector<hsize_t> coord(static_cast<size_t>(rank));
  std::uint64_t rest = index;
  for (int axis = rank - 1; axis >= 0; --axis) {
    coord[static_cast<size_t>(axis)] = rest % dims[static_cast<size_t>(axis)];
    rest /= dims[static_cast<size_t>(axis)];
  }
  H5Sselect_elements(space.get(), H5S_SELECT_SET, 1, coord.data());
  h5::Handle memory = h5::dataspaceHandle(H5Screate_simple(1, one, nullptr));
  if (H5Dwrite(dataset.get(), H5T_NATIVE_DOUBLE, memory.get(), space.get(), H5P_DEFAULT, &value) <
      0) {
    throw std::runtime_error("tamper: cannot write element of " + path);
  }
}

void setInt32Elements(const std::string& file, const std::string& path,
                      const std::vector<std::int32_t>& values, std::uint64_t offset) {
  auto handle = openForWrite(file);
  h5::Handle dataset = h5::datasetHandle(H5Dopen2(handle.get(), path.c_str(), H5P_DEFAULT));
  h5::Handle space = h5::dataspaceHandle(H5Dget_space(dataset.get()));
  // Treat the dataset as flat: select elements offset .. offset + n.
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  std::vector<hsize_t> coords;
  for (std::uint64_t flat = offset; flat < offset + values.size(); ++flat) {
    std::vector<hsize_t> coord(static_cast<size_t>(rank));
    std::uint64_t rest = flat;
    for (int axis = rank - 1; axis >= 0; --axis) {
      coord[static_cast<size_t>(axis)] = rest % dims[static_cast<size_t>(axis)];
      rest /= dims[static_cast<size_t>(axis)];
    }
    coords.insert(coords.end(), coord.begin(), coord.end());
  }
  H5Sselect_elements(space.get(), H5S_SELECT_SET, values.size(), coords.data());
  const hsize_t count[1] = {values.size()};
  h5::Handle memory = h5::dataspaceHandle(H5Screate_simple(1, count, nullptr));
  if (H5Dwrite(dataset.get(), H5T_NATIVE_INT32, memory.get(), space.get(), H5P_DEFAULT,
               values.data()) < 0) {
    throw std::runtime_error("tamper: cannot write elements of " + path);
  }
}

void truncateFile(const std::string& file, double fraction) {
  const auto size = std::filesystem::file_size(file);
  std::filesystem::resize_file(file,
                               static_cast<std::uintmax_t>(static_cast<double>(size) * fraction));
}

}  // namespace crackvis::testing

namespace crackvis::testing {
void deleteAttribute(const std::string& file, const std::string& object, const std::string& name) {
  auto handle = openForWrite(file);
  auto target = openObject(handle, object);
  if (H5Adelete(target.get(), name.c_str()) < 0) {
    throw std::runtime_error("tamper: cannot delete attribute " + name);
  }
}
}  // namespace crackvis::testing

namespace crackvis::testing {

void addSoftLink(const std::string& file, const std::string& link, const std::string& target) {
  auto handle = openForWrite(file);
  if (H5Lcreate_soft(target.c_str(), handle.get(), link.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0) {
    throw std::runtime_error("tamper: cannot create soft link " + link);
  }
}

void addExternalLink(const std::string& file, const std::string& link,
                     const std::string& targetFile, const std::string& targetObject) {
  auto handle = openForWrite(file);
  if (H5Lcreate_external(targetFile.c_str(), targetObject.c_str(), handle.get(), link.c_str(),
                         H5P_DEFAULT, H5P_DEFAULT) < 0) {
    throw std::runtime_error("tamper: cannot create external link " + link);
  }
}

}  // namespace crackvis::testing
