// Rendered frames through libx264 and back: the stream's picture quality.
#include <cmath>
#include <cstdlib>

#include <catch2/catch.hpp>

#include "cracks/crack_fixtures.hpp"
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/render/scene_renderer.hpp>

using namespace crackvis;

namespace {

// Pixels that differ clearly from the background (the top-left pixel): a
// blank frame has none, so a round trip of blank frames proves nothing.
std::size_t contentPixels(const std::vector<std::uint8_t>& rgb) {
  std::size_t count = 0;
  for (std::size_t k = 0; k + 2 < rgb.size(); k += 3) {
    const int difference =
        std::abs(rgb[k] - rgb[0]) + std::abs(rgb[k + 1] - rgb[1]) + std::abs(rgb[k + 2] - rgb[2]);
    count += difference > 60 ? 1 : 0;
  }
  return count;
}

constexpr int kWidth = 640;
constexpr int kHeight = 360;

// A frame for the encoder with the capacity swscale's SIMD reads run into
// past the last pixel (as the renderer's images have).
encode::RgbFrame paddedFrame(const render::Image& image) {
  encode::RgbFrame frame{image.width, image.height, {}};
  frame.rgb.reserve(image.rgb.size() + 256);
  frame.rgb.assign(image.rgb.begin(), image.rgb.end());
  return frame;
}

// An FCC block cut by a (111) plane, its crack from local Voronoi, and a
// 640x360 view of both with the particles coloured by damage.
struct CrackView {
  testing::PlantedCrack crack =
      testing::fccPlaneCrack(4, {1, 1, 1}, 13 / std::sqrt(2.0) + 1.5, 0.02);
  cracks::CrackMesh mesh;
  pipeline::PipelineDescription description;

  CrackView() {
    auto extractor = cracks::makeExtractor(cracks::Method::kLocalVoronoi, *crack.graph, 3);
    REQUIRE(extractor->extract(crack.input(), mesh).isOk());
    description.view.width = kWidth;
    description.view.height = kHeight;
    description.particles.colourBy = pipeline::ParticleColourBy::kDamage;
  }
  render::SceneInput input() const {
    render::SceneInput scene;
    scene.lattice = &crack.block.lattice;
    scene.step = crack.input();
    scene.cracks = &mesh;
    return scene;
  }
};

}  // namespace

TEST_CASE("rendered frames survive H.264 encode and decode at >= 35 dB PSNR",
          "[encode][render][egl]") {
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  CrackView view;
  pipeline::PipelineDescription& description = view.description;
  description.particles.opacity = 1.0;
  const render::SceneInput input = view.input();
  const auto& crack = view.crack;

  auto encoder = encode::FrameEncoder::create({kWidth, kHeight, 30, 4'000'000});
  REQUIRE(encoder.isOk());
  auto decoder = encode::FrameDecoder::create();
  REQUIRE(decoder.isOk());
  const dem::Vec3 centre = 0.5 * crack.block.extent;
  double worst = 1e9;
  int decoded = 0;
  std::vector<std::uint8_t> previous;
  for (int frame = 0; frame < 30; ++frame) {
    // The camera orbits the block, as during a rotate interaction.
    const double angle = 0.05 * frame;
    description.view.camera = pipeline::CameraDescription{
        centre + dem::Vec3{25 * std::cos(angle), 25 * std::sin(angle), 8}, centre, {0, 0, 1}, 30};
    render::Image image;
    REQUIRE((*renderer)->render(description, input, image).isOk());
    const encode::RgbFrame rgb{image.width, image.height, image.rgb};
    const bool keyframe = frame == 0 || frame == 12;  // a new client at frame 12
    auto encoded = (*encoder)->encode(rgb, keyframe);
    REQUIRE(encoded.isOk());
    CHECK(encoded->keyframe == keyframe);
    CHECK(encoded->index == frame);
    auto back = (*decoder)->decode(*encoded);
    REQUIRE(back.isOk());
    REQUIRE(back->has_value());  // zero latency: every access unit decodes at once
    ++decoded;
    worst = std::min(worst, encode::psnr(rgb, **back));
    // The block fills a good part of the view, before and after the codec.
    const std::size_t pixels = static_cast<std::size_t>(kWidth) * kHeight;
    CHECK(contentPixels(rgb.rgb) > pixels / 10);
    CHECK(contentPixels((*back)->rgb) > pixels / 10);
    CHECK((*back)->rgb != previous);  // the orbit shows in the decoded stream
    previous = (*back)->rgb;
  }
  INFO("lowest PSNR over 30 frames: " << worst << " dB");
  CHECK(decoded == 30);
  CHECK(worst >= 35.0);
}

