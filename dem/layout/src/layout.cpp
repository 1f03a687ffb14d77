#include <algorithm>
#include <array>
#include <limits>

#include <fmt/format.h>

#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::dem {
namespace {

constexpr Extent kN{Extent::kParticles};
constexpr Extent kM{Extent::kBonds};
constexpr Extent kThree{Extent::kFixed, 3};
constexpr Extent kTwo{Extent::kFixed, 2};

const std::array<DatasetSpec, 11>& table() {
  static const std::array<DatasetSpec, 11> layout = {{
      {DemDataset::kRadius, "/particles/radius", false, true, ElementType::kFloat64, {kN}},
      {DemDataset::kPairs, "/bonds/pairs", false, true, ElementType::kInt32, {kM, kTwo}},
      {DemDataset::kStrength, "/bonds/strength", false, false, ElementType::kFloat64, {kM}},
      {DemDataset::kBreakStep, "/bonds/break_step", false, true, ElementType::kInt32, {kM}},
      {DemDataset::kPositions, "positions", true, true, ElementType::kFloat64, {kN, kThree}},
      {DemDataset::kBondState, "bond_state", true, true, ElementType::kUInt8, {kM}},
      {DemDataset::kVelocities, "velocities", true, false, ElementType::kFloat32, {kN, kThree}},
      {DemDataset::kBondForce, "bond_force", true, false, ElementType::kFloat32, {kM}},
      {DemDataset::kParticleId, "/particles/id", false, false, ElementType::kInt64, {kN}},
      {DemDataset::kParticleGroup, "/particles/group", false, false, ElementType::kInt32, {kN}},
      {DemDataset::kBondFlags, "/bonds/flags", false, false, ElementType::kUInt8, {kM}},
  }};
  return layout;
}

constexpr std::uint64_t kAnyExtent = std::numeric_limits<std::uint64_t>::max();

std::uint64_t expectedExtent(const Extent& extent, const LayoutSizes& sizes) {
  switch (extent.kind) {
    case Extent::kParticles:
      return sizes.particles >= 0 ? static_cast<std::uint64_t>(sizes.particles) : kAnyExtent;
    case Extent::kBonds:
      return sizes.bonds >= 0 ? static_cast<std::uint64_t>(sizes.bonds) : kAnyExtent;
    case Extent::kFixed:
      break;
  }
  return extent.value;
}

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

}  // namespace

std::span<const DatasetSpec> demLayout() {
  return table();
}

const DatasetSpec& datasetSpec(DemDataset id) {
  return table()[static_cast<size_t>(id)];
}

std::string datasetPath(DemDataset id, int step) {
  const DatasetSpec& spec = datasetSpec(id);
  return spec.perStep ? fmt::format("{}/{}", stepGroupPath(step), spec.name)
                      : std::string(spec.name);
}

std::string appendablePath(DemDataset id) {
  const DatasetSpec& spec = datasetSpec(id);
  return spec.perStep ? fmt::format("/steps/{}", spec.name) : std::string(spec.name);
}

Status missingDataset(const std::string& path) {
  return failedPrecondition(fmt::format("missing dataset {}", path));
}

Status checkDatasetHeader(DemDataset id, const std::string& path, const DatasetHeader& header,
                          const LayoutSizes& sizes) {
  const DatasetSpec& spec = datasetSpec(id);
  if (header.type != spec.type) {
    return failedPrecondition(fmt::format("dataset {} has dtype {}, expected {}", path,
                                          header.typeName, elementTypeName(spec.type)));
  }
  std::vector<std::uint64_t> expected;
  for (const Extent& extent : spec.shape) {
    expected.push_back(expectedExtent(extent, sizes));
  }
  if (shapeMatches(header.dims, expected)) {
    return Status::ok();
  }
  std::vector<std::string> known;
  if (sizes.particles >= 0) {
    known.push_back(fmt::format("N = {}", sizes.particles));
  }
  if (sizes.bonds >= 0) {
    known.push_back(fmt::format("M = {}", sizes.bonds));
  }
  return failedPrecondition(fmt::format(
      "dataset {} has shape {}, expected {}{}", path, formatDims(header.dims),
      formatExpected(expected), known.empty() ? "" : fmt::format(" ({})", fmt::join(known, ", "))));
}

