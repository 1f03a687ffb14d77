// Real off-screen rendering under EGL (Mesa llvmpipe here): pictures checked
// by colour, with the crack surface in a colour nothing else has.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "cracks/crack_fixtures.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/render/probe_scene.hpp>
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/render/sphere_occlusion.hpp>
#include <crackvis/scene_model/scene_content.hpp>

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
    description.annotations.show = false;  // pictures counted by colour; tested on their own
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

// Particles placed by hand (no bonds: nothing culled by the scene), seen
// from (0, 0, 20) down -z at 320x240 and 30 degrees: f = 120 / tan(15 deg)
// pixels per unit at unit distance.
struct Spheres {
  static constexpr int kWidth = 320;
  static constexpr int kHeight = 240;
  static constexpr double kEye = 20.0;
  dem::Lattice lattice;
  std::vector<dem::Vec3> positions;
  cracks::CrackMesh mesh;
  pipeline::PipelineDescription description;

  Spheres() {
    lattice.dimension = 3;
    description.file = "spheres.h5";
    description.view.width = kWidth;
    description.view.height = kHeight;
    description.view.background = {0, 0, 0};
    description.view.scalarBar = false;
    description.annotations.show = false;
    description.view.camera = pipeline::CameraDescription{{0, 0, kEye}, {0, 0, 0}, {0, 1, 0}, 30};
    description.cracks.colour = {255, 0, 0};
  }
  void add(dem::Vec3 centre, double radius) {
    positions.push_back(centre);
    lattice.radius.push_back(radius);
  }
  // A crack surface: the square |x|, |y| <= half at z = height.
  void addSquare(double half, double height) {
    const auto first = static_cast<std::int32_t>(mesh.points.size());
    mesh.points.push_back({-half, -half, height});
    mesh.points.push_back({half, -half, height});
    mesh.points.push_back({half, half, height});
    mesh.points.push_back({-half, half, height});
    mesh.polygons.add({first, first + 1, first + 2, first + 3});
  }
  render::SceneInput input() const {
    return {
        &lattice, {positions, {}, lattice.radius, {}, {}, {}, {}, {}}, {}, {}, &mesh, nullptr, {},
        {}};
  }
  static double focal() { return kHeight / 2.0 / std::tan(15.0 * std::numbers::pi / 180.0); }
  // Where a point of the scene lands, in pixels from the left and the top.
  static std::array<double, 2> pixelOf(dem::Vec3 p) {
    const double depth = kEye - p.z;
    return {kWidth / 2.0 + focal() * p.x / depth, kHeight / 2.0 - focal() * p.y / depth};
  }
  // The silhouette's width: the view rays in the plane of x and the view
  // direction that touch the sphere make angles atan(x / depth) +- asin(r / d).
  static double silhouetteWidth(dem::Vec3 centre, double radius) {
    const double depth = kEye - centre.z;
    const double theta = std::atan2(centre.x, depth);
    const double alpha = std::asin(radius / std::hypot(centre.x, depth));
    return focal() * (std::tan(theta + alpha) - std::tan(theta - alpha));
  }
};

// The widest run of pixels that `match` along the rows of a window.
template <typename Match>
int widestRun(const render::Image& image, int x0, int x1, int y0, int y1, Match match) {
  int widest = 0;
  for (int y = std::max(0, y0); y <= std::min(image.height - 1, y1); ++y) {
    int run = 0;
    for (int x = std::max(0, x0); x <= std::min(image.width - 1, x1); ++x) {
      run = match(image.pixel(x, y)) ? run + 1 : 0;
      widest = std::max(widest, run);
    }
  }
  return widest;
}

int brightness(const std::uint8_t* p) {
  return p[0] + p[1] + p[2];
}
// Viridis' ends, lit or in shade: the smallest radius purple, the largest yellow.
bool purple(const std::uint8_t* p) {
  return p[2] > 20 && p[1] < p[2] / 2 && p[1] < p[0];
}
bool yellow(const std::uint8_t* p) {
  return p[0] > 60 && p[1] > 60 && p[2] < p[1] / 3;
}

// Pixels whose colours differ by more than `tolerance` (the sum over RGB),
// `margin` pixels or more from the picture's edges.
int differingPixels(const render::Image& a, const render::Image& b, int tolerance = 0,
                    int margin = 0) {
  int n = 0;
  for (int y = margin; y < a.height - margin; ++y) {
    for (int x = margin; x < a.width - margin; ++x) {
      int d = 0;
      for (int c = 0; c < 3; ++c) {
        d += std::abs(static_cast<int>(a.pixel(x, y)[c]) - static_cast<int>(b.pixel(x, y)[c]));
      }
      n += d > tolerance ? 1 : 0;
    }
  }
  return n;
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
}

namespace {

// Saturated pixels: a colour map's, not grey text or black background.
bool colourful(const std::uint8_t* p) {
  const int hi = std::max({p[0], p[1], p[2]});
  const int lo = std::min({p[0], p[1], p[2]});
  return hi - lo > 60;
}

// Runs of rows with colourful pixels in columns [x0, x1): the bars stacked there.
int barsIn(const render::Image& image, int x0, int x1) {
  int runs = 0;
  bool inRun = false;
  for (int y = 0; y < image.height; ++y) {
    bool any = false;
    for (int x = x0; x < x1; ++x) {
      any = any || colourful(image.pixel(x, y));
    }
    runs += any && !inRun ? 1 : 0;
    inRun = any;
  }
  return runs;
}

int countIn(const render::Image& image, int x0, int y0, int x1, int y1,
            bool (*match)(const std::uint8_t*)) {
  int n = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      n += match(image.pixel(x, y)) ? 1 : 0;
    }
  }
  return n;
}

}  // namespace

