#include <chrono>
#include <cmath>
#include <tuple>

#include <fmt/format.h>

#include <crackvis/common/elapsed.hpp>
#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/source/step_source.hpp>

namespace crackvis::source {
namespace {

using Clock = std::chrono::steady_clock;

// A file's data enters a session here, checked by the rules `crackvis info`
// and `extract` apply (dem::validateTopology, dem::validateStep): whatever a
// file holds, the extraction and the renderer see only finite, bounded
// positions and bonds between distinct existing particles.
Status badData(const std::string& file, const Status& problem, int step = -1) {
  return failedPrecondition(step < 0
                                ? fmt::format("{}: {}", file, problem.message())
                                : fmt::format("{}: step {}: {}", file, step, problem.message()));
}

// One colour value per row (particle or bond) from an extra array of 1 or 3
// components (a vector's magnitude); every value finite, or the step is
// refused.
Result<std::vector<float>> extraValues(const std::string& file, int step, const std::string& name,
                                       const std::vector<double>& values, int components) {
  const auto width = static_cast<std::size_t>(components);
  std::vector<float> out(width > 0 ? values.size() / width : 0);
  for (std::size_t i = 0; i < out.size(); ++i) {
    double sum = 0.0;
    for (std::size_t c = 0; c < width; ++c) {
      const double v = values[i * width + c];
      sum += width == 1 ? v : v * v;
    }
    const double value = width == 1 ? sum : std::sqrt(sum);
    if (!std::isfinite(value)) {
      return badData(
          file, invalidArgument(fmt::format("extra array '{}': value {} is not finite", name, i)),
          step);
    }
    out[i] = static_cast<float>(value);
  }
  return out;
}

// What the two sources share: the lattice, the break steps, the arrays a
// view colours by, and how a step read from either becomes a SourceStep
// (the range check, the timing, the colours, whatever the view does not use
// left out). A subclass reads the file.
class FileSource : public StepSource {
 public:
  const dem::Lattice& lattice() const final { return m_lattice; }
  const std::vector<std::int32_t>& breakSteps() const final { return m_breakSteps; }

  Status setExtraArrays(const ExtraArrays& extras) final {
    m_extras = extras;
    return loadBreakSteps();
  }

  Result<bool> refresh() final {
    auto grew = refreshSteps();
    if (grew && *grew) {
      // New steps' breaks: the writer updates /bonds/break_step with each.
      CRACKVIS_RETURN_IF_ERROR(loadBreakSteps());
    }
    return grew;
  }

  Result<SourceStep> read(int step) final {
    CRACKVIS_RETURN_IF_ERROR(checkStepInRange(file(), step, stepCount()));
    const auto start = Clock::now();
    auto state = readState(step);
    if (!state) {
      return state.status();
    }
    SourceStep out;
    out.index = step;
    out.time = state->time;
    out.positions = std::move(state->positions);
    out.bondState = std::move(state->bondState);
    if (m_extras.velocities) {
      out.velocities = std::move(state->velocities);
    }
    if (m_extras.bondForce) {
      out.bondForce = std::move(state->bondForce);
    }
    for (const auto& [owner, name, target] :
         {std::tuple{dem::ExtraOwner::kParticles, &m_extras.particleExtra, &out.particleExtra},
          std::tuple{dem::ExtraOwner::kBonds, &m_extras.bondExtra, &out.bondExtra}}) {
      if (!name->empty()) {
        CRACKVIS_RETURN_IF_ERROR(extraColours(step, *state, owner, *name, *target));
      }
    }
    out.loadMs = millisecondsSince(start);
    return out;
  }

 protected:
  virtual Result<std::vector<std::int32_t>> readBreakSteps() = 0;
  virtual Result<bool> refreshSteps() = 0;
  // A step checked by the rules of dem::validateStep, with the extra arrays
  // the view colours by among its extras (or the lattice's constant ones).
  virtual Result<dem::StepState> readState(int step) = 0;

