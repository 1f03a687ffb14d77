// crackvis bench methods: per-step time of the four crack methods, run
// incrementally over the steps as a viewer would, against the leanest honest
// global baseline: Voro++ computing each cell's neighbours and face areas of
// the same positions. Measured on equal terms: at 1 thread against one Voro++
// container, and at N threads against N Voro++ containers over slabs; the
// method passes and the baseline passes alternate, run after run, and every
// figure is the median over the runs. Beside them, the analyses of
// analysis/ (opening, fragments, orientation and modes, growth) on local
// Voronoi's crack, step by step as `crackvis report` runs them.
#include <array>
#include <chrono>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "bench_support.hpp"
#include "commands.hpp"
#include <crackvis/analysis/growth.hpp>
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/bond_mapping.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/cracks/local_voronoi.hpp>
#include <crackvis/cracks_voro/voro_reference.hpp>
#include <crackvis/dem/step_range.hpp>

namespace crackvis::cli {
namespace {

using Clock = std::chrono::steady_clock;

struct BenchMethodsOptions {
  std::string file;
  std::string steps;
  int voroEvery = 10;
  int runs = 5;
  int threads = 0;  // 0: all hardware threads
  bool json = false;
  bool quiet = false;
};

constexpr std::array<cracks::Method, 4> kMethods{
    cracks::Method::kCellAttribute, cracks::Method::kCellCut, cracks::Method::kLocalVoronoi,
    cracks::Method::kCellCentre};
constexpr std::size_t kLocalVoronoi = 2;

double milliseconds(Clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

std::string methodName(std::size_t m) {
  return std::string(cracks::toString(kMethods[m]));
}

// The crack a method made at the last measured step (not timed).
struct CrackReport {
  double coverage = 0.0;          // largest component over the section
  double separatingMapped = 0.0;  // of the bonds between the two halves
  double largestShare = 0.0;      // of the main crack's area in the largest component
  double mappedAll = 0.0;         // of all broken bonds
  std::size_t components = 0;
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

// What the methods keep between steps and the crack they made: measured
// once (the first run at 1 thread), not timed.
struct MethodFacts {
  double stateBytesPerParticle = 0.0;
  CrackReport crack;
};

// One pass of one configuration: per measured step, each method's time and
// the baseline's (negative: the baseline was not run at that step).
struct Pass {
  std::vector<std::array<double, 4>> methodMs;
  std::vector<double> analysisMs;  // the analyses after local Voronoi
  std::vector<double> voroMs;
  std::vector<std::size_t> brokenBonds;  // per step, as the methods saw it
};

struct Config {
  int threads = 1;
  std::vector<Pass> runs;
  cracks::LeanVoronoiSummary voro;  // of the last baseline step, as a check
  std::size_t haloWallFaces = 0;    // over every baseline step: 0 when every diagram was exact
};

struct Measurement {
  std::vector<int> steps;
  std::vector<std::size_t> broken;  // broken bonds per step
  std::vector<bool> voroStep;       // the baseline runs at this step
  std::vector<Config> configs;
  std::array<MethodFacts, 4> facts{};
  LoadAverage loadBefore;
  LoadAverage loadAfter;
};

struct Progress {
  ProgressBar& bar;
  std::int64_t done = 0;
  void step(const std::string& what) { bar.update(++done, what); }
};

volatile double analysisSink = 0.0;

// The analyses of one step, as `crackvis report` runs them: opening,
// fragments, modes and growth (analyse), and the orientation distribution.
double timeAnalyses(analysis::CrackAnalysis& analyses, int step, const cracks::StepInput& input,
                    const cracks::CrackMesh& mesh) {
  const auto start = Clock::now();
  analyses.analyse(step, 0.0, input, input.referencePositions, mesh);
  // Kept in a volatile: the compiler may not drop work whose result is unused.
  analysisSink = analysis::meanOrientation(analyses.openings(), 0).strength;
  analysisSink = mesh.dimension == 2 ? analysis::roseDiagram(analyses.openings(), -1, 36).weight[0]
                                     : analysis::stereonet(analyses.openings(), -1, 40).weight[0];
  return milliseconds(Clock::now() - start);
}

// One method through all steps, as a viewer runs it: reading is not timed,
// the extractor keeps its incremental state from step to step.
Status timeMethod(cracks::DemSeries& series, const std::vector<int>& steps, std::size_t m,
                  int threads, Pass& pass, MethodFacts* facts, Progress& progress) {
  auto extractor = cracks::makeExtractor(kMethods[m], series.graph(), series.lattice().dimension);
  analysis::CrackAnalysis analyses(series.lattice(), {});
  cracks::CrackMesh mesh;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    auto input = series.load(steps[k]);
    if (!input) {
      return input.status();
    }
    const auto start = Clock::now();
    CRACKVIS_RETURN_IF_ERROR(extractor->extract(*input, mesh));
    pass.methodMs[k][m] = milliseconds(Clock::now() - start);
    if (m == kLocalVoronoi) {
      pass.analysisMs[k] = timeAnalyses(analyses, steps[k], *input, mesh);
    }
    pass.brokenBonds[k] = series.state().brokenBondCount();
    progress.step(fmt::format("{}, {} thread{}, step {}", methodName(m), threads,
                              threads == 1 ? "" : "s", steps[k]));
    if (facts != nullptr && k + 1 == steps.size()) {
      facts->crack = reportCrack(mesh, *input, *extractor, series.graph());
    }
  }
  if (facts != nullptr) {
    // The state each method keeps between steps, plus the bond graph
    // (shared, but counted for each: it is part of what any one method needs).
    facts->stateBytesPerParticle =
        static_cast<double>(extractor->memoryBytes() + series.graph().memoryBytes()) /
        static_cast<double>(series.lattice().particleCount());
  }
  return Status::ok();
}

// The baseline at the steps it runs at, with as many Voro++ containers
// (slabs, one thread each) as the methods had threads.
Status timeVoro(cracks::DemSeries& series, Measurement& measurement, Config& config, Pass& pass,
                Progress& progress) {
  for (std::size_t k = 0; k < measurement.steps.size(); ++k) {
    if (!measurement.voroStep[k]) {
      continue;
    }
    auto input = series.load(measurement.steps[k]);
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
    config.voro = cracks::leanVoronoi(input->positions, box, input->radius, config.threads);
    pass.voroMs[k] = milliseconds(Clock::now() - start);
    config.haloWallFaces += config.voro.haloWallFaces;
    progress.step(fmt::format("Voro++, {} container{}, step {}", config.threads,
                              config.threads == 1 ? "" : "s", measurement.steps[k]));
  }
  return Status::ok();
}

// Runs after runs, each: per configuration, the four methods then the
// baseline, so that neither gets a quieter stretch of the machine.
Status measure(cracks::DemSeries& series, const BenchMethodsOptions& options,
               Measurement& measurement, ProgressBar& bar) {
  Progress progress{bar};
  measurement.loadBefore = loadAverage();
  for (int run = 0; run < options.runs; ++run) {
    for (std::size_t c = 0; c < measurement.configs.size(); ++c) {
      Config& config = measurement.configs[c];
      const tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                      static_cast<std::size_t>(config.threads));
      Pass pass;
      pass.methodMs.assign(measurement.steps.size(), {});
      pass.analysisMs.assign(measurement.steps.size(), 0.0);
      pass.voroMs.assign(measurement.steps.size(), -1.0);
      pass.brokenBonds.assign(measurement.steps.size(), 0);
      for (std::size_t m = 0; m < kMethods.size(); ++m) {
        const bool first = run == 0 && c == 0;
        CRACKVIS_RETURN_IF_ERROR(timeMethod(series, measurement.steps, m, config.threads, pass,
                                            first ? &measurement.facts[m] : nullptr, progress));
      }
      CRACKVIS_RETURN_IF_ERROR(timeVoro(series, measurement, config, pass, progress));
      config.runs.push_back(std::move(pass));
    }
  }
  measurement.broken = measurement.configs.front().runs.front().brokenBonds;
  measurement.loadAfter = loadAverage();
  return Status::ok();
}

// A configuration's figures: per step the median over the runs, then
// summaries over the steps.
struct StepMedians {
  std::vector<std::array<double, 4>> methodMs;
  std::vector<double> analysisMs;
  std::vector<double> voroMs;  // negative where not measured
};

StepMedians medians(const Config& config) {
  const std::size_t steps = config.runs.front().methodMs.size();
  StepMedians out;
  out.methodMs.assign(steps, {});
  out.voroMs.assign(steps, -1.0);
  for (std::size_t k = 0; k < steps; ++k) {
    std::vector<double> analysis;
    for (const Pass& pass : config.runs) {
      analysis.push_back(pass.analysisMs[k]);
    }
    out.analysisMs.push_back(median(analysis));
    for (std::size_t m = 0; m < kMethods.size(); ++m) {
      std::vector<double> values;
      for (const Pass& pass : config.runs) {
        values.push_back(pass.methodMs[k][m]);
      }
      out.methodMs[k][m] = median(values);
    }
    if (config.runs.front().voroMs[k] >= 0.0) {
      std::vector<double> values;
      for (const Pass& pass : config.runs) {
        values.push_back(pass.voroMs[k]);
      }
      out.voroMs[k] = median(values);
    }
  }
  return out;
}

std::string baselineName(int threads) {
  return threads == 1
             ? "Voro++ 0.4.6, one container, neighbours and face areas, 1 thread"
             : fmt::format(
                   "Voro++ 0.4.6, {} containers over slabs with a halo, neighbours and face "
                   "areas, {} threads",
                   threads, threads);
}

nlohmann::json configJson(const Measurement& measurement, const Config& config) {
  const StepMedians med = medians(config);
  const std::size_t last = measurement.steps.size() - 1;
  nlohmann::json methods = nlohmann::json::object();
  for (std::size_t m = 0; m < kMethods.size(); ++m) {
    std::vector<double> perStep;
    std::vector<double> ratios;
    double total = 0.0;
    double largest = 0.0;
    for (std::size_t k = 0; k < med.methodMs.size(); ++k) {
      perStep.push_back(med.methodMs[k][m]);
      total += med.methodMs[k][m];
      largest = std::max(largest, med.methodMs[k][m]);
      if (med.voroMs[k] > 0.0) {
        ratios.push_back(med.methodMs[k][m] / med.voroMs[k]);
      }
    }
    methods[methodName(m)] = {
        {"median_ms", median(perStep)},
        {"mean_ms", mean(perStep)},
        {"max_ms", largest},
        {"total_s", total / 1000.0},
        {"last_step_ms", med.methodMs[last][m]},
        // null where the baseline did not run (--voro-every 0).
        {"over_voro++_last_step", med.voroMs[last] > 0.0
                                      ? nlohmann::json(med.methodMs[last][m] / med.voroMs[last])
                                      : nlohmann::json(nullptr)},
        {"over_voro++_median_over_steps",
         ratios.empty() ? nlohmann::json(nullptr) : nlohmann::json(median(ratios))},
        {"over_voro++_max_over_steps",
         ratios.empty() ? nlohmann::json(nullptr)
                        : nlohmann::json(*std::max_element(ratios.begin(), ratios.end()))}};
  }
  // The analyses against the method whose crack they measure, per step.
  std::vector<double> analysisRatios;
  for (std::size_t k = 0; k < med.analysisMs.size(); ++k) {
    if (med.methodMs[k][kLocalVoronoi] > 0.0) {
      analysisRatios.push_back(med.analysisMs[k] / med.methodMs[k][kLocalVoronoi]);
    }
  }
  const double analysisMedian = median(med.analysisMs);
  const double lvMedian = methods[methodName(kLocalVoronoi)].at("median_ms").get<double>();
  const nlohmann::json analyses{
      {"what",
       "opening, fragments, break modes and growth (CrackAnalysis::analyse) and the "
       "orientation distribution, on local Voronoi's crack of each step"},
      {"median_ms", analysisMedian},
      {"last_step_ms", med.analysisMs[last]},
      {"max_ms", *std::max_element(med.analysisMs.begin(), med.analysisMs.end())},
      {"over_local_voronoi_median_ms", lvMedian > 0.0 ? analysisMedian / lvMedian : 0.0},
      {"over_local_voronoi_median_over_steps", median(analysisRatios)},
      {"over_local_voronoi_max_over_steps",
       analysisRatios.empty() ? 0.0
                              : *std::max_element(analysisRatios.begin(), analysisRatios.end())}};
  std::vector<double> voro;
  for (double v : med.voroMs) {
    if (v >= 0.0) {
      voro.push_back(v);
    }
  }
  nlohmann::json perStep = nlohmann::json::array();
  for (std::size_t k = 0; k < measurement.steps.size(); ++k) {
    nlohmann::json row{{"step", measurement.steps[k]}, {"broken_bonds", measurement.broken[k]}};
    for (std::size_t m = 0; m < kMethods.size(); ++m) {
      row[methodName(m) + "_ms"] = med.methodMs[k][m];
    }
    row["voro++_ms"] = med.voroMs[k] >= 0 ? nlohmann::json(med.voroMs[k]) : nlohmann::json(nullptr);
    row["analyses_ms"] = med.analysisMs[k];
    perStep.push_back(row);
  }
  return {{"threads", config.threads},
          {"baseline", baselineName(config.threads)},
          {"voro++",
           {{"steps_measured", voro.size()},
            {"median_ms", median(voro)},
            {"last_step_ms", med.voroMs[last]},
            {"containers", config.voro.containers},
            {"cells", config.voro.cells},
            {"faces", config.voro.faces},
            {"face_area_sum", config.voro.faceArea},
            {"exact", config.haloWallFaces == 0},
            {"cells_cut_by_a_slab_wall", config.haloWallFaces}}},
          {"methods", methods},
          {"analyses", analyses},
          {"per_step", perStep}};
}

nlohmann::json reportJson(const BenchMethodsOptions& options, const cracks::DemSeries& series,
                          const Measurement& measurement) {
  nlohmann::json configs = nlohmann::json::array();
  for (const Config& config : measurement.configs) {
    configs.push_back(configJson(measurement, config));
  }
  nlohmann::json facts = nlohmann::json::object();
  for (std::size_t m = 0; m < kMethods.size(); ++m) {
    const MethodFacts& f = measurement.facts[m];
    facts[methodName(m)] = {{"state_bytes_per_particle", f.stateBytesPerParticle},
                            {"coverage", f.crack.coverage},
                            {"main_crack_bonds_mapped", f.crack.separatingMapped},
                            {"main_crack_in_largest_component", f.crack.largestShare},
                            {"broken_bonds_mapped", f.crack.mappedAll},
                            {"components", f.crack.components}};
  }
  const nlohmann::json& single = configs.front().at("methods").at(methodName(kLocalVoronoi));
  const nlohmann::json& last = single.at("over_voro++_last_step");
  const nlohmann::json& overSteps = single.at("over_voro++_median_over_steps");
  // Not measured without the baseline: null, not a ratio of 0 that passes.
  const nlohmann::json met =
      last.is_null() || overSteps.is_null()
          ? nlohmann::json(nullptr)
          : nlohmann::json(last.get<double>() <= 0.02 && overSteps.get<double>() <= 0.05);
  return {{"file", options.file},
          {"particles", series.lattice().particleCount()},
          {"bonds", series.lattice().bondCount()},
          {"steps_measured", measurement.steps.size()},
          {"runs", options.runs},
          {"machine", machineDescription()},
          {"load_before", toJson(measurement.loadBefore)},
          {"load_after", toJson(measurement.loadAfter)},
          {"timed",
           "each method's extract() per step, incremental from step to step (reading the step "
           "not timed); the baseline from filling its containers to the last cell's face areas"},
          {"configs", configs},
          {"methods", facts},
          {"goals",
           {{"local_voronoi_over_voro++_1_thread_last_step", last},
            {"local_voronoi_over_voro++_1_thread_last_step_goal", 0.02},
            {"local_voronoi_over_voro++_1_thread_median_over_steps", overSteps},
            {"local_voronoi_over_voro++_1_thread_median_over_steps_goal", 0.05},
            {"met", met}}}};
}

// A ratio as a percentage, or "-" where the baseline did not run.
std::string percentOrDash(const nlohmann::json& ratio) {
  return ratio.is_null() ? std::string("-") : fmt::format("{:.2f}%", 100.0 * ratio.get<double>());
}

void printConfig(const nlohmann::json& config) {
  const int threads = config.at("threads").get<int>();
  std::printf("\n%d thread%s: the four methods against %s\n", threads, threads == 1 ? "" : "s",
              config.at("baseline").get<std::string>().c_str());
  std::printf("%6s %8s %14s %11s %16s %14s %11s %10s\n", "step", "broken", "cell-attr ms",
              "cell-cut ms", "local-voronoi ms", "cell-centre ms", "voro++ ms", "LV/voro++");
  const std::string lv = methodName(kLocalVoronoi) + "_ms";
  for (const auto& row : config.at("per_step")) {
    const bool baseline = !row.at("voro++_ms").is_null();
    const double voro = baseline ? row.at("voro++_ms").get<double>() : 0.0;
    std::printf(
        "%6d %8zu %14.3f %11.3f %16.3f %14.3f %11s %10s\n", row.at("step").get<int>(),
        row.at("broken_bonds").get<std::size_t>(), row.at(methodName(0) + "_ms").get<double>(),
        row.at(methodName(1) + "_ms").get<double>(), row.at(lv).get<double>(),
        row.at(methodName(3) + "_ms").get<double>(),
        baseline ? fmt::format("{:.3f}", voro).c_str() : "-",
        baseline ? fmt::format("{:.2f}%", 100.0 * row.at(lv).get<double>() / voro).c_str() : "-");
  }
  std::printf("%-16s %14s %13s %10s %9s %14s %16s\n", "method", "median ms/step", "last step ms",
              "max ms", "total s", "/voro++ last", "/voro++ median");
  for (std::size_t m = 0; m < kMethods.size(); ++m) {
    const auto& s = config.at("methods").at(methodName(m));
    std::printf("%-16s %14.3f %13.3f %10.3f %9.3f %14s %16s\n", methodName(m).c_str(),
                s.at("median_ms").get<double>(), s.at("last_step_ms").get<double>(),
                s.at("max_ms").get<double>(), s.at("total_s").get<double>(),
                percentOrDash(s.at("over_voro++_last_step")).c_str(),
                percentOrDash(s.at("over_voro++_median_over_steps")).c_str());
  }
  const auto& analyses = config.at("analyses");
  std::printf(
      "analyses (opening, fragments, orientation and modes, growth) on local Voronoi's crack: "
      "median %.3f ms/step, last step %.3f ms; %.2fx local Voronoi's median, per step median "
      "%.2fx, max %.2fx (goal: <= 1x)\n",
      analyses.at("median_ms").get<double>(), analyses.at("last_step_ms").get<double>(),
      analyses.at("over_local_voronoi_median_ms").get<double>(),
      analyses.at("over_local_voronoi_median_over_steps").get<double>(),
      analyses.at("over_local_voronoi_max_over_steps").get<double>());
  const auto& voro = config.at("voro++");
  std::printf("voro++: median %.3f ms over %zu steps, last step %.3f ms; %s\n",
              voro.at("median_ms").get<double>(), voro.at("steps_measured").get<std::size_t>(),
              voro.at("last_step_ms").get<double>(),
              voro.at("exact").get<bool>()
                  ? "every diagram is exact (no owned cell reached a slab's inner wall)"
                  : fmt::format("NOT exact: {} cell faces on a slab's inner wall (halo too thin)",
                                voro.at("cells_cut_by_a_slab_wall").get<std::size_t>())
                        .c_str());
}

void printReport(const nlohmann::json& json) {
  std::printf(
      "crackvis bench methods: %s (%zu particles, %zu bonds), %zu steps measured\n"
      "machine: %s; load before %s, after %s\n"
      "figures: per step the median of %d alternating runs (methods, then baseline); timed: %s\n",
      json.at("file").get<std::string>().c_str(), json.at("particles").get<std::size_t>(),
      json.at("bonds").get<std::size_t>(), json.at("steps_measured").get<std::size_t>(),
      json.at("machine").get<std::string>().c_str(), loadText(json.at("load_before")).c_str(),
      loadText(json.at("load_after")).c_str(), json.at("runs").get<int>(),
      json.at("timed").get<std::string>().c_str());
  for (const auto& config : json.at("configs")) {
    printConfig(config);
  }
  std::printf(
      "\nthe crack at the last step (main crack: the broken bonds between the two largest pieces "
      "the intact bonds hold together), and what each method keeps between steps:\n"
      "%-16s %10s %12s %14s %14s %6s %15s\n",
      "method", "coverage", "main mapped", "main in largest", "broken mapped", "comp",
      "bytes/particle");
  for (std::size_t m = 0; m < kMethods.size(); ++m) {
    const auto& f = json.at("methods").at(methodName(m));
    std::printf("%-16s %9.1f%% %11.1f%% %13.1f%% %13.1f%% %6zu %15.1f\n", methodName(m).c_str(),
                100.0 * f.at("coverage").get<double>(),
                100.0 * f.at("main_crack_bonds_mapped").get<double>(),
                100.0 * f.at("main_crack_in_largest_component").get<double>(),
                100.0 * f.at("broken_bonds_mapped").get<double>(),
                f.at("components").get<std::size_t>(),
                f.at("state_bytes_per_particle").get<double>());
  }
  const auto& goals = json.at("goals");
  if (goals.at("met").is_null()) {
    std::printf(
        "\ngoals, 1 thread, local Voronoi / lean Voro++: not measured (the baseline did not run: "
        "--voro-every 0)\n");
    return;
  }
  std::printf(
      "\ngoals, 1 thread, local Voronoi / lean Voro++: last step %s (goal <= 2 %%), median "
      "over the steps %s (goal <= 5 %%): %s\n",
      percentOrDash(goals.at("local_voronoi_over_voro++_1_thread_last_step")).c_str(),
      percentOrDash(goals.at("local_voronoi_over_voro++_1_thread_median_over_steps")).c_str(),
      goals.at("met").get<bool>() ? "met" : "NOT met");
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
  Measurement measurement;
  measurement.steps = *steps;
  for (std::size_t k = 0; k < steps->size(); ++k) {
    // Every K-th step and always the last, so the last-step ratio exists.
    measurement.voroStep.push_back(
        options.voroEvery > 0 &&
        (k % static_cast<std::size_t>(options.voroEvery) == 0 || k + 1 == steps->size()));
  }
  const int threads = options.threads > 0
                          ? options.threads
                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  measurement.configs.push_back({1, {}, {}});
  if (threads > 1) {
    measurement.configs.push_back({threads, {}, {}});
  }
  const auto voroSteps = static_cast<std::int64_t>(
      std::count(measurement.voroStep.begin(), measurement.voroStep.end(), true));
  ProgressBar bar("bench methods",
                  options.runs * static_cast<std::int64_t>(measurement.configs.size()) *
                      (static_cast<std::int64_t>(kMethods.size() * steps->size()) + voroSteps));
  bar.setEnabled(!options.quiet);
  if (Status status = measure(**series, options, measurement, bar); !status) {
    printError("bench methods", status.message());
    return kExitFailure;
  }
  bar.finish();
  const nlohmann::json json = reportJson(options, **series, measurement);
  if (options.json) {
    std::printf("%s\n", json.dump(2).c_str());
  } else {
    printReport(json);
  }
  return kExitOk;
}

}  // namespace

Command addBenchMethodsCommand(CLI::App& bench) {
  auto options = std::make_shared<BenchMethodsOptions>();
  auto* command = bench.add_subcommand(
      "methods",
      "Time the four crack methods per step, each run alone through the steps and incremental as "
      "a viewer runs it (reading not timed), against the leanest honest global baseline: Voro++ "
      "computing every cell's neighbours and face areas of the same positions. On equal terms: "
      "at 1 thread against one Voro++ container, and at N threads against N Voro++ containers "
      "over slabs (one thread each). The method passes and the baseline passes alternate for "
      "--runs runs; each figure is the median over the runs. Prints per-step times, the median "
      "over the steps beside the last step, the ratios, the load, the crack each method made, "
      "and the bytes per particle each keeps between steps (or all of it as JSON).");
  command->add_option("file", options->file, "HDF5 file in the crackvis-dem layout")->required();
  command->add_option("-s,--steps", options->steps, "Steps A, A:B or A:B:K (default: all)");
  command
      ->add_option("--voro-every", options->voroEvery,
                   "Run Voro++ every K-th measured step (and at the last); 0 skips it")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--runs", options->runs, "Alternating runs; figures are their medians")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  command
      ->add_option("--threads", options->threads,
                   "Threads of the second configuration (methods on N threads, Voro++ on N "
                   "slabs); 1 measures only the 1-thread one (default: all hardware threads)")
      ->check(CLI::Range(1, 1024));
  command->add_flag("--json", options->json, "Print JSON");
  command->add_flag("-q,--quiet", options->quiet, "No progress bar");
  command->footer(
      "Example: crackvis bench methods cuboidA.h5 --runs 5 --voro-every 10\n"
      "With --voro-every 0 the ratios are 0 and the goals cannot be met.");
  return {command, [options] { return runBenchMethods(*options); }};
}

}  // namespace crackvis::cli
