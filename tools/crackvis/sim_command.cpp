// crackvis sim: runs the lattice DEM solver on a benchmark preset of the
// dissertation's chapter 3.1, or pulls any specimen file (a random packing
// from crackvis generate) with a notch, and writes the crackvis-dem file as
// it goes.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <hdf5.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "commands.hpp"
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/partition.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/sim/presets.hpp>
#include <crackvis/sim/run.hpp>

namespace crackvis::cli {
namespace {

struct SimOptions {
  std::string preset;
  std::string specimen;  // tension: the file whose first step is pulled
  double notchDepth = 0.1;
  std::string output;
  std::string defectSet = "A";
  std::uint64_t seed = 1;
  int threads = 0;
  double scale = 1.0;
  int steps = 0;
  double duration = 0.0;
  bool quiet = false;
  int compress = 0;  // deflate level of the per-step arrays; 0 contiguous
  bool noVelocities = false;
  bool noBondForce = false;
  bool live = false;
  double pace = 0.0;
  std::string stepLog;  // a line per committed step: index, wall-clock time
  // Material overrides; unset keeps the calibrated default.
  std::optional<double> youngsModulus;
  std::optional<double> strainThreshold;
  std::optional<double> strainScale;
  std::optional<double> weibullShape;
  std::optional<double> bondDamping;
};

Result<sim::PresetOptions> presetOptions(const SimOptions& options, bool setGiven) {
  sim::PresetOptions preset;
  preset.name = options.preset;
  if (preset.name == "plate2d" && setGiven) {
    return invalidArgument("--set applies to cuboid3d only (plate2d has one defect)");
  }
  if (preset.name == "tension" && setGiven) {
    return invalidArgument("--set applies to cuboid3d only (tension cuts a notch: --notch-depth)");
  }
  preset.defectSet = options.defectSet.front();
  preset.scale = options.scale;
  preset.seed = options.seed;
  preset.duration = options.duration;
  preset.savedSteps = options.steps;
  sim::MaterialModel material = sim::defaultMaterial(preset.name == "plate2d" ? 2 : 3);
  const bool custom = options.youngsModulus || options.strainThreshold || options.strainScale ||
                      options.weibullShape || options.bondDamping;
  material.youngsModulus = options.youngsModulus.value_or(material.youngsModulus);
  material.strength.minStrain = options.strainThreshold.value_or(material.strength.minStrain);
  material.strength.scaleStrain = options.strainScale.value_or(material.strength.scaleStrain);
  material.strength.shape = options.weibullShape.value_or(material.strength.shape);
  material.bondDamping = options.bondDamping.value_or(material.bondDamping);
  preset.material = material;
  preset.customMaterial = custom;
  return preset;
}

// The specimen's first step, pulled with a notch; bonds already broken there
// stay broken.
Result<sim::Preset> tensionPreset(const SimOptions& options, const sim::PresetOptions& preset) {
  if (options.specimen.empty()) {
    return invalidArgument("tension needs the specimen file: crackvis sim tension FILE -o OUT");
  }
  auto reader = dem::DemFileReader::openGuarded(options.specimen);
  if (!reader) {
    return reader.status();
  }
  auto lattice = reader->readLattice();
  if (!lattice) {
    return lattice.status();
  }
  auto first = reader->readStep(0);
  if (!first) {
    return first.status();
  }
  CRACKVIS_RETURN_IF_ERROR(dem::validateStep(*lattice, *first));
  auto made = sim::makeTensionPreset(*lattice, first->positions, preset, options.notchDepth);
  if (!made) {
    return made.status();
  }
  for (std::size_t b = 0; b < first->bondState.size(); ++b) {
    made->setup.bondState[b] =
        static_cast<std::uint8_t>(made->setup.bondState[b] | first->bondState[b]);
  }
  return made;
}

int runSim(const SimOptions& options, bool setGiven) {
  // libhdf5 closes what is still open at exit, and crashes on a file whose
  // metadata it cannot write (a full disk: SIGSEGV in H5F__close_cb). The
  // writer closes its file itself, or leaves a failed one as its last flush
  // made it, so the library's exit handler has nothing to do; it must be
  // turned off before the first HDF5 call.
  H5dont_atexit();
  auto presetOpts = presetOptions(options, setGiven);
  if (!presetOpts) {
    printError("sim", presetOpts.status().message());
    return kExitFailure;
  }
  auto preset = options.preset == "tension" ? tensionPreset(options, *presetOpts)
                                            : sim::makePreset(*presetOpts);
  if (!preset) {
    printError("sim", preset.status().message());
    return kExitFailure;
  }
  const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                            static_cast<std::size_t>(threads));

