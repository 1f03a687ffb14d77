// DemFileWriter: creates a DEM file and appends steps to it.
#include <algorithm>
#include <array>
#include <limits>
#include <random>

#include <fmt/format.h>

#include "dem_file_internal.hpp"
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::dem {

using h5::Handle;

// The open step-axis datasets of an appendable file.
struct DemFileWriter::StepAxis {
  struct Named {
    std::string name;
    ExtraOwner owner = ExtraOwner::kParticles;
    int components = 1;
    Handle dataset;
  };
  Handle time;
  Handle positions;
  Handle bondState;
  Handle velocities;  // absent unless the first step had them
  Handle bondForce;
  Handle breakStep;
  Handle writing;
  std::vector<Named> scalars;
  std::vector<Named> extras;
  // Gives every id up without closing it: after a failed write nothing more
  // may reach the file.
  void abandon() {
    for (Handle* handle :
         {&time, &positions, &bondState, &velocities, &bondForce, &breakStep, &writing}) {
      handle->release();
    }
    for (auto* list : {&scalars, &extras}) {
      for (Named& named : *list) {
        named.dataset.release();
      }
    }
  }
};

namespace {

using detail::ownerFolder;
using h5::Handle;

// 128 random bits in hex: the root attribute run_id, by which a reader
// following a live file tells that another run replaced it under its name.
std::string newRunId() {
  std::random_device random;
  std::string id;
  for (int part = 0; part < 4; ++part) {
    id += fmt::format("{:08x}", static_cast<std::uint32_t>(random()));
  }
  return id;
}

std::string joinLines(const std::vector<std::string>& lines) {
  return fmt::format("{}", fmt::join(lines, "\n"));
}

}  // namespace

Result<DemFileWriter> DemFileWriter::create(const std::string& path, const Lattice& lattice,
                                            const DemMetadata& metadata) {
  h5::quietHdf5();
  if (Status valid = validateLattice(lattice); !valid) {
    return Status(valid.code(), fmt::format("{}: refusing to write: {}", path, valid.message()));
  }
  DemFileWriter writer;
  writer.m_path = path;
  // The default (earliest) file format keeps no "open for writing" flag in
  // the superblock, so a file whose writer was killed still opens.
  // An appendable (live) file needs the v1.10 format: SWMR's checksummed
  // metadata and extensible chunk indices; readers need libhdf5 >= 1.10.
  writer.m_layout = metadata.stepLayout;
  Handle access = h5::propertyListHandle(H5Pcreate(H5P_FILE_ACCESS));
  if (writer.m_layout == StepLayout::kAppendable) {
    H5Pset_libver_bounds(access.get(), H5F_LIBVER_V110, H5F_LIBVER_V110);
  }
  writer.m_file = h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.get()));
  if (!writer.m_file.valid()) {
    return failedPrecondition(
        fmt::format("{}: cannot create file ({})", path, h5::lastHdf5Error()));
  }
  writer.m_lattice = lattice;
  writer.m_breakStep.assign(lattice.bondCount(), -1);
  writer.m_storage = metadata.storage;
  writer.m_spatialIndex = metadata.spatialIndex;
  writer.m_decomposition = metadata.decomposition;
  writer.m_wideCells = metadata.wideCells;
  if (Status written = writer.writeTimeIndependent(metadata); !written) {
    // Every message names the file (a full disk fails any of the writes).
    return written.message().starts_with(path)
               ? written
               : Status(written.code(), fmt::format("{}: {}", path, written.message()));
  }
  return writer;
}

