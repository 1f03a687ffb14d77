#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <optional>
#include <thread>
#include <unordered_map>

#include <fmt/format.h>
#include <signal.h>
#include <sys/stat.h>

#include "scalar_table.hpp"
#include <crackvis/common/pending_file.hpp>
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/partition.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/step_range.hpp>
#include <crackvis/importers/importer.hpp>

namespace crackvis::importers {
namespace {

using dem::BondState;

constexpr auto kIntact = static_cast<std::uint8_t>(BondState::kIntact);
constexpr auto kBroken = static_cast<std::uint8_t>(BondState::kBroken);

std::uint64_t pairKey(dem::ParticleIndex a, dem::ParticleIndex b) {
  const auto lo = static_cast<std::uint32_t>(std::min(a, b));
  const auto hi = static_cast<std::uint32_t>(std::max(a, b));
  return (std::uint64_t{lo} << 32) | hi;
}

// Fixes the particle order and the lattice at the first imported step, then
// converts each later step against them.
class SeriesConverter {
 public:
  SeriesConverter(const SourceDescription& description, double timestep, const ScalarTable* table)
      : m_description(description), m_timestep(timestep), m_table(table) {}

  Status begin(const SourceStep& first);
  Result<dem::StepState> convert(const SourceStep& step);

  const dem::Lattice& lattice() const { return m_lattice; }
  std::size_t reappeared() const { return m_reappeared; }
  bool timesFromSource() const { return m_timesFromSource; }
  // Whether `step`'s time comes from the source or the table (else it is
  // the code's step number, times --timestep when given).
  bool timeKnown(const SourceStep& step) const {
    return step.timeKnown || timeFromTable(step.sourceStep).has_value();
  }

 private:
  Status placeParticles(const SourceStep& step, std::vector<dem::ParticleIndex>& rowIndex) const;
  Result<dem::ParticleIndex> indexOf(std::int64_t id, const SourceStep& step) const;
  Status updateBonds(const SourceStep& step, const std::vector<dem::ParticleIndex>& rowIndex,
                     std::vector<dem::BondIndex>& bondOfRow);
  void addExtras(const SourceStep& step, const std::vector<dem::ParticleIndex>& rowIndex,
                 const std::vector<dem::BondIndex>& bondOfRow, dem::StepState& out) const;
  std::vector<dem::StepScalar> scalarsOf(const SourceStep& step) const;
  std::optional<double> timeFromTable(std::int64_t sourceStep) const;
  Status checkSameArrays(const SourceStep& step, const dem::StepState& out);
  void matchRecordedBreaks(const SourceStep& step, const std::vector<std::uint8_t>& before,
                           const std::vector<dem::Vec3>& positions);