  const std::size_t particles = preset->setup.lattice.particleCount();
  const std::size_t bonds = preset->setup.lattice.bondCount();
  const double dt = preset->setup.timeStep;
  const std::string description = preset->description;
  const std::size_t defectBonds = preset->defectBonds;
  const std::int64_t stepsPerSave = preset->stepsPerSave;
  const int savedSteps = preset->savedSteps;
  ProgressBar progress("sim", preset->savedSteps - 1);
  progress.setEnabled(!options.quiet);
  sim::RunOptions run;
  run.path = options.output;
  run.metadata.source = invocation();
  run.metadata.sourceCode = "crackvis sim";
  run.metadata.sourceVersion = CRACKVIS_VERSION;
  run.metadata.storage.deflateLevel = options.compress;
  cracks::describeCells(run.metadata, preset->setup.lattice);
  run.stepsPerSave = preset->stepsPerSave;
  run.savedSteps = preset->savedSteps;
  run.writeVelocities = !options.noVelocities;
  run.writeBondForce = !options.noBondForce;
  run.live = options.live;
  run.pace = options.pace;
  // The header waits for the first saved step, so that a run that cannot
  // start (unwritable output) prints nothing but its error line.
  std::FILE* stepLog = nullptr;
  if (!options.stepLog.empty()) {
    stepLog = std::fopen(options.stepLog.c_str(), "w");
    if (stepLog == nullptr) {
      printError("sim", fmt::format("cannot write the step log {}", options.stepLog));
      return kExitFailure;
    }
  }
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> closeLog(
      stepLog, [](std::FILE* f) { return f != nullptr ? std::fclose(f) : 0; });
  run.onSaved = [&](const sim::RunProgress& at) {
    if (stepLog != nullptr) {
      // After the step's commit: when a reader could first see it.
      const auto now = std::chrono::system_clock::now().time_since_epoch();
      std::fprintf(stepLog, "%d %.9f\n", at.savedStep, std::chrono::duration<double>(now).count());
      std::fflush(stepLog);
    }
    if (at.savedStep == 0 && !options.quiet) {
      std::fprintf(stderr,
                   "%s: %zu particles, %zu bonds, %zu pre-broken; dt %.4g s, %lld steps per save, "
                   "%d saved steps, %d threads\n",
                   description.c_str(), particles, bonds, defectBonds, dt,
                   static_cast<long long>(stepsPerSave), savedSteps, threads);
    }
    progress.update(at.savedStep, fmt::format("step {}, t={:.4g} s, broken {}", at.step, at.time,
                                              at.brokenBonds));
  };
  auto summary = sim::runToFile(std::move(preset->setup), run);
  if (!summary) {
    progress.setEnabled(false);
    printError("sim", summary.status().message());
    return kExitFailure;
  }
  if (!options.quiet) {
    progress.finish();
    const std::size_t broken = summary->brokenPerSavedStep.back();
    std::printf(
        "wrote %s: %d saved steps, %lld time steps, t = %.6g s, broken %zu of %zu bonds "
        "(%.2f %%)\n"
        "wall %.1f s (writing %.1f s): %.0f steps/s, %.3g bond updates/s\n",
        options.output.c_str(), summary->savedSteps, static_cast<long long>(summary->steps),
        summary->simulatedTime, broken, bonds,
        100.0 * static_cast<double>(broken) / static_cast<double>(bonds), summary->wallSeconds,
        summary->writeSeconds, static_cast<double>(summary->steps) / summary->wallSeconds,
        static_cast<double>(summary->steps) * static_cast<double>(bonds) / summary->wallSeconds);
  }
  return kExitOk;
}

}  // namespace

