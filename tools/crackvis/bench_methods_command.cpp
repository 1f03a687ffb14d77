// crackvis bench methods: per-step time of the four crack methods, run
// incrementally over the steps as a viewer would, against Voro++'s global
// Voronoi diagram on the same positions; with memory per particle.
#include <array>
#include <chrono>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/bond_mapping.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/cracks/local_voronoi.hpp>
#include <crackvis/cracks/voro_reference.hpp>
#include <crackvis/dem/step_range.hpp>

namespace crackvis::cli {
namespace {

using Clock = std::chrono::steady_clock;

struct BenchMethodsOptions {
  std::string file;
  std::string steps;
  int voroEvery = 1;
  bool json = false;
  bool quiet = false;
};

constexpr std::array<cracks::Method, 4> kMethods{
    cracks::Method::kCellAttribute, cracks::Method::kCellCut, cracks::Method::kLocalVoronoi,
    cracks::Method::kCellCentre};

struct StepTiming {
  int step = 0;
  std::size_t broken = 0;
  std::array<double, 4> methodMs{};
  std::array<std::size_t, 4> primitives{};
  double voroMs = -1.0;  // not measured at this step
};

double milliseconds(Clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

// The crack a method made at the last measured step (not timed).
struct CrackReport {
  double coverage = 0.0;          // largest component over the section
  double separatingMapped = 0.0;  // of the bonds between the two halves
  double largestShare = 0.0;      // of the main crack's area in the largest component
  double mappedAll = 0.0;         // of all broken bonds
  std::size_t components = 0;
};

struct MethodSummary {
  double totalMs = 0.0;
  double maxMs = 0.0;
  double stateBytesPerParticle = 0.0;
  CrackReport crack;
};

CrackReport reportCrack(const cracks::CrackMesh& mesh, const cracks::StepInput& input,
                        const cracks::CrackExtractor& extractor, const cracks::BondGraph& graph) {
  CrackReport report;
  const cracks::CrackComponents components = cracks::findComponents(mesh);
  report.components = components.components.size();
  if (!components.components.empty()) {
    report.coverage = cracks::sectionCoverage(mesh, components, 0, input);
  }
  const std::vector<std::uint8_t> separating = cracks::separatingBonds(graph, input.bondState);
  const cracks::MainCrack main = cracks::measureMainCrack(mesh, separating, extractor);
  report.separatingMapped = main.mapped.broken > 0 ? main.mapped.fraction() : 0.0;
  report.largestShare = main.largestShare;
  report.mappedAll = cracks::mapBrokenBonds(mesh, input.bondState, extractor).fraction();
  return report;
}

// One method through all steps, as a viewer runs it: reading is not timed,
// the extractor keeps its incremental state from step to step.
Status timeMethod(cracks::DemSeries& series, const std::vector<int>& steps, std::size_t m,
                  std::vector<StepTiming>& timings, MethodSummary& summary, ProgressBar& progress,
                  std::int64_t& done) {
  auto extractor = cracks::makeExtractor(kMethods[m], series.graph(), series.lattice().dimension);
  cracks::CrackMesh mesh;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    auto input = series.load(steps[k]);
    if (!input) {
      return input.status();
    }
    const auto start = Clock::now();
    CRACKVIS_RETURN_IF_ERROR(extractor->extract(*input, mesh));
    const double ms = milliseconds(Clock::now() - start);
    timings[k].step = steps[k];
    timings[k].broken = series.state().brokenBondCount();
    timings[k].methodMs[m] = ms;
    timings[k].primitives[m] = mesh.primitiveCount();
    summary.totalMs += ms;
    summary.maxMs = std::max(summary.maxMs, ms);
    progress.update(++done, fmt::format("{}, step {}", cracks::toString(kMethods[m]), steps[k]));
    if (k + 1 == steps.size()) {
      summary.crack = reportCrack(mesh, *input, *extractor, series.graph());
    }
  }
  // The state each method keeps between steps, plus the bond graph (shared,
  // but counted for each: it is part of what any one method needs).
  summary.stateBytesPerParticle =
      static_cast<double>(extractor->memoryBytes() + series.graph().memoryBytes()) /
      static_cast<double>(series.lattice().particleCount());
  return Status::ok();
}

Status timeVoro(cracks::DemSeries& series, const std::vector<int>& steps, int every,
                std::vector<StepTiming>& timings, double& total, int& count) {
  for (std::size_t k = 0; k < steps.size(); ++k) {
    if (every <= 0 || (k % static_cast<std::size_t>(every) != 0 && k + 1 != steps.size())) {
      continue;
    }
    auto input = series.load(steps[k]);
    if (!input) {
      return input.status();
    }
    // The same domain as the local cells, a hair larger so Voro++ accepts
    // particles on its walls.
    cracks::Box box =
        cracks::defaultDomain(input->positions, input->radius, series.lattice().dimension);
    const double pad = 1e-9 * dem::norm(box.hi - box.lo);
    box.lo = box.lo - dem::Vec3{pad, pad, pad};
    box.hi = box.hi + dem::Vec3{pad, pad, pad};
    const auto start = Clock::now();
    // Voro++'s power diagram (container_poly) for unequal radii, as local
    // Voronoi's radical planes.
    (void)cracks::globalVoronoi(
        input->positions, box, [](const cracks::ReferenceCell&) {}, input->radius);
    timings[k].voroMs = milliseconds(Clock::now() - start);
    total += timings[k].voroMs;
    ++count;
  }
  return Status::ok();
}

int runBenchMethods(const BenchMethodsOptions& options) {
  auto series = cracks::DemSeries::open(options.file);
  if (!series) {
    printError("bench methods", series.status().message());
    return kExitFailure;
  }
  auto steps =
      dem::parseStepRange(options.steps.empty() ? "0:-1" : options.steps, (*series)->stepCount());
  if (!steps) {
    printError("bench methods", steps.status().message());
    return kExitFailure;
  }
  const auto& lattice = (*series)->lattice();
  std::vector<StepTiming> timings(steps->size());
  std::array<MethodSummary, 4> summary{};
  ProgressBar progress("bench methods", static_cast<std::int64_t>(kMethods.size() * steps->size()));
  progress.setEnabled(!options.quiet);
  std::int64_t done = 0;
  for (std::size_t m = 0; m < kMethods.size(); ++m) {
    if (Status status = timeMethod(**series, *steps, m, timings, summary[m], progress, done);
        !status) {
      printError("bench methods", status.message());
      return kExitFailure;
    }
  }
  progress.finish();
  double voroTotal = 0.0;
  int voroCount = 0;
  if (Status status = timeVoro(**series, *steps, options.voroEvery, timings, voroTotal, voroCount);
      !status) {
    printError("bench methods", status.message());
    return kExitFailure;
  }

  const StepTiming& last = timings.back();
  const std::size_t lv = 2;
  const double lastVoro = last.voroMs;
  nlohmann::json json = {
      {"file", options.file},
      {"particles", lattice.particleCount()},
      {"bonds", lattice.bondCount()},
      {"steps_measured", timings.size()},
      {"hardware_threads", static_cast<int>(std::thread::hardware_concurrency())}};
  if (options.json) {
    json["per_step"] = nlohmann::json::array();
    for (const StepTiming& t : timings) {
      nlohmann::json row{{"step", t.step}, {"broken_bonds", t.broken}};
      for (std::size_t m = 0; m < kMethods.size(); ++m) {
        row[std::string(cracks::toString(kMethods[m])) + "_ms"] = t.methodMs[m];
      }
      row["voro++_ms"] = t.voroMs >= 0 ? nlohmann::json(t.voroMs) : nlohmann::json(nullptr);
      json["per_step"].push_back(row);
    }
  } else {
    std::printf("%6s %8s %14s %11s %16s %14s %11s %10s\n", "step", "broken", "cell-attr ms",
                "cell-cut ms", "local-voronoi ms", "cell-centre ms", "voro++ ms", "LV/voro++");
    for (const StepTiming& t : timings) {
      std::printf("%6d %8zu %14.3f %11.3f %16.3f %14.3f ", t.step, t.broken, t.methodMs[0],
                  t.methodMs[1], t.methodMs[2], t.methodMs[3]);
      if (t.voroMs >= 0) {
        std::printf("%11.3f %9.2f%%\n", t.voroMs, 100.0 * t.methodMs[lv] / t.voroMs);
      } else {
        std::printf("%11s %10s\n", "-", "-");
      }
    }
    std::printf("\n%-16s %12s %12s %12s %18s\n", "method", "mean ms/step", "max ms", "total s",
                "bytes/particle");
  }
  nlohmann::json methods = nlohmann::json::object();
  double allMethodsSeconds = 0.0;
  for (std::size_t m = 0; m < kMethods.size(); ++m) {
    const double mean = summary[m].totalMs / static_cast<double>(timings.size());
    allMethodsSeconds += summary[m].totalMs / 1000.0;
    methods[std::string(cracks::toString(kMethods[m]))] = {
        {"mean_ms", mean},
        {"max_ms", summary[m].maxMs},
        {"total_s", summary[m].totalMs / 1000.0},
        {"last_step_ms", last.methodMs[m]},
        {"state_bytes_per_particle", summary[m].stateBytesPerParticle}};
    if (!options.json) {
      std::printf("%-16s %12.3f %12.3f %12.3f %18.1f\n",
                  std::string(cracks::toString(kMethods[m])).c_str(), mean, summary[m].maxMs,
                  summary[m].totalMs / 1000.0, summary[m].stateBytesPerParticle);
    }
  }
  if (!options.json) {
    std::printf(
        "\nthe crack at the last step (step %d; main crack: the broken bonds between the two "
        "largest pieces the intact bonds hold together):\n%-16s %10s %12s %14s %14s %6s\n",
        last.step, "method", "coverage", "main mapped", "main in largest", "broken mapped", "comp");
  }
  for (std::size_t m = 0; m < kMethods.size(); ++m) {
    const CrackReport& r = summary[m].crack;
    const std::string name(cracks::toString(kMethods[m]));
    methods[name]["coverage"] = r.coverage;
    methods[name]["main_crack_bonds_mapped"] = r.separatingMapped;
    methods[name]["main_crack_in_largest_component"] = r.largestShare;
    methods[name]["broken_bonds_mapped"] = r.mappedAll;
    methods[name]["components"] = r.components;
    if (!options.json) {
      std::printf("%-16s %9.1f%% %11.1f%% %13.1f%% %13.1f%% %6zu\n", name.c_str(),
                  100.0 * r.coverage, 100.0 * r.separatingMapped, 100.0 * r.largestShare,
                  100.0 * r.mappedAll, r.components);
    }
  }
  json["methods"] = methods;
  json["all_methods_total_s"] = allMethodsSeconds;
  json["voro++"] = {{"steps_measured", voroCount},
                    {"mean_ms", voroCount > 0 ? voroTotal / voroCount : 0.0},
                    {"last_step_ms", lastVoro}};
  json["ratios"] = {
      {"local_voronoi_over_voro++_last_step", lastVoro > 0 ? last.methodMs[lv] / lastVoro : 0.0},
      {"cell_cut_over_local_voronoi_total", summary[1].totalMs / summary[lv].totalMs},
      {"cell_centre_over_local_voronoi_total", summary[3].totalMs / summary[lv].totalMs}};
  if (options.json) {
    std::printf("%s\n", json.dump(2).c_str());
  } else {
    std::printf("\nvoro++ global diagram: mean %.3f ms over %d steps, last step %.3f ms\n",
                voroCount > 0 ? voroTotal / voroCount : 0.0, voroCount, lastVoro);
    std::printf(
        "ratios: local-voronoi / voro++ at the last step %.2f %% (dissertation 19-25 %%); "
        "cell-cut / local-voronoi %.1f %% (dissertation 20-23 %%), cell-centre / local-voronoi "
        "%.1f %% "
        "(dissertation 44-47 %%), totals over the steps\n",
        lastVoro > 0 ? 100.0 * last.methodMs[lv] / lastVoro : 0.0,
        100.0 * summary[1].totalMs / summary[lv].totalMs,
        100.0 * summary[3].totalMs / summary[lv].totalMs);
    std::printf("all four methods over %zu steps: %.3f s\n", timings.size(), allMethodsSeconds);
  }
  return kExitOk;
}

}  // namespace

Command addBenchMethodsCommand(CLI::App& bench) {
  auto options = std::make_shared<BenchMethodsOptions>();
  auto* command = bench.add_subcommand(
      "methods",
      "Time the four crack methods per step, each run alone through the steps and incremental as "
      "a viewer runs it (reading not timed), against Voro++'s global Voronoi diagram of the same "
      "positions; prints a table (or JSON) with ratios and the bytes per particle each method "
      "keeps between steps.");
  command->add_option("file", options->file, "HDF5 file in the crackvis-dem layout")->required();
  command->add_option("-s,--steps", options->steps, "Steps A, A:B or A:B:K (default: all)");
  command
      ->add_option("--voro-every", options->voroEvery,
                   "Run Voro++ every K-th measured step (and at the last); 0 skips it")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_flag("--json", options->json, "Print JSON");
  command->add_flag("-q,--quiet", options->quiet, "No progress bar");
  return {command, [options] { return runBenchMethods(*options); }};
}

}  // namespace crackvis::cli
