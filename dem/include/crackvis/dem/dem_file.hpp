// Reading and writing DEM results in the HDF5 layout `crackvis-dem` v1
// (docs/data-format.md is the contract).
//
// The reader validates as it goes and reports every problem as a Status with
// one line naming the file, the dataset or attribute, and what is wrong; it
// never lets HDF5 print to stderr. The writer appends steps to an open file
// and flushes after each, so an interrupted simulation leaves a file whose
// completed steps are readable.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/h5.hpp>
#include <crackvis/dem/model.hpp>
#include <crackvis/dem/spatial_index.hpp>
#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::dem {

// The attribute of /steps that records how many steps a writer planned.
inline constexpr const char* kPlannedStepsAttribute = "planned";
// The root attribute (v1.1, optional) naming the unit of the steps' `time`:
// absent or "s" for seconds; kTimeInIterations when a code wrote no time and
// none was given, so `time` holds the code's step (iteration) number.
inline constexpr const char* kTimeUnitAttribute = "time_unit";
inline constexpr const char* kTimeInIterations = "iteration";
// The root attribute (v1.2, optional) naming one written file: 32 random
// hex digits, new for every file a writer creates.
inline constexpr const char* kRunIdAttribute = "run_id";

// Free-form provenance stored in root attributes.
struct DemMetadata {
  std::string source;  // what produced the file, e.g. "crackvis sim cuboid3d --set A"
  std::string units = "SI";
  int plannedSteps = 0;  // steps the writer means to write (/steps@planned); 0: not recorded
  // v1.1 provenance of imported data (empty: not recorded).
  std::string sourceCode;                // "LAMMPS", "Yade", "ESyS-Particle", "crackvis sim"
  std::string sourceVersion;             // the code's version as it reported it
  std::vector<std::string> sourceFiles;  // the input files, as given
  h5::Storage storage;                   // per-step datasets: contiguous or compressed
  std::string timeUnit = "s";            // "s" or kTimeInIterations
  // kAppendable: a live file, steps along an extendible axis, readable
  // while it grows (HDF5 SWMR); every step then carries the optional arrays,
  // extras and scalar names of the first.
  StepLayout stepLayout = StepLayout::kGroups;
  // The spatial index (/index, v1.3) is written with the first step; its
  // cell decomposition, when the caller decided it on the whole bond graph
  // (cracks::decompositionOf), lets a reader of one slab skip that decision.
  bool spatialIndex = true;
  CellDecomposition decomposition = CellDecomposition::kUnknown;
  // For a triangulated packing, what makes /index/wide_cells and
  // /index/peeled_cells (unset: not written, and each rank then reads the
  // whole set).
  WideCellsMaker wideCells;
};

// Metadata naming only what produced the file.
inline DemMetadata metadataFrom(std::string source) {
  DemMetadata metadata;
  metadata.source = std::move(source);
  return metadata;
}

struct StepInfo {
  int index = 0;
  double time = 0.0;
  std::vector<StepScalar> scalars;  // the step's named scalars (v1.1)
};

// An extra array a file holds (v1.1), as its header describes it.
struct ExtraInfo {
  std::string name;
  ExtraOwner owner = ExtraOwner::kParticles;
  int components = 1;
  bool perStep = false;  // under each step group (seen in step 0), else constant
};
// "/extra/particles/NAME", or "/steps/000042/extra/bonds/NAME" per step
// ("/steps/extra/bonds/NAME", row 42, in an appendable file).
std::string extraPath(const ExtraInfo& extra, int step = 0,
                      StepLayout layout = StepLayout::kGroups);
// The appendable layout's writer flag, int32 scalar: 1 while a live writer
// has the file open, 0 once it closed it (a killed writer leaves 1).
inline constexpr const char* kStepsWritingPath = "/steps/writing";

// What a file holds, read from its attributes and dataset headers only.
struct DemFileInfo {
  std::string path;
  std::string format;
  int version = 0;
  int dimension = 0;
  std::string units;
  std::string source;
  std::int64_t particleCount = 0;  // N
  std::int64_t bondCount = 0;      // M
  std::vector<StepInfo> steps;     // complete steps, in order
  int incompleteSteps = 0;         // step groups an interrupted writer left unfinished
  std::int64_t plannedSteps = 0;   // /steps@planned: steps the writer meant to write; 0 unknown
  int minorVersion = 0;            // root attribute version_minor; 0 when absent (v1.0)
  std::string sourceCode;          // v1.1 provenance; empty when not recorded
  std::string sourceVersion;
  std::vector<std::string> sourceFiles;
  std::string timeUnit = "s";  // "s", or kTimeInIterations: `time` is the code's step
  StepLayout stepLayout = StepLayout::kGroups;
  // Appendable files: whether the writer still had the file open when it
  // was read (/steps/writing; a killed writer leaves it set).
  bool beingWritten = false;
  bool hasStrength = false;              // /bonds/strength present (required before v1.1)
  std::vector<std::string> scalarNames;  // step scalars of any step, in first-seen order
  std::vector<ExtraInfo> extras;         // constant ones, then per-step ones (of step 0)
  // Whether the writer stopped before writing the steps it planned.
  bool stoppedEarly() const { return plannedSteps > static_cast<std::int64_t>(steps.size()); }
};