  SourceDescription m_description;
  double m_timestep = 0.0;
  const ScalarTable* m_table = nullptr;
  dem::Lattice m_lattice;
  std::unordered_map<std::int64_t, dem::ParticleIndex> m_indexOfId;
  std::unordered_map<std::uint64_t, dem::BondIndex> m_bondOfPair;
  std::vector<std::uint8_t> m_state;
  std::size_t m_reappeared = 0;
  bool m_timesFromSource = false;
  bool m_arraysKnown = false;
  bool m_withVelocities = false;
  std::vector<std::string> m_extraNames;  // per-step arrays of the first step
  // Per bond, the mode the code recorded for its break (kBreakModeArray).
  std::vector<double> m_recordedModes;
};

std::vector<std::string> extraNames(const dem::StepState& state) {
  std::vector<std::string> names;
  for (const dem::ExtraArray& extra : state.extras) {
    names.push_back(fmt::format("{}", extra.name));
  }
  return names;
}

// Every step of a crackvis-dem file holds the same per-step arrays, so the
// first imported step's set is the rule for the rest.
Status SeriesConverter::checkSameArrays(const SourceStep& step, const dem::StepState& out) {
  const std::vector<std::string> names = extraNames(out);
  if (!m_arraysKnown) {
    m_arraysKnown = true;
    m_withVelocities = !out.velocities.empty();
    m_extraNames = names;
    return Status::ok();
  }
  for (const std::string& name : m_extraNames) {
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      return failedPrecondition(fmt::format(
          "{}: step {}: no array '{}', which the first imported step had (every step needs the "
          "same arrays)",
          step.origin, step.sourceStep, name));
    }
  }
  for (const std::string& name : names) {
    if (std::find(m_extraNames.begin(), m_extraNames.end(), name) == m_extraNames.end()) {
      return failedPrecondition(fmt::format(
          "{}: step {}: array '{}' is new: the first imported step had none (every step needs "
          "the same arrays)",
          step.origin, step.sourceStep, name));
    }
  }
  if (m_withVelocities != !out.velocities.empty()) {
    return failedPrecondition(
        fmt::format("{}: step {}: velocities {} (every step needs the same arrays)", step.origin,
                    step.sourceStep, m_withVelocities ? "are missing" : "appear"));
  }
  return Status::ok();
}

Status unlistedEnd(const SourceStep& step, const SourceBond& bond, std::int64_t id) {
  return failedPrecondition(
      fmt::format("{}: step {}: bond {}-{} joins particle id {}, which the step does not list",
                  step.origin, step.sourceStep, bond.first, bond.second, id));
}

Result<dem::ParticleIndex> SeriesConverter::indexOf(std::int64_t id, const SourceStep& step) const {
  const auto found = m_indexOfId.find(id);
  if (found == m_indexOfId.end()) {
    return failedPrecondition(fmt::format(
        "{}: step {}: particle id {} appears, but the first imported step has no such particle "
        "(crackvis needs the same particles at every step)",
        step.origin, step.sourceStep, id));
  }
  return found->second;
}

Status SeriesConverter::begin(const SourceStep& first) {
  const std::size_t n = first.ids.size();
  if (n == 0) {
    return failedPrecondition(
        fmt::format("{}: step {}: no particles", first.origin, first.sourceStep));
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return first.ids[a] < first.ids[b]; });
  // A 3D code's flat run (all z = 0) is a 2D data set.
  const bool flat = std::all_of(first.positions.begin(), first.positions.end(),
                                [](const dem::Vec3& p) { return p.z == 0.0; });
  m_lattice.dimension = flat ? 2 : m_description.dimension;
  m_lattice.particleId.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    m_lattice.particleId[i] = first.ids[order[i]];
    if (!m_indexOfId.emplace(m_lattice.particleId[i], static_cast<dem::ParticleIndex>(i)).second) {
      return failedPrecondition(fmt::format("{}: step {}: particle id {} is listed twice",
                                            first.origin, first.sourceStep,
                                            m_lattice.particleId[i]));
    }
  }
  m_lattice.radius.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    m_lattice.radius[i] = first.radius[order[i]];
  }
  if (!first.group.empty()) {
    m_lattice.particleGroup.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      m_lattice.particleGroup[i] = first.group[order[i]];
    }
  }
  // The lattice: every bond listed at the first step, in pair order.
  struct Listed {
    std::uint64_t key;
    bool cohesive;
    double strength;
  };
  std::vector<Listed> listed;
  listed.reserve(first.bonds.size());
  for (const SourceBond& bond : first.bonds) {
    auto a = indexOf(bond.first, first);
    auto b = indexOf(bond.second, first);
    if (!a || !b) {
      return unlistedEnd(first, bond, !a ? bond.first : bond.second);
    }
    if (*a == *b) {
      return failedPrecondition(fmt::format("{}: step {}: bond {}-{} joins a particle to itself",
                                            first.origin, first.sourceStep, bond.first,
                                            bond.second));
    }
    const std::size_t row = listed.size();
    listed.push_back({pairKey(*a, *b), bond.cohesive,
                      first.bondStrength.empty() ? 0.0 : first.bondStrength[row]});
  }
  std::sort(listed.begin(), listed.end(),
            [](const Listed& x, const Listed& y) { return x.key < y.key; });
  for (std::size_t k = 0; k < listed.size(); ++k) {
    if (k > 0 && listed[k].key == listed[k - 1].key) {
      const auto lo = static_cast<std::size_t>(listed[k].key >> 32);
      const auto hi = static_cast<std::size_t>(listed[k].key & 0xffffffffu);
      return failedPrecondition(fmt::format("{}: step {}: bond {}-{} is listed twice", first.origin,
                                            first.sourceStep, m_lattice.particleId[lo],
                                            m_lattice.particleId[hi]));
    }
    const auto lo = static_cast<dem::ParticleIndex>(listed[k].key >> 32);
    const auto hi = static_cast<dem::ParticleIndex>(listed[k].key & 0xffffffffu);
    m_bondOfPair.emplace(listed[k].key, static_cast<dem::BondIndex>(m_lattice.bonds.size()));
    m_lattice.bonds.push_back({lo, hi});
    m_lattice.bondFlags.push_back(listed[k].cohesive ? 0 : dem::kBondCutAtStart);
    if (!first.bondStrength.empty()) {
      m_lattice.strength.push_back(listed[k].strength);
    }
    m_state.push_back(listed[k].cohesive ? kIntact : kBroken);
  }
  return dem::validateLattice(m_lattice);
}