Result<int> checkRootAttributes(const RootAttributes& root) {
  if (!root.format) {
    return failedPrecondition(
        fmt::format("not a crackvis-dem file ({})", root.format.status().message()));
  }
  if (*root.format != kFormatName) {
    return failedPrecondition(
        fmt::format("not a crackvis-dem file (root attribute 'format' is '{}', expected '{}')",
                    *root.format, kFormatName));
  }
  if (!root.version) {
    return failedPrecondition(
        fmt::format("crackvis-dem file without a version ({})", root.version.status().message()));
  }
  if (*root.version != kFormatVersion) {
    return failedPrecondition(fmt::format(
        "unsupported crackvis-dem version {} (this build reads version {}.x, up to {}.{})",
        *root.version, kFormatVersion, kFormatVersion, kFormatMinorVersion));
  }
  if (!root.dimension) {
    return failedPrecondition(root.dimension.status().message());
  }
  if (*root.dimension != 2 && *root.dimension != 3) {
    return failedPrecondition(
        fmt::format("root attribute 'dimension' is {}, expected 2 or 3", *root.dimension));
  }
  return static_cast<int>(*root.dimension);
}

StepList listSteps(std::int64_t count, const StepTimeLookup& stepTime) {
  StepList list;
  constexpr std::int64_t kMaxSteps = 1'000'000;  // six-digit group names
  if (count < 0 || count > kMaxSteps) {
    list.problem = failedPrecondition(
        fmt::format("/steps attribute 'count' is {}, expected 0 .. {}", count, kMaxSteps));
    return list;
  }
  for (int step = 0; step < static_cast<int>(count); ++step) {
    auto time = stepTime(step);
    if (!time) {
      list.problem = failedPrecondition(
          fmt::format("missing step group {} (/steps says {} steps)", stepGroupPath(step), count));
      return list;
    }
    if (!*time) {
      list.problem = failedPrecondition(
          fmt::format("step group {}: {}", stepGroupPath(step), time->status().message()));
      return list;
    }
    list.steps.emplace_back(step, **time);
  }
  return list;
}

Status checkStepInRange(const std::string& file, int step, int stepCount) {
  if (step >= 0 && step < stepCount) {
    return Status::ok();
  }
  if (stepCount <= 0) {
    return outOfRange(fmt::format("{}: step {} out of range (the file has no steps)", file, step));
  }
  return outOfRange(fmt::format("{}: step {} out of range (the file has steps 0..{})", file, step,
                                stepCount - 1));
}

std::vector<std::int64_t> brokenBondsPerStep(std::span<const std::int32_t> breakSteps,
                                             int stepCount) {
  std::vector<std::int64_t> broken(static_cast<std::size_t>(std::max(0, stepCount)), 0);
  for (const std::int32_t step : breakSteps) {
    if (step >= 0 && step < stepCount) {
      ++broken[static_cast<std::size_t>(step)];
    }
  }
  for (std::size_t k = 1; k < broken.size(); ++k) {
    broken[k] += broken[k - 1];
  }
  return broken;
}

Status checkDeclaredSizes(const std::string& file, const LayoutSizes& sizes,
                          const SizeLimits& limits) {
  if (sizes.particles > limits.maxParticles) {
    return resourceExhausted(
        fmt::format("{} declares N = {} particles, more than the limit of {} (max_particles)", file,
                    sizes.particles, limits.maxParticles));
  }
  if (sizes.bonds > limits.maxBonds) {
    return resourceExhausted(
        fmt::format("{} declares M = {} bonds, more than the limit of {} (max_bonds)", file,
                    sizes.bonds, limits.maxBonds));
  }
  return Status::ok();
}

std::string stepGroupPath(int step) {
  return fmt::format("/steps/{:06d}", step);
}

std::string formatDims(const std::vector<std::uint64_t>& dims) {
  return fmt::format("[{}]", fmt::join(dims, ","));
}

const char* elementTypeName(ElementType type) {
  switch (type) {
    case ElementType::kInt32:
      return "int32";
    case ElementType::kInt64:
      return "int64";
    case ElementType::kUInt8:
      return "uint8";
    case ElementType::kFloat32:
      return "float32";
    case ElementType::kFloat64:
      return "float64";
    case ElementType::kOther:
      break;
  }
  return "other";
}

}  // namespace crackvis::dem
