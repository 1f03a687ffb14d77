// Thin RAII and error helpers over the HDF5 C API, shared by the DEM file
// reader and writer and by the data service's catalogue.
//
// HDF5 reports errors by printing its error stack to stderr; crackvis never
// lets that reach a user. quietHdf5() turns the printing off once per process,
// and lastHdf5Error() turns the innermost entry of the stack into a short text
// that a Status message can carry ("truncated file: eof = 1024, ...").
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <hdf5.h>

#include <crackvis/common/status.hpp>
#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::dem::h5 {

// Disables HDF5's automatic error printing for the calling thread (cheap to
// call again; thread-safe HDF5 keeps one setting per thread).
void quietHdf5();

// The innermost message on HDF5's error stack (then clears the stack); empty
// when the stack is empty.
std::string lastHdf5Error();

// A move-only owner of one hid_t, closed with the matching H5*close.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);

  Handle() = default;
  Handle(hid_t id, Closer closer) : m_id(id), m_closer(closer) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& other) noexcept
      : m_id(std::exchange(other.m_id, H5I_INVALID_HID)), m_closer(other.m_closer) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      m_id = std::exchange(other.m_id, H5I_INVALID_HID);
      m_closer = other.m_closer;
    }
    return *this;
  }
  ~Handle() { reset(); }

  hid_t get() const { return m_id; }
  bool valid() const { return m_id >= 0; }
  // Gives the id up without closing it.
  hid_t release() { return std::exchange(m_id, H5I_INVALID_HID); }
  // Closes now and reports whether HDF5 could (a file close writes metadata).
  herr_t reset() {
    herr_t result = 0;
    if (m_id >= 0 && m_closer != nullptr) {
      // Never printed: in a host process (ParaView) a handle can outlive
      // HDF5's own exit handler, and its close printed HDF5-DIAG noise at
      // exit. The error stack still holds the reason for the caller.
      H5E_BEGIN_TRY {
        result = m_closer(m_id);
      }
      H5E_END_TRY;
    }
    m_id = H5I_INVALID_HID;
    return result;
  }

 private:
  hid_t m_id = H5I_INVALID_HID;
  Closer m_closer = nullptr;
};

inline Handle fileHandle(hid_t id) {
  return {id, H5Fclose};
}
inline Handle groupHandle(hid_t id) {
  return {id, H5Gclose};
}
inline Handle datasetHandle(hid_t id) {
  return {id, H5Dclose};
}
inline Handle dataspaceHandle(hid_t id) {
  return {id, H5Sclose};
}
inline Handle datatypeHandle(hid_t id) {
  return {id, H5Tclose};
}
inline Handle attributeHandle(hid_t id) {
  return {id, H5Aclose};
}
inline Handle propertyListHandle(hid_t id) {
  return {id, H5Pclose};
}

// The element types crackvis files use (dem/element_type.hpp), here beside
// their HDF5 types.
using dem::ElementType;
using dem::elementTypeName;
using dem::formatDims;
// Native in-memory HDF5 type for reads and writes.
hid_t nativeType(ElementType type);

// What a stored datatype holds, whatever its byte order: the one place that
// looks at HDF5's type classes (the crackvis-dem types below and the data
// service's wider set are both made from it).
struct TypeClass {
  enum Kind { kSignedInteger, kUnsignedInteger, kFloat, kString, kCompound, kOther };
  Kind kind = kOther;
  std::size_t bytes = 0;
};
TypeClass typeClass(hid_t datatype);
// Classifies a stored datatype (any byte order).
ElementType classify(hid_t datatype);

// What a dataset is: its element type and shape (and chunking, if chunked).
struct DatasetShape {
  ElementType type = ElementType::kOther;
  std::string typeName;  // "int32", "float64", or HDF5's class for others
  std::vector<std::uint64_t> dims;
  std::vector<std::uint64_t> chunkDims;  // empty when contiguous
};
Result<DatasetShape> describeDataset(hid_t dataset);
// Bytes the file holds for `dataset`'s values (after its filters): 0 when
// nothing was written, less than the logical size when compressed or when
// chunks were never written (those read as the fill value).
std::uint64_t storedBytes(hid_t dataset);

// The path of the object `path` names in `file`, through hard links only:
// soft links on the way are followed inside the file (their targets checked
// in turn, at most kMaxLinkHops of them). NOT_FOUND when a link on the way
// is missing or dangles; PERMISSION_DENIED when an external or user-defined
// link lies anywhere on the chain (soft -> external included), since it
// would lead out of the file; FAILED_PRECONDITION for a soft-link loop.
// Open the object by the returned path, never by `path`.
inline constexpr int kMaxLinkHops = 16;
Result<std::string> resolveInFile(hid_t file, const std::string& path);
// Whether `path` names an object of the file by links that stay inside it.
bool linkExists(hid_t file, const std::string& path);
// A dataset access property list under which HDF5 refuses to traverse any
// external link (a second guard behind resolveInFile).
Handle noExternalLinks();