Status SeriesConverter::placeParticles(const SourceStep& step,
                                       std::vector<dem::ParticleIndex>& rowIndex) const {
  const std::size_t n = m_lattice.particleCount();
  rowIndex.assign(step.ids.size(), -1);
  std::vector<std::uint8_t> seen(n, 0);
  for (std::size_t row = 0; row < step.ids.size(); ++row) {
    auto index = indexOf(step.ids[row], step);
    if (!index) {
      return index.status();
    }
    if (seen[static_cast<std::size_t>(*index)] != 0) {
      return failedPrecondition(fmt::format("{}: step {}: particle id {} is listed twice",
                                            step.origin, step.sourceStep, step.ids[row]));
    }
    seen[static_cast<std::size_t>(*index)] = 1;
    rowIndex[row] = *index;
  }
  if (step.ids.size() != n) {
    const auto missing = std::find(seen.begin(), seen.end(), std::uint8_t{0}) - seen.begin();
    return failedPrecondition(fmt::format(
        "{}: step {}: particle id {} vanished (the step lists {} particles, the first imported "
        "step {}; crackvis needs the same particles at every step)",
        step.origin, step.sourceStep, m_lattice.particleId[static_cast<std::size_t>(missing)],
        step.ids.size(), n));
  }
  return Status::ok();
}

Status SeriesConverter::updateBonds(const SourceStep& step,
                                    const std::vector<dem::ParticleIndex>& rowIndex,
                                    std::vector<dem::BondIndex>& bondOfRow) {
  (void)rowIndex;
  std::vector<std::uint8_t> holds(m_state.size(), 0);
  bondOfRow.assign(step.bonds.size(), -1);
  for (std::size_t row = 0; row < step.bonds.size(); ++row) {
    const SourceBond& bond = step.bonds[row];
    auto a = indexOf(bond.first, step);
    auto b = indexOf(bond.second, step);
    if (!a || !b) {
      return unlistedEnd(step, bond, !a ? bond.first : bond.second);
    }
    const auto found = m_bondOfPair.find(pairKey(*a, *b));
    if (found == m_bondOfPair.end()) {
      if (!bond.cohesive) {
        continue;  // a new frictional contact, not a bond
      }
      return failedPrecondition(fmt::format(
          "{}: step {}: bond {}-{} appears, but the first imported step has no such bond "
          "(crackvis keeps the first step's bonds; start the import where every bond exists, "
          "with --steps)",
          step.origin, step.sourceStep, bond.first, bond.second));
    }
    bondOfRow[row] = found->second;
    if (bond.cohesive) {
      holds[static_cast<std::size_t>(found->second)] = 1;
    }
  }
  for (std::size_t b = 0; b < m_state.size(); ++b) {
    if (m_state[b] == kBroken) {
      m_reappeared += holds[b];
    } else if (holds[b] == 0) {
      m_state[b] = kBroken;
    }
  }
  return Status::ok();
}

void SeriesConverter::addExtras(const SourceStep& step,
                                const std::vector<dem::ParticleIndex>& rowIndex,
                                const std::vector<dem::BondIndex>& bondOfRow,
                                dem::StepState& out) const {
  for (const dem::ExtraArray& extra : step.extras) {
    const bool perParticle = extra.owner == dem::ExtraOwner::kParticles;
    const auto width = static_cast<std::size_t>(extra.components);
    dem::ExtraArray placed{extra.name, extra.owner, extra.components, {}};
    placed.values.assign((perParticle ? m_lattice.particleCount() : m_lattice.bondCount()) * width,
                         0.0);
    for (std::size_t row = 0; row < extra.rows(); ++row) {
      const std::int64_t target = perParticle ? rowIndex[row] : bondOfRow[row];
      if (target < 0) {
        continue;  // a contact that is not a bond
      }
      std::copy_n(extra.values.begin() + static_cast<std::ptrdiff_t>(row * width), width,
                  placed.values.begin() +
                      static_cast<std::ptrdiff_t>(static_cast<std::size_t>(target) * width));
    }
    out.extras.push_back(std::move(placed));
  }
}

std::vector<dem::StepScalar> SeriesConverter::scalarsOf(const SourceStep& step) const {
  std::vector<dem::StepScalar> scalars{{"source_step", static_cast<double>(step.sourceStep)}};
  auto add = [&](const dem::StepScalar& scalar) {
    const bool known = std::any_of(scalars.begin(), scalars.end(),
                                   [&](const dem::StepScalar& s) { return s.name == scalar.name; });
    if (!known && scalar.name != "time") {
      scalars.push_back(scalar);
    }
  };
  for (const dem::StepScalar& scalar : step.scalars) {
    add(scalar);
  }
  if (m_table != nullptr) {
    for (const dem::StepScalar& scalar : m_table->at(step.sourceStep)) {
      add(scalar);
    }
  }
  return scalars;
}

std::optional<double> SeriesConverter::timeFromTable(std::int64_t sourceStep) const {
  if (m_table == nullptr) {
    return std::nullopt;
  }
  for (const dem::StepScalar& scalar : m_table->at(sourceStep)) {
    if (scalar.name == "time") {
      return scalar.value;
    }
  }
  // A step without a row (--partial-scalars): its time on the table's line,
  // so that one file never mixes seconds and step numbers.
  return m_table->has(sourceStep) ? std::nullopt : m_table->fittedTime(sourceStep);
}

