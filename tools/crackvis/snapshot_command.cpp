// crackvis snapshot: one step rendered off screen (EGL) as a pipeline
// description says, written as PNG. The render server's scene without the
// server: for figures, checks and machines without a display.
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "commands.hpp"
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/render/scene_renderer.hpp>

namespace crackvis::cli {
namespace {

struct SnapshotOptions {
  std::string file;
  std::string pipelinePath;
  std::string output;
  std::int64_t step = -1;
  std::string method;
  int width = 0;
  int height = 0;
  bool quiet = false;
};

Result<pipeline::PipelineDescription> description(const SnapshotOptions& options) {
  pipeline::PipelineDescription d;
  if (!options.pipelinePath.empty()) {
    std::ifstream in(options.pipelinePath);
    if (!in) {
      return notFound(
          fmt::format("{}: cannot read the pipeline description", options.pipelinePath));
    }
    std::stringstream text;
    text << in.rdbuf();
    auto parsed = pipeline::parsePipeline(text.str());
    if (!parsed) {
      return Status(parsed.status().code(),
                    fmt::format("{}: {}", options.pipelinePath, parsed.status().message()));
    }
    d = std::move(parsed).value();
  }
  if (options.step >= 0) {
    d.step = options.step;
  }
  if (!options.method.empty()) {
    d.cracks.method = *cracks::parseMethod(options.method);
  }
  if (options.width > 0) {
    d.view.width = options.width;
  }
  if (options.height > 0) {
    d.view.height = options.height;
  }
  return d;
}

int runSnapshot(const SnapshotOptions& options) {
  auto d = description(options);
  if (!d) {
    printError("snapshot", d.status().message());
    return kExitFailure;
  }
  auto series = cracks::DemSeries::open(options.file);
  if (!series) {
    printError("snapshot", series.status().message());
    return kExitFailure;
  }
  const int steps = (*series)->stepCount();
  const std::int64_t step = d->step < 0 ? steps - 1 : d->step;
  if (step >= steps) {
    printError("snapshot", fmt::format("{}: step {} out of range (the file has steps 0..{})",
                                       options.file, step, steps - 1));
    return kExitFailure;
  }
  auto initial = (*series)->load(0);
  if (!initial) {
    printError("snapshot", initial.status().message());
    return kExitFailure;
  }
  const std::vector<dem::Vec3> initialPositions((*series)->state().positions);
  auto input = (*series)->load(static_cast<int>(step));
  if (!input) {
    printError("snapshot", input.status().message());
    return kExitFailure;
  }
  cracks::ExtractOptions extract;
  extract.validate = d->cracks.validation;
  extract.validationTolerance = d->cracks.validationTolerance;
  extract.mergeOctahedra = d->cracks.mergeOctahedra;
  extract.includeIntactFaces = d->showDecomposition;
  auto extractor = cracks::makeExtractor(d->cracks.method, (*series)->graph(),
                                         (*series)->lattice().dimension, extract);
  cracks::CrackMesh mesh;
  if (Status status = extractor->extract(*input, mesh); !status) {
    printError("snapshot", status.message());
    return kExitFailure;
  }
  auto renderer = render::SceneRenderer::create(d->view.width, d->view.height);
  if (!renderer) {
    printError("snapshot", renderer.status().message());
    return kExitFailure;
  }
  render::SceneInput scene{&(*series)->lattice(), *input, initialPositions,
                           (*series)->state().velocities, &mesh};
  render::Image image;
  for (const Status& status :
       {(*renderer)->render(*d, scene, image), render::writePng(image, options.output)}) {
    if (!status) {
      printError("snapshot", status.message());
      return kExitFailure;
    }
  }
  if (!options.quiet) {
    std::printf("wrote %s: step %lld, %s cracks (%zu primitives), %dx%d, %s\n",
                options.output.c_str(), static_cast<long long>(step),
                std::string(cracks::toString(d->cracks.method)).c_str(), mesh.primitiveCount(),
                image.width, image.height, (*renderer)->backend().c_str());
  }
  return kExitOk;
}

}  // namespace

Command addSnapshotCommand(CLI::App& parent) {
  auto options = std::make_shared<SnapshotOptions>();
  auto* command = parent.add_subcommand(
      "snapshot",
      "Render one step off screen (EGL: Mesa llvmpipe or an NVIDIA GPU, no display needed) as a "
      "pipeline description says (docs/pipeline.md) and write a PNG: particles as sphere "
      "impostors, crack surfaces, bonds.");
  command->add_option("file", options->file, "HDF5 file in the crackvis-dem layout")->required();
  command->add_option("-p,--pipeline", options->pipelinePath,
                      "Pipeline description (XML, pipeline-schemas/pipeline.xsd); its data file is "
                      "ignored, FILE is rendered. Default: the schema's defaults");
  command->add_option("-s,--step", options->step, "Step (default: the description's; -1 the last)");
  command->add_option("-m,--method", options->method, "Crack method, overriding the description")
      ->check(CLI::IsMember({"cell-attribute", "cell-cut", "local-voronoi", "cell-centre"}));
  command->add_option("--width", options->width, "Image width, overriding the description")
      ->check(CLI::Range(16, 7680));
  command->add_option("--height", options->height, "Image height, overriding the description")
      ->check(CLI::Range(16, 7680));
  command->add_option("-o,--output", options->output, "PNG file")->required();
  command->add_flag("-q,--quiet", options->quiet, "Print nothing on success");
  command->footer(
      "Example: crackvis snapshot cuboidA.h5 -p pipeline-schemas/examples/cracks-local-voronoi.xml "
      "-s -1 -o a.png");
  return {command, [options] { return runSnapshot(*options); }};
}

}  // namespace crackvis::cli
