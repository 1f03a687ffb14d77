// DemFileReader: opens a DEM file, checks its structure and reads it.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>

#include <fmt/format.h>

#include "dem_file_internal.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::dem {
namespace {

using detail::extraFolder;
using h5::Handle;

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

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

}  // namespace

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
  reader.m_file = h5::openReadOnly(path);
  if (!reader.m_file.valid()) {
    return failedPrecondition(fmt::format("{}: cannot open: {}", path, h5::openRefusal()));
  }
  CRACKVIS_RETURN_IF_ERROR(reader.readStructure());
  CRACKVIS_RETURN_IF_ERROR(reader.readSteps());
  CRACKVIS_RETURN_IF_ERROR(reader.listExtras());
  return reader;
}

Status DemFileReader::fail(const Status& status) const {
  return {status.code(), fmt::format("{}: {}", m_path, status.message())};
}

Result<DemFileReader::OpenedDataset> DemFileReader::openInFile(const std::string& path) const {
  auto resolved = h5::resolveInFile(m_file.get(), path);
  if (!resolved) {
    if (resolved.status().code() == StatusCode::kNotFound) {
      return fail(missingDataset(path));
    }
    return fail(
        failedPrecondition(fmt::format("dataset {}: {}; crackvis reads only data inside "
                                       "the file",
                                       path, resolved.status().message())));
  }
  Handle access = h5::noExternalLinks();
  Handle dataset = h5::datasetHandle(H5Dopen2(m_file.get(), resolved->c_str(), access.get()));
  if (!dataset.valid()) {
    return fail(failedPrecondition(
        fmt::format("{} is not a readable dataset ({})", path, h5::lastHdf5Error())));
  }
  auto shape = h5::describeDataset(dataset.get());
  if (!shape) {
    return fail(shape.status());
  }
  return OpenedDataset{std::move(dataset), std::move(*shape)};
}

Result<Handle> DemFileReader::openChecked(DemDataset id, int step) const {
  const bool row = datasetSpec(id).perStep && m_info.stepLayout == StepLayout::kAppendable;
  const std::string path = row ? appendablePath(id) : datasetPath(id, step);
  auto opened = row ? openStepAxis(path, step) : openInFile(path);
  if (!opened) {
    return opened.status();
  }
  const h5::DatasetShape* shape = &opened->shape;
  Handle dataset = std::move(opened->dataset);
  const LayoutSizes sizes{m_info.particleCount, m_info.bondCount};
  if (Status valid = checkDatasetHeader(id, row ? fmt::format("{} (step {})", path, step) : path,
                                        {shape->type, shape->typeName, shape->dims}, sizes);
      !valid) {
    return fail(valid);
  }
  return dataset;
}

Status DemFileReader::readStructure() {
  const hid_t root = m_file.get();
  m_info.particleCount = -1;  // unknown until the datasets that carry them are read
  m_info.bondCount = -1;
  RootAttributes attributes;
  attributes.format = h5::readStringAttribute(root, "format");
  if (attributes.format) {
    attributes.version = h5::readIntAttribute(root, "version");
    attributes.dimension = h5::readIntAttribute(root, "dimension");
  }
  auto dimension = checkRootAttributes(attributes);
  if (!dimension) {
    return fail(dimension.status());
  }
  m_info.format = *attributes.format;
  m_info.version = static_cast<int>(*attributes.version);
  m_info.dimension = *dimension;
  if (auto units = h5::readStringAttribute(root, "units")) {
    m_info.units = *units;
  }
  if (auto source = h5::readStringAttribute(root, "source")) {
    m_info.source = *source;
  }
  CRACKVIS_RETURN_IF_ERROR(readProvenance());

  // N and M come from the first dataset that carries them; every other
  // dataset must agree.
  auto radius = openChecked(DemDataset::kRadius);
  if (!radius) {
    return radius.status();
  }
  m_info.particleCount = static_cast<std::int64_t>(h5::describeDataset(radius->get())->dims[0]);
  auto pairs = openChecked(DemDataset::kPairs);
  if (!pairs) {
    return pairs.status();
  }
  m_info.bondCount = static_cast<std::int64_t>(h5::describeDataset(pairs->get())->dims[0]);
  CRACKVIS_RETURN_IF_ERROR(checkIndexable());
  // Kept, not returned: the file still opens, so a caller with size limits
  // reports those first (RESOURCE_EXHAUSTED); every read that allocates N or
  // M values returns this.
  m_countsStored = checkStored(DemDataset::kRadius, m_info.particleCount);
  if (m_countsStored) {
    m_countsStored = checkStored(DemDataset::kPairs, m_info.bondCount);
  }
  if (auto dataset = openChecked(DemDataset::kBreakStep); !dataset) {
    return dataset.status();
  }
  // Before v1.1 every file had strengths; now they and the new arrays are
  // optional, but checked whenever present.
  for (DemDataset id : {DemDataset::kStrength, DemDataset::kParticleId, DemDataset::kParticleGroup,
                        DemDataset::kBondFlags}) {
    if (!h5::linkExists(m_file.get(), datasetPath(id))) {
      if (id == DemDataset::kStrength && m_info.minorVersion < 1) {
        return fail(missingDataset(datasetPath(id)));
      }
      continue;
    }
    if (auto dataset = openChecked(id); !dataset) {
      return dataset.status();
    }
    m_info.hasStrength = m_info.hasStrength || id == DemDataset::kStrength;
  }
  return Status::ok();
}

// Particles and bonds are indexed by int32 (ParticleIndex, BondIndex, the
// int32 pairs): a file declaring more (a corrupt extent, 7.7e18 in one the
// fuzzer made) is refused before anything of that size is allocated.
Status DemFileReader::checkIndexable() const {
  constexpr std::int64_t kMaxIndexable = std::numeric_limits<std::int32_t>::max();
  if (m_info.particleCount < 0 || m_info.particleCount > kMaxIndexable || m_info.bondCount < 0 ||
      m_info.bondCount > kMaxIndexable) {
    return fail(failedPrecondition(fmt::format(
        "declares N = {} particles and M = {} bonds; crackvis indexes at most {} of each (file "
        "corrupt?)",
        static_cast<std::uint64_t>(m_info.particleCount),
        static_cast<std::uint64_t>(m_info.bondCount), kMaxIndexable)));
  }
  return Status::ok();
}