// Each bond first seen broken at this step gets the mode of the nearest
// break the code logged since the previous step, within the larger radius
// of its two particles of the bond's midpoint (JCFpm logs the contact
// point); the nearest pairs are matched first, each record once. A bond
// without such a record keeps 0: crackvis's own rule decides its mode.
void SeriesConverter::matchRecordedBreaks(const SourceStep& step,
                                          const std::vector<std::uint8_t>& before,
                                          const std::vector<dem::Vec3>& positions) {
  m_recordedModes.resize(m_lattice.bondCount(), 0.0);
  if (step.breaks.empty()) {
    return;
  }
  double reach = 0.0;
  for (double r : m_lattice.radius) {
    reach = std::max(reach, r);
  }
  // The records in a grid of cells `reach` wide: a bond looks in the 27
  // cells around its midpoint.
  const auto cellOf = [&](const dem::Vec3& p) {
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(std::floor(p.x / reach)),
                                       static_cast<std::int64_t>(std::floor(p.y / reach)),
                                       static_cast<std::int64_t>(std::floor(p.z / reach))};
  };
  const auto keyOf = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (static_cast<std::uint64_t>(x) * 73856093U) ^
           (static_cast<std::uint64_t>(y) * 19349663U) ^
           (static_cast<std::uint64_t>(z) * 83492791U);
  };
  std::unordered_multimap<std::uint64_t, std::size_t> grid;
  for (std::size_t r = 0; r < step.breaks.size(); ++r) {
    const auto c = cellOf(step.breaks[r].at);
    grid.emplace(keyOf(c[0], c[1], c[2]), r);
  }
  struct Candidate {
    double distance;
    std::size_t bond;
    std::size_t record;
  };
  std::vector<Candidate> candidates;
  for (std::size_t b = 0; b < m_state.size(); ++b) {
    if (m_state[b] != kBroken || before[b] == kBroken) {
      continue;
    }
    const dem::Bond& bond = m_lattice.bonds[b];
    const auto i = static_cast<std::size_t>(bond.first);
    const auto j = static_cast<std::size_t>(bond.second);
    const dem::Vec3 mid = 0.5 * (positions[i] + positions[j]);
    const double within = std::max(m_lattice.radius[i], m_lattice.radius[j]);
    const auto c = cellOf(mid);
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto [from, to] = grid.equal_range(keyOf(c[0] + dx, c[1] + dy, c[2] + dz));
          for (auto it = from; it != to; ++it) {
            const double d = dem::norm(step.breaks[it->second].at - mid);
            if (d <= within) {
              candidates.push_back({d, b, it->second});
            }
          }
        }
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.distance < b.distance || (a.distance == b.distance && a.bond < b.bond);
  });
  std::vector<char> recordUsed(step.breaks.size(), 0);
  std::vector<char> bondDone(m_state.size(), 0);
  for (const Candidate& c : candidates) {
    if (recordUsed[c.record] || bondDone[c.bond]) {
      continue;
    }
    recordUsed[c.record] = 1;
    bondDone[c.bond] = 1;
    m_recordedModes[c.bond] = static_cast<double>(step.breaks[c.record].mode);
  }
}

Result<dem::StepState> SeriesConverter::convert(const SourceStep& step) {
  std::vector<dem::ParticleIndex> rowIndex;
  CRACKVIS_RETURN_IF_ERROR(placeParticles(step, rowIndex));
  std::vector<dem::BondIndex> bondOfRow;
  // The states before this step, for matching the breaks the code logged.
  const std::vector<std::uint8_t> before =
      step.recordsBreaks ? m_state : std::vector<std::uint8_t>{};
  CRACKVIS_RETURN_IF_ERROR(updateBonds(step, rowIndex, bondOfRow));
  dem::StepState out;
  // The time: as the source wrote it, else from the scalar table's `time`
  // column, else the step number times --timestep.
  const std::optional<double> tableTime = timeFromTable(step.sourceStep);
  m_timesFromSource = step.timeKnown || tableTime.has_value();
  out.time = step.timeKnown ? step.time
             : tableTime
                 ? *tableTime
                 : static_cast<double>(step.sourceStep) * (m_timestep > 0.0 ? m_timestep : 1.0);
  out.positions.resize(m_lattice.particleCount());
  for (std::size_t row = 0; row < rowIndex.size(); ++row) {
    out.positions[static_cast<std::size_t>(rowIndex[row])] = step.positions[row];
  }
  if (!step.velocities.empty()) {
    out.velocities.resize(m_lattice.particleCount());
    for (std::size_t row = 0; row < rowIndex.size(); ++row) {
      out.velocities[static_cast<std::size_t>(rowIndex[row])] = step.velocities[row];
    }
  }
  out.bondState = m_state;
  out.scalars = scalarsOf(step);
  addExtras(step, rowIndex, bondOfRow, out);
  if (step.recordsBreaks) {
    matchRecordedBreaks(step, before, out.positions);
    out.extras.push_back(
        {std::string(dem::kBreakModeArray), dem::ExtraOwner::kBonds, 1, m_recordedModes});
  }
  CRACKVIS_RETURN_IF_ERROR(checkSameArrays(step, out));
  if (Status valid = dem::validateStep(m_lattice, out); !valid) {
    return failedPrecondition(
        fmt::format("{}: step {}: {}", step.origin, step.sourceStep, valid.message()));
  }
  return out;
}