Status DemFileWriter::writeTimeIndependent(const DemMetadata& metadata) {
  const std::string& path = m_path;
  const Lattice& lattice = m_lattice;
  const hid_t root = m_file.get();
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, "format", std::string(kFormatName)));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(root, "version", kFormatVersion));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(root, "dimension", lattice.dimension));
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, "units", metadata.units));
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, "source", metadata.source));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(root, "version_minor", kFormatMinorVersion));
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, kRunIdAttribute, newRunId()));
  if (!metadata.sourceCode.empty()) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, "source_code", metadata.sourceCode));
  }
  if (!metadata.sourceVersion.empty()) {
    CRACKVIS_RETURN_IF_ERROR(
        h5::writeStringAttribute(root, "source_version", metadata.sourceVersion));
  }
  if (!metadata.sourceFiles.empty()) {
    CRACKVIS_RETURN_IF_ERROR(
        h5::writeStringAttribute(root, "source_files", joinLines(metadata.sourceFiles)));
  }
  if (m_layout == StepLayout::kAppendable) {
    CRACKVIS_RETURN_IF_ERROR(
        h5::writeStringAttribute(root, kStepLayoutAttribute, std::string(kAppendableName)));
  }
  if (metadata.timeUnit != "s") {
    CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, kTimeUnitAttribute, metadata.timeUnit));
  }

  const auto n = static_cast<std::uint64_t>(lattice.particleCount());
  const auto m = static_cast<std::uint64_t>(lattice.bondCount());
  for (const char* group : {"/particles", "/bonds", "/steps"}) {
    Handle created =
        h5::groupHandle(H5Gcreate2(root, group, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    if (!created.valid()) {
      return internalError(
          fmt::format("{}: cannot create group {} ({})", path, group, h5::lastHdf5Error()));
    }
  }
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(root, "/particles/radius", ElementType::kFloat64, {n},
                                            lattice.radius.data()));
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeDataset(root, "/bonds/pairs", ElementType::kInt32, {m, 2}, lattice.bonds.data()));
  if (!lattice.strength.empty()) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(root, "/bonds/strength", ElementType::kFloat64, {m},
                                              lattice.strength.data()));
  }
  if (!lattice.particleId.empty()) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(root, "/particles/id", ElementType::kInt64, {n},
                                              lattice.particleId.data()));
  }
  if (!lattice.particleGroup.empty()) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(root, "/particles/group", ElementType::kInt32, {n},
                                              lattice.particleGroup.data()));
  }
  if (!lattice.bondFlags.empty()) {
    CRACKVIS_RETURN_IF_ERROR(
        h5::writeDataset(root, "/bonds/flags", ElementType::kUInt8, {m}, lattice.bondFlags.data()));
  }
  if (!lattice.extras.empty()) {
    CRACKVIS_RETURN_IF_ERROR(writeExtras(root, lattice.extras));
  }
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeDataset(root, "/bonds/break_step", ElementType::kInt32, {m}, m_breakStep.data()));
  Handle steps = h5::groupHandle(H5Gopen2(root, "/steps", H5P_DEFAULT));
  if (m_layout == StepLayout::kGroups) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(steps.get(), "count", 0));
  }
  if (metadata.plannedSteps > 0) {
    CRACKVIS_RETURN_IF_ERROR(
        h5::writeIntAttribute(steps.get(), kPlannedStepsAttribute, metadata.plannedSteps));
  }
  if (H5Fflush(root, H5F_SCOPE_GLOBAL) < 0) {
    return internalError(fmt::format("{}: flush failed ({})", path, h5::lastHdf5Error()));
  }
  return Status::ok();
}

Status DemFileWriter::recordBreaks(const StepState& step, bool& changed) {
  changed = false;
  for (size_t b = 0; b < m_breakStep.size(); ++b) {
    const bool broken = step.bondState[b] == static_cast<std::uint8_t>(BondState::kBroken);
    if (!broken && m_lattice.cutAtStart(b)) {
      return invalidArgument(
          fmt::format("{}: step {}: bond {} is flagged cut at the start (a notch) but is intact",
                      m_path, m_stepCount, b));
    }
    if (broken && m_breakStep[b] < 0) {
      m_breakStep[b] = m_stepCount;
      changed = true;
    } else if (!broken && m_breakStep[b] >= 0) {
      return invalidArgument(fmt::format(
          "{}: step {}: bond {} is intact again after breaking at step {} (bonds break for good)",
          m_path, m_stepCount, b, m_breakStep[b]));
    }
  }
  return Status::ok();
}

