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
#include <functional>
#include <memory>
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

// `crackvis import --follow`: a run that is still writing. The source is
// opened again every `poll` (the code adds files, or steps to a file), and
// each step is appended to a live crackvis-dem file (the appendable layout,
// docs/data-format.md "Live files") as soon as it is complete: a step is
// complete once a later step has appeared, or once the source's files have
// not changed for `settle` (the code finished writing it). The output takes
// its name after the first step; readers see each step as it lands.
struct FollowOptions {
  double untilIdle = 0.0;  // s without a new step after which the import ends; 0: no limit
  double settle = 1.0;     // s the files must rest before the newest step counts as complete
  double poll = 0.5;       // s between looks
  int pid = 0;             // the code's process: the import ends after it ends; 0: none
  // Asked between looks: true ends the import (a signal).
  std::function<bool()> stopRequested;
  // After each appended step: its index, the code's step number, broken bonds.
  std::function<void(int, std::int64_t, std::size_t)> appended;
};
// Opens the source as it is now (its files listed again).
using SourceOpener = std::function<Result<std::unique_ptr<StepSource>>()>;
// Ends when asked (stopRequested, the process `pid` gone, `untilIdle`),
// after appending every step the source then lists (the code is done, so
// the newest step is complete too). Refused: --steps, --scalars, --dry-run.
Result<ImportSummary> followSeries(const SourceOpener& open, const ImportOptions& options,
                                   const FollowOptions& follow);

// The lines `crackvis import` prints at the end (or for --dry-run).
std::string formatSummary(const ImportSummary& summary, const ImportOptions& options);

}  // namespace crackvis::importers
