// Real off-screen rendering under EGL (Mesa llvmpipe here): pictures checked
// by colour, with the crack surface in a colour nothing else has.
#include <catch2/catch.hpp>

#include "cracks/crack_fixtures.hpp"
#include <crackvis/render/scene_renderer.hpp>

using namespace crackvis;

namespace {

constexpr int kWidth = 160;
constexpr int kHeight = 120;

// A (100) crack through the middle of an FCC block, seen face on along x.
struct Scene {
  testing::PlantedCrack crack = testing::fccPlaneCrack(5, {1, 0, 0}, 0.5 + 4.5 / std::sqrt(2.0));
  cracks::CrackMesh mesh;
  pipeline::PipelineDescription description;

  Scene() {
    auto extractor = cracks::makeExtractor(cracks::Method::kCellCut, *crack.graph, 3);
    REQUIRE(extractor->extract(crack.input(), mesh).isOk());
    const dem::Vec3 centre = 0.5 * crack.block.extent;
    description.file = "planted.h5";
    description.view.width = kWidth;
    description.view.height = kHeight;
    description.view.background = {0, 0, 0};
    description.view.camera =
        pipeline::CameraDescription{centre + dem::Vec3{30, 0, 0}, centre, {0, 0, 1}, 30};
    description.particles.visible = false;
    description.cracks.colour = {255, 0, 0};
  }
  render::SceneInput input() const { return {&crack.block.lattice, crack.input(), {}, {}, &mesh}; }
};

int count(const render::Image& image, bool (*match)(const std::uint8_t*)) {
  int n = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      n += match(image.pixel(x, y)) ? 1 : 0;
    }
  }
  return n;
}

bool red(const std::uint8_t* p) {
  return p[0] > 120 && p[1] < 60 && p[2] < 60;
}
bool notBlack(const std::uint8_t* p) {
  return p[0] + p[1] + p[2] > 30;
}

}  // namespace

TEST_CASE("a snapshot shows the crack surface where the crack is", "[render][egl]") {
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  INFO((*renderer)->backend());
  Scene scene;
  render::Image image;
  REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
  REQUIRE(image.width == kWidth);
  REQUIRE(image.height == kHeight);
  // The crack plane faces the camera through the block's middle: the centre
  // is crack-coloured and so is a good part of the picture.
  CHECK(red(image.pixel(kWidth / 2, kHeight / 2)));
  CHECK(count(image, red) > kWidth * kHeight / 10);
  // Corners are background.
  CHECK(!notBlack(image.pixel(0, 0)));

  SECTION("without cracks nothing is crack-coloured") {
    scene.description.cracks.visible = false;
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK(count(image, red) == 0);
    CHECK(count(image, notBlack) == 0);
  }
  SECTION("particles as sphere impostors cover the block") {
    scene.description.cracks.visible = false;
    scene.description.particles.visible = true;
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK(count(image, red) == 0);
    CHECK(count(image, notBlack) > kWidth * kHeight / 5);
  }
  SECTION("a view of another size is refused") {
    scene.description.view.width = 200;
    CHECK((*renderer)->render(scene.description, scene.input(), image).message() ==
          "view 200x120 does not match the renderer's 160x120");
  }
}
