// The H.264 codec alone: settings, sizes and the round trip of frames made
// here (the rendered frames' picture quality is tests/render's..
#include <cmath>
#include <cstdlib>

#include <catch2/catch.hpp>

#include <crackvis/encode/frame_codec.hpp>

using namespace crackvis;

namespace {

// Smooth ramps that move a little per frame, over a constant blue.
encode::RgbFrame rampFrame(int width, int height, int frame, int blue) {
  encode::RgbFrame rgb{width, height,
                       std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height * 3)};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      auto* p = &rgb.rgb[(static_cast<std::size_t>(y) * width + x) * 3];
      p[0] = static_cast<std::uint8_t>((x + 4 * frame) * 200 / (width + 20));
      p[1] = static_cast<std::uint8_t>(y * 200 / height);
      p[2] = static_cast<std::uint8_t>(blue);
    }
  }
  return rgb;
}

}  // namespace

TEST_CASE("the encoder refuses bad settings, frames larger than its own and short pixel arrays",
          "[encode]") {
  struct Bad {
    encode::EncoderSettings settings;
    const char* message;
  };
  for (const Bad& bad : {
           Bad{{641, 360, 30, 4'000'000}, "frame size 641x360: H.264 needs even sizes of 16..8192"},
           Bad{{8, 8, 30, 4'000'000}, "frame size 8x8: H.264 needs even sizes of 16..8192"},
           Bad{{64, 48, 0, 4'000'000}, "encoder fps 0 outside 1..240"},
           Bad{{64, 48, -5, 4'000'000}, "encoder fps -5 outside 1..240"},
           Bad{{64, 48, 1000, 4'000'000}, "encoder fps 1000 outside 1..240"},
           Bad{{64, 48, 30, 10}, "encoder bitrate 10 below 1 kbit per frame (30 fps)"},
           Bad{{64, 48, 30, -4'000'000},
               "encoder bitrate -4000000 below 1 kbit per frame (30 fps)"},
           Bad{{64, 48, 30, 0, 60}, "encoder crf 60 outside 0..51"},
           Bad{{64, 48, 30, 0, 20, "warp-speed"}, "libx264 has no preset 'warp-speed'"},
       }) {
    const auto created = encode::FrameEncoder::create(bad.settings);
    CHECK(created.status().code() == StatusCode::kInvalidArgument);
    CHECK(created.status().message() == bad.message);
  }
  // Bitrate 0: constant quality, the movies' mode.
  auto quality = encode::FrameEncoder::create({64, 48, 30, 0, 20, "medium"});
  REQUIRE(quality.isOk());
  const encode::RgbFrame grey{64, 48, std::vector<std::uint8_t>(64 * 48 * 3, 128)};
  CHECK(quality.value()->encode(grey, true).isOk());
  auto encoder = encode::FrameEncoder::create({64, 48, 30, 1'000'000});
  REQUIRE(encoder.isOk());
  const encode::RgbFrame wider{66, 32, std::vector<std::uint8_t>(66 * 32 * 3, 0)};
  CHECK(encoder.value()->encode(wider, false).status().message() ==
        "frame 66x32 for an encoder of 64x48");
  const encode::RgbFrame taller{32, 50, std::vector<std::uint8_t>(32 * 50 * 3, 0)};
  CHECK(encoder.value()->encode(taller, false).status().code() == StatusCode::kInvalidArgument);
  const encode::RgbFrame short_{32, 32, std::vector<std::uint8_t>(32 * 31 * 3, 0)};
  CHECK(encoder.value()->encode(short_, false).status().message() ==
        "frame 32x32 for an encoder of 64x48");
  // A smaller frame is a reduced render: enlarged, not refused.
  encode::RgbFrame reduced{32, 24, {}};
  reduced.rgb.reserve(32 * 24 * 3 + 256);  // swscale's SIMD reads run past the last pixel
  reduced.rgb.assign(32 * 24 * 3, 90);
  CHECK(encoder.value()->encode(reduced, false).isOk());
}

TEST_CASE("frames of any even width survive the round trip, and the stream may change size",
          "[encode]") {
  // Rows that are not a multiple of 16 bytes (1046 * 3) once made the
  // decoder's colour conversion write past its buffer; one decoder follows
  // a stream through size changes as a client does after a resize.
  auto decoder = encode::FrameDecoder::create();
  REQUIRE(decoder.isOk());
  for (auto [width, height] : {std::pair{1046, 700}, std::pair{322, 242}, std::pair{640, 360}}) {
    auto encoder = encode::FrameEncoder::create({width, height, 30, 4'000'000});
    REQUIRE(encoder.isOk());
    for (int frame = 0; frame < 5; ++frame) {
      const encode::RgbFrame rgb = rampFrame(width, height, frame, 128);
      auto encoded = (*encoder)->encode(rgb, frame == 0);
      REQUIRE(encoded.isOk());
      auto back = (*decoder)->decode(*encoded);
      REQUIRE(back.isOk());
      REQUIRE(back->has_value());
      CHECK((*back)->width == width);
      CHECK((*back)->rgb.size() == rgb.rgb.size());
      INFO(width << "x" << height << " frame " << frame);
      CHECK(encode::psnr(rgb, **back) >= 35.0);
    }
  }
}

TEST_CASE("decoding into one picture gives decode's pixels, reusing its memory across frames",
          "[encode]") {
  // Clients decode every frame of a stream into one picture (crackvis-client,
  // bench render); across a size change it follows the stream.
  auto fresh = encode::FrameDecoder::create();
  auto reusing = encode::FrameDecoder::create();
  REQUIRE(fresh.isOk());
  REQUIRE(reusing.isOk());
  encode::RgbFrame picture;
  for (auto [width, height] : {std::pair{640, 360}, std::pair{1046, 700}, std::pair{322, 242}}) {
    auto encoder = encode::FrameEncoder::create({width, height, 30, 4'000'000});
    REQUIRE(encoder.isOk());
    const std::uint8_t* storage = nullptr;
    for (int frame = 0; frame < 4; ++frame) {
      // Blue differs per frame: nothing of the last picture may be left.
      const encode::RgbFrame rgb = rampFrame(width, height, frame, 60 + 20 * frame);
      auto encoded = (*encoder)->encode(rgb, frame == 0);
      REQUIRE(encoded.isOk());
      auto expected = (*fresh)->decode(*encoded);
      auto decoded = (*reusing)->decodeInto(*encoded, picture);
      REQUIRE(expected.isOk());
      REQUIRE(expected->has_value());
      REQUIRE(decoded.isOk());
      REQUIRE(*decoded);
      INFO(width << "x" << height << " frame " << frame);
      CHECK(picture.width == width);
      CHECK(picture.height == height);
      CHECK(picture.rgb == (*expected)->rgb);  // nothing of the last frame left
      CHECK(encode::psnr(rgb, picture) >= 35.0);
      if (frame > 0) {
        CHECK(picture.rgb.data() == storage);  // no new buffer for a frame of the same size
      }
      storage = picture.rgb.data();
    }
  }
}