// N and M size every array the lattice allocates, so they must be backed by
// data the file really holds: a 20 KB file the fuzzer made declared 9e8
// radii in unwritten chunks (read as the fill value) and the reader
// allocated 7 GB for them. Deflate cannot compress more than about 1032:1,
// so a dataset claiming more than kMaxExpansion times its stored bytes is
// corrupt or unwritten, never a real packing.
Status DemFileReader::checkStored(DemDataset id, std::int64_t rows) const {
  constexpr std::uint64_t kRowBytes = 8;  // one float64 radius, or two int32 particle indices
  auto dataset = openChecked(id);
  if (!dataset) {
    return dataset.status();
  }
  return checkStoredBytes(dataset->get(), datasetPath(id), static_cast<std::uint64_t>(rows),
                          kRowBytes);
}

Status DemFileReader::checkStoredBytes(hid_t dataset, const std::string& path, std::uint64_t rows,
                                       std::uint64_t rowBytes) const {
  constexpr std::uint64_t kMaxExpansion = 1100;
  const std::uint64_t declared = rows * rowBytes;
  const std::uint64_t stored = h5::storedBytes(dataset);
  if (declared > 0 && (stored == 0 || declared / kMaxExpansion > stored)) {
    return fail(failedPrecondition(fmt::format(
        "dataset {} declares {} rows ({} bytes) but the file stores only {} bytes of it "
        "(unwritten or corrupt; deflate compresses at most about 1000:1)",
        path, rows, declared, stored)));
  }
  return Status::ok();
}

Status DemFileReader::readProvenance() {
  const hid_t root = m_file.get();
  if (H5Aexists(root, "version_minor") > 0) {
    auto minor = h5::readIntAttribute(root, "version_minor");
    if (!minor || *minor < 0) {
      return fail(
          failedPrecondition("root attribute 'version_minor' is not a non-negative integer"));
    }
    m_info.minorVersion = static_cast<int>(*minor);
  }
  if (auto code = h5::readStringAttribute(root, "source_code")) {
    m_info.sourceCode = *code;
  }
  if (auto version = h5::readStringAttribute(root, "source_version")) {
    m_info.sourceVersion = *version;
  }
  if (auto files = h5::readStringAttribute(root, "source_files")) {
    m_info.sourceFiles = splitLines(*files);
  }
  if (H5Aexists(root, kStepLayoutAttribute) > 0) {
    auto layout = h5::readStringAttribute(root, kStepLayoutAttribute);
    if (!layout || *layout != kAppendableName) {
      return fail(failedPrecondition(fmt::format(
          "root attribute '{}' is {}, expected '{}' (or absent: a group per step)",
          kStepLayoutAttribute, layout ? "'" + echoed(*layout) + "'" : std::string("not a string"),
          kAppendableName)));
    }
    m_info.stepLayout = StepLayout::kAppendable;
  }
  if (H5Aexists(root, kTimeUnitAttribute) > 0) {
    auto unit = h5::readStringAttribute(root, kTimeUnitAttribute);
    if (!unit || (*unit != "s" && *unit != kTimeInIterations)) {
      return fail(failedPrecondition(fmt::format(
          "root attribute '{}' is {}, expected 's' or '{}'", kTimeUnitAttribute,
          unit ? "'" + echoed(*unit) + "'" : std::string("not a string"), kTimeInIterations)));
    }
    m_info.timeUnit = *unit;
  }
  return Status::ok();
}

// Extra arrays are found by listing /extra/{particles,bonds} and step 0's
// extra groups; each must be float64 [N] / [N,3] (or M for bonds).
Status DemFileReader::listExtras() {
  // Per-step extras are listed from step 0, once it is complete.
  const bool anyStep = stepCount() > 0;
  for (bool perStep : {false, true}) {
    if (perStep && !anyStep) {
      continue;
    }
    for (ExtraOwner owner : {ExtraOwner::kParticles, ExtraOwner::kBonds}) {
      const std::string folder = extraFolder(owner, perStep, 0, m_info.stepLayout);
      auto resolved = h5::resolveInFile(m_file.get(), folder);
      if (!resolved) {
        if (resolved.status().code() == StatusCode::kNotFound) {
          continue;
        }
        return fail(
            failedPrecondition(fmt::format("group {}: {}; crackvis reads only data "
                                           "inside the file",
                                           folder, resolved.status().message())));
      }
      Handle group = h5::groupHandle(H5Gopen2(m_file.get(), resolved->c_str(), H5P_DEFAULT));
      if (!group.valid()) {
        return fail(failedPrecondition(
            fmt::format("{} is not a readable group ({})", folder, h5::lastHdf5Error())));
      }
      auto names = h5::memberNames(group.get());
      if (!names) {
        return fail(names.status());
      }
      for (const std::string& name : *names) {
        ExtraInfo extra{name, owner, 1, perStep};
        if (Status valid = validateName("extra array", name); !valid) {
          return fail(failedPrecondition(fmt::format("{}/{}: {}", folder, name, valid.message())));
        }
        auto dataset = openExtra(extra, 0);
        if (!dataset) {
          return dataset.status();
        }
        const auto& dims = dataset->shape.dims;
        extra.components = dims.size() == 2 ? static_cast<int>(dims[1]) : 1;
        m_info.extras.push_back(extra);
      }
    }
  }
  return Status::ok();
}

Result<DemFileReader::OpenedDataset> DemFileReader::openExtra(const ExtraInfo& extra,
                                                              int step) const {
  const std::string path = extraPath(extra, step, m_info.stepLayout);
  const bool row = extra.perStep && m_info.stepLayout == StepLayout::kAppendable;
  auto opened = row ? openStepAxis(path, step) : openInFile(path);
  if (!opened) {
    return opened.status();
  }
  const h5::DatasetShape* shape = &opened->shape;
  const std::int64_t rows =
      extra.owner == ExtraOwner::kParticles ? m_info.particleCount : m_info.bondCount;
  const bool rowsMatch = !shape->dims.empty() && shape->dims[0] == static_cast<std::uint64_t>(rows);
  const bool widthValid = shape->dims.size() == 1 ||
                          (shape->dims.size() == 2 && (shape->dims[1] == 1 || shape->dims[1] == 3));
  if (shape->type != ElementType::kFloat64 || !rowsMatch || !widthValid) {
    return fail(failedPrecondition(
        fmt::format("dataset {} is {} {}, expected float64 [{}] or [{},3] ({} = {})", path,
                    shape->typeName, h5::formatDims(shape->dims), rows, rows,
                    extra.owner == ExtraOwner::kParticles ? "N" : "M", rows)));
  }
  return opened;
}

