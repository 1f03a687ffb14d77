// crackvis movie: a view (a pipeline description, as the client saves it)
// rendered at full resolution over a range of steps, optionally orbiting the
// camera, and written as H.264 (libx264 through libavcodec) in an MP4. Every
// frame is rendered for the movie: unlike a recording of the stream, no
// frame is a reduced interactive one.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

#include <fmt/format.h>

#include "commands.hpp"
#include "pipeline_file.hpp"
#include <crackvis/common/progress.hpp>
#include <crackvis/dem/step_range.hpp>
#include <crackvis/record/movie_writer.hpp>
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/scene/scene_pipeline.hpp>
#include <crackvis/source/step_source.hpp>

namespace crackvis::cli {
namespace {

struct MovieOptions {
  std::string file;
  std::string pipelinePath;
  std::string output;
  std::string steps = "0:-1";
  double orbit = 0.0;  // degrees over the whole movie
  int frames = 0;      // 0: one per step (120 for a single step with --orbit)
  std::string size;    // WxH
  int fps = 30;
  int bitrate = 0;  // 0: constant quality (libx264 crf 20)
  bool quiet = false;
};

// The camera turned `degrees` about its view-up through the focal point.
pipeline::CameraDescription orbited(const pipeline::CameraDescription& c, double degrees) {
  const double a = degrees * std::numbers::pi / 180.0;
  const dem::Vec3 k = (1.0 / dem::norm(c.viewUp)) * c.viewUp;
  const dem::Vec3 v = c.position - c.focalPoint;
  const dem::Vec3 kxv{k.y * v.z - k.z * v.y, k.z * v.x - k.x * v.z, k.x * v.y - k.y * v.x};
  // Rodrigues' rotation of the eye about the axis k.
  const dem::Vec3 turned =
      std::cos(a) * v + std::sin(a) * kxv + (dem::dot(k, v) * (1 - std::cos(a))) * k;
  pipeline::CameraDescription out = c;
  out.position = c.focalPoint + turned;
  return out;
}

int fail(const Status& status) {
  printError("movie", status.message());
  return kExitFailure;
}

// Ten turns: more is a typo, and NaN or infinity would turn the camera into
// NaN (a black movie).
constexpr double kMaxOrbitDegrees = 3600.0;

int runMovie(const MovieOptions& options) {
  if (!(std::abs(options.orbit) <= kMaxOrbitDegrees)) {
    return fail(invalidArgument(fmt::format("--orbit {}: degrees from -{:g} to {:g}", options.orbit,
                                            kMaxOrbitDegrees, kMaxOrbitDegrees)));
  }
  auto d = readPipelineFile(options.pipelinePath);
  if (!d) {
    return fail(d.status());
  }
  if (!options.size.empty()) {
    auto size = cli::parseFrameSize(options.size);
    if (!size) {
      return fail(size.status());
    }
    std::tie(d->view.width, d->view.height) = *size;
  } else if (d->view.width % 2 != 0 || d->view.height % 2 != 0) {
    return fail(invalidArgument(fmt::format(
        "the view is {}x{}: H.264 needs even sizes (give --size)", d->view.width, d->view.height)));
  }
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
  auto steps = dem::parseStepRange(options.steps, (*scene)->stepCount());
  if (!steps) {
    return fail(steps.status());
  }
  const auto stepCount = static_cast<int>(steps->size());
  int frames = options.frames > 0 ? options.frames : stepCount;
  if (options.frames == 0 && stepCount == 1 && options.orbit != 0.0) {
    frames = 4 * options.fps;  // a turn needs frames even at one step
  }
  const int width = d->view.width;
  const int height = d->view.height;
  auto renderer = render::SceneRenderer::create(width, height);
  if (!renderer) {
    return fail(renderer.status());
  }
  auto movie =
      record::MovieWriter::start(options.output, {width, height, options.fps, options.bitrate});
  if (!movie) {
    return fail(movie.status());
  }
  ProgressBar progress("movie", frames);
  progress.setEnabled(!options.quiet);
  std::optional<pipeline::CameraDescription> start;
  render::Image image;
  encode::RgbFrame rgb;
  for (int i = 0; i < frames; ++i) {
    // Frames spread evenly over the steps (held when there are more frames).
    const int step = (*steps)[static_cast<std::size_t>(static_cast<std::int64_t>(i) * stepCount /
                                                       std::max(1, frames))];
    if (i == 0 || step != (*scene)->step()) {
      if (Status status = (*scene)->showStep(step); !status) {
        return fail(status);
      }
      if (Status status = (*renderer)->setScene(*d, (*scene)->input(), i == 0); !status) {
        return fail(status);
      }
    }
    if (!start) {
      start = (*renderer)->camera();
    }
    if (options.orbit != 0.0) {
      (*renderer)->setCamera(orbited(*start, options.orbit * i / std::max(1, frames)));
    }
    if (Status status = (*renderer)->renderFrame(width, height, image); !status) {
      return fail(status);
    }
    rgb.width = image.width;
    rgb.height = image.height;
    rgb.rgb.swap(image.rgb);
    const Status added = (*movie)->add(rgb);
    rgb.rgb.swap(image.rgb);
    if (!added) {
      return fail(added);
    }
    progress.update(i + 1, fmt::format("step {}", step));
  }
  if (Status status = (*movie)->finish(); !status) {
    return fail(status);
  }
  progress.finish();
  if (!options.quiet) {
    std::printf(
        "wrote %s: %d frames at %dx%d, %d fps (%.1f s), steps %d..%d%s, %s\n",
        options.output.c_str(), frames, width, height, options.fps,
        static_cast<double>(frames) / options.fps, steps->front(), steps->back(),
        options.orbit != 0.0 ? fmt::format(", orbit {:g} degrees", options.orbit).c_str() : "",
        (*renderer)->backend().c_str());
  }
  return kExitOk;
}

}  // namespace

Command addMovieCommand(CLI::App& parent) {
  auto options = std::make_shared<MovieOptions>();
  auto* command = parent.add_subcommand(
      "movie",
      "Render a view over a range of steps at full resolution (off screen, EGL) and write an "
      "H.264 MP4: the client's saved view (File > Save view) or any pipeline description.");
  command->add_option("file", options->file, "HDF5 file in the crackvis-dem layout")->required();
  command->add_option("-p,--pipeline", options->pipelinePath,
                      "Pipeline description (XML; docs/pipeline.md): what is shown, the camera, "
                      "the size; its data file is ignored, FILE is rendered. Default: the "
                      "schema's defaults");
  command->add_option("-s,--steps", options->steps,
                      "Steps A:B:K (inclusive, stride K; -1 the last). Default: all");
  command->add_option("--orbit", options->orbit,
                      "Turn the camera this many degrees about its view-up over the movie");
  command
      ->add_option("--frames", options->frames,
                   "Number of frames (default: one per step; 4 s worth for one step with "
                   "--orbit); steps are held or skipped to fit")
      ->check(CLI::Range(1, 100000));
  command->add_option("--size", options->size, "WIDTHxHEIGHT, even (default: the view's)");
  command->add_option("--fps", options->fps, "Frames per second (default 30)")
      ->check(CLI::Range(1, 120));
  command
      ->add_option("--bitrate", options->bitrate,
                   "H.264 bitrate cap, bits per second (default: none, constant quality: crf 20)")
      ->check(CLI::Range(100'000, 200'000'000));
  command->add_option("-o,--output", options->output, "MP4 file")->required();
  command->add_flag("-q,--quiet", options->quiet, "No progress bar, nothing printed on success");
  command->footer(
      "Example: crackvis movie cuboidA.h5 -p view.xml -s 0:-1:2 --orbit 90 --size 1920x1080 "
      "-o fracture.mp4");
  return {command, [options] { return runMovie(*options); }};
}

}  // namespace crackvis::cli
