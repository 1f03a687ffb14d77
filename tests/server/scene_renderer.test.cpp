// Real off-screen rendering under EGL (Mesa llvmpipe here): pictures checked
// by colour, with the crack surface in a colour nothing else has.
#include <cstring>

#include <catch2/catch.hpp>

#include "cracks/crack_fixtures.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/scene/scene_content.hpp>

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
  SECTION("a view larger than the renderer is refused") {
    scene.description.view.width = 200;
    CHECK((*renderer)->render(scene.description, scene.input(), image).message() ==
          "frame 200x120 does not fit the renderer's 160x120");
  }
  SECTION("a reduced-resolution frame comes from the same scene") {
    render::Image small;
    REQUIRE((*renderer)->renderFrame(kWidth / 2, kHeight / 2, small).isOk());
    REQUIRE(small.width == kWidth / 2);
    CHECK(red(small.pixel(kWidth / 4, kHeight / 4)));
    CHECK(std::abs(count(small, red) * 4 - count(image, red)) < count(image, red) / 5);
    render::Image upscaled;
    render::resample(small, kWidth, kHeight, upscaled);
    CHECK(upscaled.width == kWidth);
    CHECK(std::abs(count(upscaled, red) - count(image, red)) < count(image, red) / 5);
  }
  SECTION("rotating the camera turns the crack plane away; reset brings it back") {
    const int faceOn = count(image, red);
    (*renderer)->moveCamera(render::CameraMove::kRotate, 0.35, 0.0);  // 70 degrees
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, image).isOk());
    CHECK(count(image, red) < faceOn * 2 / 3);
    (*renderer)->moveCamera(render::CameraMove::kZoom, 0.5, 0.0);
    const auto zoomed = (*renderer)->camera();
    CHECK(dem::norm(zoomed.position - zoomed.focalPoint) < 30.0 * std::exp(-0.4));
    (*renderer)->setCamera(*scene.description.view.camera);
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, image).isOk());
    CHECK(count(image, red) == faceOn);
  }
  SECTION("a pan moves the picture with the drag") {
    (*renderer)->moveCamera(render::CameraMove::kPan, 0.25, 0.0);
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, image).isOk());
    int left = 0;
    int right = 0;
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        if (red(image.pixel(x, y))) {
          (x < kWidth / 2 ? left : right) += 1;
        }
      }
    }
    CHECK(right > left);
  }
}

TEST_CASE("bonds as tubes, the decomposition and the scalar bar are drawn", "[render][egl]") {
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  Scene scene;
  scene.description.cracks.visible = false;
  render::Image image;
  auto green = [](const std::uint8_t* p) { return p[1] > 120 && p[0] < 60 && p[2] < 60; };

  SECTION("bonds as lines and as tubes of the described radius") {
    // The broken bonds seen from the side: short segments across the crack.
    scene.description.bonds.show = pipeline::BondSelection::kBroken;
    scene.description.bonds.colourBy = pipeline::BondColourBy::kSolid;
    scene.description.bonds.colour = {0, 255, 0};
    auto& camera = *scene.description.view.camera;
    camera.position = camera.focalPoint + dem::Vec3{0, 30, 0};
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    const int lines = count(image, notBlack);
    CHECK(lines > 0);
    CHECK(count(image, green) > lines / 2);
    scene.description.bonds.representation = pipeline::BondRepresentation::kTubes;
    scene.description.bonds.tubeRadius = 0.1;
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    const int thin = count(image, notBlack);
    CHECK(thin > 0);
    scene.description.bonds.tubeRadius = 0.8;
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK(count(image, notBlack) > thin * 3 / 2);
  }
  SECTION("the decomposition's edges show around the crack") {
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK(count(image, notBlack) == 0);
    auto extractor = cracks::makeExtractor(cracks::Method::kCellCut, *scene.crack.graph, 3);
    REQUIRE(extractor->extract(scene.crack.input(), scene.mesh).isOk());
    auto input = scene.input();
    input.decomposition = extractor->decomposition();
    REQUIRE(input.decomposition != nullptr);
    scene.description.showDecomposition = true;
    REQUIRE((*renderer)->render(scene.description, input, image).isOk());
    CHECK(count(image, notBlack) > kWidth * kHeight / 20);
  }
  SECTION("a scalar bar appears at the right when something is coloured by a value") {
    scene.description.cracks.visible = true;
    scene.description.cracks.colourBy = pipeline::CrackColourBy::kBondId;
    scene.description.view.camera->position.x += 200;  // the crack small in the middle
    scene.description.view.scalarBar = false;
    auto rightStrip = [&] {
      int n = 0;
      for (int y = 0; y < kHeight; ++y) {
        for (int x = kWidth * 7 / 8; x < kWidth; ++x) {
          n += notBlack(image.pixel(x, y)) ? 1 : 0;
        }
      }
      return n;
    };
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK(rightStrip() == 0);
    scene.description.view.scalarBar = true;
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK(rightStrip() > 100);
  }
}