Result<ExtraArray> DemFileReader::readExtra(const ExtraInfo& extra, int step) const {
  auto dataset = openExtra(extra, step);
  if (!dataset) {
    return dataset.status();
  }
  const auto& dims = dataset->shape.dims;
  ExtraArray array{extra.name, extra.owner, dims.size() == 2 ? static_cast<int>(dims[1]) : 1, {}};
  array.values.resize(dims[0] * static_cast<std::uint64_t>(array.components));
  const hid_t id = dataset->dataset.get();
  const Status read = extra.perStep && m_info.stepLayout == StepLayout::kAppendable
                          ? h5::readRow(id, ElementType::kFloat64, static_cast<std::uint64_t>(step),
                                        array.values.data())
                          : h5::readDataset(id, ElementType::kFloat64, array.values.data());
  if (!read) {
    return fail(Status(
        read.code(),
        fmt::format("dataset {}: {}", extraPath(extra, step, m_info.stepLayout), read.message())));
  }
  return array;
}

Result<std::vector<StepScalar>> DemFileReader::readScalars(hid_t stepGroup, int step) const {
  auto names = h5::attributeNames(stepGroup);
  if (!names) {
    return fail(Status(names.status().code(), fmt::format("step group {}: {}", stepGroupPath(step),
                                                          names.status().message())));
  }
  std::vector<StepScalar> scalars;
  for (const std::string& name : *names) {
    if (name == "time") {
      continue;
    }
    auto value = h5::readDoubleAttribute(stepGroup, name);
    if (!value) {
      return fail(failedPrecondition(fmt::format(
          "step group {}: scalar '{}': {}", stepGroupPath(step), name, value.status().message())));
    }
    scalars.push_back({name, *value});
  }
  return scalars;
}

Status DemFileReader::readSteps() {
  auto stepsPath = h5::resolveInFile(m_file.get(), "/steps");
  if (!stepsPath) {
    return fail(
        failedPrecondition(stepsPath.status().code() == StatusCode::kNotFound
                               ? std::string("missing group /steps")
                               : fmt::format("group /steps: {}", stepsPath.status().message())));
  }
  Handle steps = h5::groupHandle(H5Gopen2(m_file.get(), stepsPath->c_str(), H5P_DEFAULT));
  if (!steps.valid()) {
    return fail(failedPrecondition(
        fmt::format("/steps is not a readable group ({})", h5::lastHdf5Error())));
  }
  if (auto planned = h5::readIntAttribute(steps.get(), kPlannedStepsAttribute)) {
    m_info.plannedSteps = *planned;
  }
  m_info.steps.clear();
  m_info.scalarNames.clear();
  return m_info.stepLayout == StepLayout::kAppendable ? readAppendableSteps()
                                                      : readGroupSteps(steps.get());
}

Status DemFileReader::refreshSteps() {
  const std::vector<StepInfo> before = m_info.steps;
  CRACKVIS_RETURN_IF_ERROR(readSteps());
  if (m_info.steps.size() < before.size()) {
    // Steps are committed for good; fewer now means another file.
    return fail(failedPrecondition(
        fmt::format("had {} complete steps, now {}: the file was replaced while it was read",
                    before.size(), m_info.steps.size())));
  }
  if (before.empty() && !m_info.steps.empty()) {
    m_info.extras.clear();  // per-step extras are listed from step 0, now there
    return listExtras();
  }
  return Status::ok();
}

Status DemFileReader::readGroupSteps(hid_t steps) {
  auto count = h5::readIntAttribute(steps, "count");
  if (!count) {
    return fail(failedPrecondition(fmt::format("group /steps: {}", count.status().message())));
  }
  StepNames names;
  if (H5Literate(steps, H5_INDEX_NAME, H5_ITER_INC, nullptr, collectStepName, &names) < 0) {
    return fail(failedPrecondition(
        fmt::format("cannot list /steps: file is truncated or corrupt ({})", h5::lastHdf5Error())));
  }
  if (!names.unexpected.empty()) {
    return fail(failedPrecondition(
        fmt::format("unexpected member /steps/{} (step groups are named 000000, 000001, ...)",
                    names.unexpected)));
  }
  std::sort(names.indices.begin(), names.indices.end());
  const StepList list = listSteps(*count, [&](int step) -> std::optional<Result<double>> {
    if (!std::binary_search(names.indices.begin(), names.indices.end(), step)) {
      return std::nullopt;
    }
    auto group = h5::resolveInFile(m_file.get(), stepGroupPath(step));
    if (!group) {
      return Result<double>(group.status());
    }
    Handle handle = h5::groupHandle(H5Gopen2(m_file.get(), group->c_str(), H5P_DEFAULT));
    return h5::readDoubleAttribute(handle.get(), "time");
  });
  if (!list.problem) {
    return fail(list.problem);
  }
  for (const auto& [index, time] : list.steps) {
    Handle group =
        h5::groupHandle(H5Gopen2(m_file.get(), stepGroupPath(index).c_str(), H5P_DEFAULT));
    auto scalars = readScalars(group.get(), index);
    if (!scalars) {
      return scalars.status();
    }
    for (const StepScalar& scalar : *scalars) {
      if (std::find(m_info.scalarNames.begin(), m_info.scalarNames.end(), scalar.name) ==
          m_info.scalarNames.end()) {
        m_info.scalarNames.push_back(scalar.name);
      }
    }
    m_info.steps.push_back({index, time, std::move(*scalars)});
  }
  const auto complete = static_cast<int>(*count);
  m_info.incompleteSteps = static_cast<int>(std::count_if(
      names.indices.begin(), names.indices.end(), [&](int i) { return i >= complete; }));
  return Status::ok();
}

