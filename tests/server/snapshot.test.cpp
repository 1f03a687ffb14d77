// `crackvis snapshot` and `crackvis-render --snapshot` make one picture of one
// description: both run the scene pipeline, so the PNGs are the same bytes
// (they drifted once: the CLI dropped the decomposition's edges).
#include <fstream>
#include <iterator>

#include <catch2/catch.hpp>

#include "support/process.hpp"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>

namespace crackvis {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

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
    const std::string png = slurp(dir.file(tag + "-cli.png"));
    REQUIRE(png.size() > 100);
    CHECK(png == slurp(dir.file(tag + "-server.png")));
    return png;
  };
  // The edges are in the picture: showing the decomposition changes it.
  CHECK(render(true) != render(false));
}

}  // namespace crackvis