TEST_CASE("each coloured layer gets its own scalar bar, beside the specimen", "[render][egl]") {
  constexpr int kW = 320;
  constexpr int kH = 240;
  auto renderer = render::SceneRenderer::create(kW, kH);
  REQUIRE(renderer.isOk());
  Scene scene;
  auto& d = scene.description;
  d.view.width = kW;
  d.view.height = kH;
  d.cracks.colourBy = pipeline::CrackColourBy::kBondId;
  render::Image image;
  // The strip: a fifth of the width at this aspect.
  const int strip = kW * 4 / 5;
  d.view.scalarBar = false;
  REQUIRE((*renderer)->render(d, scene.input(), image).isOk());
  CHECK(countIn(image, strip, 0, kW, kH, notBlack) == 0);
  d.view.scalarBar = true;
  REQUIRE((*renderer)->render(d, scene.input(), image).isOk());
  CHECK(barsIn(image, strip, kW) == 1);
  // Bonds coloured too: a second bar, below the first.
  d.bonds.show = pipeline::BondSelection::kBroken;
  d.bonds.colourBy = pipeline::BondColourBy::kState;
  REQUIRE((*renderer)->render(d, scene.input(), image).isOk());
  CHECK(barsIn(image, strip, kW) == 2);
  // Particles as well: three.
  d.particles.visible = true;
  d.particles.colourBy = pipeline::ParticleColourBy::kDamage;
  d.particles.opacity = 0.2;
  REQUIRE((*renderer)->render(d, scene.input(), image).isOk());
  CHECK(barsIn(image, strip, kW) == 3);

  SECTION("the bars cover none of the specimen: the scene is the same picture beside them") {
    const render::Image withBars = image;
    auto narrow = render::SceneRenderer::create(strip, kH);
    REQUIRE(narrow.isOk());
    d.view.scalarBar = false;
    d.view.width = strip;
    REQUIRE((*narrow)->render(d, scene.input(), image).isOk());
    int differing = 0;
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < strip; ++x) {
        int diff = 0;
        for (int c = 0; c < 3; ++c) {
          diff += std::abs(withBars.pixel(x, y)[c] - image.pixel(x, y)[c]);
        }
        differing += diff > 24 ? 1 : 0;
      }
    }
    CHECK(differing < strip * kH / 500);
    CHECK(count(image, notBlack) > strip * kH / 10);
  }
}

TEST_CASE("annotations: step and method text, axes triad, scale bar", "[render][egl]") {
  constexpr int kW = 320;
  constexpr int kH = 240;
  auto renderer = render::SceneRenderer::create(kW, kH);
  REQUIRE(renderer.isOk());
  Scene scene;
  auto& d = scene.description;
  d.view.width = kW;
  d.view.height = kH;
  d.cracks.visible = false;  // an empty scene: only the annotations draw
  auto input = scene.input();
  input.stepIndex = 3;
  input.stepCount = 10;
  input.time = 0.5;
  render::Image image;
  REQUIRE((*renderer)->render(d, input, image).isOk());
  CHECK(count(image, notBlack) == 0);
  d.annotations.show = true;
  REQUIRE((*renderer)->render(d, input, image).isOk());
  const auto white = [](const std::uint8_t* p) { return p[0] > 150 && p[1] > 150 && p[2] > 150; };
  // Text at the top left.
  CHECK(countIn(image, 0, 0, kW / 2, kH / 8, white) > 30);
  // The triad at the bottom left: coloured shafts (y green, z yellow here, x
  // pointing at the viewer).
  CHECK(countIn(image, 0, kH * 3 / 4, kW / 4, kH, colourful) > 20);
  // The scale bar at the bottom right: a white line at most a fifth of the width long.
  int longest = 0;
  for (int y = kH * 7 / 8; y < kH; ++y) {
    longest = std::max(longest, widestRun(image, kW / 2, kW - 1, y, y, white));
  }
  CHECK(longest >= kW / 5 * 2 / 5);
  CHECK(longest <= kW / 5 + 1);
  SECTION("each can be switched off") {
    d.annotations.axes = false;
    REQUIRE((*renderer)->render(d, input, image).isOk());
    CHECK(countIn(image, 0, kH * 3 / 4, kW / 4, kH, colourful) == 0);
    CHECK(countIn(image, 0, 0, kW / 2, kH / 8, white) > 30);
    d.annotations.time = false;
    d.annotations.method = false;
    d.annotations.scaleBar = false;
    REQUIRE((*renderer)->render(d, input, image).isOk());
    CHECK(count(image, notBlack) == 0);
  }
  SECTION("the scale bar follows the zoom, at any frame size") {
    (*renderer)->moveCamera(render::CameraMove::kZoom, 1.2, 0.0);
    render::Image half;
    REQUIRE((*renderer)->renderFrame(kW / 2, kH / 2, half).isOk());
    int run = 0;
    for (int y = kH / 2 * 7 / 8; y < kH / 2; ++y) {
      run = std::max(run, widestRun(half, kW / 4, kW / 2 - 1, y, y, white));
    }
    CHECK(run >= kW / 10 * 2 / 5 - 1);
    CHECK(run <= kW / 10 + 1);
  }
}

TEST_CASE("a clip plane cuts cracks and bonds too", "[render][egl]") {
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  Scene scene;
  render::Image image;
  REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
  const int whole = count(image, red);
  REQUIRE(whole > 0);
  // Hide the crack above the block's middle (+z is up in the picture).
  const dem::Vec3 centre = 0.5 * scene.crack.block.extent;
  scene.description.cracks.clip = pipeline::ClipPlane{centre, {0, 0, 1}};
  REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
  const int clipped = count(image, red);
  CHECK(clipped > whole / 3);
  CHECK(clipped < whole * 2 / 3);
  CHECK(countIn(image, 0, 0, kWidth, kHeight / 2 - 2, red) == 0);
  // Bonds: the broken ones seen from the side, then clipped away entirely.
  scene.description.cracks.visible = false;
  scene.description.bonds.show = pipeline::BondSelection::kBroken;
  scene.description.bonds.colourBy = pipeline::BondColourBy::kSolid;
  scene.description.bonds.colour = {255, 0, 0};
  REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
  REQUIRE(count(image, red) > 0);
  scene.description.bonds.clip = pipeline::ClipPlane{{-1e3, 0, 0}, {1, 0, 0}};
  REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
  CHECK(count(image, red) == 0);
}