// The appendable layout: the length of /steps/time is the number of
// complete steps (the writer grows it last, after every other array of the
// step is on disk); longer per-step arrays hold an unfinished step.
Status DemFileReader::readAppendableSteps() {
  auto time = openInFile(kStepTimePath);
  if (!time) {
    return time.status();
  }
  CRACKVIS_RETURN_IF_ERROR(refreshed(kStepTimePath, time->dataset.get()));
  auto shape = h5::describeDataset(time->dataset.get());
  if (!shape || shape->type != ElementType::kFloat64 || shape->dims.size() != 1) {
    return fail(failedPrecondition(fmt::format(
        "dataset {} is {} {}, expected float64 [K]", kStepTimePath,
        shape ? shape->typeName : "unreadable", shape ? h5::formatDims(shape->dims) : "")));
  }
  constexpr std::uint64_t kMaxSteps = 1'000'000;
  const std::uint64_t count = shape->dims[0];
  if (count > kMaxSteps) {
    return fail(failedPrecondition(
        fmt::format("dataset {} holds {} steps, more than {}", kStepTimePath, count, kMaxSteps)));
  }
  std::vector<double> times(count);
  if (Status read =
          h5::readLeading(time->dataset.get(), ElementType::kFloat64, count, times.data());
      !read) {
    return fail(Status(read.code(), fmt::format("dataset {}: {}", kStepTimePath, read.message())));
  }
  for (std::uint64_t k = 0; k < count; ++k) {
    m_info.steps.push_back({static_cast<int>(k), times[k], {}});
  }
  CRACKVIS_RETURN_IF_ERROR(readAppendableScalars(count));
  m_info.incompleteSteps = 0;
  if (h5::linkExists(m_file.get(), appendablePath(DemDataset::kPositions))) {
    if (auto positions = openInFile(appendablePath(DemDataset::kPositions))) {
      CRACKVIS_RETURN_IF_ERROR(
          refreshed(appendablePath(DemDataset::kPositions), positions->dataset.get()));
      if (auto rows = h5::describeDataset(positions->dataset.get());
          rows && !rows->dims.empty() && rows->dims[0] > count) {
        m_info.incompleteSteps = static_cast<int>(rows->dims[0] - count);
      }
    }
  } else if (count > 0) {
    return fail(missingDataset(appendablePath(DemDataset::kPositions)));
  }
  m_info.beingWritten = false;
  if (h5::linkExists(m_file.get(), kStepsWritingPath)) {
    if (auto writing = openInFile(kStepsWritingPath)) {
      CRACKVIS_RETURN_IF_ERROR(refreshed(kStepsWritingPath, writing->dataset.get()));
      std::int32_t flag = 0;
      if (writing->shape.dims.empty() &&
          h5::readDataset(writing->dataset.get(), ElementType::kInt32, &flag)) {
        m_info.beingWritten = flag != 0;
      }
    }
  }
  return Status::ok();
}

// /steps/scalars/NAME, float64 [>= K]: a NaN is a step without that scalar.
Status DemFileReader::readAppendableScalars(std::uint64_t count) {
  if (!h5::linkExists(m_file.get(), kStepScalarsPath)) {
    return Status::ok();
  }
  Handle group = h5::groupHandle(H5Gopen2(m_file.get(), kStepScalarsPath, H5P_DEFAULT));
  auto names = group.valid() ? h5::memberNames(group.get())
                             : Result<std::vector<std::string>>(failedPrecondition(
                                   fmt::format("{} is not a readable group", kStepScalarsPath)));
  if (!names) {
    return fail(names.status());
  }
  for (const std::string& name : *names) {
    const std::string path = fmt::format("{}/{}", kStepScalarsPath, name);
    if (Status valid = validateName("step scalar", name); !valid) {
      return fail(failedPrecondition(fmt::format("{}: {}", path, valid.message())));
    }
    auto dataset = openInFile(path);
    if (!dataset) {
      return dataset.status();
    }
    CRACKVIS_RETURN_IF_ERROR(refreshed(path, dataset->dataset.get()));
    auto shape = h5::describeDataset(dataset->dataset.get());
    if (!shape || shape->type != ElementType::kFloat64 || shape->dims.size() != 1 ||
        shape->dims[0] < count) {
      return fail(
          failedPrecondition(fmt::format("dataset {} is {} {}, expected float64 [{}] or longer",
                                         path, shape ? shape->typeName : "unreadable",
                                         shape ? h5::formatDims(shape->dims) : "", count)));
    }
    std::vector<double> values(count);
    if (Status read =
            h5::readLeading(dataset->dataset.get(), ElementType::kFloat64, count, values.data());
        !read) {
      return fail(Status(read.code(), fmt::format("dataset {}: {}", path, read.message())));
    }
    m_info.scalarNames.push_back(name);
    for (std::uint64_t k = 0; k < count; ++k) {
      if (!std::isnan(values[k])) {
        m_info.steps[k].scalars.push_back({name, values[k]});
      }
    }
  }
  return Status::ok();
}

Status DemFileReader::refreshed(const std::string& path, hid_t dataset) const {
  if (Status status = h5::refreshDataset(dataset); !status) {
    return fail(failedPrecondition(fmt::format("dataset {}: {}", path, status.message())));
  }
  return Status::ok();
}

std::string DemFileReader::stepDatasetPath(DemDataset id, int step) const {
  return m_info.stepLayout == StepLayout::kAppendable ? appendablePath(id) : datasetPath(id, step);
}

Result<DemFileReader::OpenedDataset> DemFileReader::openStepAxis(const std::string& path,
                                                                 int step) const {
  auto opened = openInFile(path);
  if (!opened) {
    return opened;
  }
  const auto row = static_cast<std::uint64_t>(step);
  if (opened->shape.dims.empty() || opened->shape.dims[0] <= row) {
    // This process may hold the dataset's metadata from before the writer
    // added the row.
    CRACKVIS_RETURN_IF_ERROR(refreshed(path, opened->dataset.get()));
    auto shape = h5::describeDataset(opened->dataset.get());
    if (!shape) {
      return fail(shape.status());
    }
    opened->shape = std::move(*shape);
  }
  if (opened->shape.dims.empty() || opened->shape.dims[0] <= row) {
    return fail(failedPrecondition(fmt::format("dataset {} has shape {}, without a row for step {}",
                                               path, h5::formatDims(opened->shape.dims), step)));
  }
  opened->shape.dims.erase(opened->shape.dims.begin());  // the shape of one step's row
  return opened;
}