TEST_CASE("a reduced frame is enlarged by the encoder as resample enlarges it",
          "[encode][render][egl]") {
  // A drag's frames are rendered at 1/k of the view and streamed at its
  // size: the encoder converts the small frame and replicates its planes.
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  const CrackView view;
  const render::SceneInput input = view.input();
  const pipeline::PipelineDescription& description = view.description;
  REQUIRE((*renderer)->setScene(description, input, true).isOk());

  auto replicating = encode::FrameEncoder::create({kWidth, kHeight, 30, 4'000'000});
  auto enlarged = encode::FrameEncoder::create({kWidth, kHeight, 30, 4'000'000});
  REQUIRE((replicating.isOk() && enlarged.isOk()));
  auto replicatingDecoder = encode::FrameDecoder::create();
  auto enlargedDecoder = encode::FrameDecoder::create();
  REQUIRE((replicatingDecoder.isOk() && enlargedDecoder.isOk()));
  // 3 and 7 do not divide the view: the rule for the pixels left over is
  // resample's. 1 is the whole frame again, after reduced ones.
  int frame = 0;
  for (const int factor : {2, 3, 7, 2, 1}) {
    INFO("reduction " << factor);
    render::Image small;
    REQUIRE((*renderer)->renderFrame(kWidth / factor, kHeight / factor, small).isOk());
    render::Image big;
    render::resample(small, kWidth, kHeight, big);
    const encode::RgbFrame reference = paddedFrame(big);
    const bool keyframe = frame++ == 0;
    auto viaReplication = (*replicating)->encode(paddedFrame(small), keyframe);
    auto viaResample = (*enlarged)->encode(reference, keyframe);
    REQUIRE((viaReplication.isOk() && viaResample.isOk()));
    auto a = (*replicatingDecoder)->decode(*viaReplication);
    auto b = (*enlargedDecoder)->decode(*viaResample);
    REQUIRE((a.isOk() && b.isOk() && a->has_value() && b->has_value()));
    CHECK((*a)->width == kWidth);
    CHECK((*a)->height == kHeight);
    CHECK(contentPixels((*a)->rgb) > static_cast<std::size_t>(kWidth) * kHeight / 10);
    const double replicated = encode::psnr(reference, **a);
    const double resampled = encode::psnr(reference, **b);
    INFO("PSNR against the enlarged frame: replicated planes " << replicated << " dB, enlarged RGB "
                                                               << resampled << " dB");
    CHECK(replicated >= 35.0);
    CHECK(replicated >= resampled - 1.0);
  }
  // A frame larger than the stream is refused, and the encoder goes on.
  const encode::RgbFrame tooWide{kWidth + 2, kHeight,
                                 std::vector<std::uint8_t>((kWidth + 2) * kHeight * 3)};
  const auto refused = (*replicating)->encode(tooWide, false);
  CHECK(refused.status().code() == StatusCode::kInvalidArgument);
  render::Image small;
  REQUIRE((*renderer)->renderFrame(kWidth / 4, kHeight / 4, small).isOk());
  CHECK((*replicating)->encode(paddedFrame(small), false).isOk());
}
