// crackvis extract: crack surfaces of a range of steps with one of the four
// methods, written as a ParaView time series (.pvd + one file per step) or as
// .vtp/.vtu/.stl/.obj files, with per-step metrics on request.
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include <crackvis/common/progress.hpp>
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/cracks/mesh_writers.hpp>
#include <crackvis/cracks/metrics.hpp>

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
  bool noValidation = false;
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

nlohmann::json metricsJson(int step, double time, std::size_t broken,
                           const cracks::SurfaceMetrics& m) {
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
          {"inconsistent_bonds", m.inconsistentBonds}};
}

void printMetricsHeader() {
  std::printf("%6s %12s %8s %9s %12s %12s %10s %10s %6s %6s %6s\n", "step", "time [s]", "broken",
              "polygons", "area", "total depth", "max depth", "max d/r", "comp", "n-man", "incon");
}

void printMetricsRow(int step, double time, std::size_t broken, const cracks::SurfaceMetrics& m) {
  std::printf("%6d %12.6g %8zu %9zu %12.6g %12.6g %10.4g %10.4f %6zu %6zu %6zu\n", step, time,
              broken, m.polygons + (m.polygons == 0 ? m.lines : 0), m.area, m.totalDepth,
              m.maxDepth, m.maxRelativeDepth, m.components, m.nonManifoldEdges,
              m.inconsistentBonds);
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
  auto steps = cracks::parseStepRange(options.steps.empty() ? "0:-1" : options.steps,
                                      (*series)->stepCount());
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
        metricRows.push_back(metricsJson(step, time, broken, metrics));
      } else {
        printMetricsRow(step, time, broken, metrics);
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
  if (options.metrics && options.json) {
    std::printf(
        "%s\n",
        nlohmann::json{{"file", options.file}, {"method", options.method}, {"steps", metricRows}}
            .dump(2)
            .c_str());
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
                    "edges, inconsistent bonds");
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
  command->footer(
      "Examples:\n"
      "  crackvis extract run.h5 -m local-voronoi -s 0:-1:10 -o cracks.pvd\n"
      "  crackvis extract run.h5 -m cell-cut -s -1 -o last.stl\n"
      "  crackvis extract run.h5 -m cell-centre --metrics --json -s 100:199");
  return {command, [options] { return runExtract(*options); }};
}

}  // namespace crackvis::cli