Result<Lattice> DemFileReader::readLattice() const {
  Lattice lattice;
  lattice.dimension = m_info.dimension;
  const auto n = static_cast<std::uint64_t>(m_info.particleCount);
  const auto m = static_cast<std::uint64_t>(m_info.bondCount);
  CRACKVIS_RETURN_IF_ERROR(m_countsStored);
  lattice.radius.resize(n);
  lattice.bonds.resize(m);
  CRACKVIS_RETURN_IF_ERROR(readWhole(DemDataset::kRadius, 0, lattice.radius.data()));
  CRACKVIS_RETURN_IF_ERROR(readWhole(DemDataset::kPairs, 0, lattice.bonds.data()));
  CRACKVIS_RETURN_IF_ERROR(readOptional(DemDataset::kStrength, m, lattice.strength));
  CRACKVIS_RETURN_IF_ERROR(readOptional(DemDataset::kParticleId, n, lattice.particleId));
  CRACKVIS_RETURN_IF_ERROR(readOptional(DemDataset::kParticleGroup, n, lattice.particleGroup));
  CRACKVIS_RETURN_IF_ERROR(readOptional(DemDataset::kBondFlags, m, lattice.bondFlags));
  for (const ExtraInfo& extra : m_info.extras) {
    if (!extra.perStep) {
      auto array = readExtra(extra, 0);
      if (!array) {
        return array.status();
      }
      lattice.extras.push_back(std::move(*array));
    }
  }
  if (Status valid = validateLattice(lattice); !valid) {
    return fail(failedPrecondition(valid.message()));
  }
  return lattice;
}

Status DemFileReader::readWhole(DemDataset id, int step, void* out) const {
  auto dataset = openChecked(id, step);
  if (!dataset) {
    return dataset.status();
  }
  const DatasetSpec& spec = datasetSpec(id);
  const Status read =
      spec.perStep && m_info.stepLayout == StepLayout::kAppendable
          ? h5::readRow(dataset->get(), spec.type, static_cast<std::uint64_t>(step), out)
          : h5::readDataset(dataset->get(), spec.type, out);
  if (!read) {
    return fail(Status(read.code(),
                       fmt::format("dataset {}: {}", stepDatasetPath(id, step), read.message())));
  }
  return Status::ok();
}

// An optional time-independent array: `count` values when the file has it,
// empty when not.
template <typename T>
Status DemFileReader::readOptional(DemDataset id, std::uint64_t count, std::vector<T>& out) const {
  out.clear();
  if (!h5::linkExists(m_file.get(), datasetPath(id))) {
    return Status::ok();
  }
  out.resize(count);
  return readWhole(id, 0, out.data());
}

Result<std::vector<std::int32_t>> DemFileReader::readBreakSteps() const {
  CRACKVIS_RETURN_IF_ERROR(m_countsStored);
  std::vector<std::int32_t> breakStep(static_cast<std::uint64_t>(m_info.bondCount));
  CRACKVIS_RETURN_IF_ERROR(readWhole(DemDataset::kBreakStep, 0, breakStep.data()));
  for (size_t b = 0; b < breakStep.size(); ++b) {
    if (breakStep[b] < -1) {
      return fail(failedPrecondition(fmt::format(
          "/bonds/break_step[{}] is {}, expected -1 or a step index", b, breakStep[b])));
    }
  }
  return breakStep;
}

namespace {

// `recycled` ready to take a step of n particles and m bonds: its arrays
// keep their memory (a vector resized to the size it has is left as it is;
// the read overwrites its values). The optional arrays are sized, or
// emptied, by the read.
StepState reuse(StepState recycled, std::uint64_t n, std::uint64_t m) {
  StepState state = std::move(recycled);
  state.positions.resize(n);
  state.bondState.resize(m);
  state.scalars.clear();
  state.extras.clear();
  return state;
}

}  // namespace

Result<StepState> DemFileReader::readStep(int step, StepState recycled) const {
  CRACKVIS_RETURN_IF_ERROR(checkStepInRange(m_path, step, stepCount()));
  CRACKVIS_RETURN_IF_ERROR(m_countsStored);
  const auto n = static_cast<std::uint64_t>(m_info.particleCount);
  const auto m = static_cast<std::uint64_t>(m_info.bondCount);
  StepState state = reuse(std::move(recycled), n, m);
  state.time = m_info.steps[static_cast<size_t>(step)].time;
  CRACKVIS_RETURN_IF_ERROR(readWhole(DemDataset::kPositions, step, state.positions.data()));
  CRACKVIS_RETURN_IF_ERROR(readWhole(DemDataset::kBondState, step, state.bondState.data()));
  if (h5::linkExists(m_file.get(), stepDatasetPath(DemDataset::kVelocities, step))) {
    state.velocities.resize(n);
    CRACKVIS_RETURN_IF_ERROR(readWhole(DemDataset::kVelocities, step, state.velocities.data()));
  } else {
    state.velocities.clear();
  }
  if (h5::linkExists(m_file.get(), stepDatasetPath(DemDataset::kBondForce, step))) {
    state.bondForce.resize(m);
    CRACKVIS_RETURN_IF_ERROR(readWhole(DemDataset::kBondForce, step, state.bondForce.data()));
  } else {
    state.bondForce.clear();
  }
  state.scalars = m_info.steps[static_cast<size_t>(step)].scalars;
  for (const ExtraInfo& extra : m_info.extras) {
    if (extra.perStep) {
      auto array = readExtra(extra, step);
      if (!array) {
        return array.status();
      }
      state.extras.push_back(std::move(*array));
    }
  }
  if (Status valid = validateStep(m_info.dimension, n, m, state); !valid) {
    return fail(failedPrecondition(fmt::format("step {}: {}", step, valid.message())));
  }
  return state;
}

Result<std::vector<std::uint8_t>> DemFileReader::readBondState(int step) const {
  CRACKVIS_RETURN_IF_ERROR(checkStepInRange(m_path, step, stepCount()));
  CRACKVIS_RETURN_IF_ERROR(m_countsStored);
  std::vector<std::uint8_t> state(static_cast<std::uint64_t>(m_info.bondCount));
  CRACKVIS_RETURN_IF_ERROR(readWhole(DemDataset::kBondState, step, state.data()));
  if (Status valid = validateBondStates(state); !valid) {
    return fail(failedPrecondition(fmt::format("step {}: {}", step, valid.message())));
  }
  return state;
}

// --- The spatial index and partial reads -----------------------------------

Result<Handle> DemFileReader::openIndexDataset(const char* path, ElementType type,
                                               std::vector<std::uint64_t> dims) const {
  auto opened = openInFile(path);
  if (!opened) {
    return opened.status();
  }
  if (opened->shape.type != type || opened->shape.dims != dims) {
    return fail(failedPrecondition(
        fmt::format("dataset {} is {} {}, expected {} {} (N = {})", path, opened->shape.typeName,
                    h5::formatDims(opened->shape.dims), elementTypeName(type), h5::formatDims(dims),
                    m_info.particleCount)));
  }
  return std::move(opened->dataset);
}

