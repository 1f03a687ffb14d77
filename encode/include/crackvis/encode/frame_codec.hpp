// H.264 for the render server's stream: FrameEncoder turns RGB frames into
// H.264 access units with libavcodec + libx264 (ultrafast, zerolatency,
// capped bitrate, periodic intra refresh off, keyframes on demand: a new
// client, a resize, a reconnect); FrameDecoder turns them back into RGB (the
// client's path, and the tests' check of the round trip).
//
// Every FFmpeg call is checked and its error text (av_strerror) is in the
// Status; codec contexts, frames and packets are owned by unique_ptrs.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>

namespace crackvis::encode {

struct RgbFrame {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // rows top to bottom, 3 bytes per pixel
};

struct EncodedFrame {
  std::vector<std::uint8_t> data;  // one H.264 access unit (Annex B)
  bool keyframe = false;
  std::int64_t index = 0;  // frame number in the stream
};

struct EncoderSettings {
  int width = 1280;  // even
  int height = 720;  // even
  int fps = 30;
  int bitrate = 4'000'000;  // bits per second, capped (VBV); 0: constant quality (crf)
  int crf = 20;             // libx264's constant rate factor when bitrate is 0
  // libx264's speed/quality trade: the stream's frames must be ready in
  // milliseconds; an offline movie (crackvis movie) affords "medium", which
  // gives visibly sharper frames at the same bitrate.
  std::string preset = "ultrafast";
};

class FrameEncoder {
 public:
  static Result<std::unique_ptr<FrameEncoder>> create(const EncoderSettings& settings);
  ~FrameEncoder();

  // Encodes one frame of the settings' size; `keyframe` forces an IDR frame.
  // With zerolatency every frame yields its access unit at once. A smaller
  // frame (a reduced render) is enlarged to the settings' size by pixel
  // replication, as render::resample does (the stream's pixel x shows the
  // frame's pixel x * width / settings' width, rows alike): it is converted
  // to YUV at its own size and its planes replicated, a fraction of the cost
  // of converting the enlarged frame.
  Result<EncodedFrame> encode(const RgbFrame& frame, bool keyframe);
  const EncoderSettings& settings() const { return m_settings; }

 private:
  FrameEncoder() = default;
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  EncoderSettings m_settings;
};

class FrameDecoder {
 public:
  static Result<std::unique_ptr<FrameDecoder>> create();
  ~FrameDecoder();

  // Decodes one access unit; an RGB frame when the decoder has one.
  Result<std::optional<RgbFrame>> decode(const EncodedFrame& frame);
  // The same into `picture`, reusing its storage; false while the decoder
  // has no picture. A client that made a fresh frame per access unit zeroed
  // and faulted in its memory every time (2.7 MB at 1280x720, at 50 frames
  // per second). After an error the picture is empty.
  Result<bool> decodeInto(const EncodedFrame& frame, RgbFrame& picture);

 private:
  FrameDecoder() = default;
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

// Peak signal-to-noise ratio of two frames of the same size, dB.
double psnr(const RgbFrame& a, const RgbFrame& b);

// FFmpeg (and libx264 through it) prints per-encoder statistics at the info
// level when each stream closes: unstructured lines a service's log should
// not carry. Process-wide; warnings and errors still go to stderr.
void limitCodecLogsToWarnings();

// libavcodec's version, as FFmpeg prints it ("59.37.100").
std::string codecLibraryVersion();

}  // namespace crackvis::encode
