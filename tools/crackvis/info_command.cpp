// crackvis info: what a crackvis-dem file holds, as text or JSON. Reading the
// file validates it, so `info` doubles as a checker: a malformed file gets one
// line on stderr and exit status 1.
#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include <crackvis/analysis/growth.hpp>
#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/lattice_generator.hpp>

namespace crackvis::cli {
namespace {

struct InfoOptions {
  std::string file;
  bool perStep = false;
  bool json = false;
  std::string cracks;  // a method: the per-step table gains the crack's numbers
};

struct StepRow {
  int step = 0;
  double time = 0.0;
  std::int64_t broken = 0;
  std::int64_t newlyBroken = 0;
};

struct FileSummary {
  dem::DemFileInfo info;
  double meanCoordination = 0.0;
  std::int64_t cutAtStart = 0;       // bonds flagged as a notch (v1.1)
  std::vector<std::int32_t> groups;  // distinct particle group labels (v1.1)
  // The cells the crack methods use by default (--decomposition auto) and
  // why: the lattice's, or a triangulation, Delaunay or regular.
  std::string cells;
  // The spatial index (v1.3), if the file has one.
  std::optional<dem::SpatialIndexInfo> index;
  std::vector<StepRow> rows;  // first and last only, unless per-step was asked
  // With --cracks: per step (all of them), the crack's analyses and front.
  std::vector<analysis::StepAnalysis> cracks;
  analysis::CrackFront front;
};

// Whether the ParaView plugin's MPI ranks read only their slab of this file
// (cracks::readIndexedPiece's conditions).
bool perRankReads(const dem::SpatialIndexInfo& index) {
  return index.hasBondStart && (index.decomposition == dem::CellDecomposition::kLattice ||
                                (index.decomposition == dem::CellDecomposition::kTriangulation &&
                                 index.hasWideCells && index.hasPeeledCells));
}

nlohmann::json indexJson(const std::optional<dem::SpatialIndexInfo>& index) {
  if (!index) {
    return nullptr;
  }
  const char* decomposition = dem::decompositionName(index->decomposition);
  return {{"axis", analysis::axisName(index->axis)},
          {"decomposition", *decomposition != '\0' ? nlohmann::json(decomposition) : nullptr},
          {"per_rank_reads", perRankReads(*index)}};
}

std::string indexText(const std::optional<dem::SpatialIndexInfo>& index) {
  if (!index) {
    return "none (a file before v1.3): MPI ranks read every particle";
  }
  return fmt::format("order along {}: MPI ranks read {}", analysis::axisName(index->axis),
                     perRankReads(*index) ? "only their slab"
                                          : "every particle (bonds not sorted by first end, no "
                                            "decomposition recorded, or a triangulated packing "
                                            "without its wide and peeled cells, as written "
                                            "before 2026-11-30)");
}

double percent(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

Result<StepRow> summarizeStep(const dem::DemFileReader& reader, int step, bool fullStep) {
  StepRow row{step, reader.info().steps[static_cast<size_t>(step)].time, 0, 0};
  if (fullStep) {
    // Reading positions too validates them (finite, z = 0 in 2D).
    auto state = reader.readStep(step);
    if (!state) {
      return state.status();
    }
    row.broken = static_cast<std::int64_t>(state->brokenBondCount());
  } else {
    auto bondState = reader.readBondState(step);
    if (!bondState) {
      return bondState.status();
    }
    row.broken = std::count(bondState->begin(), bondState->end(), std::uint8_t{1});
  }
  return row;
}

// What `extract` and the render server do with --decomposition auto, so a
// user sees before extracting whether the bonds span a lattice.
std::string defaultCells(const dem::Lattice& lattice, int dimension) {
  if (lattice.particleCount() == 0 || lattice.bondCount() == 0) {
    return "none (no bonds)";
  }
  const cracks::BondGraph graph(lattice.particleCount(), lattice.bonds);
  if (cracks::isLatticeGraph(graph, dimension)) {
    return "lattice (the bonds span a lattice: its own cells)";
  }
  const auto [lo, hi] = std::minmax_element(lattice.radius.begin(), lattice.radius.end());
  return *hi - *lo > 1e-9 * *hi
             ? "regular triangulation (the bonds span no lattice, the radii are unequal)"
             : "Delaunay triangulation (the bonds span no lattice)";
}

Result<FileSummary> summarize(const InfoOptions& options) {
  auto reader = dem::DemFileReader::openGuarded(options.file);
  if (!reader) {
    return reader.status();
  }
  FileSummary summary;
  summary.info = reader->info();
  auto lattice = reader->readLattice();
  if (!lattice) {
    return lattice.status();
  }
  if (auto breakSteps = reader->readBreakSteps(); !breakSteps) {
    return breakSteps.status();
  }
  summary.meanCoordination = lattice->particleCount() > 0
                                 ? 2.0 * static_cast<double>(lattice->bondCount()) /
                                       static_cast<double>(lattice->particleCount())
                                 : 0.0;
  summary.cells = defaultCells(*lattice, summary.info.dimension);
  auto index = reader->readSpatialIndexInfo();
  if (!index) {
    return index.status();
  }
  summary.index = *index;
  for (std::size_t b = 0; b < lattice->bondCount(); ++b) {
    summary.cutAtStart += lattice->cutAtStart(b) ? 1 : 0;
  }
  summary.groups = lattice->particleGroup;
  std::sort(summary.groups.begin(), summary.groups.end());
  summary.groups.erase(std::unique(summary.groups.begin(), summary.groups.end()),
                       summary.groups.end());
  const int steps = reader->stepCount();
  // Every step's shapes, as a render session or extract will read them:
  // headers only, so a file info accepts is one they accept.
  for (int step = 0; step < steps; ++step) {
    CRACKVIS_RETURN_IF_ERROR(reader->checkStepHeaders(step));
  }
  std::vector<int> wanted;
  if (options.perStep) {
    for (int step = 0; step < steps; ++step) {
      wanted.push_back(step);
    }
  } else if (steps > 0) {
    wanted = steps > 1 ? std::vector<int>{0, steps - 1} : std::vector<int>{0};
  }
  for (int step : wanted) {
    const bool firstOrLast = step == 0 || step == steps - 1;
    auto row = summarizeStep(*reader, step, firstOrLast);
    if (!row) {
      return row.status();
    }
    row->newlyBroken = summary.rows.empty() || summary.rows.back().step != step - 1
                           ? row->broken
                           : row->broken - summary.rows.back().broken;
    summary.rows.push_back(*row);
  }
  return summary;
}

std::string extraLabel(const dem::ExtraInfo& extra) {
  return fmt::format("{}/{}{}{}",
                     extra.owner == dem::ExtraOwner::kParticles ? "particles" : "bonds", extra.name,
                     extra.components == 3 ? " [3]" : "", extra.perStep ? " (per step)" : "");
}

nlohmann::json extrasJson(const dem::DemFileInfo& info) {
  nlohmann::json out = nlohmann::json::array();
  for (const dem::ExtraInfo& extra : info.extras) {
    out.push_back({{"name", extra.name},
                   {"owner", extra.owner == dem::ExtraOwner::kParticles ? "particles" : "bonds"},
                   {"components", extra.components},
                   {"per_step", extra.perStep}});
  }
  return out;
}

// A step's scalar by name; NaN when that step has none.
double scalarOf(const dem::StepInfo& step, const std::string& name) {
  for (const dem::StepScalar& scalar : step.scalars) {
    if (scalar.name == name) {
      return scalar.value;
    }
  }
  return std::nan("");
}

// Every step through the method and the analyses, in order (as `crackvis
// report` does): the columns --cracks adds.
Status analyseCracks(const InfoOptions& options, FileSummary& summary) {
  auto method = cracks::parseMethod(options.cracks);
  CRACKVIS_RETURN_IF_ERROR(method.status());
  auto series = cracks::DemSeries::open(options.file);
  CRACKVIS_RETURN_IF_ERROR(series.status());
  const dem::Lattice& lattice = (*series)->lattice();
  auto extractor = cracks::makeExtractor(*method, (*series)->graph(), lattice.dimension);
  analysis::CrackAnalysis analyses(lattice, {});
  cracks::CrackMesh mesh;
  for (int step = 0; step < (*series)->stepCount(); ++step) {
    auto input = (*series)->load(step);
    CRACKVIS_RETURN_IF_ERROR(input.status());
    CRACKVIS_RETURN_IF_ERROR(extractor->extract(*input, mesh));
    const double time = summary.info.steps[static_cast<std::size_t>(step)].time;
    summary.cracks.push_back(
        analyses.analyse(step, time, *input, input->referencePositions, mesh,
                         analysis::recordedBreakModes((*series)->state().extras)));
  }
  // The front's axes follow the last main crack's plane.
  if (!summary.cracks.empty() && summary.cracks.back().hasMain) {
    summary.cracks.back().mainNormal = analyses.mainPlane(mesh).normal;
  }
  summary.front = analysis::crackFront(summary.cracks, lattice.dimension);
  return Status::ok();
}

nlohmann::json crackJson(const FileSummary& summary, int step) {
  const analysis::StepAnalysis& s = summary.cracks[static_cast<std::size_t>(step)];
  return {{"area", s.totalArea},
          {"main_area", s.mainArea},
          {"front_extent", summary.front.extent[static_cast<std::size_t>(step)]},
          {"front_axis", analysis::axisName(summary.front.axis)},
          {"fragments", s.fragments},
          {"largest_fragment_share", s.largestFragmentShare},
          {"tension_breaks", s.tension},
          {"shear_breaks", s.shear}};
}

nlohmann::json toJson(const FileSummary& summary, bool perStep) {
  const auto& info = summary.info;
  nlohmann::json out = {
      {"file", info.path},
      {"format", info.format},
      {"version", info.version},
      {"version_minor", info.minorVersion},
      {"source_code", info.sourceCode},
      {"source_version", info.sourceVersion},
      {"source_files", info.sourceFiles},
      {"bonds_cut_at_start", summary.cutAtStart},
      {"particle_groups", summary.groups},
      {"step_scalars", info.scalarNames},
      {"extras", extrasJson(info)},
      {"dimension", info.dimension},
      {"units", info.units},
      {"time_unit", info.timeUnit},
      {"source", info.source},
      {"particles", info.particleCount},
      {"bonds", info.bondCount},
      {"mean_coordination", summary.meanCoordination},
      {"cells", summary.cells},
      {"steps", info.steps.size()},
      {"incomplete_steps", info.incompleteSteps},
      {"planned_steps", info.plannedSteps > 0 ? nlohmann::json(info.plannedSteps) : nullptr},
      {"stopped_early", info.stoppedEarly()},
      {"step_layout", info.stepLayout == dem::StepLayout::kAppendable ? "appendable" : "groups"},
      {"being_written", info.beingWritten},
      {"spatial_index", indexJson(summary.index)},
  };
  if (summary.rows.empty()) {
    out["time"] = nullptr;
    out["broken_bonds"] = nullptr;
  } else {
    out["time"] = {{"first", info.steps.front().time}, {"last", info.steps.back().time}};
    out["broken_bonds"] = {{"first", summary.rows.front().broken},
                           {"last", summary.rows.back().broken}};
  }
  if (perStep) {
    out["per_step"] = nlohmann::json::array();
    for (const StepRow& row : summary.rows) {
      nlohmann::json entry = {
          {"step", row.step}, {"time", row.time}, {"broken", row.broken}, {"new", row.newlyBroken}};
      const auto& stepInfo = info.steps[static_cast<std::size_t>(row.step)];
      for (const dem::StepScalar& scalar : stepInfo.scalars) {
        entry["scalars"][scalar.name] = scalar.value;
      }
      if (!summary.cracks.empty()) {
        entry["cracks"] = crackJson(summary, row.step);
      }
      out["per_step"].push_back(entry);
    }
  }
  return out;
}

void printText(const FileSummary& summary, bool perStep) {
  const auto& info = summary.info;
  const auto m = info.bondCount;
  fmt::print("file          {}\n", info.path);
  fmt::print("format        {} v{}.{}\n", info.format, info.version, info.minorVersion);
  fmt::print("dimension     {}D\n", info.dimension);
  fmt::print("particles     N = {}\n", info.particleCount);
  fmt::print("bonds         M = {} (mean coordination {:.3f}{})\n", m, summary.meanCoordination,
             summary.cutAtStart > 0
                 ? fmt::format(", {} cut at the start: a notch", summary.cutAtStart)
                 : std::string());
  if (!summary.groups.empty()) {
    fmt::print("groups        {}\n", fmt::join(summary.groups, ", "));
  }
  fmt::print("crack cells   {}\n", summary.cells);
  fmt::print("index         {}\n", indexText(summary.index));
  if (summary.rows.empty()) {
    fmt::print("steps         0\n");
  } else {
    if (info.timeUnit == dem::kTimeInIterations) {
      fmt::print("steps         {} (iterations {:.12g} .. {:.12g}; the code wrote no time)\n",
                 info.steps.size(), info.steps.front().time, info.steps.back().time);
    } else {
      fmt::print("steps         {} (time {:.6g} .. {:.6g} s)\n", info.steps.size(),
                 info.steps.front().time, info.steps.back().time);
    }
    const StepRow& first = summary.rows.front();
    const StepRow& last = summary.rows.back();
    fmt::print("broken bonds  first step: {} ({:.2f} %), last step: {} ({:.2f} %){}\n",
               first.broken, percent(first.broken, m), last.broken, percent(last.broken, m),
               summary.cutAtStart > 0
                   ? fmt::format("; {} of them by load", last.broken - summary.cutAtStart)
                   : std::string());
  }
  if (info.stepLayout == dem::StepLayout::kAppendable) {
    fmt::print("live file     {}\n",
               info.beingWritten
                   ? "being written: steps appear as the writer commits them (a writer that "
                     "was killed leaves this too)"
                   : "the writer closed it: the run ended");
  }
  if (info.stoppedEarly()) {
    fmt::print("stopped early the run wrote {} of {} planned steps\n", info.steps.size(),
               info.plannedSteps);
  }
  if (info.incompleteSteps > 0) {
    fmt::print("incomplete    {} step group(s) left unfinished by an interrupted writer\n",
               info.incompleteSteps);
  }
  if (!info.scalarNames.empty()) {
    fmt::print("step scalars  {}\n", fmt::join(info.scalarNames, ", "));
  }
  if (!info.extras.empty()) {
    std::vector<std::string> labels;
    for (const dem::ExtraInfo& extra : info.extras) {
      labels.push_back(extraLabel(extra));
    }
    fmt::print("extra arrays  {}\n", fmt::join(labels, ", "));
  }
  if (!info.sourceCode.empty()) {
    fmt::print("made by       {}{}\n", info.sourceCode,
               info.sourceVersion.empty() ? "" : fmt::format(" ({})", info.sourceVersion));
  }
  if (!info.sourceFiles.empty()) {
    fmt::print("input files   {}{}\n", info.sourceFiles.size(),
               info.sourceFiles.size() > 0 ? fmt::format(" ({} ...)", info.sourceFiles.front())
                                           : std::string());
  }
  if (!info.source.empty()) {
    fmt::print("source        {}\n", info.source);
  }
  if (perStep) {
    fmt::print("\n{:>8} {:>14} {:>10} {:>9} {:>8}", "step",
               info.timeUnit == dem::kTimeInIterations ? "iteration" : "time [s]", "broken",
               "broken %", "new");
    for (const std::string& name : info.scalarNames) {
      fmt::print(" {:>14}", name.substr(0, 14));
    }
    if (!summary.cracks.empty()) {
      fmt::print(" {:>12} {:>12} {:>10} {:>9} {:>7} {:>7}", "crack area", "main area",
                 "front " + analysis::axisName(summary.front.axis), "fragments", "tension",
                 "shear");
    }
    fmt::print("\n");
    for (const StepRow& row : summary.rows) {
      fmt::print("{:>8} {:>14.6g} {:>10} {:>9.3f} {:>8}", row.step, row.time, row.broken,
                 percent(row.broken, m), row.newlyBroken);
      for (const std::string& name : info.scalarNames) {
        fmt::print(" {:>14.6g}", scalarOf(info.steps[static_cast<std::size_t>(row.step)], name));
      }
      if (!summary.cracks.empty()) {
        const analysis::StepAnalysis& s = summary.cracks[static_cast<std::size_t>(row.step)];
        fmt::print(" {:>12.6g} {:>12.6g} {:>10.4g} {:>9} {:>7} {:>7}", s.totalArea, s.mainArea,
                   summary.front.extent[static_cast<std::size_t>(row.step)], s.fragments, s.tension,
                   s.shear);
      }
      fmt::print("\n");
    }
  }
}

int runInfo(const InfoOptions& options) {
  if (!options.cracks.empty() && !options.perStep) {
    printError("info", "--cracks adds columns to the per-step table: give --steps too");
    return kExitUsage;
  }
  auto summary = summarize(options);
  if (!summary) {
    printError("info", summary.status().message());
    return kExitFailure;
  }
  if (!options.cracks.empty()) {
    if (Status status = analyseCracks(options, *summary); !status) {
      printError("info", status.message());
      return kExitFailure;
    }
  }
  if (options.json) {
    std::printf("%s\n", toJson(*summary, options.perStep).dump(2).c_str());
  } else {
    printText(*summary, options.perStep);
  }
  return kExitOk;
}

}  // namespace

Command addInfoCommand(CLI::App& parent) {
  auto options = std::make_shared<InfoOptions>();
  auto* command = parent.add_subcommand(
      "info",
      "Describe a crackvis-dem file: format, dimension, particles N, bonds M, steps, time range, "
      "the cells the crack methods use (the lattice's, or a triangulation when the bonds span no "
      "lattice) and broken bonds. Validates the file on the way: a malformed file is reported in "
      "one "
      "line and the exit status is 1.");
  command->add_option("file", options->file, "HDF5 file in the crackvis-dem layout")->required();
  command->add_flag("--steps", options->perStep,
                    "Add a per-step table: time, broken bonds, newly broken bonds and the "
                    "file's step scalars (load, displacement...)");
  command->add_flag("--json", options->json, "Print JSON instead of text");
  command
      ->add_option("--cracks", options->cracks,
                   "With --steps: extract every step with this method and add the crack's numbers "
                   "(total and main crack area, the main crack's front, fragments, bonds broken in "
                   "tension and shear) beside the step scalars, as `crackvis report` measures them")
      ->check(CLI::IsMember({"cell-attribute", "cell-cut", "local-voronoi", "cell-centre"}));
  return {command, [options] { return runInfo(*options); }};
}

}  // namespace crackvis::cli