Result<std::optional<SpatialIndexInfo>> DemFileReader::readSpatialIndexInfo() const {
  if (!h5::linkExists(m_file.get(), kSpatialIndexGroup)) {
    return std::optional<SpatialIndexInfo>{};
  }
  auto resolved = h5::resolveInFile(m_file.get(), kSpatialIndexGroup);
  if (!resolved) {
    return fail(failedPrecondition(
        fmt::format("group {}: {}", kSpatialIndexGroup, resolved.status().message())));
  }
  Handle group = h5::groupHandle(H5Gopen2(m_file.get(), resolved->c_str(), H5P_DEFAULT));
  auto axis = h5::readIntAttribute(group.get(), "axis");
  auto radius = h5::readDoubleAttribute(group.get(), "largest_radius");
  auto longest = h5::readDoubleAttribute(group.get(), "longest_bond");
  if (!group.valid() || !axis || *axis < 0 || *axis > 2 || !radius || !std::isfinite(*radius) ||
      !longest || !std::isfinite(*longest) || *longest < 0.0) {
    return fail(failedPrecondition(
        fmt::format("group {}: needs attributes axis (0, 1 or 2), largest_radius and "
                    "longest_bond (finite, >= 0)",
                    kSpatialIndexGroup)));
  }
  SpatialIndexInfo info;
  info.axis = static_cast<int>(*axis);
  info.largestRadius = *radius;
  info.longestBond = *longest;
  if (H5Aexists(group.get(), "decomposition") > 0) {
    auto name = h5::readStringAttribute(group.get(), "decomposition");
    info.decomposition = name ? decompositionNamed(*name) : CellDecomposition::kUnknown;
    if (info.decomposition == CellDecomposition::kUnknown) {
      return fail(failedPrecondition(fmt::format(
          "{}@decomposition is {}, expected 'lattice' or 'triangulation'", kSpatialIndexGroup,
          name ? "'" + echoed(*name) + "'" : std::string("not a string"))));
    }
  }
  const auto n = static_cast<std::uint64_t>(m_info.particleCount);
  auto box = openIndexDataset(kIndexBoxPath, ElementType::kFloat64, {2, 3});
  if (!box) {
    return box.status();
  }
  std::array<Vec3, 2> corners{};
  if (Status read = h5::readDataset(box->get(), ElementType::kFloat64, corners.data()); !read) {
    return fail(read);
  }
  info.box = {corners[0], corners[1]};
  if (auto order = openIndexDataset(kIndexOrderPath, ElementType::kInt32, {n}); !order) {
    return order.status();
  }
  if (auto coordinate = openIndexDataset(kIndexCoordinatePath, ElementType::kFloat64, {n});
      !coordinate) {
    return coordinate.status();
  }
  if (h5::linkExists(m_file.get(), kIndexBondStartPath)) {
    if (auto dataset = openIndexDataset(kIndexBondStartPath, ElementType::kInt64, {n + 1});
        !dataset) {
      return dataset.status();
    }
    info.hasBondStart = true;
  }
  if (h5::linkExists(m_file.get(), kIndexWideCellsPath)) {
    CRACKVIS_RETURN_IF_ERROR(readWideCellsInfo(group.get(), info));
  }
  return std::optional<SpatialIndexInfo>{info};
}

// /index/wide_cells' shape and the attributes that go with it.
Status DemFileReader::readWideCellsInfo(hid_t group, SpatialIndexInfo& info) const {
  CRACKVIS_RETURN_IF_ERROR(checkCellListShape(kIndexWideCellsPath));
  auto reach = h5::readDoubleAttribute(group, "wide_cell_reach");
  auto weighted = h5::readIntAttribute(group, "weighted_triangulation");
  if (!reach || !std::isfinite(*reach) || *reach < 0.0 || !weighted ||
      (*weighted != 0 && *weighted != 1)) {
    return fail(failedPrecondition(
        fmt::format("group {} holds {} but not its attributes wide_cell_reach (finite, >= 0) and "
                    "weighted_triangulation (0 or 1)",
                    kSpatialIndexGroup, kIndexWideCellsPath)));
  }
  info.hasWideCells = true;
  info.wideCellReach = *reach;
  info.weightedTriangulation = *weighted == 1;
  if (h5::linkExists(m_file.get(), kIndexPeeledCellsPath)) {
    CRACKVIS_RETURN_IF_ERROR(checkCellListShape(kIndexPeeledCellsPath));
    info.hasPeeledCells = true;
  }
  return Status::ok();
}

Status DemFileReader::checkCellListShape(const char* path) const {
  auto opened = openInFile(path);
  if (!opened) {
    return opened.status();
  }
  const h5::DatasetShape& shape = opened->shape;
  if (shape.type != ElementType::kInt32 || shape.dims.size() != 2 || shape.dims[1] != 4) {
    return fail(failedPrecondition(fmt::format("dataset {} is {} {}, expected int32 [K, 4]", path,
                                               shape.typeName, h5::formatDims(shape.dims))));
  }
  // Rows the file does not store are refused before they are allocated,
  // as they are for the lattice's arrays.
  return checkStoredBytes(opened->dataset.get(), path, shape.dims[0], 16);
}

Result<std::optional<WideCells>> DemFileReader::readWideCells() const {
  auto index = readSpatialIndexInfo();
  if (!index) {
    return index.status();
  }
  if (!*index) {
    return std::optional<WideCells>{};
  }
  return readWideCells(**index);
}

Result<std::optional<WideCells>> DemFileReader::readWideCells(const SpatialIndexInfo& index) const {
  if (!index.hasWideCells) {
    return std::optional<WideCells>{};
  }
  WideCells wide;
  wide.reach = index.wideCellReach;
  wide.weighted = index.weightedTriangulation;
  auto cells = readCellList(kIndexWideCellsPath);
  if (!cells) {
    return cells.status();
  }
  wide.cells = std::move(*cells);
  if (index.hasPeeledCells) {
    auto peeled = readCellList(kIndexPeeledCellsPath);
    if (!peeled) {
      return peeled.status();
    }
    // Sorted as the writer stores them, whatever a file says: a rank takes
    // them out of its cells by a sorted difference.
    std::sort(peeled->begin(), peeled->end());
    wide.peeled = std::move(*peeled);
  }
  return std::optional<WideCells>{std::move(wide)};
}

