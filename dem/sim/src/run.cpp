#include <chrono>
#include <thread>

#include <fmt/format.h>

#include <crackvis/common/pending_file.hpp>
#include <crackvis/sim/run.hpp>

namespace crackvis::sim {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A run that stops part way (a full disk) keeps its complete steps in the
// partial file, readable, and says where; the output's name still holds
// what it held before.
Status keptSteps(PendingFile& output, int steps, bool published, const Status& failure) {
  const Status named = output.named(failure);
  if (steps == 0) {
    return named;
  }
  output.keep();
  return {named.code(), fmt::format("{} (the {} complete steps are in {})", named.message(), steps,
                                    published ? output.target() : output.path())};
}

}  // namespace

Result<RunSummary> runToFile(SimulationSetup setup, const RunOptions& options) {
  if (options.savedSteps < 1 || options.stepsPerSave < 1) {
    return invalidArgument(
        fmt::format("need at least 1 saved step and 1 step per save, got {} and {}",
                    options.savedSteps, options.stepsPerSave));
  }
  const auto start = std::chrono::steady_clock::now();
  const dem::Lattice lattice = setup.lattice;
  auto simulator = Simulator::create(std::move(setup));
  if (!simulator) {
    return simulator.status();
  }
  dem::DemMetadata metadata = options.metadata;
  metadata.plannedSteps = options.savedSteps;
  if (options.live) {
    metadata.stepLayout = dem::StepLayout::kAppendable;
  }
  // Written beside the output and renamed over it at the end: an existing
  // file stays as it was until the run is complete (a killed run leaves its
  // complete steps readable in OUTPUT.partial).
  PendingFile output(options.path);
  auto writer = dem::DemFileWriter::create(output.path(), lattice, metadata);
  if (!writer) {
    return output.named(writer.status());
  }
  // A live file takes the output's name once its first step is complete, so
  // readers can follow it; until then the old file stays.
  bool published = false;
  RunSummary summary;
  summary.particles = simulator->particleCount();
  summary.bonds = simulator->bondCount();
  for (int saved = 0; saved < options.savedSteps; ++saved) {
    if (saved > 0) {
      simulator->advance(options.stepsPerSave);
    }
    const auto writeStart = std::chrono::steady_clock::now();
    if (Status written = writer->appendStep(
            simulator->snapshot(options.writeVelocities, options.writeBondForce));
        !written) {
      return keptSteps(output, writer->stepCount(), published, written);
    }
    if (options.pace > 0.0) {
      std::this_thread::sleep_until(start +
                                    std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                        std::chrono::duration<double>(options.pace * (saved + 1))));
    }
    if (options.live && !published) {
      CRACKVIS_RETURN_IF_ERROR(output.named(output.commit()));
      published = true;
    }
    summary.writeSeconds += secondsSince(writeStart);
    summary.brokenPerSavedStep.push_back(simulator->brokenBondCount());
    if (options.onSaved) {
      options.onSaved({saved, options.savedSteps, simulator->stepIndex(), simulator->time(),
                       summary.brokenPerSavedStep.back()});
    }
  }
  CRACKVIS_RETURN_IF_ERROR(output.named(writer->close()));
  if (!published) {
    CRACKVIS_RETURN_IF_ERROR(output.named(output.commit()));
  }
  summary.savedSteps = options.savedSteps;
  summary.steps = simulator->stepIndex();
  summary.simulatedTime = simulator->time();
  summary.wallSeconds = secondsSince(start);
  return summary;
}

}  // namespace crackvis::sim
