#include <algorithm>
#include <filesystem>
#include <limits>

#include <fmt/format.h>

#include <crackvis/dem/dem_file.hpp>

namespace crackvis::dem {
namespace {

using h5::ElementType;
using h5::Handle;

constexpr std::uint64_t kAnyExtent = std::numeric_limits<std::uint64_t>::max();

std::string formatExpected(const std::vector<std::uint64_t>& dims) {
  std::vector<std::string> parts;
  for (auto d : dims) {
    parts.push_back(d == kAnyExtent ? "*" : std::to_string(d));
  }
  return fmt::format("[{}]", fmt::join(parts, ","));
}

bool shapeMatches(const std::vector<std::uint64_t>& actual,
                  const std::vector<std::uint64_t>& expected) {
  if (actual.size() != expected.size()) {
    return false;
  }
  for (size_t i = 0; i < actual.size(); ++i) {
    if (expected[i] != kAnyExtent && expected[i] != actual[i]) {
      return false;
    }
  }
  return true;
}

// Step groups are named by their zero-padded index; anything else under
// /steps is not ours.
bool parseStepName(const char* name, int& index) {
  const std::string_view text(name);
  if (text.size() != 6 ||
      !std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return false;
  }
  index = std::stoi(std::string(text));
  return true;
}

struct StepNames {
  std::vector<int> indices;
  std::string unexpected;
};

herr_t collectStepName(hid_t, const char* name, const H5L_info_t*, void* data) {
  auto* names = static_cast<StepNames*>(data);
  int index = 0;
  if (parseStepName(name, index)) {
    names->indices.push_back(index);
  } else if (names->unexpected.empty()) {
    names->unexpected = name;
  }
  return 0;
}

}  // namespace

std::string stepGroupPath(int step) {
  return fmt::format("/steps/{:06d}", step);
}

// ---------------------------------------------------------------- reader --

Result<DemFileReader> DemFileReader::open(const std::string& path) {
  h5::quietHdf5();
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    return notFound(fmt::format("{}: no such file", path));
  }
  if (!std::filesystem::is_regular_file(path, error)) {
    return invalidArgument(fmt::format("{}: not a regular file", path));
  }
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    h5::lastHdf5Error();
    return failedPrecondition(fmt::format("{}: not an HDF5 file", path));
  }
  DemFileReader reader;
  reader.m_path = path;
  reader.m_info.path = path;
  reader.m_file = h5::fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!reader.m_file.valid()) {
    return failedPrecondition(fmt::format("{}: cannot open: file is truncated or corrupt ({})",
                                          path, h5::lastHdf5Error()));
  }
  CRACKVIS_RETURN_IF_ERROR(reader.readStructure());
  CRACKVIS_RETURN_IF_ERROR(reader.readSteps());
  return reader;
}

Status DemFileReader::fail(const Status& status) const {
  return {status.code(), fmt::format("{}: {}", m_path, status.message())};
}

Result<Handle> DemFileReader::openChecked(const std::string& path, ElementType type,
                                          const std::vector<std::uint64_t>& dims) const {
  if (!h5::linkExists(m_file.get(), path)) {
    return fail(failedPrecondition(fmt::format("missing dataset {}", path)));
  }
  Handle dataset = h5::datasetHandle(H5Dopen2(m_file.get(), path.c_str(), H5P_DEFAULT));
  if (!dataset.valid()) {
    return fail(failedPrecondition(
        fmt::format("{} is not a readable dataset ({})", path, h5::lastHdf5Error())));
  }
  auto shape = h5::describeDataset(dataset.get());
  if (!shape) {
    return fail(shape.status());
  }
  if (shape->type != type) {
    return fail(failedPrecondition(fmt::format("dataset {} has dtype {}, expected {}", path,
                                               shape->typeName, h5::elementTypeName(type))));
  }
  if (!shapeMatches(shape->dims, dims)) {
    std::vector<std::string> known;
    if (m_info.particleCount >= 0) {
      known.push_back(fmt::format("N = {}", m_info.particleCount));
    }
    if (m_info.bondCount >= 0) {
      known.push_back(fmt::format("M = {}", m_info.bondCount));
    }
    return fail(failedPrecondition(fmt::format(
        "dataset {} has shape {}, expected {}{}", path, h5::formatDims(shape->dims),
        formatExpected(dims), known.empty() ? "" : fmt::format(" ({})", fmt::join(known, ", ")))));
  }
  return dataset;
}