TEST_CASE("a camera reset fits the whole specimen, whatever is hidden or clipped",
          "[render][egl]") {
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  Scene scene;
  scene.description.view.camera.reset();
  scene.description.particles.visible = true;
  REQUIRE((*renderer)->setScene(scene.description, scene.input(), true).isOk());
  (*renderer)->moveCamera(render::CameraMove::kReset, 0, 0);
  const pipeline::CameraDescription whole = (*renderer)->camera();
  // Only the crack's half-plane shown, particles hidden: VTK's own reset
  // would zoom onto what is visible; the reset fits the specimen still.
  scene.description.particles.visible = false;
  const dem::Vec3 centre = 0.5 * scene.crack.block.extent;
  scene.description.cracks.clip = pipeline::ClipPlane{centre, {0, 0, 1}};
  (*renderer)->moveCamera(render::CameraMove::kZoom, 1.5, 0);
  REQUIRE((*renderer)->setScene(scene.description, scene.input(), false).isOk());
  (*renderer)->moveCamera(render::CameraMove::kReset, 0, 0);
  const pipeline::CameraDescription fitted = (*renderer)->camera();
  CHECK(dem::norm(fitted.focalPoint - whole.focalPoint) < 1e-9);
  CHECK(dem::norm(fitted.position - whole.position) < 1e-9);
  // The specimen's centre, with the particles' radii.
  CHECK(dem::norm(whole.focalPoint - centre) < 0.6);
}

TEST_CASE("a rehearsal on the probe specimen leaves the next scene drawn as on a fresh renderer",
          "[render][egl]") {
  Scene scene;
  scene.description.view.camera.reset();  // the first scene fits the camera to itself
  scene.description.particles.visible = true;
  scene.description.particles.colourBy = pipeline::ParticleColourBy::kDamage;
  scene.description.annotations.show = true;
  auto fresh = render::SceneRenderer::create(kWidth, kHeight);
  auto rehearsed = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(fresh.isOk());
  REQUIRE(rehearsed.isOk());
  // Another description than the scene's: bonds, another colour-by, a camera.
  pipeline::PipelineDescription other = scene.description;
  other.bonds.show = pipeline::BondSelection::kAll;
  other.cracks.colourBy = pipeline::CrackColourBy::kComponent;
  other.view.camera = pipeline::CameraDescription{{40, 3, 2}, {1, 1, 1}, {0, 1, 0}, 20};
  REQUIRE(render::rehearseOnProbe(**rehearsed, scene.description).isOk());
  REQUIRE(render::rehearseOnProbe(**rehearsed, other).isOk());
  render::Image expected;
  render::Image got;
  REQUIRE((*fresh)->setScene(scene.description, scene.input()).isOk());
  REQUIRE((*fresh)->renderFrame(kWidth, kHeight, expected).isOk());
  REQUIRE((*rehearsed)->setScene(scene.description, scene.input()).isOk());
  REQUIRE((*rehearsed)->renderFrame(kWidth, kHeight, got).isOk());
  CHECK(count(got, notBlack) > kWidth * kHeight / 10);
  CHECK(got.rgb == expected.rgb);
  const pipeline::CameraDescription a = (*fresh)->camera();
  const pipeline::CameraDescription b = (*rehearsed)->camera();
  CHECK(dem::norm(a.position - b.position) < 1e-12);
  CHECK(dem::norm(a.focalPoint - b.focalPoint) < 1e-12);
  CHECK(dem::norm(a.viewUp - b.viewUp) < 1e-12);
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

// The mean colour of the pixels that are not background (black).
std::array<double, 3> meanContentColour(const render::Image& image) {
  std::array<double, 3> sum{};
  int n = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = image.pixel(x, y);
      if (notBlack(p)) {
        for (int c = 0; c < 3; ++c) {
          sum[static_cast<std::size_t>(c)] += p[c];
        }
        ++n;
      }
    }
  }
  for (double& c : sum) {
    c /= std::max(n, 1);
  }
  return sum;
}