std::size_t brokenCount(const dem::StepState& state) {
  return state.brokenBondCount();
}

void describeArrays(const dem::StepState& state, ImportSummary& summary) {
  summary.scalarNames.clear();
  for (const dem::StepScalar& scalar : state.scalars) {
    summary.scalarNames.push_back(scalar.name);
  }
  summary.extraNames.clear();
  for (const dem::ExtraArray& extra : state.extras) {
    summary.extraNames.push_back(fmt::format(
        "{}/{}", extra.owner == dem::ExtraOwner::kParticles ? "particles" : "bonds", extra.name));
  }
  summary.withVelocities = !state.velocities.empty();
}

Result<SourceStep> readChecked(StepSource& source, int index) {
  auto step = source.readStep(index);
  if (!step) {
    return step.status();
  }
  const std::size_t n = step->ids.size();
  if (step->positions.size() != n || step->radius.size() != n ||
      (!step->group.empty() && step->group.size() != n) ||
      (!step->velocities.empty() && step->velocities.size() != n)) {
    return internalError(fmt::format("{}: step {}: the reader returned ragged rows", step->origin,
                                     step->sourceStep));
  }
  return step;
}

Status writeSeries(StepSource& source, SeriesConverter& converter, SourceStep first,
                   const std::string& path, const dem::DemMetadata& metadata,
                   const ImportOptions& options, ImportSummary& summary);

// How many imported steps the --scalars table has a row for: none is a
// table of another run (or another step numbering) and is refused; some is
// refused unless asked for, since those steps would lack the scalars and,
// with a time column, fall back to another unit of time.
Status matchScalarRows(StepSource& source, const ScalarTable& table, const ImportOptions& options,
                       ImportSummary& summary) {
  std::vector<std::int64_t> missing;
  for (int index : summary.selected) {
    const std::int64_t step = source.sourceStepNumber(index);
    if (table.has(step)) {
      ++summary.scalarRowsMatched;
    } else {
      missing.push_back(step);
    }
  }
  const std::string& path = options.scalarsTable;
  if (summary.scalarRowsMatched == 0) {
    return failedPrecondition(fmt::format(
        "{}: no row matches an imported step (the table's {} rows are for code steps {} .. {}; "
        "the imported steps are {} .. {}): is it the table of this run?",
        path, table.rowCount(), table.firstStep(), table.lastStep(), summary.firstSourceStep,
        summary.lastSourceStep));
  }
  std::vector<std::string> shown;
  for (std::size_t i = 0; i < std::min<std::size_t>(missing.size(), 5); ++i) {
    shown.push_back(std::to_string(missing[i]));
  }
  const std::string missingText =
      fmt::format("{}{}", fmt::join(shown, ", "), missing.size() > shown.size() ? ", ..." : "");
  if (!missing.empty() && !options.partialScalars) {
    return failedPrecondition(fmt::format(
        "{}: rows for {} of the {} imported steps (none for code steps {}); those steps would get "
        "no scalars{}: pass --partial-scalars to import anyway",
        path, summary.scalarRowsMatched, summary.selected.size(), missingText,
        table.fitsTime() ? " and a time from a straight line through the table's times" : ""));
  }
  if (!missing.empty()) {
    summary.notes.push_back(fmt::format(
        "{} has no row for {} imported steps (code steps {}): they have no table scalars{}", path,
        missing.size(), missingText,
        table.fitsTime() ? ", and their time lies on a straight line through the table's" : ""));
  }
  if (!table.textColumns().empty()) {
    summary.notes.push_back(fmt::format("{}: skipped the columns that hold text: {}", path,
                                        fmt::join(table.textColumns(), ", ")));
  }
  return Status::ok();
}

}  // namespace