Status DemFileReader::readStructure() {
  const hid_t root = m_file.get();
  m_info.particleCount = -1;  // unknown until the datasets that carry them are read
  m_info.bondCount = -1;
  auto format = h5::readStringAttribute(root, "format");
  if (!format) {
    return fail(
        failedPrecondition(fmt::format("not a crackvis-dem file ({})", format.status().message())));
  }
  if (*format != kFormatName) {
    return fail(failedPrecondition(
        fmt::format("not a crackvis-dem file (root attribute 'format' is '{}', expected '{}')",
                    *format, kFormatName)));
  }
  m_info.format = *format;
  auto version = h5::readIntAttribute(root, "version");
  if (!version) {
    return fail(failedPrecondition(
        fmt::format("crackvis-dem file without a version ({})", version.status().message())));
  }
  if (*version != kFormatVersion) {
    return fail(failedPrecondition(
        fmt::format("unsupported crackvis-dem version {} (this build reads version {})", *version,
                    kFormatVersion)));
  }
  m_info.version = static_cast<int>(*version);
  auto dimension = h5::readIntAttribute(root, "dimension");
  if (!dimension) {
    return fail(dimension.status());
  }
  if (*dimension != 2 && *dimension != 3) {
    return fail(failedPrecondition(
        fmt::format("root attribute 'dimension' is {}, expected 2 or 3", *dimension)));
  }
  m_info.dimension = static_cast<int>(*dimension);
  if (auto units = h5::readStringAttribute(root, "units")) {
    m_info.units = *units;
  }
  if (auto source = h5::readStringAttribute(root, "source")) {
    m_info.source = *source;
  }

  // N and M come from the first dataset that carries them; every other
  // dataset must agree.
  auto radius = openChecked("/particles/radius", ElementType::kFloat64, {kAnyExtent});
  if (!radius) {
    return radius.status();
  }
  m_info.particleCount = static_cast<std::int64_t>(h5::describeDataset(radius->get())->dims[0]);
  auto pairs = openChecked("/bonds/pairs", ElementType::kInt32, {kAnyExtent, 2});
  if (!pairs) {
    return pairs.status();
  }
  const auto m = h5::describeDataset(pairs->get())->dims[0];
  m_info.bondCount = static_cast<std::int64_t>(m);
  for (const char* path : {"/bonds/strength"}) {
    if (auto dataset = openChecked(path, ElementType::kFloat64, {m}); !dataset) {
      return dataset.status();
    }
  }
  if (auto dataset = openChecked("/bonds/break_step", ElementType::kInt32, {m}); !dataset) {
    return dataset.status();
  }
  return Status::ok();
}

Status DemFileReader::readSteps() {
  if (!h5::linkExists(m_file.get(), "/steps")) {
    return fail(failedPrecondition("missing group /steps"));
  }
  Handle steps = h5::groupHandle(H5Gopen2(m_file.get(), "/steps", H5P_DEFAULT));
  if (!steps.valid()) {
    return fail(failedPrecondition(
        fmt::format("/steps is not a readable group ({})", h5::lastHdf5Error())));
  }
  auto count = h5::readIntAttribute(steps.get(), "count");
  if (!count) {
    return fail(failedPrecondition(fmt::format("group /steps: {}", count.status().message())));
  }
  StepNames names;
  if (H5Literate(steps.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr, collectStepName, &names) < 0) {
    return fail(failedPrecondition(
        fmt::format("cannot list /steps: file is truncated or corrupt ({})", h5::lastHdf5Error())));
  }
  if (!names.unexpected.empty()) {
    return fail(failedPrecondition(
        fmt::format("unexpected member /steps/{} (step groups are named 000000, 000001, ...)",
                    names.unexpected)));
  }
  std::sort(names.indices.begin(), names.indices.end());
  const auto complete = static_cast<int>(*count);
  if (complete < 0) {
    return fail(failedPrecondition(fmt::format("/steps attribute 'count' is {}", complete)));
  }
  for (int step = 0; step < complete; ++step) {
    if (!std::binary_search(names.indices.begin(), names.indices.end(), step)) {
      return fail(failedPrecondition(fmt::format("missing step group {} (/steps says {} steps)",
                                                 stepGroupPath(step), complete)));
    }
    Handle group =
        h5::groupHandle(H5Gopen2(m_file.get(), stepGroupPath(step).c_str(), H5P_DEFAULT));
    auto time = h5::readDoubleAttribute(group.get(), "time");
    if (!time) {
      return fail(failedPrecondition(
          fmt::format("step group {}: {}", stepGroupPath(step), time.status().message())));
    }
    m_info.steps.push_back({step, *time});
  }
  m_info.incompleteSteps = static_cast<int>(std::count_if(
      names.indices.begin(), names.indices.end(), [&](int i) { return i >= complete; }));
  return Status::ok();
}