// A [K, 4] list of cells under /index, checked: nodes ascending particle
// indices, in 2D the fourth -1.
Result<std::vector<std::array<ParticleIndex, 4>>> DemFileReader::readCellList(
    const char* path) const {
  auto opened = openInFile(path);
  if (!opened) {
    return opened.status();
  }
  std::vector<std::array<ParticleIndex, 4>> cells(static_cast<std::size_t>(opened->shape.dims[0]));
  if (!cells.empty()) {
    if (Status read = h5::readDataset(opened->dataset.get(), ElementType::kInt32, cells.data());
        !read) {
      return fail(read);
    }
  }
  const auto last = static_cast<ParticleIndex>(m_info.particleCount - 1);
  const int nodes = m_info.dimension == 3 ? 4 : 3;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const auto& cell = cells[c];
    bool good = nodes == 4 || cell[3] == -1;
    for (int k = 0; k < nodes && good; ++k) {
      const ParticleIndex node = cell[static_cast<std::size_t>(k)];
      good = node >= 0 && node <= last && (k == 0 || cell[static_cast<std::size_t>(k) - 1] < node);
    }
    if (!good) {
      return fail(failedPrecondition(fmt::format(
          "{} row {} is [{}, {}, {}, {}]: expected {} ascending particle indices in 0..{}{}", path,
          c, cell[0], cell[1], cell[2], cell[3], nodes, last, nodes == 3 ? ", then -1" : "")));
    }
  }
  return cells;
}

Result<std::vector<ParticleIndex>> DemFileReader::readIndexOrder(std::int64_t first,
                                                                 std::int64_t last) const {
  if (first < 0 || last < first || last > m_info.particleCount) {
    return fail(outOfRange(fmt::format("{}[{}, {}) asked of N = {}", kIndexOrderPath, first, last,
                                       m_info.particleCount)));
  }
  const auto n = static_cast<std::uint64_t>(m_info.particleCount);
  auto dataset = openIndexDataset(kIndexOrderPath, ElementType::kInt32, {n});
  if (!dataset) {
    return dataset.status();
  }
  std::vector<std::int32_t> rows(static_cast<std::size_t>(last - first));
  std::iota(rows.begin(), rows.end(), static_cast<std::int32_t>(first));
  std::vector<ParticleIndex> order(rows.size());
  if (Status read = h5::readRowsAt(dataset->get(), ElementType::kInt32, -1, rows, order.data());
      !read) {
    return fail(read);
  }
  for (ParticleIndex i : order) {
    if (i < 0 || i >= m_info.particleCount) {
      return fail(failedPrecondition(fmt::format("{} names particle {}, outside 0..{}",
                                                 kIndexOrderPath, i, m_info.particleCount - 1)));
    }
  }
  return order;
}

Result<double> DemFileReader::readIndexCoordinate(std::int64_t k) const {
  const auto n = static_cast<std::uint64_t>(m_info.particleCount);
  auto dataset = openIndexDataset(kIndexCoordinatePath, ElementType::kFloat64, {n});
  if (!dataset) {
    return dataset.status();
  }
  if (k < 0 || k >= m_info.particleCount) {
    return fail(outOfRange(fmt::format("{}[{}] asked of N = {}", kIndexCoordinatePath, k, n)));
  }
  const std::array<std::int32_t, 1> row{static_cast<std::int32_t>(k)};
  double value = 0.0;
  if (Status read = h5::readRowsAt(dataset->get(), ElementType::kFloat64, -1, row, &value); !read) {
    return fail(read);
  }
  return value;
}

Result<std::vector<std::int64_t>> DemFileReader::readBondStarts(
    std::span<const std::int32_t> rows) const {
  const auto n = static_cast<std::uint64_t>(m_info.particleCount);
  auto dataset = openIndexDataset(kIndexBondStartPath, ElementType::kInt64, {n + 1});
  if (!dataset) {
    return dataset.status();
  }
  std::vector<std::int64_t> starts(rows.size());
  if (Status read = h5::readRowsAt(dataset->get(), ElementType::kInt64, -1, rows, starts.data());
      !read) {
    return fail(Status(read.code(), fmt::format("{}: {}", kIndexBondStartPath, read.message())));
  }
  for (std::int64_t start : starts) {
    if (start < 0 || start > m_info.bondCount) {
      return fail(failedPrecondition(fmt::format("{} holds {}, outside 0..{} (M)",
                                                 kIndexBondStartPath, start, m_info.bondCount)));
    }
  }
  return starts;
}

Status DemFileReader::readRows(DemDataset id, int step, std::span<const std::int32_t> rows,
                               void* out) const {
  auto dataset = openChecked(id, step);
  if (!dataset) {
    return dataset.status();
  }
  const DatasetSpec& spec = datasetSpec(id);
  const bool row = spec.perStep && m_info.stepLayout == StepLayout::kAppendable;
  if (Status read = h5::readRowsAt(dataset->get(), spec.type, row ? step : -1, rows, out); !read) {
    return fail(Status(read.code(),
                       fmt::format("dataset {}: {}", stepDatasetPath(id, step), read.message())));
  }
  return Status::ok();
}

template <typename T>
Status DemFileReader::readOptionalRows(DemDataset id, std::span<const std::int32_t> rows,
                                       std::vector<T>& out) const {
  out.clear();
  if (!h5::linkExists(m_file.get(), datasetPath(id))) {
    return Status::ok();
  }
  out.resize(rows.size());
  return readRows(id, 0, rows, out.data());
}

Result<ExtraArray> DemFileReader::readExtraRows(const ExtraInfo& extra, int step,
                                                std::span<const std::int32_t> rows) const {
  auto dataset = openExtra(extra, step);
  if (!dataset) {
    return dataset.status();
  }
  const auto& dims = dataset->shape.dims;
  ExtraArray array{extra.name, extra.owner, dims.size() == 2 ? static_cast<int>(dims[1]) : 1, {}};
  array.values.resize(rows.size() * static_cast<std::size_t>(array.components));
  const bool row = extra.perStep && m_info.stepLayout == StepLayout::kAppendable;
  if (Status read = h5::readRowsAt(dataset->dataset.get(), ElementType::kFloat64, row ? step : -1,
                                   rows, array.values.data());
      !read) {
    return fail(Status(
        read.code(),
        fmt::format("dataset {}: {}", extraPath(extra, step, m_info.stepLayout), read.message())));
  }
  return array;
}