Result<ImportSummary> importSeries(StepSource& source, const ImportOptions& options) {
  ImportSummary summary;
  summary.source = source.description();
  summary.sourceSteps = source.stepCount();
  if (summary.sourceSteps == 0) {
    return failedPrecondition("the source holds no steps");
  }
  auto selected =
      dem::parseStepRange(options.steps.empty() ? "0:-1" : options.steps, summary.sourceSteps);
  if (!selected) {
    return selected.status();
  }
  summary.selected = *selected;
  summary.firstSourceStep = source.sourceStepNumber(summary.selected.front());
  summary.lastSourceStep = source.sourceStepNumber(summary.selected.back());
  std::optional<ScalarTable> table;
  if (!options.scalarsTable.empty()) {
    auto read = ScalarTable::read(options.scalarsTable);
    if (!read) {
      return read.status();
    }
    table = std::move(*read);
    CRACKVIS_RETURN_IF_ERROR(matchScalarRows(source, *table, options, summary));
  }
  SeriesConverter converter(summary.source, options.timestep, table ? &*table : nullptr);

  auto first = readChecked(source, summary.selected.front());
  if (!first) {
    return first.status();
  }
  CRACKVIS_RETURN_IF_ERROR(converter.begin(*first));
  const dem::Lattice& lattice = converter.lattice();
  summary.dimension = lattice.dimension;
  summary.particles = lattice.particleCount();
  summary.bonds = lattice.bondCount();
  summary.withGroups = !lattice.particleGroup.empty();
  summary.cutAtStart = static_cast<std::size_t>(
      std::count_if(lattice.bondFlags.begin(), lattice.bondFlags.end(),
                    [](std::uint8_t f) { return (f & dem::kBondCutAtStart) != 0; }));

  if (options.dryRun) {
    // The first and last step tell N, M, the arrays and how far the crack
    // went, without reading the steps between.
    auto state = converter.convert(*first);
    if (!state) {
      return state.status();
    }
    summary.brokenFirst = brokenCount(*state);
    describeArrays(*state, summary);
    if (summary.selected.size() > 1) {
      auto last = readChecked(source, summary.selected.back());
      if (!last) {
        return last.status();
      }
      auto lastState = converter.convert(*last);
      if (!lastState) {
        return lastState.status();
      }
      summary.brokenLast = brokenCount(*lastState);
    } else {
      summary.brokenLast = summary.brokenFirst;
    }
    summary.timesFromSource = converter.timesFromSource();
    return summary;
  }

  dem::DemMetadata metadata;
  metadata.source = options.invocation;
  metadata.sourceCode = summary.source.code;
  metadata.sourceVersion = summary.source.version;
  metadata.sourceFiles = summary.source.files;
  if (!options.scalarsTable.empty()) {
    metadata.sourceFiles.push_back(options.scalarsTable);
  }
  metadata.plannedSteps = static_cast<int>(summary.selected.size());
  metadata.storage = options.storage;
  // Without a time from the code, the table or --timestep, `time` is the
  // code's step number: the file says so, and readers label it iterations.
  if (!converter.timeKnown(*first) && !(options.timestep > 0.0)) {
    metadata.timeUnit = dem::kTimeInIterations;
  }
  // Written beside the output and renamed at the end, so a failed import
  // leaves no half file and an existing output as it was.
  const std::string partial = options.output + ".importing";
  auto status =
      writeSeries(source, converter, std::move(*first), partial, metadata, options, summary);
  std::error_code error;
  if (!status) {
    std::filesystem::remove(partial, error);
    return status;
  }
  std::filesystem::rename(partial, options.output, error);
  if (error) {
    std::filesystem::remove(partial, error);
    return failedPrecondition(
        fmt::format("{}: cannot move the import into place ({})", options.output, error.message()));
  }
  summary.reappeared = converter.reappeared();
  summary.timesFromSource = converter.timesFromSource();
  return summary;
}

namespace {

Status writeSeries(StepSource& source, SeriesConverter& converter, SourceStep first,
                   const std::string& path, const dem::DemMetadata& metadata,
                   const ImportOptions& options, ImportSummary& summary) {
  dem::DemMetadata indexed = metadata;
  cracks::describeCells(indexed, converter.lattice());
  auto writer = dem::DemFileWriter::create(path, converter.lattice(), indexed);
  if (!writer) {
    return writer.status();
  }
  ProgressBar progress("import", static_cast<std::int64_t>(summary.selected.size()));
  progress.setEnabled(options.progress);
  for (std::size_t k = 0; k < summary.selected.size(); ++k) {
    Result<SourceStep> step =
        k == 0 ? Result<SourceStep>(std::move(first)) : readChecked(source, summary.selected[k]);
    if (!step) {
      return step.status();
    }
    auto state = converter.convert(*step);
    if (!state) {
      return state.status();
    }
    CRACKVIS_RETURN_IF_ERROR(writer->appendStep(*state));
    const std::size_t broken = brokenCount(*state);
    if (k == 0) {
      summary.brokenFirst = broken;
      describeArrays(*state, summary);
    }
    summary.brokenLast = broken;
    summary.stepsWritten = static_cast<int>(k + 1);
    progress.update(static_cast<std::int64_t>(k + 1),
                    fmt::format("step {}, broken {}", step->sourceStep, broken));
  }
  progress.finish();
  return writer->close();
}

}  // namespace