Result<Lattice> DemFileReader::readLattice() const {
  Lattice lattice;
  lattice.dimension = m_info.dimension;
  const auto n = static_cast<std::uint64_t>(m_info.particleCount);
  const auto m = static_cast<std::uint64_t>(m_info.bondCount);
  lattice.radius.resize(n);
  lattice.bonds.resize(m);
  lattice.strength.resize(m);
  struct Part {
    const char* path;
    ElementType type;
    std::vector<std::uint64_t> dims;
    void* out;
  };
  for (const Part& part :
       {Part{"/particles/radius", ElementType::kFloat64, {n}, lattice.radius.data()},
        Part{"/bonds/pairs", ElementType::kInt32, {m, 2}, lattice.bonds.data()},
        Part{"/bonds/strength", ElementType::kFloat64, {m}, lattice.strength.data()}}) {
    auto dataset = openChecked(part.path, part.type, part.dims);
    if (!dataset) {
      return dataset.status();
    }
    if (Status read = h5::readDataset(dataset->get(), part.type, part.out); !read) {
      return fail(Status(read.code(), fmt::format("dataset {}: {}", part.path, read.message())));
    }
  }
  if (Status valid = validateLattice(lattice); !valid) {
    return fail(valid);
  }
  return lattice;
}

Result<std::vector<std::int32_t>> DemFileReader::readBreakSteps() const {
  const auto m = static_cast<std::uint64_t>(m_info.bondCount);
  auto dataset = openChecked("/bonds/break_step", ElementType::kInt32, {m});
  if (!dataset) {
    return dataset.status();
  }
  std::vector<std::int32_t> breakStep(m);
  if (Status read = h5::readDataset(dataset->get(), ElementType::kInt32, breakStep.data()); !read) {
    return fail(read);
  }
  for (size_t b = 0; b < breakStep.size(); ++b) {
    if (breakStep[b] < -1) {
      return fail(failedPrecondition(fmt::format(
          "/bonds/break_step[{}] is {}, expected -1 or a step index", b, breakStep[b])));
    }
  }
  return breakStep;
}

Status DemFileReader::checkStepIndex(int step) const {
  if (step < 0 || step >= stepCount()) {
    return fail(invalidArgument(
        fmt::format("step {} out of range (the file has steps 0..{})", step, stepCount() - 1)));
  }
  return Status::ok();
}

Result<StepState> DemFileReader::readStep(int step) const {
  CRACKVIS_RETURN_IF_ERROR(checkStepIndex(step));
  const auto n = static_cast<std::uint64_t>(m_info.particleCount);
  const auto m = static_cast<std::uint64_t>(m_info.bondCount);
  const std::string group = stepGroupPath(step);
  StepState state;
  state.time = m_info.steps[static_cast<size_t>(step)].time;
  state.positions.resize(n);
  state.bondState.resize(m);

  auto readInto = [&](const std::string& name, ElementType type,
                      const std::vector<std::uint64_t>& dims, void* out) -> Status {
    auto dataset = openChecked(group + "/" + name, type, dims);
    if (!dataset) {
      return dataset.status();
    }
    if (Status read = h5::readDataset(dataset->get(), type, out); !read) {
      return fail(
          Status(read.code(), fmt::format("dataset {}/{}: {}", group, name, read.message())));
    }
    return Status::ok();
  };
  CRACKVIS_RETURN_IF_ERROR(
      readInto("positions", ElementType::kFloat64, {n, 3}, state.positions.data()));
  CRACKVIS_RETURN_IF_ERROR(
      readInto("bond_state", ElementType::kUInt8, {m}, state.bondState.data()));
  if (h5::linkExists(m_file.get(), group + "/velocities")) {
    state.velocities.resize(n);
    CRACKVIS_RETURN_IF_ERROR(
        readInto("velocities", ElementType::kFloat32, {n, 3}, state.velocities.data()));
  }
  if (h5::linkExists(m_file.get(), group + "/bond_force")) {
    state.bondForce.resize(m);
    CRACKVIS_RETURN_IF_ERROR(
        readInto("bond_force", ElementType::kFloat32, {m}, state.bondForce.data()));
  }
  if (Status valid = validateStep(m_info.dimension, n, m, state); !valid) {
    return fail(Status(valid.code(), fmt::format("step {}: {}", step, valid.message())));
  }
  return state;
}

