// crackvis extract: crack surfaces of a range of steps with one of the four
// methods, written as a ParaView time series (.pvd + one file per step) or as
// .vtp/.vtu/.stl/.obj files, with per-step metrics on request.
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/bond_mapping.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/cracks/mesh_writers.hpp>
#include <crackvis/cracks/metrics.hpp>
#include <crackvis/dem/step_range.hpp>

namespace crackvis::cli {
namespace {

namespace fs = std::filesystem;

struct ExtractCommandOptions {
  std::string file;
  std::string method = "cell-cut";
  std::string steps;
  std::string output;
  bool metrics = false;
  bool json = false;
  bool quiet = false;
  cracks::ExtractOptions extract;
  std::string decomposition = "auto";
  bool noValidation = false;
  cracks::ComponentFilter components;
};

// What a step's crack is made of beyond the surface metrics: its components
// (largest first), the largest one's coverage, and the broken bonds mapped.
struct StepSummary {
  cracks::CrackComponents components;
  double coverage = 0.0;
  cracks::BondMapping mapping;
};

// The lowest mapped fraction of the run, for the one warning at its end.
struct MappingWarning {
  int step = -1;
  cracks::BondMapping mapping;
  std::string cause;
  std::size_t steps = 0;  // steps below kMappedWarning
};

// Where step k goes: a single step is written to OUTPUT itself; a series to
// OUTPUT_STEM/OUTPUT_STEM_NNNNNN.ext beside a .pvd, or OUTPUT_STEM_NNNNNN.ext.
class OutputPlan {
 public:
  OutputPlan(const std::string& output, bool series) : m_output(output), m_series(series) {
    const fs::path path(output);
    m_extension = path.extension().string();
    m_stem = path.stem().string();
    m_folder = path.parent_path();
  }
  bool isPvd() const { return m_extension == ".pvd"; }
  Status check() const {
    for (const char* known : {".pvd", ".vtp", ".vtu", ".stl", ".obj"}) {
      if (m_extension == known) {
        return Status::ok();
      }
    }
    return invalidArgument(
        fmt::format("{}: unknown output format '{}' (expected .pvd, .vtp, .vtu, .stl or .obj)",
                    m_output, m_extension));
  }
  // The file for a step, and its name relative to the .pvd's folder.
  std::pair<std::string, std::string> fileFor(int step, const cracks::CrackMesh& mesh) const {
    if (isPvd()) {
      const std::string relative =
          fmt::format("{}/{}_{:06d}.{}", m_stem, m_stem, step, cracks::vtkExtensionFor(mesh));
      return {(m_folder / relative).string(), relative};
    }
    if (!m_series) {
      return {m_output, m_output};
    }
    const std::string name = fmt::format("{}_{:06d}{}", m_stem, step, m_extension);
    return {(m_folder / name).string(), name};
  }
  Status prepare() const {
    std::error_code error;
    const fs::path dataFolder = isPvd() ? m_folder / m_stem : m_folder;
    if (!dataFolder.empty()) {
      fs::create_directories(dataFolder, error);
    }
    if (error) {
      return failedPrecondition(
          fmt::format("{}: cannot create folder ({})", dataFolder.string(), error.message()));
    }
    return Status::ok();
  }

