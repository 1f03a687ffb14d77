// `crackvis import`: turns a StepSource's series into a crackvis-dem v1.1
// file, one step at a time (memory independent of the number of steps).
//
// The first imported step fixes the particle order (ascending id) and the
// bond lattice: every bond listed there. A bond listed there without
// cohesion (a turned-off bond, a contact on a joint) is flagged cut at the
// start (a notch) and broken throughout. From then on a bond is broken from
// the first step at which it is missing or not cohesive, and stays broken
// (bonds never heal: a later reappearance is counted, not believed).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/h5.hpp>
#include <crackvis/importers/step_source.hpp>

namespace crackvis::importers {

struct ImportOptions {
  std::string output;        // the crackvis-dem file to write
  std::string steps;         // "A", "A:B" or "A:B:K" over the source's steps; empty: all
  double timestep = 0.0;     // s per source step, for sources that write no time
  std::string scalarsTable;  // optional table of per-step scalars (scalar_table.hpp)
  // Import although the table has rows for only some of the imported steps
  // (the others get no table scalars; with a time column, their time from
  // a straight line through the table's times). Without it that is refused.
  bool partialScalars = false;
  bool dryRun = false;  // read the first and last step only, write nothing
  bool progress = true;
  dem::h5::Storage storage;
  std::string invocation;  // the command line, recorded as the file's `source`
};

struct ImportSummary {
  SourceDescription source;
  int sourceSteps = 0;               // steps the source holds
  std::vector<int> selected;         // indices imported
  std::int64_t firstSourceStep = 0;  // the code's step numbers of the first and
  std::int64_t lastSourceStep = 0;   // last imported step
  int dimension = 3;
  std::size_t particles = 0;     // N
  std::size_t bonds = 0;         // M
  std::size_t cutAtStart = 0;    // bonds flagged as a notch
  std::size_t brokenFirst = 0;   // broken at the first and last imported
  std::size_t brokenLast = 0;    // step (cut-at-start bonds included)
  std::size_t reappeared = 0;    // broken bonds a later step listed again (kept broken)
  bool timesFromSource = false;  // false: time = step number x --timestep
  int stepsWritten = 0;
  std::vector<std::string> scalarNames;
  std::size_t scalarRowsMatched = 0;    // imported steps the --scalars table has a row for
  std::vector<std::string> notes;       // the summary's "note" lines, beside the source's
  std::vector<std::string> extraNames;  // "particles/NAME", "bonds/NAME"
  bool withVelocities = false;
  bool withGroups = false;
};

Result<ImportSummary> importSeries(StepSource& source, const ImportOptions& options);

// The lines `crackvis import` prints at the end (or for --dry-run).
std::string formatSummary(const ImportSummary& summary, const ImportOptions& options);

}  // namespace crackvis::importers
