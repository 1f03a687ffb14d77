// The catalogue of a data root: listing, describing, hyperslab reads and
// whole-file reads of the files under it. The data service's handlers call
// it after they have checked the caller; it knows nothing of gRPC.
//
// Every HDF5 call the catalogue makes holds hdf5Mutex(), one lock per
// process. Debian 12's HDF5 is built thread-safe and serializes itself
// anyway (dem/src/h5.cpp, docs/protocol.md); the lock keeps the catalogue
// correct on builds that are not. A read is split into pieces of about
// 1 MiB, each read under the lock, so concurrent streams take turns rather
// than wait for each other's whole request.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_h5/data_root.hpp>
#include <crackvis/dataservice_protocol/types.hpp>

namespace crackvis::dataservice {

// Describes and reads a small crackvis-dem file held in memory (HDF5's core
// driver; nothing on disk): a fresh HDF5 worker makes these calls before it
// says it is ready, so that libhdf5's first use in the process (its
// packages' start, free lists, the filters, the heap's first pages) is not
// paid by the first caller's Describe, which took about twice a later one's
// time. Returns the description (for the worker to encode once, too).
Result<FileDescription> rehearseDescribeAndRead();

// The lock around every HDF5 call in this process that may run beside the
// service (the catalogue's, and a test's or tool's direct reads).
std::mutex& hdf5Mutex();

// One validated hyperslab of a Read.
struct SlabPlan {
  std::string dataset;          // as the client named it
  std::string resolvedDataset;  // the same through hard links only (soft links resolved)
  DataType dtype = DataType::kUnspecified;
  std::vector<std::uint64_t> datasetShape;
  std::vector<std::uint64_t> start;  // one per dimension (empty for a scalar)
  std::vector<std::uint64_t> count;  // the slab's shape
  std::uint64_t bytes = 0;
  std::uint64_t rowBytes = 0;  // bytes of one index of the first dimension
};

// The part of a slab read in one go, at most kMaxChunkBytes whatever the
// dataset's shape: whole rows of the first dimension where a row fits, else
// a run along the first dimension whose inner block fits, the indices before
// it fixed. A piece is contiguous in the slab's row-major bytes.
struct Piece {
  std::size_t slab = 0;
  std::uint64_t offset = 0;  // within the slab, bytes
  std::uint64_t bytes = 0;
  std::vector<std::uint64_t> start;  // within the slab, one per dimension
  std::vector<std::uint64_t> count;  // the piece's shape
};

// Walks the pieces of a Read's slabs: slab order, then byte order. Pure
// arithmetic, so a process that holds only the plans (the data service,
// whose HDF5 work runs in worker processes) splits a Read as the reader does.
class PieceCursor {
 public:
  // The next piece, or nothing when every slab is done.
  std::optional<Piece> next(const std::vector<SlabPlan>& slabs);

 private:
  std::size_t m_slab = 0;
  std::vector<std::uint64_t> m_start;  // the next piece's start in the current slab
  std::uint64_t m_offset = 0;          // its offset in bytes
};

// An open, validated Read: the file stays open until the reader is
// destroyed; pieces come in slab order, then byte order.
class SlabReader {
 public:
  SlabReader(const SlabReader&) = delete;
  SlabReader& operator=(const SlabReader&) = delete;
  ~SlabReader();

  const std::vector<SlabPlan>& slabs() const { return m_slabs; }
  std::uint64_t totalBytes() const { return m_totalBytes; }

  // The next piece to read, or nothing when every slab is done.
  std::optional<Piece> nextPiece();
  // Reads a piece into `out` (piece.bytes long), little-endian.
  Status read(const Piece& piece, void* out);

 private:
  friend class Catalogue;
  struct Handles;
  SlabReader();

  std::string m_file;
  std::unique_ptr<Handles> m_handles;
  std::vector<SlabPlan> m_slabs;
  std::uint64_t m_totalBytes = 0;
  PieceCursor m_pieces;
};

// An open file streamed as stored (Fetch).
class FileReader {
 public:
  FileReader(const FileReader&) = delete;
  FileReader& operator=(const FileReader&) = delete;
  ~FileReader();

  std::uint64_t size() const { return m_size; }
  // Reads up to `bytes` at `offset`; returns how many were read.
  Result<std::size_t> readAt(std::uint64_t offset, void* out, std::size_t bytes);

 private:
  friend class Catalogue;
  FileReader(int fd, std::uint64_t size, std::string name)
      : m_fd(fd), m_size(size), m_name(std::move(name)) {}

  int m_fd = -1;
  std::uint64_t m_size = 0;
  std::string m_name;
};

// Bounds on one Describe, so that one hostile file cannot hold the HDF5
// lock for long: RESOURCE_EXHAUSTED past them.
struct DescribeLimits {
  int maxDepth = 64;                            // levels of nested groups
  std::size_t maxObjects = 100'000;             // groups, datasets and other links
  std::chrono::duration<double> maxTime{10.0};  // walking the tree (seconds, as configured)
};

struct DescribeOptions {
  DescribeLimits limits;
  // Asked between objects; true stops the walk (UNAVAILABLE "cancelled"),
  // e.g. the gRPC context's IsCancelled.
  std::function<bool()> cancelled;
};

class Catalogue {
 public:
  explicit Catalogue(DataRoot root);

  const DataRoot& root() const { return m_root; }

  // Files under `folder` (relative, "" for the root), sorted by path; only
  // those `mayRead` accepts (called with the real relative path), and never
  // a symlink that leaves the root.
  using AccessFilter = std::function<bool(const std::string& relative)>;
  Result<std::vector<FileEntry>> listFiles(std::string_view folder, bool recursive,
                                           const AccessFilter& mayRead) const;

  // The whole tree of a file. FAILED_PRECONDITION for a file that is not
  // HDF5 or that HDF5 cannot open (truncated, corrupt); RESOURCE_EXHAUSTED
  // past `options.limits`.
  Result<FileDescription> describe(const ResolvedPath& file,
                                   const DescribeOptions& options = {}) const;

  // Validates every slab (dataset present and readable, start and count
  // inside its shape) and the total against `maxBytes`, and opens the file.
  Result<std::unique_ptr<SlabReader>> openRead(const ResolvedPath& file,
                                               const std::vector<Hyperslab>& slabs,
                                               std::uint64_t maxBytes) const;

  // Reads one piece of a slab that openRead() planned (possibly in another
  // process: the plan is data) into `out` (piece.bytes long). The dataset is
  // opened by the plan's hard-link path; a file changed since the plan gives
  // an error, never a read outside `out`.
  Status readPiece(const ResolvedPath& file, const SlabPlan& slab, const Piece& piece,
                   void* out) const;

  // Opens a file for streaming as stored; it must be HDF5 and at most
  // `maxBytes` long.
  Result<std::unique_ptr<FileReader>> openFetch(const ResolvedPath& file,
                                                std::uint64_t maxBytes) const;

  // describe() and openRead() keep the HDF5 files they open open for later
  // calls (at most 16, each checked against the file on disk at every use);
  // this closes those no call used for 2 s, so that a writer (which HDF5's
  // file locking keeps out while a reader has the file open) is not kept
  // out for long. Copies of a catalogue share these files.
  void closeIdleFiles() const;

 private:
  class OpenFiles;
  DataRoot m_root;
  std::shared_ptr<OpenFiles> m_openFiles;
};

}  // namespace crackvis::dataservice