class DemFileReader {
 public:
  // Opens and checks the file's structure: HDF5 signature, format and
  // version attributes, the time-independent datasets' presence, dtypes and
  // shapes, and the list of steps. Array contents are checked when read.
  static Result<DemFileReader> open(const std::string& path);
  // open(), for a reader without a supervised HDF5 worker (the CLI, an
  // offline render): libhdf5 first reads the file's structure in a forked
  // child, so a corrupt file that makes libhdf5 fault (the fuzzer keeps one,
  // tests/fuzz/crashes) gives FAILED_PRECONDITION naming the file and the
  // signal instead of killing the process; a structure that takes longer
  // than `limit` to read is refused the same way. Not for processes whose
  // other threads use libhdf5, nor under MPI (fork).
  static Result<DemFileReader> openGuarded(
      const std::string& path, std::chrono::milliseconds limit = std::chrono::minutes(5));

  const DemFileInfo& info() const { return m_info; }
  // Reads the list of steps again: a live file's writer may have added
  // some since open(). Each complete step is read once as it was written.
  Status refreshSteps();
  int stepCount() const { return static_cast<int>(m_info.steps.size()); }

  // Radii, bonds, strengths and the optional v1.1 arrays (ids, groups, bond
  // flags, constant extras); validated (bond indices, self and duplicate
  // bonds, radii). Every content problem is FAILED_PRECONDITION naming the
  // file and the first bad index; a step out of range is OUT_OF_RANGE
  // (checkStepInRange).
  Result<Lattice> readLattice() const;
  // /bonds/break_step: first step at which each bond is broken, -1 never.
  Result<std::vector<std::int32_t>> readBreakSteps() const;
  // One whole step with its scalars and extra arrays: a few contiguous reads,
  // validated against N and M. `recycled`, a step read before, lends its
  // arrays' memory (their values are overwritten): a reader stepping through
  // a run then takes no fresh pages from the kernel at every step (their
  // zeroing took a third of a 10^7 ParaView rank's samples over its later
  // steps).
  Result<StepState> readStep(int step, StepState recycled = {}) const;
  // Only the bond states of a step (for statistics over many steps).
  Result<std::vector<std::uint8_t>> readBondState(int step) const;
  // The file's spatial index (/index, v1.3; docs/data-format.md): its
  // attributes, its datasets' shapes checked against N and M; nullopt when
  // the file has none (files before v1.3, a writer told not to).
  Result<std::optional<SpatialIndexInfo>> readSpatialIndexInfo() const;
  // /index/order at positions [first, last) of the order.
  Result<std::vector<ParticleIndex>> readIndexOrder(std::int64_t first, std::int64_t last) const;
  // /index/coordinate at position k (a binary search probes a few).
  Result<double> readIndexCoordinate(std::int64_t k) const;
  // /index/bond_start at `rows` (ascending particle indices, N included).
  Result<std::vector<std::int64_t>> readBondStarts(std::span<const std::int32_t> rows) const;
  // /index/wide_cells with its attributes, and /index/peeled_cells where
  // stored, checked (nodes in range and ascending); nullopt when the file
  // has no wide cells.
  Result<std::optional<WideCells>> readWideCells() const;
  // The same with the index's information already read (readSpatialIndexInfo).
  Result<std::optional<WideCells>> readWideCells(const SpatialIndexInfo& index) const;

  // Partial reads, for a reader of one piece of the specimen (an MPI rank;
  // cracks::readIndexedPiece): rows `particles` of the per-particle arrays
  // and `bonds` of the per-bond arrays (ascending whole-set indices, each
  // once), read in spans through a bounded buffer (h5::readRowsAt), so that
  // memory follows the piece, not the file. Contents are checked as far as
  // the rows allow: radii, bond ends in range, finite positions, bond states.
  Result<std::vector<Bond>> readBondRows(std::span<const BondIndex> bonds) const;
  // The lattice's rows; its bonds keep whole-set particle indices.
  Result<Lattice> readLatticeRows(std::span<const ParticleIndex> particles,
                                  std::span<const BondIndex> bonds) const;
  Result<std::vector<std::int32_t>> readBreakStepRows(std::span<const BondIndex> bonds) const;
  // `recycled`: as for readStep.
  Result<StepState> readStepRows(int step, std::span<const ParticleIndex> particles,
                                 std::span<const BondIndex> bonds, StepState recycled = {}) const;

  // The headers of a step's datasets (type and shape against N and M),
  // without reading their data: what readStep would refuse for its shape.
  Status checkStepHeaders(int step) const;