Command addSimCommand(CLI::App& parent) {
  auto options = std::make_shared<SimOptions>();
  auto* command = parent.add_subcommand(
      "sim",
      "Run the lattice DEM solver on a benchmark of the dissertation's chapter 3.1 (uniaxial "
      "tension of a notched specimen), or pull any specimen file with a notch, and write a "
      "crackvis-dem file, step by step.");
  command
      ->add_option("preset", options->preset,
                   "plate2d: 2D plate, 4,680 particles, 1,284 saved steps; cuboid3d: 3D cuboid, "
                   "46,875 particles, 200 saved steps; tension FILE: the first step of FILE (a "
                   "random packing from crackvis generate, say) pulled along x with a notch, 200 "
                   "saved steps")
      ->required()
      ->check(CLI::IsMember({"plate2d", "cuboid3d", "tension"}));
  command->add_option("specimen", options->specimen, "tension: the specimen file (crackvis-dem)");
  command
      ->add_option("--notch-depth", options->notchDepth,
                   "tension: the notch's depth from the bottom face (z; y in 2D), as a fraction "
                   "of the height, across the whole width at mid-length")
      ->check(CLI::Range(0.0, 0.9))
      ->capture_default_str();
  command->add_option("-o,--output", options->output, "Output HDF5 file")->required();
  auto* set = command
                  ->add_option("--set", options->defectSet,
                               "cuboid3d initial defect: A (125 bonds), B (245) or C (121)")
                  ->check(CLI::IsMember({"A", "B", "C"}))
                  ->capture_default_str();
  command->add_option("--seed", options->seed, "Seed of the bond strengths")->capture_default_str();
  command->add_option("--threads", options->threads, "Worker threads (0: all cores)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--scale", options->scale,
                   "Shrink the preset: S times the spheres per axis, radius / S, same geometry "
                   "(0 < S <= 1)")
      ->check(CLI::Range(1e-3, 1.0))
      ->capture_default_str();
  command
      ->add_option("--steps", options->steps,
                   "Saved steps to write (default: the preset's 1,284 or 200), same time between "
                   "saves")
      ->check(CLI::PositiveNumber);
  command
      ->add_option("--duration", options->duration,
                   "Simulated time of the preset's last saved step, s (default: calibrated)")
      ->check(CLI::PositiveNumber);
  command->add_flag("--no-velocities", options->noVelocities,
                    "Do not write the optional per-step velocities");
  command->add_flag("--no-bond-force", options->noBondForce,
                    "Do not write the optional per-step bond forces");
  command->add_flag(
      "--live", options->live,
      "Write a live file that clients can follow while the run goes on: OUTPUT is replaced "
      "once the first step is complete, and each later step is visible to readers as soon as "
      "it is written (HDF5 SWMR, docs/data-format.md \"Live files\")");
  command
      ->add_option("--pace", options->pace,
                   "Write saved steps at least SECONDS apart in wall time, so that a small "
                   "--live run can be watched as it grows (demos, tests)")
      ->check(CLI::Range(0.0, 3600.0));
  command->add_option("--step-log", options->stepLog,
                      "Write a line per saved step as it is committed: its index and the "
                      "wall-clock time (Unix seconds), for measuring how soon followers see it "
                      "(tools/bench/live-follow.sh)");
  command->add_flag("-q,--quiet", options->quiet, "No progress bar and no summary");
  command
      ->add_option("--compress", options->compress,
                   "Store per-step arrays chunked with shuffle + deflate at this level (1-9); "
                   "default contiguous, uncompressed (docs/data-format.md)")
      ->check(CLI::Range(1, 9));
  const char* material = "Material (overrides the calibrated defaults)";
  command->add_option("--youngs-modulus", options->youngsModulus, "Lattice Young's modulus E, Pa")
      ->check(CLI::PositiveNumber)
      ->group(material);
  command
      ->add_option("--strain-threshold", options->strainThreshold,
                   "Bond strain below which no bond breaks")
      ->check(CLI::NonNegativeNumber)
      ->group(material);
  command
      ->add_option("--strain-scale", options->strainScale,
                   "Weibull scale of the bond strain at break above the threshold")
      ->check(CLI::PositiveNumber)
      ->group(material);
  command->add_option("--weibull-shape", options->weibullShape, "Weibull modulus m")
      ->check(CLI::PositiveNumber)
      ->group(material);
  command->add_option("--bond-damping", options->bondDamping, "Damping ratio of the bonds")
      ->check(CLI::NonNegativeNumber)
      ->group(material);
  command->footer(
      "Examples:\n"
      "  crackvis sim cuboid3d --set A -o cuboidA.h5\n"
      "  crackvis sim plate2d --scale 0.25 --seed 7 -o plate-small.h5\n"
      "  crackvis generate --packing random --radius-range 5e-4:1e-3 --box 0.06 0.02 0.02 -o "
      "random.h5\n"
      "  crackvis sim tension random.h5 -o random-run.h5\n"
      "The model, its parameters and their calibration: docs/simulator.md.");
  return {command, [options, set] { return runSim(*options, set->count() > 0); }};
}

}  // namespace crackvis::cli