TEST_CASE(
    "a coarse frame draws stand-ins for the particles and cracks, as they are coloured and "
    "clipped",
    "[render][egl]") {
  using Detail = render::SceneRenderer::FrameDetail;
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  Scene scene;
  render::Image full;
  render::Image coarse;
  render::Image again;
  SECTION("the crack plane stays where it is, and the next full frame is as before") {
    REQUIRE((*renderer)->render(scene.description, scene.input(), full).isOk());
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, coarse, Detail::kCoarse).isOk());
    const int fullRed = count(full, red);
    INFO("red pixels: full " << fullRed << ", coarse " << count(coarse, red));
    CHECK(red(coarse.pixel(kWidth / 2, kHeight / 2)));
    CHECK(count(coarse, red) > fullRed / 2);
    CHECK(count(coarse, red) < fullRed * 3 / 2);
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, again).isOk());
    CHECK(again.rgb == full.rgb);
  }
  SECTION("fewer spheres, the same colouring, the same clip plane") {
    pipeline::PipelineDescription& d = scene.description;
    d.cracks.visible = false;
    d.particles.visible = true;
    d.particles.colourBy = pipeline::ParticleColourBy::kDamage;
    d.view.scalarBar = false;
    REQUIRE((*renderer)->render(d, scene.input(), full).isOk());
    const auto fullSpheres = (*renderer)->impostorStats();
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, coarse, Detail::kCoarse).isOk());
    const auto coarseSpheres = (*renderer)->impostorStats();
    INFO("spheres: full " << fullSpheres.spheres << ", coarse " << coarseSpheres.spheres);
    CHECK(coarseSpheres.spheres > 0);
    CHECK(coarseSpheres.spheres * 4 < fullSpheres.spheres);
    // The coarse spheres hold their members: the block's outline grows a
    // little, it does not open.
    const int fullPixels = count(full, notBlack);
    INFO("pixels: full " << fullPixels << ", coarse " << count(coarse, notBlack));
    const int coarsePixels = count(coarse, notBlack);
    CHECK(coarsePixels >= fullPixels * 9 / 10);
    CHECK(coarsePixels <= fullPixels * 3 / 2);
    // Coloured by the same map (not the actor's plain colour).
    const auto fullColour = meanContentColour(full);
    const auto coarseColour = meanContentColour(coarse);
    for (std::size_t c = 0; c < 3; ++c) {
      INFO("channel " << c << ": full " << fullColour[c] << ", coarse " << coarseColour[c]);
      CHECK(std::abs(fullColour[c] - coarseColour[c]) < 25.0);
    }
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, again).isOk());
    CHECK(again.rgb == full.rgb);
    CHECK((*renderer)->impostorStats().spheres == fullSpheres.spheres);
    // A clip plane through the middle, across the view, hides half of
    // the block in both.
    const dem::Vec3 centre = 0.5 * scene.crack.block.extent;
    d.particles.clip = pipeline::ClipPlane{centre, {0, 0, 1}};
    REQUIRE((*renderer)->render(d, scene.input(), full).isOk());
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, coarse, Detail::kCoarse).isOk());
    INFO("clipped pixels: full " << count(full, notBlack) << ", coarse "
                                 << count(coarse, notBlack));
    CHECK(count(full, notBlack) < fullPixels * 2 / 3);
    CHECK(count(coarse, notBlack) < coarsePixels * 2 / 3);
    const auto clippedSpheres = (*renderer)->impostorStats().spheres;
    // A new scene makes its own stand-ins: particles twice as wide, so
    // cells twice as wide and fewer clusters. Stand-ins kept from the last
    // scene would have as many spheres as before.
    render::SceneInput wider = scene.input();
    std::vector<double> radius(wider.step.radius.begin(), wider.step.radius.end());
    for (double& r : radius) {
      r *= 2.0;
    }
    wider.step.radius = radius;
    REQUIRE((*renderer)->setScene(d, wider).isOk());
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, coarse, Detail::kCoarse).isOk());
    INFO("stand-in spheres: " << clippedSpheres << ", then "
                              << (*renderer)->impostorStats().spheres);
    CHECK((*renderer)->impostorStats().spheres > 0);
    CHECK((*renderer)->impostorStats().spheres * 2 < clippedSpheres);
    CHECK((*renderer)->drewStandIns());
    // A full frame draws none.
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, again).isOk());
    CHECK_FALSE((*renderer)->drewStandIns());
    // Without particles or cracks to stand in for, a coarse frame draws
    // none either.
    d.particles.visible = false;
    REQUIRE((*renderer)->setScene(d, scene.input()).isOk());
    REQUIRE((*renderer)->renderFrame(kWidth, kHeight, coarse, Detail::kCoarse).isOk());
    CHECK_FALSE((*renderer)->drewStandIns());
  }
}

TEST_CASE("A PNG that cannot be written is the call's error, naming the file and why", "[render]") {
  // The PNG is encoded in memory (VTK's writer never touches the disk, so
  // libpng prints nothing) and written through a partial file.
  render::Image image{16, 16, std::vector<std::uint8_t>(16 * 16 * 3, 128)};
  const Status status = render::writePng(image, "/nonexistent-folder/x.png");
  CHECK(status.code() == StatusCode::kFailedPrecondition);
  INFO(status.message());
  CHECK(status.message() ==
        "/nonexistent-folder/x.png: cannot open for writing (No such file or directory)");
  // An error is the call's own: the next call succeeds.
  testing::TempDir dir;
  CHECK(render::writePng(image, dir.file("x.png")));
}

