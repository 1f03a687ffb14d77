// Read: the plan of a request's hyperslabs, the pieces they are read in,
// and the reads of those pieces.
#include <algorithm>
#include <limits>

#include <fmt/format.h>

#include "catalogue_internal.hpp"
#include "open_files.hpp"
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::dataservice {
namespace h5 = crackvis::dem::h5;

namespace {

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

}  // namespace crackvis::dataservice