  const ExtraArrays& extras() const { return m_extras; }
  dem::Lattice m_lattice;

 private:
  // The extra array by name: the step's own, else the lattice's constant
  // one; one value per row.
  Status extraColours(int step, const dem::StepState& state, dem::ExtraOwner owner,
                      const std::string& name, std::vector<float>& out) const {
    std::vector<std::string> known;
    for (const auto* extras : {&state.extras, &m_lattice.extras}) {
      for (const dem::ExtraArray& extra : *extras) {
        if (extra.owner != owner) {
          continue;
        }
        if (extra.name == name) {
          auto values = extraValues(file(), step, name, extra.values, extra.components);
          if (!values) {
            return values.status();
          }
          out = std::move(values).value();
          return Status::ok();
        }
        known.push_back(extra.name);
      }
    }
    return failedPrecondition(fmt::format(
        "{}: no per-{} extra array '{}' at step {} (the file has: {})", file(),
        owner == dem::ExtraOwner::kBonds ? "bond" : "particle", name, step,
        known.empty() ? std::string("none") : fmt::format("{}", fmt::join(known, ", "))));
  }

  Status loadBreakSteps() {
    m_breakSteps.clear();
    if (m_extras.breakStep) {
      auto breakSteps = readBreakSteps();
      if (!breakSteps) {
        return breakSteps.status();
      }
      m_breakSteps = std::move(breakSteps).value();
    }
    return Status::ok();
  }

  ExtraArrays m_extras;
  std::vector<std::int32_t> m_breakSteps;
};

class RemoteSource final : public FileSource {
 public:
  explicit RemoteSource(dataservice::RemoteDemFile remote) : m_remote(std::move(remote)) {}

  Status load() {
    auto bonds = m_remote.takeBonds();  // the lattice keeps them: not copied
    if (!bonds) {
      return bonds.status();
    }
    auto radii = m_remote.radii();
    if (!radii) {
      return radii.status();
    }
    m_lattice.dimension = m_remote.dimension();
    m_lattice.bonds = std::move(bonds).value();
    m_lattice.radius = std::move(radii).value();
    // The bond list's range was checked as it arrived (RemoteDemFile).
    if (Status valid = dem::validateTopology(m_lattice, dem::BondEnds::kCheckedAlready); !valid) {
      return badData(file(), valid);
    }
    return Status::ok();
  }

  const std::string& file() const override { return m_remote.file(); }
  int stepCount() const override { return m_remote.stepCount(); }
  double describeMs() const override { return m_remote.describeMs(); }
  dem::CellDecomposition recordedDecomposition() const override {
    return m_remote.recordedDecomposition();
  }
  bool timeInIterations() const override { return m_remote.timeInIterations(); }
  bool appendable() const override { return m_remote.appendable(); }
  bool beingWritten() const override { return m_remote.beingWritten(); }

 private:
  Result<std::vector<std::int32_t>> readBreakSteps() override { return m_remote.breakSteps(); }
  Result<bool> refreshSteps() override { return m_remote.refresh(); }

  // Only what the view uses crosses the network: the extras are asked for.
  Result<dem::StepState> readState(int step) override {
    const ExtraArrays& wanted = extras();
    auto remote = m_remote.readStep(
        step, {wanted.velocities, wanted.bondForce, wanted.particleExtra, wanted.bondExtra});
    if (!remote) {
      return remote.status();
    }
    dem::StepState state;
    state.time = remote->time;
    state.positions = std::move(remote->positions);
    state.bondState = std::move(remote->bondState);
    state.velocities = std::move(remote->velocities);
    state.bondForce = std::move(remote->bondForce);
    if (Status valid = dem::validateStep(m_lattice, state); !valid) {
      return badData(file(), valid, step);
    }
    if (!wanted.particleExtra.empty()) {
      state.extras.push_back({wanted.particleExtra, dem::ExtraOwner::kParticles,
                              remote->particleExtraComponents, std::move(remote->particleExtra)});
    }
    if (!wanted.bondExtra.empty()) {
      state.extras.push_back({wanted.bondExtra, dem::ExtraOwner::kBonds,
                              remote->bondExtraComponents, std::move(remote->bondExtra)});
    }
    return state;
  }

