// `crackvis snapshot` and `crackvis-render --snapshot` make one picture of one
// description: both run the scene pipeline, so the PNGs are the same bytes
// (they drifted once: the CLI dropped the decomposition's edges).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <catch2/catch.hpp>

#include "pipeline/bad_attributes.hpp"
#include "support/process.hpp"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>

namespace crackvis {
namespace {}  // namespace

TEST_CASE("crackvis snapshot draws what crackvis-render --snapshot draws",
          "[scene][snapshot][integration]") {
  testing::TempDir dir;
  testing::writeSampleFile(dir.file("run.h5"), 3, 3);
  pipeline::PipelineDescription d;
  d.file = "run.h5";
  d.step = -1;
  d.cracks.method = cracks::Method::kCellCut;
  d.particles.visible = false;  // nothing in front of the decomposition's edges
  d.view.width = 160;
  d.view.height = 120;
  auto render = [&](bool decomposition) {
    d.showDecomposition = decomposition;
    const std::string tag = decomposition ? "with" : "without";
    std::ofstream(dir.file(tag + ".xml")) << pipeline::toXml(d);
    const auto cli =
        testing::runProcess({CRACKVIS_CLI, "snapshot", dir.file("run.h5"), "-p",
                             dir.file(tag + ".xml"), "-o", dir.file(tag + "-cli.png")});
    INFO(cli.err);
    REQUIRE(cli.exitCode == 0);
    const auto server =
        testing::runProcess({CRACKVIS_RENDER, "--snapshot", dir.file(tag + ".xml"), "--data-root",
                             dir.path().string(), "-o", dir.file(tag + "-server.png")});
    INFO(server.err);
    REQUIRE(server.exitCode == 0);
    const std::string png = crackvis::testing::fileText(dir.file(tag + "-cli.png"));
    REQUIRE(png.size() > 100);
    CHECK(png == crackvis::testing::fileText(dir.file(tag + "-server.png")));
    return png;
  };
  // The edges are in the picture: showing the decomposition changes it.
  CHECK(render(true) != render(false));
}

}  // namespace crackvis

namespace crackvis {
namespace {

// The frames of a video or picture as raw RGB, through ffmpeg.
std::string rawFrames(const testing::TempDir& dir, const std::string& input,
                      const std::string& name) {
  const auto run = testing::runProcess({"ffmpeg", "-v", "error", "-y", "-i", input, "-f",
                                        "rawvideo", "-pix_fmt", "rgb24", dir.file(name)});
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  return crackvis::testing::fileText(dir.file(name));
}

// Peak signal-to-noise ratio of two RGB byte strings of one size, dB.
double psnr(const std::string& a, const std::string& b) {
  REQUIRE(a.size() == b.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = static_cast<unsigned char>(a[i]) - static_cast<unsigned char>(b[i]);
    sum += d * d;
  }
  const double mse = sum / static_cast<double>(a.size());
  return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

}  // namespace

TEST_CASE("crackvis movie renders every frame at full resolution, orbiting",
          "[scene][movie][integration]") {
  testing::TempDir dir;
  testing::writeSampleFile(dir.file("run.h5"), 3, 3);
  pipeline::PipelineDescription d;
  d.file = "run.h5";
  d.cracks.method = cracks::Method::kCellCut;
  d.view.width = 160;
  d.view.height = 120;
  std::ofstream(dir.file("view.xml")) << pipeline::toXml(d);
  const std::string movie = dir.file("run.mp4");
  auto made =
      testing::runProcess({CRACKVIS_CLI, "movie", dir.file("run.h5"), "-p", dir.file("view.xml"),
                           "-s", "0:-1", "--orbit", "90", "--frames", "6", "-o", movie});
  INFO(made.err);
  REQUIRE(made.exitCode == 0);
  CHECK_THAT(made.out, Catch::Contains("6 frames at 160x120"));
  const auto probe = testing::runProcess(
      {"ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
       "stream=codec_name,width,height,nb_read_frames", "-of", "csv=p=0", movie});
  CHECK(probe.out.substr(0, probe.out.find('\n')) == "h264,160,120,6");
  const std::string frames = rawFrames(dir, movie, "frames.rgb");
  const std::size_t frameBytes = 160 * 120 * 3;
  REQUIRE(frames.size() == 6 * frameBytes);
  // The first frame is step 0 as `crackvis snapshot` draws it (not a reduced
  // frame scaled up): only the encoding differs.
  const auto snapshot =
      testing::runProcess({CRACKVIS_CLI, "snapshot", dir.file("run.h5"), "-p", dir.file("view.xml"),
                           "-s", "0", "-o", dir.file("step0.png")});
  REQUIRE(snapshot.exitCode == 0);
  const std::string still = rawFrames(dir, dir.file("step0.png"), "step0.rgb");
  CHECK(psnr(frames.substr(0, frameBytes), still) > 30.0);
  // The camera turned: the last frame is another picture.
  CHECK(psnr(frames.substr(0, frameBytes), frames.substr(5 * frameBytes)) < 25.0);

  SECTION("bad sizes, steps and files are refused with one line") {
    struct Bad {
      std::vector<std::string> args;
      std::string says;
    };
    for (const Bad& bad : std::vector<Bad>{
             {{"--size", "161x120"}, "even sizes"},
             {{"--size", "huge"}, "expected WIDTHxHEIGHT"},
             {{"-s", "2:0"}, "step"},
             {{"-p", dir.file("missing.xml")}, "cannot read the pipeline description"}}) {
      std::vector<std::string> args{CRACKVIS_CLI, "movie", dir.file("run.h5"), "-o",
                                    dir.file("bad.mp4")};
      args.insert(args.end(), bad.args.begin(), bad.args.end());
      const auto run = testing::runProcess(args);
      INFO(run.err);
      CHECK(run.exitCode == 1);
      CHECK_THAT(run.err, Catch::Contains(bad.says));
      CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
    }
  }
}

TEST_CASE("crackvis-render --snapshot with a bad description exits 1 with one line",
          "[pipeline][validation][cli]") {
  using testing::lines;
  using testing::runProcess;
  testing::TempDir dir;
  for (const testing::BadAttribute& bad : testing::badAttributes()) {
    DYNAMIC_SECTION(bad.name) {
      const std::string path = dir.file("view.xml");
      std::ofstream(path) << bad.xml;
      auto run = runProcess({CRACKVIS_RENDER, "--snapshot", path, "--data-root",
                             dir.path().string(), "-o", dir.file("view.png")});
      CHECK(run.exitCode == 1);
      CHECK(run.out.empty());
      const auto errorLines = lines(run.err);
      REQUIRE(errorLines.size() == 1);
      CHECK_THAT(errorLines[0],
                 Catch::StartsWith("crackvis-render: " + path + ": pipeline " + bad.where));
      CHECK_THAT(errorLines[0], Catch::Contains("attribute '" + bad.attribute + "'"));
      CHECK_FALSE(std::filesystem::exists(dir.file("view.png")));
    }
  }
}

}  // namespace crackvis
