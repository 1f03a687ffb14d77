// The crackvis-dem v1 layout (docs/data-format.md) as one table, and the
// checks every reader of the layout shares: the local reader (HDF5 headers),
// the remote reader and the data service's catalogue (a Describe's
// attributes and dataset headers). Each check takes what it needs as plain
// values, so one message and one status code come out whichever way the file
// was seen. Messages do not name the file; callers prefix it.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem_layout/element_type.hpp>

namespace crackvis::dem {

inline constexpr std::string_view kFormatName = "crackvis-dem";
// The major version: a reader refuses any other. The minor version (root
// attribute `version_minor`, absent in v1.0 files) only adds optional parts.
inline constexpr int kFormatVersion = 1;
inline constexpr int kFormatMinorVersion = 3;

// How a file stores its steps (v1.2). kGroups: a group per step,
// /steps/NNNNNN, committed by /steps@count (every file before v1.2, and
// what a writer makes by default). kAppendable: one dataset per array with a
// leading step axis, /steps/positions [K, N, 3], committed by the length of
// /steps/time; what a live writer makes, since HDF5's SWMR mode can grow
// datasets while readers watch but cannot add groups.
enum class StepLayout { kGroups, kAppendable };
// The root attribute that names an appendable file's layout (absent: groups).
inline constexpr const char* kStepLayoutAttribute = "step_layout";
inline constexpr std::string_view kAppendableName = "appendable";
// The appendable layout's commit mark: its length is the number of complete
// steps K, and it holds their times.
inline constexpr const char* kStepTimePath = "/steps/time";
// The appendable layout's step scalars: /steps/scalars/NAME, float64 [K].
inline constexpr const char* kStepScalarsPath = "/steps/scalars";

// "/steps/000042": the group that holds step 42.
std::string stepGroupPath(int step);
// "[2,3]": a dataset's shape in messages.
std::string formatDims(const std::vector<std::uint64_t>& dims);

// The datasets of the layout.
enum class DemDataset {
  kRadius,
  kPairs,
  kStrength,
  kBreakStep,
  kPositions,   // per step
  kBondState,   // per step
  kVelocities,  // per step, optional
  kBondForce,   // per step, optional
  // v1.1, all optional:
  kParticleId,
  kParticleGroup,
  kBondFlags,
};

// One extent of a dataset's shape: the particle count N, the bond count M,
// or a fixed number.
struct Extent {
  enum Kind { kParticles, kBonds, kFixed } kind = kFixed;
  std::uint64_t value = 0;  // for kFixed
};

struct DatasetSpec {
  DemDataset id;
  std::string_view name;  // absolute, or relative to its step group when perStep
  bool perStep = false;
  bool required = true;
  ElementType type = ElementType::kOther;
  std::vector<Extent> shape;
};

// Every dataset of the layout, in the order of docs/data-format.md.
std::span<const DatasetSpec> demLayout();
const DatasetSpec& datasetSpec(DemDataset id);
// "/particles/radius", or "/steps/000042/positions" for a per-step dataset.
std::string datasetPath(DemDataset id, int step = 0);
// "/steps/positions": where an appendable file keeps a per-step dataset
// (step k is row k of its first axis); datasetPath() for the others.
std::string appendablePath(DemDataset id);

// N and M where known (-1: not yet, any extent accepted).
struct LayoutSizes {
  std::int64_t particles = -1;
  std::int64_t bonds = -1;
};

// The most particles and bonds a reader will allocate for, so that a tiny
// file declaring 10^8 bonds cannot make a server allocate gigabytes. The
// default accepts everything (a CLI reading the user's own file); servers
// set their configured limits.
struct SizeLimits {
  std::int64_t maxParticles = std::numeric_limits<std::int64_t>::max();
  std::int64_t maxBonds = std::numeric_limits<std::int64_t>::max();
};
// RESOURCE_EXHAUSTED "FILE declares N = 100000000 bonds, more than the limit
// of 1000 (max_bonds)" before anything of that size is allocated.
Status checkDeclaredSizes(const std::string& file, const LayoutSizes& sizes,
                          const SizeLimits& limits);

// What a reader saw of a stored dataset.
struct DatasetHeader {
  ElementType type = ElementType::kOther;
  std::string typeName;  // as h5::describeDataset names it
  std::vector<std::uint64_t> dims;
};

// FAILED_PRECONDITION "dataset P has dtype T, expected U" or "... has shape
// [..], expected [..] (N = .., M = ..)"; `path` is datasetPath(id, step).
Status checkDatasetHeader(DemDataset id, const std::string& path, const DatasetHeader& header,
                          const LayoutSizes& sizes);
// FAILED_PRECONDITION "missing dataset P".
Status missingDataset(const std::string& path);

// The root attributes as read (each may have failed to read).
struct RootAttributes {
  Result<std::string> format = notFound("missing attribute 'format'");
  Result<std::int64_t> version = notFound("missing attribute 'version'");
  Result<std::int64_t> dimension = notFound("missing attribute 'dimension'");
};
// Format, version and dimension; the dimension on success. Any minor version
// of major version 1 is read: v1.1 only adds optional datasets.
Result<int> checkRootAttributes(const RootAttributes& root);

// The complete steps /steps@count promises. `stepTime(k)` reads the time
// attribute of step group k; nothing when the group is missing. Lenient
// callers (a Describe) keep the steps found before the first problem.
struct StepList {
  std::vector<std::pair<int, double>> steps;  // index, time
  Status problem;
};
using StepTimeLookup = std::function<std::optional<Result<double>>(int step)>;
StepList listSteps(std::int64_t count, const StepTimeLookup& stepTime);

// The one step check of every reader: OUT_OF_RANGE "FILE: step K out of
// range (the file has steps 0..N-1)" ("... has no steps" when empty).
Status checkStepInRange(const std::string& file, int step, int stepCount);

// The bonds broken at or before each of the file's `stepCount` steps, from
// /bonds/break_step (bonds never heal; a break step beyond the complete
// steps, which a writer may have named already, counts nowhere).
std::vector<std::int64_t> brokenBondsPerStep(std::span<const std::int32_t> breakSteps,
                                             int stepCount);

}  // namespace crackvis::dem