 private:
  std::string m_output;
  bool m_series;
  std::string m_extension;
  std::string m_stem;
  fs::path m_folder;
};

nlohmann::json componentJson(const cracks::CrackComponent& c) {
  auto vec = [](cracks::Vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); };
  return {{"area", c.area},
          {"primitives", c.primitives},
          {"box", {{"lo", vec(c.box.lo)}, {"hi", vec(c.box.hi)}}},
          {"centroid", vec(c.centroid)},
          {"normal", vec(c.normal)}};
}

nlohmann::json metricsJson(int step, double time, std::size_t broken,
                           const cracks::SurfaceMetrics& m, const StepSummary& summary) {
  nlohmann::json components = nlohmann::json::array();
  for (const auto& component : summary.components.components) {
    components.push_back(componentJson(component));
  }
  return {{"step", step},
          {"time", time},
          {"broken_bonds", broken},
          {"points", m.points},
          {"polygons", m.polygons},
          {"lines", m.lines},
          {"vertices", m.vertices},
          {"area", m.area},
          {"total_depth", m.totalDepth},
          {"max_depth", m.maxDepth},
          {"max_relative_depth", m.maxRelativeDepth},
          {"cut_particles", m.cutParticles},
          {"components", m.components},
          {"non_manifold_edges", m.nonManifoldEdges},
          {"inconsistent_bonds", m.inconsistentBonds},
          {"mapped_bonds", summary.mapping.mapped},
          {"mapped_fraction", summary.mapping.fraction()},
          {"largest_component_coverage", summary.coverage},
          {"component_list", components}};
}

void printMetricsHeader() {
  std::printf("%6s %12s %8s %9s %12s %12s %10s %10s %6s %6s %6s %7s %12s %7s\n", "step", "time [s]",
              "broken", "polygons", "area", "total depth", "max depth", "max d/r", "comp", "n-man",
              "incon", "mapped", "main area", "cover");
}

void printMetricsRow(int step, double time, std::size_t broken, const cracks::SurfaceMetrics& m,
                     const StepSummary& summary) {
  const double mainArea =
      summary.components.components.empty() ? 0.0 : summary.components.components[0].area;
  std::printf(
      "%6d %12.6g %8zu %9zu %12.6g %12.6g %10.4g %10.4f %6zu %6zu %6zu %6.1f%% %12.6g "
      "%6.1f%%\n",
      step, time, broken, m.polygons + (m.polygons == 0 ? m.lines : 0), m.area, m.totalDepth,
      m.maxDepth, m.maxRelativeDepth, m.components, m.nonManifoldEdges, m.inconsistentBonds,
      100.0 * summary.mapping.fraction(), mainArea, 100.0 * summary.coverage);
}

StepSummary summarise(const cracks::CrackMesh& mesh, const cracks::StepInput& input,
                      const cracks::CrackExtractor& extractor, bool withComponents,
                      bool withCoverage) {
  StepSummary summary;
  if (withComponents) {
    summary.components = cracks::findComponents(mesh);
  }
  if (withCoverage && !summary.components.components.empty()) {
    summary.coverage = cracks::sectionCoverage(mesh, summary.components, 0, input);
  }
  summary.mapping = cracks::mapBrokenBonds(mesh, input.bondState, extractor);
  return summary;
}

void noteMapping(int step, const cracks::BondMapping& mapping,
                 const cracks::CrackExtractor& extractor, const cracks::BondGraph& graph,
                 int dimension, const cracks::StepInput& input,
                 const cracks::ExtractOptions& options, MappingWarning& warning) {
  if (mapping.fraction() >= cracks::kMappedWarning) {
    return;
  }
  ++warning.steps;
  if (warning.step < 0 || mapping.fraction() < warning.mapping.fraction()) {
    warning.step = step;
    warning.mapping = mapping;
    warning.cause =
        cracks::diagnoseMapping(mapping, extractor, graph, dimension, input.radius, options);
  }
}

std::string warningText(const MappingWarning& warning) {
  return fmt::format(
      "only {:.1f} % of the {} broken bonds at step {} became surface elements ({} step{} below "
      "{:.0f} %): {}",
      100.0 * warning.mapping.fraction(), warning.mapping.broken, warning.step, warning.steps,
      warning.steps == 1 ? "" : "s", 100.0 * cracks::kMappedWarning, warning.cause);
}

int runExtract(ExtractCommandOptions options) {
  auto method = cracks::parseMethod(options.method);
  if (!method) {
    printError("extract", method.status().message());
    return kExitUsage;
  }
  if (options.output.empty() && !options.metrics) {
    printError("extract", "nothing to do: give -o OUTPUT, --metrics, or both");
    return kExitUsage;
  }
  auto series = cracks::DemSeries::open(options.file);
  if (!series) {
    printError("extract", series.status().message());
    return kExitFailure;
  }
  auto steps =
      dem::parseStepRange(options.steps.empty() ? "0:-1" : options.steps, (*series)->stepCount());
  if (!steps) {
    printError("extract", steps.status().message());
    return kExitFailure;
  }
  OutputPlan plan(options.output, steps->size() > 1);
  if (!options.output.empty()) {
    for (const Status& status : {plan.check(), plan.prepare()}) {
      if (!status) {
        printError("extract", status.message());
        return kExitFailure;
      }
    }
  }
  options.extract.validate = !options.noValidation;
  auto decomposition = cracks::parseDecomposition(options.decomposition);
  if (!decomposition) {
    printError("extract", decomposition.status().message());
    return kExitUsage;
  }
  options.extract.decomposition = *decomposition;
  const int dimension = (*series)->lattice().dimension;
  auto extractor = cracks::makeExtractor(*method, (*series)->graph(), dimension, options.extract);
  ProgressBar progress(fmt::format("extract {}", options.method),
                       static_cast<std::int64_t>(steps->size()));
  progress.setEnabled(!options.quiet);
  std::vector<cracks::CollectionEntry> collection;
  nlohmann::json metricRows = nlohmann::json::array();
  if (options.metrics && !options.json) {
    printMetricsHeader();
  }
  cracks::CrackMesh mesh;
  MappingWarning warning;
  for (std::size_t k = 0; k < steps->size(); ++k) {
    const int step = (*steps)[k];
    auto input = (*series)->load(step);
    if (!input) {
      printError("extract", input.status().message());
      return kExitFailure;
    }
    if (Status status = extractor->extract(*input, mesh); !status) {
      printError("extract", fmt::format("step {}: {}", step, status.message()));
      return kExitFailure;
    }
    const double time = (*series)->info().steps[static_cast<std::size_t>(step)].time;
    const std::size_t broken = (*series)->state().brokenBondCount();
    // Mapping and components are judged on the whole crack, before a
    // component filter drops pieces.
    const StepSummary summary = summarise(
        mesh, *input, *extractor, options.metrics || options.components.active(), options.metrics);
    noteMapping(step, summary.mapping, *extractor, (*series)->graph(), dimension, *input,
                options.extract, warning);
    cracks::keepComponents(mesh, summary.components, options.components);
    if (!options.output.empty()) {
      const auto [path, relative] = plan.fileFor(step, mesh);
      if (Status status = cracks::writeMesh(mesh, path); !status) {
        printError("extract", status.message());
        return kExitFailure;
      }
      collection.push_back({time, relative});
    }
    if (options.metrics) {
      const auto metrics = cracks::computeMetrics(mesh, input->positions, input->radius);
      if (options.json) {
        metricRows.push_back(metricsJson(step, time, broken, metrics, summary));
      } else {
        printMetricsRow(step, time, broken, metrics, summary);
      }
    }
    progress.update(
        static_cast<std::int64_t>(k + 1),
        fmt::format("step {}, broken {}, primitives {}", step, broken, mesh.primitiveCount()));
  }
  progress.finish();
  if (plan.isPvd() && !options.output.empty()) {
    if (Status status = cracks::writePvd(collection, options.output); !status) {
      printError("extract", status.message());
      return kExitFailure;
    }
  }
  const std::string decompositionUsed(cracks::toString(extractor->decompositionKind()));
  if (options.metrics && options.json) {
    nlohmann::json report{{"file", options.file},
                          {"method", options.method},
                          {"decomposition", decompositionUsed},
                          {"steps", metricRows}};
    if (warning.step >= 0) {
      report["warning"] = warningText(warning);
    }
    std::printf("%s\n", report.dump(2).c_str());
  }
  if (warning.step >= 0) {
    std::fprintf(stderr, "crackvis extract: warning: %s\n", warningText(warning).c_str());
  }
  if (!options.quiet && !options.output.empty()) {
    std::fprintf(stderr, "wrote %s (%zu step%s)\n", options.output.c_str(), steps->size(),
                 steps->size() == 1 ? "" : "s");
  }
  return kExitOk;
}

}  // namespace

