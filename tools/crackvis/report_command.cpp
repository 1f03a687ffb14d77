// crackvis report: the numbers of a fracture paper from a run: crack growth
// against step and load, crack opening and slip, fragments, orientation and
// break modes, as CSV tables, gnuplot PNGs and a page that links them
// (report_writer.hpp). The analyses are those of analysis/, fed every step
// in order as the crack methods are.
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "commands.hpp"
#include "report_writer.hpp"
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/dem/step_range.hpp>

namespace crackvis::cli {
namespace {

struct ReportCommandOptions {
  std::string file;
  std::string output;
  std::string method = "local-voronoi";
  std::string steps;
  int at = std::numeric_limits<int>::min();
  std::size_t minFragment = 2;
  int bins = 20;
  double smoothingRadius = 0.0;
  std::string decomposition = "auto";
  bool noPlots = false;
  bool quiet = false;
};

// The step scalars' names in order of first appearance, and a row's values.
void collectScalars(const dem::StepState& state, std::vector<std::string>& names,
                    std::vector<double>& values) {
  for (const dem::StepScalar& scalar : state.scalars) {
    auto at = std::find(names.begin(), names.end(), scalar.name);
    if (at == names.end()) {
      names.push_back(scalar.name);
      at = names.end() - 1;
    }
    const auto column = static_cast<std::size_t>(at - names.begin());
    values.resize(std::max(values.size(), column + 1), std::numeric_limits<double>::quiet_NaN());
    values[column] = scalar.value;
  }
}

ReportSnapshot snapshotOf(int step, const analysis::CrackAnalysis& analysis) {
  ReportSnapshot at;
  at.step = step;
  at.openings = analysis.openings();
  at.components =
      analysis::summariseByComponent(analysis.openings(), analysis.components().components.size());
  at.fragments = analysis.fragments();
  return at;
}

int runReport(const ReportCommandOptions& options) {
  auto method = cracks::parseMethod(options.method);
  auto decomposition = cracks::parseDecomposition(options.decomposition);
  if (!method || !decomposition) {
    printError("report", (method ? decomposition.status() : method.status()).message());
    return kExitUsage;
  }
  auto series = cracks::DemSeries::open(options.file);
  if (!series) {
    printError("report", series.status().message());
    return kExitFailure;
  }
  auto steps =
      dem::parseStepRange(options.steps.empty() ? "0:-1" : options.steps, (*series)->stepCount());
  if (!steps) {
    printError("report", steps.status().message());
    return kExitFailure;
  }
  int at = steps->back();
  if (options.at != std::numeric_limits<int>::min()) {
    at = options.at < 0 ? (*series)->stepCount() + options.at : options.at;
    if (std::find(steps->begin(), steps->end(), at) == steps->end()) {
      printError("report", fmt::format("--at {}: step {} is not among the steps read ({} to {}{})",
                                       options.at, at, steps->front(), steps->back(),
                                       options.steps.empty() ? "" : ", --steps " + options.steps));
      return kExitUsage;
    }
  }
  cracks::ExtractOptions extract;
  extract.decomposition = *decomposition;
  const dem::Lattice& lattice = (*series)->lattice();
  auto extractor = cracks::makeExtractor(*method, (*series)->graph(), lattice.dimension, extract);
  analysis::AnalysisOptions analysisOptions;
  analysisOptions.opening.smoothingRadius = options.smoothingRadius;
  analysisOptions.minFragment = options.minFragment;
  analysis::CrackAnalysis analysis(lattice, analysisOptions);

  ReportData data;
  data.file = options.file;
  data.method = options.method;
  data.options = invocation();
  data.dimension = lattice.dimension;
  data.minFragment = options.minFragment;
  data.bins = options.bins;
  ProgressBar progress(fmt::format("report {}", options.method),
                       static_cast<std::int64_t>(steps->size()));
  progress.setEnabled(!options.quiet);
  cracks::CrackMesh mesh;
  for (std::size_t k = 0; k < steps->size(); ++k) {
    const int step = (*steps)[k];
    auto input = (*series)->load(step);
    if (!input) {
      printError("report", input.status().message());
      return kExitFailure;
    }
    if (Status status = extractor->extract(*input, mesh); !status) {
      printError("report", fmt::format("step {}: {}", step, status.message()));
      return kExitFailure;
    }
    const double time = (*series)->info().steps[static_cast<std::size_t>(step)].time;
    ReportRow row{analysis.analyse(step, time, *input, input->referencePositions, mesh,
                                   analysis::recordedBreakModes((*series)->state().extras)),
                  {}};
    // The main crack's plane where the report reads it: the profile's step
    // and the front's last step.
    if (row.step.hasMain && (step == at || k + 1 == steps->size())) {
      row.step.mainNormal = analysis.mainPlane(mesh).normal;
    }
    collectScalars((*series)->state(), data.scalarNames, row.scalars);
    data.rows.push_back(std::move(row));
    if (step == at) {
      data.at = snapshotOf(step, analysis);
    }
    progress.update(static_cast<std::int64_t>(k + 1),
                    fmt::format("step {}, broken {}, fragments {}", step,
                                data.rows.back().step.broken, data.rows.back().step.fragments));
  }
  progress.finish();
  for (ReportRow& row : data.rows) {
    row.scalars.resize(data.scalarNames.size(), std::numeric_limits<double>::quiet_NaN());
  }
  std::vector<analysis::StepAnalysis> growth;
  for (const ReportRow& row : data.rows) {
    growth.push_back(row.step);
  }
  data.front = analysis::crackFront(growth, lattice.dimension);
  data.breaks = analysis.modes().breaks();
  auto files = writeReport(data, options.output, !options.noPlots);
  if (!files) {
    printError("report", files.status().message());
    return kExitFailure;
  }
  if (!files->plotProblem.empty() && !options.noPlots) {
    std::fprintf(stderr, "crackvis report: warning: %s\n", files->plotProblem.c_str());
  }
  if (!options.quiet) {
    std::fprintf(stderr, "wrote %s/index.md: %zu tables, %zu plots\n", options.output.c_str(),
                 files->tables.size(), files->plots.size());
  }
  return kExitOk;
}

}  // namespace

Command addReportCommand(CLI::App& parent) {
  auto options = std::make_shared<ReportCommandOptions>();
  auto* command = parent.add_subcommand(
      "report",
      "The numbers of a fracture paper from a run: crack growth against step and load, crack "
      "opening and slip, fragments, crack orientation and the mode each bond broke in, as CSV "
      "tables and PNG plots in a folder, linked from its index.md.");
  command->add_option("file", options->file, "HDF5 file in the crackvis-dem layout")->required();
  command->add_option("-o,--output", options->output, "The report's folder (made if missing)")
      ->required();
  command
      ->add_option("-m,--method", options->method,
                   "The crack method: local-voronoi | cell-centre | cell-cut | cell-attribute "
                   "(cell attribute's cells carry no bonds: no opening)")
      ->check(CLI::IsMember({"cell-attribute", "cell-cut", "local-voronoi", "cell-centre"}))
      ->capture_default_str();
  command->add_option("-s,--steps", options->steps,
                      "Steps A, A:B or A:B:K (inclusive, stride K; negative counts from the end). "
                      "Every step is best: growth and break modes are per step read. Default: all");
  command->add_option("--at", options->at,
                      "The step of the opening, fragment and orientation tables (negative counts "
                      "from the end). Default: the last step read");
  command
      ->add_option("--min-fragment", options->minFragment,
                   "Fragments of fewer particles are dust: not counted or plotted")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command->add_option("--bins", options->bins, "Bins of the histograms and the opening profile")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  command
      ->add_option("--smoothing-radius", options->smoothingRadius,
                   "Radius (m) of the neighbourhood that gives the crack's local normal; 0: three "
                   "mean bond lengths")
      ->check(CLI::NonNegativeNumber);
  command
      ->add_option("--decomposition", options->decomposition,
                   "auto | lattice | triangulation (as crackvis extract)")
      ->check(CLI::IsMember({"auto", "lattice", "triangulation"}))
      ->capture_default_str();
  command->add_flag("--no-plots", options->noPlots,
                    "Write the tables and the gnuplot scripts, but do not run gnuplot");
  command->add_flag("-q,--quiet", options->quiet, "No progress bar");
  command->footer(
      "Examples:\n"
      "  crackvis report run.h5 -o run-report\n"
      "  crackvis report yade.h5 -o report -m cell-centre --min-fragment 10 --at -1\n"
      "Writes growth.csv, opening_components.csv, opening_histogram.csv, opening_profile.csv,\n"
      "fragments.csv, fragments_cdf.csv, orientation.csv, break_modes.csv, a .gp script and a\n"
      ".png per plot (gnuplot), and index.md. The rules: docs/methods.md.");
  return {command, [options] { return runReport(*options); }};
}

}  // namespace crackvis::cli