std::string formatSummary(const ImportSummary& s, const ImportOptions& options) {
  std::string out;
  const std::string code = s.source.version.empty()
                               ? s.source.code
                               : fmt::format("{} ({})", s.source.code, s.source.version);
  out += fmt::format("source        {}, {} files, {} steps (code steps {} .. {})\n", code,
                     s.source.files.size(), s.sourceSteps, s.firstSourceStep, s.lastSourceStep);
  out += fmt::format("imported      {} of {} steps{}\n",
                     options.dryRun ? s.selected.size() : static_cast<std::size_t>(s.stepsWritten),
                     s.sourceSteps, options.dryRun ? " (dry run: would import)" : "");
  out += fmt::format("particles     N = {} ({}D{})\n", s.particles, s.dimension,
                     s.withGroups ? ", with group labels" : "");
  out +=
      fmt::format("bonds         M = {} at the first step, {} of them cut at the start (notch)\n",
                  s.bonds, s.cutAtStart);
  out += fmt::format(
      "broken        {} at the first step, {} at the last ({:.1f} %)\n", s.brokenFirst,
      s.brokenLast,
      s.bonds > 0 ? 100.0 * static_cast<double>(s.brokenLast) / static_cast<double>(s.bonds) : 0.0);
  out += fmt::format(
      "time          {}\n",
      s.timesFromSource
          ? "as the source wrote it"
          : (options.timestep > 0.0
                 ? fmt::format("the code's step number x {} s (--timestep)", options.timestep)
                 : std::string("the code's step number, labelled as iterations (the source "
                               "writes no time; give --timestep to convert to seconds)")));
  out +=
      fmt::format("step scalars  {}{}\n", fmt::join(s.scalarNames, ", "),
                  options.scalarsTable.empty()
                      ? std::string()
                      : fmt::format(" ({} matched rows for {} of {} imported steps)",
                                    options.scalarsTable, s.scalarRowsMatched, s.selected.size()));
  std::vector<std::string> arrays{"positions", "radius", "id"};
  if (s.withGroups) {
    arrays.emplace_back("group");
  }
  if (s.withVelocities) {
    arrays.emplace_back("velocities");
  }
  arrays.insert(arrays.end(), s.extraNames.begin(), s.extraNames.end());
  out += fmt::format("arrays        {}\n", fmt::join(arrays, ", "));
  for (const auto* notes : {&s.source.notes, &s.notes}) {
    for (const std::string& note : *notes) {
      out += fmt::format("note          {}\n", note);
    }
  }
  if (s.reappeared > 0) {
    out += fmt::format(
        "note          {} listings of broken bonds reappeared later; they stay broken (bonds "
        "never heal)\n",
        s.reappeared);
  }
  if (!options.dryRun) {
    std::error_code error;
    const auto bytes = std::filesystem::file_size(options.output, error);
    out += fmt::format("wrote         {} ({:.1f} MB)\n", options.output,
                       error ? 0.0 : static_cast<double>(bytes) / 1e6);
  }
  return out;
}

}  // namespace crackvis::importers

namespace crackvis::importers {
namespace {

using FollowClock = std::chrono::steady_clock;

double secondsSince(FollowClock::time_point start) {
  return std::chrono::duration<double>(FollowClock::now() - start).count();
}

// What the source's files are now: names, sizes and modification times. A
// step is complete once this has not changed for a while.
std::string filesFingerprint(const SourceDescription& source) {
  std::string print;
  for (const std::string& file : source.files) {
    struct stat info {};
    if (::stat(file.c_str(), &info) == 0) {
      print += fmt::format("{}:{}:{}.{};", file, info.st_size, info.st_mtim.tv_sec,
                           info.st_mtim.tv_nsec);
    } else {
      print += file + ":gone;";
    }
  }
  return print;
}

// Gone, or a zombie its parent has not reaped yet (the run is over either way).
bool processEnded(int pid) {
  if (pid <= 0) {
    return false;
  }
  if (::kill(pid, 0) != 0 && errno == ESRCH) {
    return true;
  }
  std::ifstream stat(fmt::format("/proc/{}/stat", pid));
  std::string line;
  std::getline(stat, line);
  const std::size_t close = line.rfind(')');  // the name may hold spaces and parentheses
  return close != std::string::npos && close + 2 < line.size() && line[close + 2] == 'Z';
}

// The live file a follow writes: created with the first step, which gives
// it the output's name.
class LiveOutput {
 public:
  LiveOutput(const ImportOptions& options, const SourceDescription& source)
      : m_options(options), m_source(source), m_file(options.output) {}

  bool started() const { return m_writer.has_value(); }
  int steps() const { return m_writer ? m_writer->stepCount() : 0; }

  Status append(SeriesConverter& converter, const SourceStep& step, ImportSummary& summary) {
    if (!m_writer) {
      CRACKVIS_RETURN_IF_ERROR(converter.begin(step));
    }
    auto state = converter.convert(step);
    if (!state) {
      return state.status();
    }
    if (!m_writer) {
      CRACKVIS_RETURN_IF_ERROR(create(converter, step, summary));
      describeArrays(*state, summary);
      summary.brokenFirst = brokenCount(*state);
    }
    CRACKVIS_RETURN_IF_ERROR(m_file.named(m_writer->appendStep(*state)));
    if (!m_published) {
      CRACKVIS_RETURN_IF_ERROR(m_file.named(m_file.commit()));
      m_published = true;
    }
    summary.brokenLast = brokenCount(*state);
    summary.stepsWritten = m_writer->stepCount();
    summary.lastSourceStep = step.sourceStep;
    return Status::ok();
  }

