// A Describe and a Read of a small crackvis-dem file held in memory, for a
// fresh HDF5 worker to make before its first caller's file (catalogue.hpp).
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "catalogue_internal.hpp"
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::dataservice {
namespace h5 = crackvis::dem::h5;

namespace {

// Big enough for a few chunks of each kind of dataset, small enough to
// cost a fraction of a millisecond to write.
constexpr std::uint64_t kParticles = 512;
constexpr std::uint64_t kBonds = 1024;
constexpr int kSteps = 2;

// A file in HDF5's core driver that is never written to disk, so the worker
// needs no writable folder. Its name is one no open() can find: libhdf5
// first tries to open an existing file of the name (the core driver would
// read it in whole), and a worker's working folder may be the data root.
constexpr const char* kRehearsalName = "/dev/null/crackvis-worker-rehearsal.h5";

h5::Handle memoryFile() {
  h5::Handle access = h5::propertyListHandle(H5Pcreate(H5P_FILE_ACCESS));
  if (!access.valid() || H5Pset_fapl_core(access.get(), 1 << 20, /*backing_store=*/0) < 0) {
    return h5::fileHandle(-1);
  }
  return h5::fileHandle(H5Fcreate(kRehearsalName, H5F_ACC_TRUNC, H5P_DEFAULT, access.get()));
}

Status writeGroupWithDatasets(hid_t parent, const std::string& name,
                              const std::vector<double>& positions,
                              const std::vector<std::uint8_t>& states, double time) {
  h5::Handle group =
      h5::groupHandle(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!group.valid()) {
    return failedPrecondition(fmt::format("cannot create {} ({})", name, h5::lastHdf5Error()));
  }
  CRACKVIS_RETURN_IF_ERROR(h5::writeDoubleAttribute(group.get(), "time", time));
  CRACKVIS_RETURN_IF_ERROR(h5::writeDoubleAttribute(group.get(), "load", time * 2.0));
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(group.get(), "positions", h5::ElementType::kFloat64,
                                            {kParticles, 3}, positions.data()));
  // Chunked and deflated as `--compress` writes them: the filters' first use.
  h5::Storage compressed;
  compressed.deflateLevel = 1;
  compressed.chunkValues = kBonds / 4;
  return h5::writeDataset(group.get(), "bond_state", h5::ElementType::kUInt8, {kBonds},
                          states.data(), compressed);
}

// The root attributes, bonds, radii and steps of a crackvis-dem file.
Status writeRehearsalFile(hid_t file) {
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(file, "format", std::string(dem::kFormatName)));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(file, "version", 1));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(file, "dimension", 3));
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(file, "units", "SI"));
  std::vector<double> radii(kParticles, 0.5);
  std::vector<std::int32_t> pairs(kBonds * 2);
  for (std::uint64_t b = 0; b < kBonds; ++b) {
    pairs[2 * b] = static_cast<std::int32_t>(b % kParticles);
    pairs[2 * b + 1] = static_cast<std::int32_t>((b + 1 + b / kParticles) % kParticles);
  }
  std::vector<double> positions(kParticles * 3);
  for (std::uint64_t k = 0; k < positions.size(); ++k) {
    positions[k] = static_cast<double>(k % 97);
  }
  std::vector<std::uint8_t> states(kBonds, 0);
  for (const char* name : {"particles", "bonds", "steps"}) {
    h5::Handle group =
        h5::groupHandle(H5Gcreate2(file, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    if (!group.valid()) {
      return failedPrecondition(fmt::format("cannot create {} ({})", name, h5::lastHdf5Error()));
    }
  }
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(file, "/particles/radius", h5::ElementType::kFloat64,
                                            {kParticles}, radii.data()));
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeDataset(file, "/bonds/pairs", h5::ElementType::kInt32, {kBonds, 2}, pairs.data()));
  h5::Handle steps = h5::groupHandle(H5Gopen2(file, "/steps", H5P_DEFAULT));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(steps.get(), "count", kSteps));
  for (int k = 0; k < kSteps; ++k) {
    states[static_cast<std::size_t>(k)] = 1;
    CRACKVIS_RETURN_IF_ERROR(writeGroupWithDatasets(file, dem::stepGroupPath(k), positions, states,
                                                    0.1 * static_cast<double>(k)));
  }
  return Status::ok();
}

// Rows of a step's positions (a hyperslab, through the readers' own
// h5::readRowsAt) and the whole of a compressed dataset: the two kinds of
// read a view's Read makes.
Status readSlabs(hid_t file) {
  const std::string last = dem::stepGroupPath(kSteps - 1);
  h5::Handle positions =
      h5::datasetHandle(H5Dopen2(file, (last + "/positions").c_str(), H5P_DEFAULT));
  h5::Handle states =
      h5::datasetHandle(H5Dopen2(file, (last + "/bond_state").c_str(), H5P_DEFAULT));
  if (!positions.valid() || !states.valid()) {
    return failedPrecondition(fmt::format("cannot open {} ({})", last, h5::lastHdf5Error()));
  }
  std::vector<std::int32_t> rows(kParticles / 2);
  std::iota(rows.begin(), rows.end(), static_cast<std::int32_t>(kParticles / 4));
  std::vector<double> slab(rows.size() * 3);
  CRACKVIS_RETURN_IF_ERROR(
      h5::readRowsAt(positions.get(), h5::ElementType::kFloat64, -1, rows, slab.data()));
  std::vector<std::uint8_t> values(kBonds);
  return h5::readDataset(states.get(), h5::ElementType::kUInt8, values.data());
}

}  // namespace

Result<FileDescription> rehearseDescribeAndRead() {
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  h5::Handle file = memoryFile();
  if (!file.valid()) {
    return failedPrecondition(
        fmt::format("cannot create a file in memory ({})", h5::lastHdf5Error()));
  }
  CRACKVIS_RETURN_IF_ERROR(writeRehearsalFile(file.get()));
  auto description = describeOpenFile(file.get(), "(rehearsal)", DescribeOptions{});
  if (!description) {
    return description.status();
  }
  CRACKVIS_RETURN_IF_ERROR(readSlabs(file.get()));
  return description;
}

}  // namespace crackvis::dataservice