TEST_CASE("sphere impostors: silhouettes, shading and depth", "[render][egl]") {
  auto renderer = render::SceneRenderer::create(Spheres::kWidth, Spheres::kHeight);
  REQUIRE(renderer.isOk());
  Spheres scene;
  render::Image image;

  SECTION("a sphere's silhouette has its projected size, on the axis and off it") {
    const dem::Vec3 onAxis{0, 0, 0};
    const dem::Vec3 offAxis{5.5, 3.5, 0};  // the silhouette an ellipse, stretched outwards
    scene.add(onAxis, 1.0);
    scene.add(offAxis, 1.0);
    scene.addSquare(0.0, -5.0);  // no crack: a point behind, for the clipping range
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    const auto stats = (*renderer)->impostorStats();
    CHECK(stats.points);
    CHECK(stats.drawn == 2);
    CHECK(stats.spheres == 2);
    for (const dem::Vec3& centre : {onAxis, offAxis}) {
      const double expected = Spheres::silhouetteWidth(centre, 1.0);
      const auto [u, v] = Spheres::pixelOf(centre);
      const auto x = static_cast<int>(u);
      const auto y = static_cast<int>(v);
      INFO("centre pixel " << u << ", " << v << "; width " << expected);
      const int width = widestRun(image, x - 40, x + 40, y - 10, y + 10, notBlack);
      CHECK(std::abs(width - expected) < 1.5);
      // Lit by the headlight: brightest where the normal faces the eye,
      // darkening towards the rim.
      const int centreLight = brightness(image.pixel(x, y));
      CHECK(centreLight > 300);
      CHECK(brightness(image.pixel(x + static_cast<int>(0.4 * expected), y)) < centreLight - 60);
    }
    // Off the axis the silhouette is wider than on it (by 2 pixels here).
    CHECK(Spheres::silhouetteWidth(offAxis, 1.0) > Spheres::silhouetteWidth(onAxis, 1.0) + 1.5);
  }

  SECTION("nearer surfaces hide farther ones, pixel by pixel") {
    // Coloured by radius: the large sphere yellow, the small ones purple.
    scene.description.particles.colourBy = pipeline::ParticleColourBy::kRadius;
    const dem::Vec3 big{0, 0, 0};
    scene.add(big, 1.0);
    // Behind the big one and drawn after it: hidden where they overlap.
    const dem::Vec3 behind{-1.2, 0, -1.5};
    scene.add(behind, 0.6);
    // Its centre in front of the big one's, but the big surface is nearer
    // up to x = 0.55, where the two surfaces cross: only a depth per pixel
    // puts the boundary there (a depth per sphere would show the small
    // sphere from its rim at x = 0.2).
    const dem::Vec3 crossing{0.8, 0, 0.3};
    scene.add(crossing, 0.6);
    scene.addSquare(0.0, -5.0);
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    auto at = [&](double x, double z) {
      const auto [u, v] = Spheres::pixelOf({x, 0, z});
      return image.pixel(static_cast<int>(u), static_cast<int>(v));
    };
    CHECK(yellow(at(0.0, 1.0)));
    CHECK(yellow(at(-0.9, 0.4)));   // over the sphere behind
    CHECK(purple(at(-1.5, -1.0)));  // the one behind, beside the big one
    CHECK(yellow(at(0.35, 0.94)));  // the big surface nearer
    CHECK(purple(at(0.75, 0.9)));   // the small surface nearer
    CHECK(purple(at(1.3, 0.3)));    // the small sphere outside the big one
  }

  SECTION("a crack surface through a sphere cuts it") {
    // The plane z = 0.5 cuts the unit sphere's cap at radius sqrt(0.75):
    // the cap shows inside, the plane (red) outside.
    scene.add({0, 0, 0}, 1.0);
    scene.addSquare(3.0, 0.5);
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    const auto [u, v] = Spheres::pixelOf({0, 0, 0});
    const auto y = static_cast<int>(v);
    CHECK(!red(image.pixel(static_cast<int>(u), y)));
    CHECK(brightness(image.pixel(static_cast<int>(u), y)) > 300);
    // The cap's silhouette on the plane: the circle of radius sqrt(0.75) at z = 0.5.
    const double cap = 2.0 * Spheres::focal() * std::sqrt(0.75) / (Spheres::kEye - 0.5);
    auto sphereLit = [](const std::uint8_t* p) { return !red(p) && brightness(p) > 30; };
    const int width = widestRun(image, static_cast<int>(u) - 40, static_cast<int>(u) + 40, y - 3,
                                y + 3, sphereLit);
    INFO("cap width " << cap);
    CHECK(std::abs(width - cap) < 2.0);
    CHECK(red(image.pixel(static_cast<int>(u + 0.5 * cap + 3), y)));
  }

  SECTION("a sphere centred just off the picture shows the part in it") {
    // The picture's left edge at depth 20 is at x = -20 tan(15 deg) * 4 / 3.
    const double edge = -Spheres::kEye * std::tan(15.0 * std::numbers::pi / 180.0) * 4.0 / 3.0;
    scene.add({edge - 0.3, 0, 0}, 1.0);
    SECTION("alone (all centres outside the view)") {}
    SECTION("with another in the middle") {
      scene.add({0, 0, 0}, 1.0);
    }
    scene.addSquare(0.0, -5.0);
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    const int y = Spheres::kHeight / 2;
    // About 0.7 of 22 pixels per unit in view.
    const int shown = widestRun(image, 0, 40, y - 2, y + 2, notBlack);
    CHECK(std::abs(shown - 0.7 * Spheres::focal() / Spheres::kEye) < 2.0);
    CHECK((*renderer)->impostorStats().drawn == static_cast<std::int64_t>(scene.positions.size()));
  }

  SECTION("a clipping plane removes the spheres on the side it hides") {
    scene.add({-3, 0, 0}, 1.0);
    scene.add({3, 0, 0}, 1.0);
    scene.addSquare(0.0, -5.0);
    scene.description.particles.clip = pipeline::ClipPlane{{0, 0, 0}, {1, 0, 0}};
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    auto centre = [&](double x) {
      const auto [u, v] = Spheres::pixelOf({x, 0, 1});
      return image.pixel(static_cast<int>(u), static_cast<int>(v));
    };
    CHECK(notBlack(centre(-3)));
    CHECK(!notBlack(centre(3)));
    CHECK((*renderer)->impostorStats().drawn == 1);
  }

  SECTION("translucent spheres show what is behind them, and none is left out") {
    scene.description.particles.colourBy = pipeline::ParticleColourBy::kRadius;
    scene.description.particles.opacity = 0.5;
    scene.add({0, 0, 0}, 1.0);       // yellow, in front
    scene.add({0.2, 0, -3.0}, 0.5);  // purple, right behind it
    scene.addSquare(0.0, -5.0);
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK((*renderer)->impostorStats().drawn == 2);
    const auto [u, v] = Spheres::pixelOf({0.2, 0, 0.98});
    const std::uint8_t* both = image.pixel(static_cast<int>(u), static_cast<int>(v));
    const auto [u1, v1] = Spheres::pixelOf({-0.6, 0, 0.8});
    const std::uint8_t* front = image.pixel(static_cast<int>(u1), static_cast<int>(v1));
    // The purple behind takes green away and adds blue.
    CHECK(both[2] > front[2] + 10);
    CHECK(both[1] + 10 < front[1]);
  }

  SECTION("a sphere wider than the largest point falls back to the geometry shader") {
    scene.add({0, 0, 0}, 1.0);
    scene.add({0, 0, -3}, 1.0);
    scene.description.view.camera->position = {0, 0, 2.5};  // about 390 pixels wide
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK(!(*renderer)->impostorStats().points);
    CHECK(brightness(image.pixel(Spheres::kWidth / 2, Spheres::kHeight / 2)) > 300);
    CHECK(count(image, notBlack) > Spheres::kWidth * Spheres::kHeight * 9 / 10);
    // Back out: points again.
    scene.description.view.camera->position = {0, 0, Spheres::kEye};
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    CHECK((*renderer)->impostorStats().points);
  }
}