  Status close() { return m_writer ? m_file.named(m_writer->close()) : Status::ok(); }

 private:
  Status create(const SeriesConverter& converter, const SourceStep& first, ImportSummary& summary) {
    const dem::Lattice& lattice = converter.lattice();
    summary.dimension = lattice.dimension;
    summary.particles = lattice.particleCount();
    summary.bonds = lattice.bondCount();
    summary.withGroups = !lattice.particleGroup.empty();
    summary.firstSourceStep = first.sourceStep;
    summary.cutAtStart = static_cast<std::size_t>(
        std::count_if(lattice.bondFlags.begin(), lattice.bondFlags.end(),
                      [](std::uint8_t f) { return (f & dem::kBondCutAtStart) != 0; }));
    dem::DemMetadata metadata;
    metadata.source = m_options.invocation;
    metadata.sourceCode = m_source.code;
    metadata.sourceVersion = m_source.version;
    metadata.sourceFiles = m_source.files;
    metadata.storage = m_options.storage;
    metadata.stepLayout = dem::StepLayout::kAppendable;
    cracks::describeCells(metadata, lattice);
    if (!converter.timeKnown(first) && !(m_options.timestep > 0.0)) {
      metadata.timeUnit = dem::kTimeInIterations;
    }
    auto writer = dem::DemFileWriter::create(m_file.path(), lattice, metadata);
    if (!writer) {
      return m_file.named(writer.status());
    }
    m_writer.emplace(std::move(writer).value());
    return Status::ok();
  }

  const ImportOptions& m_options;
  SourceDescription m_source;
  PendingFile m_file;
  std::optional<dem::DemFileWriter> m_writer;
  bool m_published = false;
};

Status refuseWithFollow(const ImportOptions& options) {
  if (!options.steps.empty()) {
    return invalidArgument("--steps cannot be combined with --follow (it follows every step)");
  }
  if (!options.scalarsTable.empty()) {
    return invalidArgument(
        "--scalars cannot be combined with --follow (the table is read once, before the run "
        "has written it): import the finished run again with it");
  }
  if (options.dryRun) {
    return invalidArgument("--dry-run cannot be combined with --follow");
  }
  if (options.output.empty()) {
    return invalidArgument("--follow needs the output file: -o FILE.h5");
  }
  return Status::ok();
}

}  // namespace

Result<ImportSummary> followSeries(const SourceOpener& open, const ImportOptions& options,
                                   const FollowOptions& follow) {
  CRACKVIS_RETURN_IF_ERROR(refuseWithFollow(options));
  ImportSummary summary;
  std::optional<SeriesConverter> converter;
  std::optional<LiveOutput> output;
  Status lastProblem = failedPrecondition("the source has written nothing yet");
  std::string fingerprint;
  auto unchangedSince = FollowClock::now();
  auto lastStepAt = FollowClock::now();
  const auto pause = std::chrono::duration<double>(follow.poll);
  while (true) {
    // Asked before the look: the look after the code ended takes every step.
    const bool ending = (follow.stopRequested && follow.stopRequested()) ||
                        processEnded(follow.pid) ||
                        (follow.untilIdle > 0.0 && secondsSince(lastStepAt) >= follow.untilIdle);
    auto source = open();
    if (!source) {
      lastProblem = source.status();  // not written yet, or a file half written
    } else {
      if (!converter) {
        summary.source = (*source)->description();
        converter.emplace(summary.source, options.timestep, nullptr);
        output.emplace(options, summary.source);
      }
      const std::string now = filesFingerprint((*source)->description());
      if (now != fingerprint) {
        fingerprint = now;
        unchangedSince = FollowClock::now();
      }
      const int listed = (*source)->stepCount();
      summary.sourceSteps = listed;
      const bool settled = secondsSince(unchangedSince) >= follow.settle;
      const int complete = ending || settled ? listed : listed - 1;
      for (int k = output->steps(); k < complete; ++k) {
        auto step = readChecked(**source, k);
        if (!step) {
          lastProblem = step.status();
          break;  // read again at the next look
        }
        CRACKVIS_RETURN_IF_ERROR(output->append(*converter, *step, summary));
        summary.selected.push_back(k);
        lastStepAt = FollowClock::now();
        if (follow.appended) {
          follow.appended(k, step->sourceStep, summary.brokenLast);
        }
      }
    }
    if (ending) {
      break;
    }
    std::this_thread::sleep_for(pause);
  }
  if (!output || !output->started()) {
    return failedPrecondition(fmt::format("no complete step appeared before the follow ended ({})",
                                          lastProblem.message()));
  }
  CRACKVIS_RETURN_IF_ERROR(output->close());
  summary.reappeared = converter->reappeared();
  summary.timesFromSource = converter->timesFromSource();
  return summary;
}

}  // namespace crackvis::importers