 private:
  DemFileReader() = default;
  Status fail(const Status& status) const;
  Status readStructure();
  Status readSteps();
  Status readGroupSteps(hid_t steps);
  Status readAppendableSteps();
  Status readAppendableScalars(std::uint64_t count);
  // Where step `step` of a per-step dataset lives in this file's layout.
  std::string stepDatasetPath(DemDataset id, int step) const;
  struct OpenedDataset {
    h5::Handle dataset;
    h5::DatasetShape shape;
  };
  // Opens a dataset by links inside the file only, with its shape.
  Result<OpenedDataset> openInFile(const std::string& path) const;
  // An appendable per-step dataset, checked to hold row `step` (its metadata
  // reloaded when this process saw fewer rows); its shape is the row's.
  Result<OpenedDataset> openStepAxis(const std::string& path, int step) const;
  // h5::refreshDataset, its failure naming the file and the dataset.
  Status refreshed(const std::string& path, hid_t dataset) const;
  Result<h5::Handle> openChecked(DemDataset id, int step = 0) const;
  Status readWhole(DemDataset id, int step, void* out) const;
  Status readRows(DemDataset id, int step, std::span<const std::int32_t> rows, void* out) const;
  template <typename T>
  Status readOptionalRows(DemDataset id, std::span<const std::int32_t> rows,
                          std::vector<T>& out) const;
  Result<ExtraArray> readExtraRows(const ExtraInfo& extra, int step,
                                   std::span<const std::int32_t> rows) const;
  Result<h5::Handle> openIndexDataset(const char* path, ElementType type,
                                      std::vector<std::uint64_t> dims) const;
  template <typename T>
  Status readOptional(DemDataset id, std::uint64_t count, std::vector<T>& out) const;
  Status readProvenance();
  Status checkIndexable() const;
  Status readWideCellsInfo(hid_t group, SpatialIndexInfo& info) const;
  Status checkCellListShape(const char* path) const;
  Result<std::vector<std::array<ParticleIndex, 4>>> readCellList(const char* path) const;
  Status checkStored(DemDataset id, std::int64_t rows) const;
  Status checkStoredBytes(hid_t dataset, const std::string& path, std::uint64_t rows,
                          std::uint64_t rowBytes) const;
  Status listExtras();
  Result<OpenedDataset> openExtra(const ExtraInfo& extra, int step) const;
  Result<ExtraArray> readExtra(const ExtraInfo& extra, int step) const;
  Result<std::vector<StepScalar>> readScalars(hid_t stepGroup, int step) const;

  std::string m_path;
  h5::Handle m_file;
  DemFileInfo m_info;
  Status m_countsStored;  // whether N and M are backed by stored data (checkStored)
};

class DemFileWriter {
 public:
  // Creates (or truncates) `path` and writes the time-independent part
  // (crackvis-dem v1.1: the optional arrays only when the lattice has them).
  static Result<DemFileWriter> create(const std::string& path, const Lattice& lattice,
                                      const DemMetadata& metadata);

  // Writes the next step, updates /bonds/break_step and flushes to disk;
  // only then raises /steps@count (flushed again), so the first `count`
  // steps are on disk whatever happens next (a full disk, a kill). Refuses a
  // step that disagrees with the lattice or that heals a bond (bonds break
  // for good). After a failed write the writer is closed: later calls fail.
  Status appendStep(const StepState& step);
  // Closes the file; the destructor closes too but cannot report errors.
  Status close();

  int stepCount() const { return m_stepCount; }
  const std::vector<std::int32_t>& breakSteps() const { return m_breakStep; }

 private:
  DemFileWriter() = default;
  // The root attributes, groups and time-independent datasets of a new file.
  Status writeTimeIndependent(const DemMetadata& metadata);
  Status recordBreaks(const StepState& step, bool& changed);
  Status writeStepData(const StepState& step, bool breaksChanged);
  Status writeExtras(hid_t location, const std::vector<ExtraArray>& extras);
  Status writeSpatialIndex(const StepState& first);
  Status writeWideCells(hid_t group, const StepState& first);
  // One step in the appendable layout, or as a step group; the commit last.
  Status writeAppendableStep(const StepState& step, bool breaksChanged);
  Status writeGroupStep(const StepState& step, bool breaksChanged);
  Status flush();
  void abandon();

  // The appendable layout: the step-axis datasets, created for the first
  // step (which fixes the optional arrays, extras and scalar names of all),
  // after which the file is switched to HDF5's SWMR write mode.
  struct StepAxis;
  Status startStepAxis(const StepState& first);
  Status checkLikeFirst(const StepState& step) const;
  Status writeStepRows(const StepState& step, bool breaksChanged);
  Status commitStepRow(double time);

  std::string m_path;
  h5::Handle m_file;
  Lattice m_lattice;
  h5::Storage m_storage;
  std::vector<std::int32_t> m_breakStep;
  int m_stepCount = 0;
  StepLayout m_layout = StepLayout::kGroups;
  bool m_spatialIndex = true;
  CellDecomposition m_decomposition = CellDecomposition::kUnknown;
  WideCellsMaker m_wideCells;
  std::shared_ptr<StepAxis> m_axis;  // appendable, from the first step on
};

}  // namespace crackvis::dem