TEST_CASE("hidden spheres are left out without changing the picture", "[render][egl]") {
  // A block of particles with a crack through it, coloured by damage, seen
  // from a corner close enough for spheres 10 to 20 pixels wide: most
  // spheres are behind others.
  constexpr int kSize[2] = {320, 240};
  auto renderer = render::SceneRenderer::create(kSize[0], kSize[1]);
  REQUIRE(renderer.isOk());
  Scene scene;
  scene.description.view.width = kSize[0];
  scene.description.view.height = kSize[1];
  scene.description.particles.visible = true;
  scene.description.particles.colourBy = pipeline::ParticleColourBy::kDamage;
  scene.description.view.scalarBar = false;
  const dem::Vec3 centre = 0.5 * scene.crack.block.extent;
  scene.description.view.camera =
      pipeline::CameraDescription{centre + dem::Vec3{10, 7, 5}, centre, {0, 0, 1}, 30};
  // Above a threshold of spheres in view (1e6-particle specimens) culling
  // goes by cells of spheres: forced here, the picture must not change.
  const bool cells = GENERATE(false, true);
  INFO((cells ? "by cells" : "sphere by sphere"));
  (*renderer)->setImpostorOptions({.occlusionCellThreshold = cells ? 0u : 1u << 30});
  SECTION("from outside") {}
  SECTION("with a clipping plane through the block") {
    scene.description.particles.clip = pipeline::ClipPlane{centre, {1, 1, 0}};
  }
  SECTION("close: cells too wide on screen go sphere by sphere") {
    scene.description.view.camera =
        pipeline::CameraDescription{centre + dem::Vec3{7, 4.9, 3.5}, centre, {0, 0, 1}, 30};
  }
  render::Image culled;
  REQUIRE((*renderer)->render(scene.description, scene.input(), culled).isOk());
  const auto stats = (*renderer)->impostorStats();
  INFO(stats.drawn << " of " << stats.spheres << " spheres drawn");
  CHECK(stats.points);
  CHECK(stats.drawn < stats.spheres * 2 / 3);
  CHECK(count(culled, notBlack) > kSize[0] * kSize[1] / 5);
  render::Image all;
  (*renderer)->setImpostorOptions({.geometryShader = false,
                                   .occlusionCulling = false,
                                   .occlusionCellThreshold = cells ? 0u : 1u << 30});
  REQUIRE((*renderer)->renderFrame(kSize[0], kSize[1], all).isOk());
  INFO("culled by cells: " << cells);
  // Sphere by sphere, only the spheres a clipping plane removes are left out;
  // by cells (inViewCells), also the cells out of view.
  const auto unculled = (*renderer)->impostorStats();
  if (!cells) {
    CHECK((unculled.drawn < unculled.spheres) == scene.description.particles.clip.has_value());
  } else {
    CHECK(unculled.drawn <= unculled.spheres);
    CHECK(unculled.drawn > stats.drawn);
  }
  CHECK(differingPixels(all, culled) == 0);
  // VTK's own impostors (geometry shader): the same picture but for
  // silhouette pixels and small differences of shading, away from the edges
  // (where VTK's misses the spheres whose centres are outside the picture).
  (*renderer)->setImpostorOptions({.geometryShader = true,
                                   .occlusionCulling = false,
                                   .occlusionCellThreshold = cells ? 0u : 1u << 30});
  render::Image vtk;
  REQUIRE((*renderer)->renderFrame(kSize[0], kSize[1], vtk).isOk());
  CHECK(!(*renderer)->impostorStats().points);
  CHECK(differingPixels(vtk, all, 30, 24) < count(all, notBlack) / 100);
}

namespace {
// Perspective at 100x100 pixels, 100 pixels per view unit at unit depth: a
// sphere of radius 1 at depth 10 is about 20 pixels wide.
render::OcclusionView hundredPixelView() {
  render::OcclusionView view;
  view.width = 100;
  view.height = 100;
  view.rayScale = {0.01, 0.01};
  view.rayOffset = {-0.5, -0.5};
  view.nearDepth = 1.0;
  view.farDepth = 100.0;
  return view;
}
// Model coordinates that are the view's.
render::ModelToView identityTransform() {
  render::ModelToView identity;
  identity.rows = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};
  return identity;
}
}  // namespace

