// The recorder's MP4 files as ffprobe sees them: codec, size and frame count
// of streams from crackvis::encode::FrameEncoder, remuxed without re-encoding.
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/record/stream_recorder.hpp>

using namespace crackvis;

namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr int kFps = 30;

// A diagonal gradient that moves with the frame number: the encoder gets
// motion to code, so P-frames are not empty.
encode::RgbFrame gradient(int width, int height, int frame) {
  encode::RgbFrame rgb{width, height,
                       std::vector<std::uint8_t>(static_cast<std::size_t>(width) *
                                                 static_cast<std::size_t>(height) * 3)};
  std::size_t k = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      rgb.rgb[k++] = static_cast<std::uint8_t>(x + 4 * frame);
      rgb.rgb[k++] = static_cast<std::uint8_t>(y + 2 * frame);
      rgb.rgb[k++] = static_cast<std::uint8_t>((x + y) / 2);
    }
  }
  return rgb;
}

// `count` access units of a width x height stream with keyframes at the
// given frame numbers (frame 0 is always one: x264 starts with an IDR).
std::vector<encode::EncodedFrame> encodeStream(int width, int height, int count,
                                               const std::set<int>& keyframes) {
  auto encoder = encode::FrameEncoder::create({width, height, kFps, 1'000'000});
  REQUIRE(encoder.isOk());
  std::vector<encode::EncodedFrame> frames;
  for (int frame = 0; frame < count; ++frame) {
    auto encoded = (*encoder)->encode(gradient(width, height, frame), keyframes.contains(frame));
    REQUIRE(encoded.isOk());
    frames.push_back(std::move(encoded.value()));
  }
  return frames;
}

// "codec,width,height,frames" of the file's video stream, decoded by ffprobe.
std::string probe(const std::string& path) {
  const auto result = testing::runProcess(
      {"ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
       "stream=codec_name,width,height,nb_read_frames", "-of", "csv=p=0", path});
  INFO("ffprobe stderr: " << result.err);
  CHECK(result.exitCode == 0);
  CHECK(result.err.empty());
  const auto lines = testing::lines(result.out);
  return lines.empty() ? std::string() : lines.front();
}

}  // namespace

TEST_CASE("45 frames recorded to MP4 read back as h264 320x240 with 45 frames", "[record]") {
  const auto frames = encodeStream(kWidth, kHeight, 45, {0, 22});
  REQUIRE(frames[0].keyframe);
  REQUIRE(frames[22].keyframe);
  testing::TempDir dir;
  const std::string path = dir.file("stream.mp4");
  auto recorder = record::StreamRecorder::start(path, kWidth, kHeight, kFps);
  REQUIRE(recorder.isOk());
  for (const auto& frame : frames) {
    const Status added = (*recorder)->add(frame, static_cast<double>(frame.index) / kFps);
    INFO(added.message());
    REQUIRE(added.isOk());
  }
  CHECK((*recorder)->framesWritten() == 45);
  CHECK((*recorder)->framesSkipped() == 0);
  const Status finished = (*recorder)->finish();
  INFO(finished.message());
  REQUIRE(finished.isOk());
  CHECK((*recorder)->finish().isOk());  // idempotent
  CHECK(probe(path) == "h264,320,240,45");

  const Status late = (*recorder)->add(frames[0], 2.0);
  CHECK(late.code() == StatusCode::kFailedPrecondition);
  CHECK(late.message() == "recording " + path + ": frame 0 added after finish()");
}

TEST_CASE("frames before the first keyframe are skipped and repeated times are nudged",
          "[record]") {
  // A client that joins mid-stream: its first frames refer to a keyframe it
  // never received, until the server sends it a new one (frame 5).
  const auto frames = encodeStream(kWidth, kHeight, 16, {0, 5});
  testing::TempDir dir;
  const std::string path = dir.file("joined.mp4");
  {
    auto recorder = record::StreamRecorder::start(path, kWidth, kHeight, kFps);
    REQUIRE(recorder.isOk());
    for (std::size_t k = 1; k < frames.size(); ++k) {
      // Two frames arrive in the same tick of a coarse receive clock.
      const double seconds = static_cast<double>(k / 2) / kFps;
      const Status added = (*recorder)->add(frames[k], seconds);
      INFO("frame " << k << ": " << added.message());
      REQUIRE(added.isOk());
    }
    CHECK((*recorder)->framesSkipped() == 4);
    CHECK((*recorder)->framesWritten() == 11);
  }  // the destructor finishes the file
  CHECK(probe(path) == "h264,320,240,11");
}

TEST_CASE("a recording without a keyframe reports it and leaves no file", "[record]") {
  const auto frames = encodeStream(kWidth, kHeight, 4, {0});
  testing::TempDir dir;
  const std::string path = dir.file("empty.mp4");
  auto recorder = record::StreamRecorder::start(path, kWidth, kHeight, kFps);
  REQUIRE(recorder.isOk());
  for (std::size_t k = 1; k < frames.size(); ++k) {
    REQUIRE((*recorder)->add(frames[k], static_cast<double>(k) / kFps).isOk());
  }
  const Status finished = (*recorder)->finish();
  CHECK(finished.code() == StatusCode::kFailedPrecondition);
  CHECK(finished.message() == "recording " + path +
                                  ": no keyframe arrived (3 frames skipped); nothing recorded, "
                                  "file removed");
  CHECK_FALSE(std::filesystem::exists(path));
}

TEST_CASE("an unwritable path and a frame of another size give clear errors", "[record]") {
  const std::string missing = "/nonexistent-crackvis-dir/stream.mp4";
  const auto unwritable = record::StreamRecorder::start(missing, kWidth, kHeight, kFps);
  CHECK(unwritable.status().code() == StatusCode::kNotFound);
  CHECK(unwritable.status().message() ==
        "recording " + missing + ": cannot open the file for writing: No such file or directory");

  const auto small = encodeStream(kWidth, kHeight, 2, {0});
  const auto large = encodeStream(640, 480, 2, {0});
  testing::TempDir dir;

  SECTION("a resized stream is refused once recording has begun") {
    const std::string path = dir.file("resized.mp4");
    auto recorder = record::StreamRecorder::start(path, kWidth, kHeight, kFps);
    REQUIRE(recorder.isOk());
    REQUIRE((*recorder)->add(small[0], 0.0).isOk());
    const Status resized = (*recorder)->add(large[0], 1.0 / kFps);
    CHECK(resized.code() == StatusCode::kInvalidArgument);
    CHECK(resized.message() ==
          "recording " + path + ": frame 0 is 640x480, the recording is 320x240");
    CHECK((*recorder)->add(large[1], 2.0 / kFps).code() == StatusCode::kInvalidArgument);
    CHECK((*recorder)->framesWritten() == 1);
    REQUIRE((*recorder)->finish().isOk());
    CHECK(probe(path) == "h264,320,240,1");
  }

  SECTION("a first keyframe of another size is refused") {
    const std::string path = dir.file("wrong.mp4");
    auto recorder = record::StreamRecorder::start(path, 640, 480, kFps);
    REQUIRE(recorder.isOk());
    const Status refused = (*recorder)->add(small[0], 0.0);
    CHECK(refused.code() == StatusCode::kInvalidArgument);
    CHECK(refused.message() ==
          "recording " + path + ": frame 0 is 320x240, the recording is 640x480");
    CHECK((*recorder)->framesWritten() == 0);
  }
}