Result<std::vector<std::uint8_t>> DemFileReader::readBondState(int step) const {
  CRACKVIS_RETURN_IF_ERROR(checkStepIndex(step));
  const auto m = static_cast<std::uint64_t>(m_info.bondCount);
  const std::string path = stepGroupPath(step) + "/bond_state";
  auto dataset = openChecked(path, ElementType::kUInt8, {m});
  if (!dataset) {
    return dataset.status();
  }
  std::vector<std::uint8_t> state(m);
  if (Status read = h5::readDataset(dataset->get(), ElementType::kUInt8, state.data()); !read) {
    return fail(Status(read.code(), fmt::format("dataset {}: {}", path, read.message())));
  }
  for (size_t b = 0; b < m; ++b) {
    if (state[b] > 1) {
      return fail(failedPrecondition(
          fmt::format("step {}: state of bond {} is {}, expected 0 (intact) or 1 (broken)", step, b,
                      state[b])));
    }
  }
  return state;
}

// ---------------------------------------------------------------- writer --

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

  const hid_t root = writer.m_file.get();
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, "format", std::string(kFormatName)));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(root, "version", kFormatVersion));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(root, "dimension", lattice.dimension));
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, "units", metadata.units));
  CRACKVIS_RETURN_IF_ERROR(h5::writeStringAttribute(root, "source", metadata.source));

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
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(root, "/bonds/strength", ElementType::kFloat64, {m},
                                            lattice.strength.data()));
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(root, "/bonds/break_step", ElementType::kInt32, {m},
                                            writer.m_breakStep.data()));
  Handle steps = h5::groupHandle(H5Gopen2(root, "/steps", H5P_DEFAULT));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(steps.get(), "count", 0));
  if (H5Fflush(root, H5F_SCOPE_GLOBAL) < 0) {
    return internalError(fmt::format("{}: flush failed ({})", path, h5::lastHdf5Error()));
  }
  return writer;
}

Status DemFileWriter::recordBreaks(const StepState& step, bool& changed) {
  changed = false;
  for (size_t b = 0; b < m_breakStep.size(); ++b) {
    const bool broken = step.bondState[b] == static_cast<std::uint8_t>(BondState::kBroken);
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

  const hid_t root = m_file.get();
  const std::string path = stepGroupPath(m_stepCount);
  const auto n = static_cast<std::uint64_t>(m_lattice.particleCount());
  const auto m = static_cast<std::uint64_t>(m_lattice.bondCount());
  Handle group =
      h5::groupHandle(H5Gcreate2(root, path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!group.valid()) {
    return internalError(
        fmt::format("{}: cannot create group {} ({})", m_path, path, h5::lastHdf5Error()));
  }
  CRACKVIS_RETURN_IF_ERROR(h5::writeDoubleAttribute(group.get(), "time", step.time));
  CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(group.get(), "positions", ElementType::kFloat64, {n, 3},
                                            step.positions.data()));
  CRACKVIS_RETURN_IF_ERROR(
      h5::writeDataset(group.get(), "bond_state", ElementType::kUInt8, {m}, step.bondState.data()));
  if (!step.velocities.empty()) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(group.get(), "velocities", ElementType::kFloat32,
                                              {n, 3}, step.velocities.data()));
  }
  if (!step.bondForce.empty()) {
    CRACKVIS_RETURN_IF_ERROR(h5::writeDataset(group.get(), "bond_force", ElementType::kFloat32, {m},
                                              step.bondForce.data()));
  }
  if (breaksChanged) {
    CRACKVIS_RETURN_IF_ERROR(
        h5::overwriteDataset(root, "/bonds/break_step", ElementType::kInt32, m_breakStep.data()));
  }
  // The count is the commit mark: a reader ignores step groups past it, so a
  // writer killed in the middle of a step leaves the earlier steps valid.
  Handle steps = h5::groupHandle(H5Gopen2(root, "/steps", H5P_DEFAULT));
  CRACKVIS_RETURN_IF_ERROR(h5::writeIntAttribute(steps.get(), "count", m_stepCount + 1));
  if (H5Fflush(root, H5F_SCOPE_GLOBAL) < 0) {
    return internalError(fmt::format("{}: flush failed ({})", m_path, h5::lastHdf5Error()));
  }
  ++m_stepCount;
  return Status::ok();
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