TEST_CASE("occlusion culling keeps a sphere that peeks out", "[render]") {
  render::OcclusionView view = hundredPixelView();
  // A large sphere in front; behind it one fully hidden, one whose rim
  // shows beside it, and one behind the first but off the screen.
  const std::vector<double> x{0.0, 0.0, 1.3, 100.0};
  const std::vector<double> y{0.0, 0.0, 0.0, 0.0};
  const std::vector<double> z{-10.0, -13.0, -13.0, -13.0};
  const std::vector<float> r{1.0f, 0.5f, 0.5f, 0.5f};
  render::SphereSet spheres{x, y, z, r, {}};
  CHECK(render::unoccludedSpheres(view, spheres) == std::vector<std::int32_t>{0, 2});
  // The same by cells of spheres (used from 16,384 spheres on), the model
  // coordinates being the view's.
  std::vector<double> xyz;
  for (std::size_t i = 0; i < x.size(); ++i) {
    xyz.insert(xyz.end(), {x[i], y[i], z[i]});
  }
  render::SphereCells cells;
  cells.build(xyz, r);
  render::ModelToView identity = identityTransform();
  render::SphereOcclusion byCells;
  byCells.projectCells(view, cells, identity, 255.0);
  CHECK(byCells.unoccludedInCells(0) == std::vector<std::int32_t>{0, 2});
  // A clipping plane z <= -11 removes the large sphere: the one behind it
  // shows. One through the large sphere's centre (x >= 0) lets it hide
  // nothing.
  const std::vector<render::ClipPlane> behind{{0, 0, -1, -11}};
  identity.planes = behind;
  byCells.projectCells(view, cells, identity, 255.0);
  CHECK(byCells.unoccludedInCells(0) == std::vector<std::int32_t>{1, 2});
  const std::vector<render::ClipPlane> throughCentre{{1, 0, 0, 0}};
  identity.planes = throughCentre;
  byCells.projectCells(view, cells, identity, 255.0);
  CHECK(byCells.unoccludedInCells(0) == std::vector<std::int32_t>{0, 1, 2});
  identity.planes = {};
  // A sphere that may not be drawn (clipped) hides nothing.
  const std::vector<std::uint8_t> mayHide{0, 1, 1, 1};
  spheres.mayHide = mayHide;
  CHECK(render::unoccludedSpheres(view, spheres) == std::vector<std::int32_t>{0, 1, 2});
  // Nor does one that crosses the near plane.
  view.nearDepth = 9.5;
  spheres.mayHide = {};
  CHECK(render::unoccludedSpheres(view, spheres) == std::vector<std::int32_t>{0, 1, 2});
}

TEST_CASE("without culling, cells out of view are left out and no sphere in view is", "[render]") {
  // A 200 x 200 sheet of spheres 2 apart, facing the eye at depth 50, seen
  // through a 100 x 100 pixel view of about 50 x 50 units: most of the sheet
  // is outside. No sphere hides another, so the spheres unoccluded() keeps
  // are exactly those whose points reach the viewport.
  render::OcclusionView view = hundredPixelView();
  std::vector<double> xyz, x, y, z;
  std::vector<float> r;
  for (int i = 0; i < 200; ++i) {
    for (int j = 0; j < 200; ++j) {
      x.push_back(2.0 * i - 200.0);
      y.push_back(2.0 * j - 200.0);
      z.push_back(-50.0);
      r.push_back(0.4f);
      xyz.insert(xyz.end(), {x.back(), y.back(), z.back()});
    }
  }
  const auto shows = render::unoccludedSpheres(view, render::SphereSet{x, y, z, r, {}});
  REQUIRE(shows.size() > 100);
  render::SphereCells cells;
  cells.build(xyz, r);
  render::ModelToView identity = identityTransform();
  render::SphereOcclusion byCells;
  byCells.projectCells(view, cells, identity, 255.0);
  const std::vector<std::int32_t> inView = byCells.inViewCells();
  INFO(shows.size() << " spheres show; " << inView.size() << " of " << x.size() << " drawn");
  CHECK(std::is_sorted(inView.begin(), inView.end()));
  CHECK(std::includes(inView.begin(), inView.end(), shows.begin(), shows.end()));
  CHECK(inView.size() < x.size() / 4);
  // A clipping plane x <= -1 leaves out every sphere right of it, and no other.
  const std::vector<render::ClipPlane> left{{-1, 0, 0, -1}};
  identity.planes = left;
  byCells.projectCells(view, cells, identity, 255.0);
  const std::vector<std::int32_t> clipped = byCells.inViewCells();
  std::vector<std::int32_t> expected;
  for (const std::int32_t i : inView) {
    if (x[static_cast<std::size_t>(i)] <= -1.0) {
      expected.push_back(i);
    }
  }
  CHECK(!expected.empty());
  CHECK(clipped == expected);
  // Cells whose spheres may be wider than the largest point are projected
  // sphere by sphere (open): they keep every sphere that shows too.
  identity.planes = {};
  byCells.projectCells(view, cells, identity, 1.0);
  const std::vector<std::int32_t> open = byCells.inViewCells();
  CHECK(std::is_sorted(open.begin(), open.end()));
  CHECK(std::includes(open.begin(), open.end(), shows.begin(), shows.end()));
}

TEST_CASE("occlusion culling is on for a software rasteriser and off for a GPU", "[render]") {
  using render::SceneRenderer;
  CHECK(*SceneRenderer::occlusionCullingFor("llvmpipe (LLVM 15.0.6, 256 bits)", nullptr));
  CHECK(*SceneRenderer::occlusionCullingFor("SwiftShader Device (LLVM 10.0.0)", "auto"));
  CHECK(!*SceneRenderer::occlusionCullingFor("NVIDIA H200/PCIe/SSE2", nullptr));
  CHECK(!*SceneRenderer::occlusionCullingFor("AMD Radeon Pro W7800 (radeonsi, navi31)", ""));
  // CRACKVIS_OCCLUSION_CULLING overrides the choice, and nothing else passes.
  CHECK(*SceneRenderer::occlusionCullingFor("NVIDIA H200/PCIe/SSE2", "on"));
  CHECK(*SceneRenderer::occlusionCullingFor("NVIDIA H200/PCIe/SSE2", "On"));
  CHECK(!*SceneRenderer::occlusionCullingFor("llvmpipe (LLVM 15.0.6, 256 bits)", "off"));
  const auto wrong = SceneRenderer::occlusionCullingFor("llvmpipe", "yes");
  REQUIRE(!wrong.isOk());
  CHECK_THAT(wrong.status().message(), Catch::Contains("CRACKVIS_OCCLUSION_CULLING"));
  // The renderer here says which it chose.
  auto renderer = SceneRenderer::create(64, 64);
  REQUIRE(renderer.isOk());
  CHECK_THAT((*renderer)->backend(), Catch::Contains("; occlusion culling o"));
}