Status DemFileWriter::appendStep(const StepState& step) {
  if (!m_file.valid()) {
    return failedPrecondition(fmt::format("{}: writer is closed", m_path));
  }
  if (Status valid = validateStep(m_lattice, step); !valid) {
    return Status(valid.code(),
                  fmt::format("{}: step {}: {}", m_path, m_stepCount, valid.message()));
  }
  if (m_axis) {
    CRACKVIS_RETURN_IF_ERROR(checkLikeFirst(step));
  }
  std::vector<std::int32_t> previous = m_breakStep;
  bool breaksChanged = false;
  if (Status breaks = recordBreaks(step, breaksChanged); !breaks) {
    m_breakStep = std::move(previous);
    return breaks;
  }

  // The step's data first, flushed; only then the commit mark, flushed
  // again. A write that fails (a full disk) leaves the file as the last
  // commit mark describes it, and the writer closed.
  Status written = m_stepCount == 0 && m_spatialIndex ? writeSpatialIndex(step) : Status::ok();
  if (written) {
    written = m_layout == StepLayout::kAppendable ? writeAppendableStep(step, breaksChanged)
                                                  : writeGroupStep(step, breaksChanged);
  }
  if (!written) {
    m_breakStep = std::move(previous);
    abandon();
    return Status(written.code(), fmt::format("{}: step {} not written: {}", m_path, m_stepCount,
                                              written.message()));
  }
  ++m_stepCount;
  return Status::ok();
}

Status DemFileWriter::writeAppendableStep(const StepState& step, bool breaksChanged) {
  CRACKVIS_RETURN_IF_ERROR(m_axis ? Status::ok() : startStepAxis(step));
  CRACKVIS_RETURN_IF_ERROR(writeStepRows(step, breaksChanged));
  return commitStepRow(step.time);
}

Status DemFileWriter::writeGroupStep(const StepState& step, bool breaksChanged) {
  CRACKVIS_RETURN_IF_ERROR(writeStepData(step, breaksChanged));
  CRACKVIS_RETURN_IF_ERROR(flush());
  Handle steps = h5::groupHandle(H5Gopen2(m_file.get(), "/steps", H5P_DEFAULT));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(steps.get(), "count", m_stepCount + 1));
  return flush();
}

// The spatial index of the first step's configuration, before the step
// itself (and, in a live file, before SWMR writing starts, after which no
// dataset can be added): a reader that finds the step finds the index.
Status DemFileWriter::writeSpatialIndex(const StepState& first) {
  const SpatialIndex index = buildSpatialIndex(first.positions, m_lattice, m_decomposition);
  const SpatialIndexInfo& info = index.info;
  const hid_t root = m_file.get();
  Handle group =
      h5::groupHandle(H5Gcreate2(root, kSpatialIndexGroup, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!group.valid()) {
    return internalError(
        fmt::format("cannot create group {} ({})", kSpatialIndexGroup, h5::lastHdf5Error()));
  }
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(group.get(), "axis", info.axis));
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeDoubleAttribute(group.get(), "largest_radius", info.largestRadius));
  CRACKVIS_RETURN_IF_ERROR(h5::writeDoubleAttribute(group.get(), "longest_bond", info.longestBond));
  if (info.decomposition != CellDecomposition::kUnknown) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(group.get(), "decomposition",
                                                      decompositionName(info.decomposition)));
  }
  const auto n = static_cast<std::uint64_t>(index.order.size());
  const std::array<Vec3, 2> box{info.box.lo, info.box.hi};
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeDataset(root, kIndexBoxPath, ElementType::kFloat64, {2, 3}, box.data()));
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeDataset(root, kIndexOrderPath, ElementType::kInt32, {n}, index.order.data()));
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(root, kIndexCoordinatePath, ElementType::kFloat64, {n},
                                            index.coordinate.data()));
  if (info.hasBondStart) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(root, kIndexBondStartPath, ElementType::kInt64,
                                              {n + 1}, index.bondStart.data()));
  }
  if (info.decomposition == CellDecomposition::kTriangulation && m_wideCells) {
    return writeWideCells(group.get(), first);
  }
  return Status::ok();
}

// A triangulated packing's wide cells (/index/wide_cells) and the hull's
// slivers its triangulation peels (/index/peeled_cells), found on the
// first step as written. A packing that cannot be triangulated gets none:
// its ranks then read the whole set, and report what extraction reports.
Status DemFileWriter::writeWideCells(hid_t group, const StepState& first) {
  auto wide = m_wideCells(first.positions, m_lattice);
  if (!wide) {
    return Status::ok();
  }
  CRACKVIS_RETURN_IF_ERROR(h5::writeDoubleAttribute(group, "wide_cell_reach", wide->reach));
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeIntAttribute(group, "weighted_triangulation", wide->weighted ? 1 : 0));
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(m_file.get(), kIndexWideCellsPath, ElementType::kInt32,
                                            {static_cast<std::uint64_t>(wide->cells.size()), 4},
                                            wide->cells.data()));
  // Stored even when empty: its presence says the set was peeled.
  return h5::writeDataset(m_file.get(), kIndexPeeledCellsPath, ElementType::kInt32,
                          {static_cast<std::uint64_t>(wide->peeled.size()), 4},
                          wide->peeled.data());
}