TEST_CASE("hidden particles are culled without changing the picture", "[render][egl]") {
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  // A block with an interior: particles three layers below the surface and
  // away from the crack are culled; the picture must not show it.
  testing::PlantedCrack crack = testing::fccPlaneCrack(9, {1, 0, 0}, 0.5 + 8.5 / std::sqrt(2.0));
  auto extractor = cracks::makeExtractor(cracks::Method::kCellCut, *crack.graph, 3);
  cracks::CrackMesh mesh;
  REQUIRE(extractor->extract(crack.input(), mesh).isOk());
  pipeline::PipelineDescription d;
  d.view.width = kWidth;
  d.view.height = kHeight;
  d.view.scalarBar = false;
  d.cracks.visible = false;
  d.particles.colourBy = pipeline::ParticleColourBy::kDamage;
  const dem::Vec3 centre = 0.5 * crack.block.extent;
  d.view.camera =
      pipeline::CameraDescription{centre + dem::Vec3{40, 25, 15}, centre, {0, 0, 1}, 30};
  render::SceneInput input{&crack.block.lattice, crack.input(), {}, {}, &mesh};
  // Culling is at work here: a good share of the particles is not drawn.
  const std::size_t n = crack.block.positions.size();
  const std::size_t drawn = scene::visibleParticles(d.particles, input).size();
  INFO(drawn << " of " << n << " particles drawn");
  CHECK(n - drawn > n / 10);
  render::Image culled;
  REQUIRE((*renderer)->render(d, input, culled).isOk());
  // A clip plane far outside the block keeps every particle (no culling).
  d.particles.clip = pipeline::ClipPlane{centre + dem::Vec3{1000, 0, 0}, {1, 0, 0}};
  REQUIRE(scene::visibleParticles(d.particles, input).size() == n);
  render::Image all;
  REQUIRE((*renderer)->render(d, input, all).isOk());
  int differing = 0;
  for (std::size_t i = 0; i < all.rgb.size(); i += 3) {
    differing += std::memcmp(&all.rgb[i], &culled.rgb[i], 3) != 0 ? 1 : 0;
  }
  CHECK(count(all, notBlack) > kWidth * kHeight / 10);
  CHECK(differing < kWidth * kHeight / 500);
}

TEST_CASE("VTK's errors become the call's error, not a line on stderr", "[render]") {
  render::Image image{16, 16, std::vector<std::uint8_t>(16 * 16 * 3, 128)};
  const Status status = render::writePng(image, "/nonexistent-folder/x.png");
  CHECK(status.code() == StatusCode::kFailedPrecondition);
  INFO(status.message());
  // The writer's own words, with its class and without its address.
  CHECK_THAT(status.message(),
             Catch::StartsWith("/nonexistent-folder/x.png: cannot write the PNG (vtkPNGWriter: "
                               "VTK: vtkPNGWriter: "));
  CHECK_THAT(status.message(), !Catch::Contains("0x"));
  // An error is the call's own: the next call succeeds.
  testing::TempDir dir;
  CHECK(render::writePng(image, dir.file("x.png")));
}
