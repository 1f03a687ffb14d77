// crackvis snapshot: one step rendered off screen (EGL) as a pipeline
// description says, written as PNG. The render server's scene without the
// server: for figures, checks and machines without a display.
#include <optional>

#include <fmt/format.h>

#include "commands.hpp"
#include "pipeline_file.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/scene/scene_pipeline.hpp>
#include <crackvis/source/step_source.hpp>

namespace crackvis::cli {
namespace {

struct SnapshotOptions {
  std::string file;
  std::string pipelinePath;
  std::string output;
  std::optional<std::int64_t> step;  // unset: the description's; negative: the last
  std::string method;
  int width = 0;
  int height = 0;
  bool quiet = false;
};

Result<pipeline::PipelineDescription> description(const SnapshotOptions& options) {
  auto read = readPipelineFile(options.pipelinePath);
  if (!read) {
    return read.status();
  }
  pipeline::PipelineDescription d = std::move(read).value();
  if (options.step) {
    d.step = *options.step;
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

// Prints the command's one error line.
int fail(const Status& status) {
  printError("snapshot", status.message());
  return kExitFailure;
}

int runSnapshot(const SnapshotOptions& options) {
  auto d = description(options);
  if (!d) {
    return fail(d.status());
  }
  // The render server's scene pipeline on FILE: the same data, extraction and
  // scene input as a session's (and `crackvis-render --snapshot`'s) picture.
  d->file = options.file;
  auto scene = scene::ScenePipeline::open(
      *d,
      [](const std::string& file) {
        return source::openLocalSource(file, {}, source::LocalOpen::kStructureInChild);
      },
      1);
  if (!scene) {
    return fail(scene.status());
  }
  auto renderer = render::SceneRenderer::create(d->view.width, d->view.height);
  if (!renderer) {
    return fail(renderer.status());
  }
  render::Image image;
  for (const Status& status : {(*renderer)->render(*d, (*scene)->input(), image),
                               render::writePng(image, options.output)}) {
    if (!status) {
      return fail(status);
    }
  }
  if (!options.quiet) {
    std::printf("wrote %s: step %d, %s cracks (%zu primitives), %dx%d, %s\n",
                options.output.c_str(), (*scene)->step(),
                std::string(cracks::toString(d->cracks.method)).c_str(),
                (*scene)->cracks().primitiveCount(), image.width, image.height,
                (*renderer)->backend().c_str());
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