Status DemFileWriter::writeStepData(const StepState& step, bool breaksChanged) {
  const hid_t root = m_file.get();
  const std::string path = stepGroupPath(m_stepCount);
  const auto n = static_cast<std::uint64_t>(m_lattice.particleCount());
  const auto m = static_cast<std::uint64_t>(m_lattice.bondCount());
  Handle group =
      h5::groupHandle(H5Gcreate2(root, path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!group.valid()) {
    return internalError(fmt::format("cannot create group {} ({})", path, h5::lastHdf5Error()));
  }
  CRACKVIS_RETURN_IF_ERROR(h5::writeDoubleAttribute(group.get(), "time", step.time));
  for (const StepScalar& scalar : step.scalars) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDoubleAttribute(group.get(), scalar.name, scalar.value));
  }
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(group.get(), "positions", ElementType::kFloat64, {n, 3},
                                            step.positions.data(), m_storage));
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(group.get(), "bond_state", ElementType::kUInt8, {m},
                                            step.bondState.data(), m_storage));
  if (!step.velocities.empty()) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(group.get(), "velocities", ElementType::kFloat32,
                                              {n, 3}, step.velocities.data(), m_storage));
  }
  if (!step.bondForce.empty()) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(group.get(), "bond_force", ElementType::kFloat32, {m},
                                              step.bondForce.data(), m_storage));
  }
  if (!step.extras.empty()) {
    CRACKVIS_RETURN_IF_ERROR(writeExtras(group.get(), step.extras));
  }
  if (breaksChanged) {
    CRACKVIS_RETURN_IF_ERROR(
        h5::overwriteDataset(root, "/bonds/break_step", ElementType::kInt32, m_breakStep.data()));
  }
  return Status::ok();
}