TEST_CASE("a kept renderer culls as a new one: the choice for its OpenGL survives a cleared scene",
          "[render][egl]") {
  // The same block as above, seen from a corner: most spheres are hidden.
  constexpr int kSize[2] = {320, 240};
  Scene scene;
  scene.description.view.width = kSize[0];
  scene.description.view.height = kSize[1];
  scene.description.particles.visible = true;
  scene.description.view.scalarBar = false;
  const dem::Vec3 centre = 0.5 * scene.crack.block.extent;
  scene.description.view.camera =
      pipeline::CameraDescription{centre + dem::Vec3{10, 7, 5}, centre, {0, 0, 1}, 30};
  const char* before = std::getenv("CRACKVIS_OCCLUSION_CULLING");
  const std::string saved = before != nullptr ? before : "";
  const bool culling = GENERATE(false, true);
  INFO("CRACKVIS_OCCLUSION_CULLING=" << (culling ? "on" : "off"));
  ::setenv("CRACKVIS_OCCLUSION_CULLING", culling ? "on" : "off", 1);
  auto renderer = render::SceneRenderer::create(kSize[0], kSize[1]);
  if (before != nullptr) {
    ::setenv("CRACKVIS_OCCLUSION_CULLING", saved.c_str(), 1);
  } else {
    ::unsetenv("CRACKVIS_OCCLUSION_CULLING");
  }
  REQUIRE(renderer.isOk());
  // A session's scene, then the scene cleared as a session's end shelves the
  // renderer, then the next session's.
  for (int session = 0; session < 2; ++session) {
    INFO("session " << session);
    render::Image image;
    REQUIRE((*renderer)->render(scene.description, scene.input(), image).isOk());
    const auto stats = (*renderer)->impostorStats();
    INFO(stats.drawn << " of " << stats.spheres << " spheres drawn");
    CHECK(stats.spheres > 0);
    CHECK((stats.drawn < stats.spheres * 2 / 3) == culling);
    REQUIRE((*renderer)->clearScene().isOk());
  }
}

TEST_CASE("a pick finds the particle or crack element under the point, as shown", "[render]") {
  Scene scene;
  const render::SceneInput input = scene.input();
  const dem::Vec3 centre = 0.5 * scene.crack.block.extent;
  const auto& positions = scene.crack.block.positions;
  // A ray along -x through the centre: the particle it meets first is the
  // one nearest the eye among those on the line, and the hit lies on its
  // sphere.
  const scene::Ray ray{centre + dem::Vec3{100, 0.01, 0.02}, {-1, 0, 0}};
  scene.description.particles.visible = true;
  scene::PickResult hit = scene::pick(scene.description, input, ray);
  REQUIRE(hit.kind == scene::PickedKind::kParticle);
  const auto i = static_cast<std::size_t>(hit.index);
  CHECK(dem::norm(hit.point - positions[i]) == Approx(0.5).epsilon(1e-9));
  double farthest = -1e300;  // the largest x of a sphere the line passes through
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const dem::Vec3 off = positions[k] - ray.origin;
    const double dy = off.y;
    const double dz = off.z;
    if (dy * dy + dz * dz < 0.25) {
      farthest = std::max(farthest, positions[k].x + std::sqrt(0.25 - dy * dy - dz * dz));
    }
  }
  CHECK(hit.point.x == Approx(farthest));
  CHECK(hit.values.front().name == "radius");
  CHECK(hit.values.front().value == 0.5);
  CHECK(scene::describePick(hit).starts_with(fmt::format("particle {} at (", hit.index)));

  // Particles hidden: the crack plane (x = const) is met, with its bond.
  scene.description.particles.visible = false;
  hit = scene::pick(scene.description, input, ray);
  REQUIRE(hit.kind == scene::PickedKind::kCrack);
  const auto& cell = scene.mesh.polygons;
  REQUIRE(cell.size() > 0);
  CHECK(std::any_of(hit.values.begin(), hit.values.end(),
                    [](const scene::PickedValue& v) { return v.name.starts_with("bond_id"); }));
  CHECK(std::abs(hit.point.y - ray.origin.y) < 1e-9);
  CHECK(hit.point.x > 0.0);
  CHECK(hit.point.x < scene.crack.block.extent.x);
  // Clipped away (the eye's side of x = centre), nothing is left on the line.
  scene.description.cracks.clip = pipeline::ClipPlane{centre - dem::Vec3{3, 0, 0}, {1, 0, 0}};
  CHECK(scene::pick(scene.description, input, ray).kind == scene::PickedKind::kNothing);
  // A ray that misses the block.
  const scene::Ray miss{centre + dem::Vec3{100, 50, 0}, {-1, 0, 0}};
  CHECK(scene::pick(scene.description, input, miss).kind == scene::PickedKind::kNothing);
}

TEST_CASE("the view's ray goes through the focal point at the centre of the view",
          "[render][egl]") {
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  Scene scene;
  REQUIRE((*renderer)->setScene(scene.description, scene.input(), true).isOk());
  const pipeline::CameraDescription camera = (*renderer)->camera();
  const scene::Ray ray = (*renderer)->viewRay(0.5, 0.5, kWidth, kHeight);
  const dem::Vec3 view = camera.focalPoint - camera.position;
  const dem::Vec3 along = (1.0 / dem::norm(ray.direction)) * ray.direction;
  CHECK(dem::dot(along, (1.0 / dem::norm(view)) * view) == Approx(1.0).epsilon(1e-6));
  // The top of the view is up (+z here), its right is -y seen along -x.
  const scene::Ray top = (*renderer)->viewRay(0.5, 0.0, kWidth, kHeight);
  CHECK(top.direction.z / dem::norm(top.direction) > along.z + 0.1);
}
