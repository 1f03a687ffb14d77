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

}  // namespace

TEST_CASE("rendered frames survive H.264 encode and decode at >= 35 dB PSNR",
          "[encode][render][egl]") {
  constexpr int kWidth = 640;
  constexpr int kHeight = 360;
  auto renderer = render::SceneRenderer::create(kWidth, kHeight);
  REQUIRE(renderer.isOk());
  const auto crack = testing::fccPlaneCrack(4, {1, 1, 1}, 13 / std::sqrt(2.0) + 1.5, 0.02);
  auto extractor = cracks::makeExtractor(cracks::Method::kLocalVoronoi, *crack.graph, 3);
  cracks::CrackMesh mesh;
  REQUIRE(extractor->extract(crack.input(), mesh).isOk());
  pipeline::PipelineDescription description;
  description.view.width = kWidth;
  description.view.height = kHeight;
  description.particles.opacity = 1.0;
  description.particles.colourBy = pipeline::ParticleColourBy::kDamage;
  const render::SceneInput input{&crack.block.lattice, crack.input(), {}, {}, &mesh};

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