  dataservice::RemoteDemFile m_remote;
};

// The local reader validates with the same rules as it reads (readLattice,
// readStep): FAILED_PRECONDITION "FILE: step K: ..." as above. It reads
// every optional array of a step anyway.
class LocalSource final : public FileSource {
 public:
  LocalSource(std::string path, dem::DemFileReader reader)
      : m_path(std::move(path)), m_reader(std::move(reader)) {}

  Status load() {
    auto lattice = m_reader.readLattice();
    if (!lattice) {
      return lattice.status();
    }
    m_lattice = std::move(lattice).value();
    // An index the reader refuses only loses the shortcut: "auto" decides.
    if (auto index = m_reader.readSpatialIndexInfo(); index && *index) {
      m_decomposition = (*index)->decomposition;
    }
    return Status::ok();
  }

  const std::string& file() const override { return m_path; }
  int stepCount() const override { return m_reader.stepCount(); }
  bool timeInIterations() const override {
    return m_reader.info().timeUnit == dem::kTimeInIterations;
  }
  bool appendable() const override {
    return m_reader.info().stepLayout == dem::StepLayout::kAppendable;
  }
  bool beingWritten() const override { return m_reader.info().beingWritten; }
  dem::CellDecomposition recordedDecomposition() const override { return m_decomposition; }

 private:
  Result<std::vector<std::int32_t>> readBreakSteps() override { return m_reader.readBreakSteps(); }
  Result<bool> refreshSteps() override {
    if (!appendable()) {
      return false;
    }
    const int before = m_reader.stepCount();
    CRACKVIS_RETURN_IF_ERROR(m_reader.refreshSteps());
    return m_reader.stepCount() > before;
  }
  Result<dem::StepState> readState(int step) override { return m_reader.readStep(step); }

  std::string m_path;
  dem::DemFileReader m_reader;
  dem::CellDecomposition m_decomposition = dem::CellDecomposition::kUnknown;
};

}  // namespace

Result<std::unique_ptr<StepSource>> openRemoteSource(const dataservice::DataClient& client,
                                                     const std::string& file,
                                                     const dem::SizeLimits& limits) {
  // A view shows a step next: its bond list and radii stream while the file
  // is described.
  auto remote = dataservice::RemoteDemFile::open(client, file,
                                                 {.prefetchBondList = true, .prefetchRadii = true});
  if (!remote) {
    return remote.status();
  }
  CRACKVIS_RETURN_IF_ERROR(
      dem::checkDeclaredSizes(file, {remote->particleCount(), remote->bondCount()}, limits));
  auto source = std::make_unique<RemoteSource>(std::move(remote).value());
  CRACKVIS_RETURN_IF_ERROR(source->load());
  return std::unique_ptr<StepSource>(std::move(source));
}

Result<std::unique_ptr<StepSource>> openLocalSource(const std::string& path,
                                                    const dem::SizeLimits& limits, LocalOpen how) {
  auto reader = how == LocalOpen::kStructureInChild ? dem::DemFileReader::openGuarded(path)
                                                    : dem::DemFileReader::open(path);
  if (!reader) {
    return reader.status();
  }
  CRACKVIS_RETURN_IF_ERROR(dem::checkDeclaredSizes(
      path, {reader->info().particleCount, reader->info().bondCount}, limits));
  auto source = std::make_unique<LocalSource>(path, std::move(reader).value());
  CRACKVIS_RETURN_IF_ERROR(source->load());
  return std::unique_ptr<StepSource>(std::move(source));
}

}  // namespace crackvis::source
