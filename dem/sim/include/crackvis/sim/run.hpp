// Runs a simulation and writes it, saved step by saved step, to a
// crackvis-dem file (docs/data-format.md). Each saved step is appended and
// flushed as soon as it is computed, so an interrupted run leaves a readable
// file with the steps done so far.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/sim/simulator.hpp>

namespace crackvis::sim {

struct RunProgress {
  int savedStep = 0;  // just written
  int savedSteps = 0;
  std::int64_t step = 0;  // time steps done
  double time = 0.0;
  std::size_t brokenBonds = 0;
};

struct RunOptions {
  std::string path;
  dem::DemMetadata metadata;
  std::int64_t stepsPerSave = 1;
  int savedSteps = 1;  // including the initial state, saved step 0
  bool writeVelocities = true;
  bool writeBondForce = true;
  // Write a live file (the appendable layout, docs/data-format.md): it takes
  // the output's name after its first step, and readers see each step as it
  // is committed.
  bool live = false;
  // Saved steps at least this many seconds apart in wall time (0: as fast as
  // the solver goes): a small run that a viewer can watch grow.
  double pace = 0.0;
  std::function<void(const RunProgress&)> onSaved;  // called after each saved step
};

struct RunSummary {
  int savedSteps = 0;
  std::int64_t steps = 0;
  double simulatedTime = 0.0;
  double wallSeconds = 0.0;   // simulation and writing
  double writeSeconds = 0.0;  // of which writing the file
  std::size_t particles = 0;
  std::size_t bonds = 0;
  std::vector<std::size_t> brokenPerSavedStep;
};

Result<RunSummary> runToFile(SimulationSetup setup, const RunOptions& options);

}  // namespace crackvis::sim