Result<std::vector<Bond>> DemFileReader::readBondRows(std::span<const BondIndex> bonds) const {
  CRACKVIS_RETURN_IF_ERROR(m_countsStored);
  std::vector<Bond> pairs(bonds.size());
  CRACKVIS_RETURN_IF_ERROR(readRows(DemDataset::kPairs, 0, bonds, pairs.data()));
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const Bond& pair = pairs[k];
    if (pair.first < 0 || pair.second < 0 || pair.first >= m_info.particleCount ||
        pair.second >= m_info.particleCount || pair.first == pair.second) {
      return fail(failedPrecondition(
          fmt::format("bond {} joins particles {} and {}, expected two distinct in 0..{}", bonds[k],
                      pair.first, pair.second, m_info.particleCount - 1)));
    }
  }
  return pairs;
}

Result<Lattice> DemFileReader::readLatticeRows(std::span<const ParticleIndex> particles,
                                               std::span<const BondIndex> bonds) const {
  CRACKVIS_RETURN_IF_ERROR(m_countsStored);
  Lattice lattice;
  lattice.dimension = m_info.dimension;
  lattice.radius.resize(particles.size());
  CRACKVIS_RETURN_IF_ERROR(readRows(DemDataset::kRadius, 0, particles, lattice.radius.data()));
  for (std::size_t k = 0; k < particles.size(); ++k) {
    if (!(lattice.radius[k] > 0.0) || !std::isfinite(lattice.radius[k])) {
      return fail(failedPrecondition(
          fmt::format("particle {} has radius {}, expected > 0", particles[k], lattice.radius[k])));
    }
  }
  auto pairs = readBondRows(bonds);
  if (!pairs) {
    return pairs.status();
  }
  lattice.bonds = std::move(*pairs);
  CRACKVIS_RETURN_IF_ERROR(readOptionalRows(DemDataset::kStrength, bonds, lattice.strength));
  CRACKVIS_RETURN_IF_ERROR(
      readOptionalRows(DemDataset::kParticleId, particles, lattice.particleId));
  CRACKVIS_RETURN_IF_ERROR(
      readOptionalRows(DemDataset::kParticleGroup, particles, lattice.particleGroup));
  CRACKVIS_RETURN_IF_ERROR(readOptionalRows(DemDataset::kBondFlags, bonds, lattice.bondFlags));
  for (const ExtraInfo& extra : m_info.extras) {
    if (!extra.perStep) {
      auto array =
          readExtraRows(extra, 0, extra.owner == ExtraOwner::kParticles ? particles : bonds);
      if (!array) {
        return array.status();
      }
      lattice.extras.push_back(std::move(*array));
    }
  }
  return lattice;
}

Result<std::vector<std::int32_t>> DemFileReader::readBreakStepRows(
    std::span<const BondIndex> bonds) const {
  CRACKVIS_RETURN_IF_ERROR(m_countsStored);
  std::vector<std::int32_t> breakStep(bonds.size());
  CRACKVIS_RETURN_IF_ERROR(readRows(DemDataset::kBreakStep, 0, bonds, breakStep.data()));
  for (std::size_t k = 0; k < breakStep.size(); ++k) {
    if (breakStep[k] < -1) {
      return fail(failedPrecondition(fmt::format(
          "/bonds/break_step[{}] is {}, expected -1 or a step index", bonds[k], breakStep[k])));
    }
  }
  return breakStep;
}

Result<StepState> DemFileReader::readStepRows(int step, std::span<const ParticleIndex> particles,
                                              std::span<const BondIndex> bonds,
                                              StepState recycled) const {
  CRACKVIS_RETURN_IF_ERROR(checkStepInRange(m_path, step, stepCount()));
  CRACKVIS_RETURN_IF_ERROR(m_countsStored);
  StepState state = reuse(std::move(recycled), particles.size(), bonds.size());
  state.time = m_info.steps[static_cast<size_t>(step)].time;
  CRACKVIS_RETURN_IF_ERROR(
      readRows(DemDataset::kPositions, step, particles, state.positions.data()));
  CRACKVIS_RETURN_IF_ERROR(readRows(DemDataset::kBondState, step, bonds, state.bondState.data()));
  if (h5::linkExists(m_file.get(), stepDatasetPath(DemDataset::kVelocities, step))) {
    state.velocities.resize(particles.size());
    CRACKVIS_RETURN_IF_ERROR(
        readRows(DemDataset::kVelocities, step, particles, state.velocities.data()));
  } else {
    state.velocities.clear();
  }
  if (h5::linkExists(m_file.get(), stepDatasetPath(DemDataset::kBondForce, step))) {
    state.bondForce.resize(bonds.size());
    CRACKVIS_RETURN_IF_ERROR(readRows(DemDataset::kBondForce, step, bonds, state.bondForce.data()));
  } else {
    state.bondForce.clear();
  }
  state.scalars = m_info.steps[static_cast<size_t>(step)].scalars;
  for (const ExtraInfo& extra : m_info.extras) {
    if (extra.perStep) {
      auto array =
          readExtraRows(extra, step, extra.owner == ExtraOwner::kParticles ? particles : bonds);
      if (!array) {
        return array.status();
      }
      state.extras.push_back(std::move(*array));
    }
  }
  if (Status valid = validateStep(m_info.dimension, particles.size(), bonds.size(), state);
      !valid) {
    return fail(failedPrecondition(fmt::format("step {}: {}", step, valid.message())));
  }
  return state;
}

Status DemFileReader::checkStepHeaders(int step) const {
  CRACKVIS_RETURN_IF_ERROR(checkStepInRange(m_path, step, stepCount()));
  for (DemDataset id : {DemDataset::kPositions, DemDataset::kBondState, DemDataset::kVelocities,
                        DemDataset::kBondForce}) {
    const bool optional = id == DemDataset::kVelocities || id == DemDataset::kBondForce;
    if (optional && !h5::linkExists(m_file.get(), stepDatasetPath(id, step))) {
      continue;
    }
    if (auto opened = openChecked(id, step); !opened) {
      return opened.status();
    }
  }
  for (const ExtraInfo& extra : m_info.extras) {
    if (extra.perStep) {
      if (auto opened = openExtra(extra, step); !opened) {
        return opened.status();
      }
    }
  }
  return Status::ok();
}

}  // namespace crackvis::dem