Command addExtractCommand(CLI::App& parent) {
  auto options = std::make_shared<ExtractCommandOptions>();
  auto* command = parent.add_subcommand(
      "extract",
      "Extract crack surfaces with one of the dissertation's four methods, for a range of steps, "
      "as a ParaView time series (.pvd) or .vtp/.vtu/.stl/.obj files; --metrics prints accuracy "
      "and quality metrics per step.");
  command->add_option("file", options->file, "HDF5 file in the crackvis-dem layout")->required();
  command
      ->add_option("-m,--method", options->method,
                   "cell-attribute | cell-cut | local-voronoi | cell-centre")
      ->check(CLI::IsMember({"cell-attribute", "cell-cut", "local-voronoi", "cell-centre"}))
      ->capture_default_str();
  command->add_option("-s,--steps", options->steps,
                      "Steps A, A:B or A:B:K (inclusive, stride K; negative counts from the end). "
                      "Default: all");
  command->add_option("-o,--output", options->output,
                      "OUT.pvd (a folder OUT/ of per-step files plus the collection), or OUT.vtp, "
                      ".vtu, .stl, .obj (OUT_NNNNNN.ext per step when several)");
  command->add_flag("--metrics", options->metrics,
                    "Print per step: area, cut depth into particles, components, non-manifold "
                    "edges, inconsistent bonds, the broken bonds mapped to surface elements, the "
                    "largest component's area and its coverage of the specimen's section; with "
                    "--json also every component's area, box, centroid and best-fit plane");
  command->add_flag("--json", options->json, "Print the metrics as JSON");
  command->add_flag("-q,--quiet", options->quiet, "No progress bar");
  command->add_flag("--global", options->extract.globalDecomposition,
                    "cell-attribute: decompose the whole lattice, not only the fractured region");
  command
      ->add_option("--min-broken", options->extract.minBrokenBonds,
                   "cell-attribute: fewest broken bonds a cell needs to be output")
      ->capture_default_str();
  command->add_flag(
      "--no-validation", options->noValidation,
      "local-voronoi: skip the empty-sphere validation (faster, no inconsistency marks "
      "except missing faces)");
  command
      ->add_option("--validation-tolerance", options->extract.validationTolerance,
                   "local-voronoi: a particle must lie this fraction of the sphere's radius inside "
                   "a vertex's empty sphere to make it invalid")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  command->add_flag(
      "--intact-faces", options->extract.includeIntactFaces,
      "local-voronoi: also output the faces of intact bonds (the local decomposition)");
  command->add_flag("--merge-octahedra", options->extract.mergeOctahedra,
                    "cell-centre: one centre per octahedron instead of one per pyramid");
  command
      ->add_option("--decomposition", options->decomposition,
                   "auto: the lattice's cells when the bonds span a lattice, else a Delaunay "
                   "(regular for unequal radii) triangulation of the first step; lattice; "
                   "triangulation")
      ->check(CLI::IsMember({"auto", "lattice", "triangulation"}))
      ->capture_default_str();
  command
      ->add_option("--min-component", options->components.minArea,
                   "Keep only crack components of at least this area (m^2; 2D: length, m)")
      ->check(CLI::NonNegativeNumber);
  command
      ->add_option("--largest", options->components.largest,
                   "Keep only the K largest crack components (the main crack: 1)")
      ->check(CLI::PositiveNumber);
  command->footer(
      "Examples:\n"
      "  crackvis extract run.h5 -m local-voronoi -s 0:-1:10 -o cracks.pvd\n"
      "  crackvis extract run.h5 -m cell-cut -s -1 -o last.stl\n"
      "  crackvis extract run.h5 -m cell-centre --metrics --json -s 100:199\n"
      "  crackvis extract random.h5 -m local-voronoi -s -1 --largest 1 -o main-crack.vtp\n"
      "A warning on stderr (and in the JSON) says when fewer than 95 % of the broken bonds became "
      "surface elements, and why that is likely.");
  return {command, [options] { return runExtract(*options); }};
}

}  // namespace crackvis::cli
