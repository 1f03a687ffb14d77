// DemFileWriter: creates a DEM file and appends steps to it.
#include <algorithm>

#include <fmt/format.h>

#include "dem_file_internal.hpp"
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::dem {
namespace {

using detail::ownerFolder;
using h5::Handle;

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
  writer.m_file = h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  if (!writer.m_file.valid()) {
    return failedPrecondition(
        fmt::format("{}: cannot create file ({})", path, h5::lastHdf5Error()));
  }
  writer.m_lattice = lattice;
  writer.m_breakStep.assign(lattice.bondCount(), -1);
  writer.m_storage = metadata.storage;
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
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(steps.get(), "count", 0));
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
  std::vector<std::int32_t> previous = m_breakStep;
  bool breaksChanged = false;
  if (Status breaks = recordBreaks(step, breaksChanged); !breaks) {
    m_breakStep = std::move(previous);
    return breaks;
  }

  // The step's data first, flushed; only then the commit mark, flushed
  // again. A write that fails (a full disk) leaves the file as the last
  // commit mark describes it, and the writer closed.
  Status written = writeStepData(step, breaksChanged);
  if (written) {
    written = flush();
  }
  if (written) {
    Handle steps = h5::groupHandle(H5Gopen2(m_file.get(), "/steps", H5P_DEFAULT));
    written = h5::writeIntAttribute(steps.get(), "count", m_stepCount + 1);
  }
  if (written) {
    written = flush();
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
  m_file.release();
  h5::lastHdf5Error();
}

Status DemFileWriter::close() {
  if (!m_file.valid()) {
    return Status::ok();
  }
  if (m_file.reset() < 0) {
    return internalError(fmt::format("{}: close failed ({})", m_path, h5::lastHdf5Error()));
  }
  return Status::ok();
}

}  // namespace crackvis::dem
