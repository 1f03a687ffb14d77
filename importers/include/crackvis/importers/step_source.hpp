// What every importer reads out of a DEM code's output: a series of steps,
// each with its particles (by the code's ids) and the bonds present at that
// step (by the particle ids they join). The import driver (importer.hpp)
// turns such a series into crackvis-dem: it fixes the particle order and
// the bond lattice at the first imported step and marks bonds broken from
// the step they vanish or lose cohesion.
//
// One StepSource per code (LAMMPS, ESyS-Particle, Yade, CSV folder). Steps
// are read one at a time by index, so an import holds one step in memory
// whatever the length of the series.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::importers {

// A bond as a source lists it: the ids of the particles it joins, and
// whether it still holds (a contact that lost cohesion, a bond turned off).
struct SourceBond {
  std::int64_t first = 0;
  std::int64_t second = 0;
  bool cohesive = true;
};

// A break the code itself logged, with its mode (Yade JCFpm's crack file):
// where (the contact point) and how the bond broke.
struct RecordedBreak {
  enum class Mode : std::uint8_t { kTension = 1, kShear = 2 };
  dem::Vec3 at;
  Mode mode = Mode::kTension;
};

// One step of a source, rows in the source's own order.
struct SourceStep {
  std::int64_t sourceStep = 0;  // the code's step or iteration number
  double time = 0.0;            // s; the step number times --timestep when unknown
  bool timeKnown = false;       // whether the source wrote the time
  std::string origin;           // the file(s) the step came from, for messages
  std::vector<std::int64_t> ids;
  std::vector<dem::Vec3> positions;
  std::vector<double> radius;
  std::vector<std::int32_t> group;               // optional
  std::vector<std::array<float, 3>> velocities;  // optional
  std::vector<SourceBond> bonds;                 // the bonds listed at this step
  std::vector<double> bondStrength;              // optional, as `bonds` (first step only)
  std::vector<dem::StepScalar> scalars;          // named scalars the source wrote
  std::vector<dem::ExtraArray> extras;           // per-particle rows as `ids`, per-bond as `bonds`
  // Whether the code logs its breaks (then every step says so), and those it
  // logged after the previous step, up to and including this one.
  bool recordsBreaks = false;
  std::vector<RecordedBreak> breaks;
};

// Provenance of a source (crackvis-dem v1.1 root attributes).
struct SourceDescription {
  std::string code;     // "LAMMPS"
  std::string version;  // as the code wrote it, when it did
  std::vector<std::string> files;
  int dimension = 3;
  // What the source skipped or guessed, for the summary's "note" lines
  // ("skipped 11 files of VTKRecorder's 'cracks' recorder ...").
  std::vector<std::string> notes;
};

class StepSource {
 public:
  virtual ~StepSource() = default;
  virtual const SourceDescription& description() const = 0;
  // The steps found, in the code's step order.
  virtual int stepCount() const = 0;
  virtual std::int64_t sourceStepNumber(int index) const = 0;
  virtual Result<SourceStep> readStep(int index) = 0;
};

// The sources. Each takes the files or folders a user names (a folder is
// searched for the files that source writes) and lists the steps without
// reading them; a missing or unrecognised file is an error naming it.
Result<std::unique_ptr<StepSource>> openLammps(const std::vector<std::string>& inputs);
Result<std::unique_ptr<StepSource>> openEsys(const std::vector<std::string>& inputs);
Result<std::unique_ptr<StepSource>> openYade(const std::vector<std::string>& inputs);
Result<std::unique_ptr<StepSource>> openCsv(const std::vector<std::string>& inputs);

}  // namespace crackvis::importers