// Attribute access; strings may be fixed-length or variable-length.
Result<std::string> readStringAttribute(hid_t object, const std::string& name);
Result<std::int64_t> readIntAttribute(hid_t object, const std::string& name);
Result<double> readDoubleAttribute(hid_t object, const std::string& name);
Status writeStringAttribute(hid_t object, const std::string& name, const std::string& value);
Status writeIntAttribute(hid_t object, const std::string& name, std::int64_t value);
Status writeDoubleAttribute(hid_t object, const std::string& name, double value);

// How a written dataset is stored: contiguous (the default, what partial
// reads of uncompressed files rely on), or chunked along its first axis with
// HDF5's shuffle and deflate filters (both built into every libhdf5).
struct Storage {
  int deflateLevel = 0;                  // 0: contiguous; 1..9: chunked + shuffle + deflate
  std::uint64_t chunkValues = 1u << 16;  // values per chunk (rows x row width)
  bool compressed() const { return deflateLevel > 0; }
};

// Rows per chunk of a dataset of `rows` rows of `rowValues` values: at most
// `chunkValues` values a chunk, in as few chunks as that allows, all but the
// last equal and the last as full as can be. (The plain most-per-chunk
// split left cuboid A's positions in chunks of 21,845, 21,845 and 3,185
// rows: an uncompressed edge chunk is stored whole, 28 % of the dataset
// unused.) At least 1.
hsize_t balancedChunkRows(std::uint64_t rows, std::uint64_t rowValues, std::uint64_t chunkValues);

// Creates a dataset of the given shape and writes `data` into it.
Status writeDataset(hid_t location, const std::string& name, ElementType type,
                    const std::vector<std::uint64_t>& dims, const void* data,
                    const Storage& storage = {});
// The names of an object's attributes, in name order.
Result<std::vector<std::string>> attributeNames(hid_t object);
// The names of a group's members (links), in name order.
Result<std::vector<std::string>> memberNames(hid_t group);
// Overwrites the whole of an existing dataset.
Status overwriteDataset(hid_t location, const std::string& name, ElementType type,
                        const void* data);
// Reads the whole dataset into `out` (sized by the caller), converting to the
// native type.
Status readDataset(hid_t dataset, ElementType type, void* out);

// Datasets with a leading step axis (the appendable layout, crackvis-dem
// v1.2, docs/data-format.md): created empty, [0, rowDims...] up to
// [unlimited, rowDims...], chunked one step row at a time (at most
// storage.chunkValues values per chunk; 1-D ones 256 steps per chunk), with
// shuffle + deflate when storage asks for it. HDF5's SWMR mode can grow
// such datasets while readers have the file open.
Result<Handle> createStepAxisDataset(hid_t location, const std::string& name, ElementType type,
                                     const std::vector<std::uint64_t>& rowDims,
                                     const Storage& storage);
// Grows a step-axis dataset to `row` + 1 rows, writes `data` as row `row`
// and flushes the dataset to the file (its data, then its metadata).
Status appendRow(hid_t dataset, ElementType type, std::uint64_t row, const void* data);
// Reads row `row` of a dataset whose first axis counts steps (the rest of
// its shape) into `out`.
Status readRow(hid_t dataset, ElementType type, std::uint64_t row, void* out);
// Reads the rows `rows` (ascending, no repeats) of a dataset along its first
// axis, or along its second when `stepRow` >= 0 names a row of its leading
// step axis (the appendable layout); a row is the rest of the shape. Rows
// close together are read as one span through a buffer of a few MiB and
// picked from it, so a scattered selection (a slab of a specimen) costs few
// reads, and memory follows the rows asked for, not the dataset.
Status readRowsAt(hid_t dataset, ElementType type, std::int64_t stepRow,
                  std::span<const std::int32_t> rows, void* out);
// Reads the first `count` values of a 1-D dataset.
Status readLeading(hid_t dataset, ElementType type, std::uint64_t count, void* out);
// Reloads what this process holds of a dataset's metadata (its extent and
// chunk index) from the file: a file a writer is still growing (SWMR)
// shows new rows only after this.
Status refreshDataset(hid_t dataset);
// How every crackvis reader opens a file: read-only; and when libhdf5
// refuses that because a live writer is growing the file (or was killed,
// which leaves the superblock marked as open for SWMR writing), again in
// SWMR read mode. Files no writer holds open the plain way, as before live
// files existed. An invalid handle when both fail, with the reason left for
// openRefusal().
Handle openReadOnly(const std::string& path, hid_t access = H5P_DEFAULT);
// Why openReadOnly failed, for "PATH: cannot open: <this>": the file is
// truncated or corrupt, or another process is writing it without making it
// a live file (SWMR), with libhdf5's reasons. Clears the error stack.
std::string openRefusal();

}  // namespace crackvis::dem::h5