// Extras go under `location`/extra/{particles,bonds}/NAME (location: the
// root for constant arrays, a step group for per-step ones).
Status DemFileWriter::writeExtras(hid_t location, const std::vector<ExtraArray>& extras) {
  Handle extra =
      h5::groupHandle(H5Gcreate2(location, "extra", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!extra.valid()) {
    return internalError(fmt::format("cannot create group extra ({})", h5::lastHdf5Error()));
  }
  for (ExtraOwner owner : {ExtraOwner::kParticles, ExtraOwner::kBonds}) {
    const bool any = std::any_of(extras.begin(), extras.end(),
                                 [&](const ExtraArray& e) { return e.owner == owner; });
    if (!any) {
      continue;
    }
    Handle folder = h5::groupHandle(
        H5Gcreate2(extra.get(), ownerFolder(owner), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    if (!folder.valid()) {
      return internalError(fmt::format("cannot create group extra/{} ({})", ownerFolder(owner),
                                       h5::lastHdf5Error()));
    }
    for (const ExtraArray& array : extras) {
      if (array.owner != owner) {
        continue;
      }
      std::vector<std::uint64_t> dims{array.rows()};
      if (array.components > 1) {
        dims.push_back(static_cast<std::uint64_t>(array.components));
      }
      CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(folder.get(), array.name, ElementType::kFloat64,
                                                dims, array.values.data(), m_storage));
    }
  }
  return Status::ok();
}

Status DemFileWriter::flush() {
  if (H5Fflush(m_file.get(), H5F_SCOPE_GLOBAL) < 0) {
    return internalError(fmt::format("flush failed ({})", h5::lastHdf5Error()));
  }
  return Status::ok();
}

void DemFileWriter::abandon() {
  // What HDF5 still holds of the failed step cannot reach the disk either;
  // the close reports that, and the file stays as its last flush left it.
  if (m_axis) {
    m_axis->abandon();
    m_axis.reset();
  }
  m_file.release();
  h5::lastHdf5Error();
}

Status DemFileWriter::close() {
  if (!m_file.valid()) {
    return Status::ok();
  }
  if (m_axis) {
    // Readers learn the run ended: /steps/writing drops to 0.
    const std::int32_t done = 0;
    if (H5Dwrite(m_axis->writing.get(), H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, &done) <
            0 ||
        H5Dflush(m_axis->writing.get()) < 0) {
      abandon();
      return internalError(fmt::format("{}: close failed ({})", m_path, h5::lastHdf5Error()));
    }
    m_axis.reset();
  }
  if (m_file.reset() < 0) {
    return internalError(fmt::format("{}: close failed ({})", m_path, h5::lastHdf5Error()));
  }
  return Status::ok();
}

}  // namespace crackvis::dem

namespace crackvis::dem {

// Creates the step-axis datasets the first step needs, then switches the
// file to SWMR writing: from here on datasets only grow, and a reader that
// opens the file (h5::openReadOnly) sees the steps committed so far.
Status DemFileWriter::startStepAxis(const StepState& first) {
  const hid_t root = m_file.get();
  const auto n = static_cast<std::uint64_t>(m_lattice.particleCount());
  const auto m = static_cast<std::uint64_t>(m_lattice.bondCount());
  auto axis = std::make_shared<StepAxis>();
  auto create = [&](hid_t location, const std::string& name, ElementType type,
                    std::vector<std::uint64_t> row, Handle& into) -> Status {
    auto made = h5::createStepAxisDataset(location, name, type, row, m_storage);
    if (!made) {
      return made.status();
    }
    into = std::move(*made);
    return Status::ok();
  };
  CRACKVIS_RETURN_IF_ERROR(create(root, kStepTimePath, ElementType::kFloat64, {}, axis->time));
  CRACKVIS_RETURN_IF_ERROR(create(root, appendablePath(DemDataset::kPositions),
                                  ElementType::kFloat64, {n, 3}, axis->positions));
  CRACKVIS_RETURN_IF_ERROR(create(root, appendablePath(DemDataset::kBondState), ElementType::kUInt8,
                                  {m}, axis->bondState));
  if (!first.velocities.empty()) {
    CRACKVIS_RETURN_IF_ERROR(create(root, appendablePath(DemDataset::kVelocities),
                                    ElementType::kFloat32, {n, 3}, axis->velocities));
  }
  if (!first.bondForce.empty()) {
    CRACKVIS_RETURN_IF_ERROR(create(root, appendablePath(DemDataset::kBondForce),
                                    ElementType::kFloat32, {m}, axis->bondForce));
  }
  for (const StepScalar& scalar : first.scalars) {
    if (axis->scalars.empty()) {
      Handle group = h5::groupHandle(
          H5Gcreate2(root, kStepScalarsPath, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    }
    StepAxis::Named named{scalar.name, ExtraOwner::kParticles, 1, {}};
    CRACKVIS_RETURN_IF_ERROR(create(root, fmt::format("{}/{}", kStepScalarsPath, scalar.name),
                                    ElementType::kFloat64, {}, named.dataset));
    axis->scalars.push_back(std::move(named));
  }
  for (const ExtraArray& extra : first.extras) {
    for (const char* group : {"/steps/extra", "/steps/extra/particles", "/steps/extra/bonds"}) {
      if (!h5::linkExists(root, group)) {
        Handle made =
            h5::groupHandle(H5Gcreate2(root, group, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
      }
    }
    StepAxis::Named named{extra.name, extra.owner, extra.components, {}};
    std::vector<std::uint64_t> row{extra.rows()};
    if (extra.components > 1) {
      row.push_back(static_cast<std::uint64_t>(extra.components));
    }
    const ExtraInfo info{extra.name, extra.owner, extra.components, true};
    CRACKVIS_RETURN_IF_ERROR(create(root, extraPath(info, 0, StepLayout::kAppendable),
                                    ElementType::kFloat64, row, named.dataset));
    axis->extras.push_back(std::move(named));
  }
  // Set while a writer has the file open; close() clears it.
  const std::int32_t writing = 1;
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeDataset(root, kStepsWritingPath, ElementType::kInt32, {}, &writing));
  axis->writing = h5::datasetHandle(H5Dopen2(root, kStepsWritingPath, H5P_DEFAULT));
  axis->breakStep =
      h5::datasetHandle(H5Dopen2(root, datasetPath(DemDataset::kBreakStep).c_str(), H5P_DEFAULT));
  if (!axis->writing.valid() || !axis->breakStep.valid()) {
    return internalError(fmt::format("cannot open the step datasets ({})", h5::lastHdf5Error()));
  }
  CRACKVIS_RETURN_IF_ERROR(flush());
  if (H5Fstart_swmr_write(root) < 0) {
    return internalError(
        fmt::format("cannot start SWMR writing for live readers ({})", h5::lastHdf5Error()));
  }
  m_axis = std::move(axis);
  return Status::ok();
}

// Every step of an appendable file has the arrays of its first: its
// datasets were fixed when SWMR writing began.
Status DemFileWriter::checkLikeFirst(const StepState& step) const {
  auto refuse = [&](const std::string& what) {
    return invalidArgument(fmt::format(
        "{}: step {}: {} (every step of a live file carries the arrays and scalars of its first)",
        m_path, m_stepCount, what));
  };
  if (step.velocities.empty() == m_axis->velocities.valid()) {
    return refuse(step.velocities.empty() ? "no velocities" : "velocities the first step lacked");
  }
  if (step.bondForce.empty() == m_axis->bondForce.valid()) {
    return refuse(step.bondForce.empty() ? "no bond forces" : "bond forces the first step lacked");
  }
  for (const StepScalar& scalar : step.scalars) {
    if (std::none_of(m_axis->scalars.begin(), m_axis->scalars.end(),
                     [&](const StepAxis::Named& named) { return named.name == scalar.name; })) {
      return refuse(fmt::format("scalar '{}' the first step lacked", scalar.name));
    }
  }
  if (step.extras.size() != m_axis->extras.size()) {
    return refuse(fmt::format("{} extra arrays, the first step had {}", step.extras.size(),
                              m_axis->extras.size()));
  }
  for (size_t i = 0; i < step.extras.size(); ++i) {
    const ExtraArray& extra = step.extras[i];
    const StepAxis::Named& named = m_axis->extras[i];
    if (extra.name != named.name || extra.owner != named.owner ||
        extra.components != named.components) {
      return refuse(
          fmt::format("extra array '{}' where the first step had '{}'", extra.name, named.name));
    }
  }
  return Status::ok();
}

// Row m_stepCount of every step-axis dataset but /steps/time, each flushed,
// and /bonds/break_step; the step is not committed yet.
Status DemFileWriter::writeStepRows(const StepState& step, bool breaksChanged) {
  const auto row = static_cast<std::uint64_t>(m_stepCount);
  CRACKVIS_RETURN_IF_ERROR(
      h5::appendRow(m_axis->positions.get(), ElementType::kFloat64, row, step.positions.data()));
  CRACKVIS_RETURN_IF_ERROR(
      h5::appendRow(m_axis->bondState.get(), ElementType::kUInt8, row, step.bondState.data()));
  if (m_axis->velocities.valid()) {
    CRACKVIS_RETURN_IF_ERROR(h5::appendRow(m_axis->velocities.get(), ElementType::kFloat32, row,
                                           step.velocities.data()));
  }
  if (m_axis->bondForce.valid()) {
    CRACKVIS_RETURN_IF_ERROR(
        h5::appendRow(m_axis->bondForce.get(), ElementType::kFloat32, row, step.bondForce.data()));
  }
  for (const StepAxis::Named& named : m_axis->scalars) {
    // A step without one of the first step's scalars stores NaN: "none".
    double value = std::numeric_limits<double>::quiet_NaN();
    for (const StepScalar& scalar : step.scalars) {
      value = scalar.name == named.name ? scalar.value : value;
    }
    CRACKVIS_RETURN_IF_ERROR(
        h5::appendRow(named.dataset.get(), ElementType::kFloat64, row, &value));
  }
  for (size_t i = 0; i < m_axis->extras.size(); ++i) {
    CRACKVIS_RETURN_IF_ERROR(h5::appendRow(m_axis->extras[i].dataset.get(), ElementType::kFloat64,
                                           row, step.extras[i].values.data()));
  }
  if (breaksChanged) {
    if (H5Dwrite(m_axis->breakStep.get(), H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                 m_breakStep.data()) < 0 ||
        H5Dflush(m_axis->breakStep.get()) < 0) {
      return internalError(
          fmt::format("cannot write dataset /bonds/break_step ({})", h5::lastHdf5Error()));
    }
  }
  return flush();
}

// The commit mark of an appendable file: /steps/time grows by the step's
// time only after every other array of the step is on disk.
Status DemFileWriter::commitStepRow(double time) {
  CRACKVIS_RETURN_IF_ERROR(h5::appendRow(m_axis->time.get(), ElementType::kFloat64,
                                         static_cast<std::uint64_t>(m_stepCount), &time));
  return flush();
}

}  // namespace crackvis::dem
