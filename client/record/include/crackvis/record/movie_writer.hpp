// An MP4 of frames rendered for it, not a copy of the interactive stream:
// `crackvis movie` and crackvis-client's full-resolution recording. Each RGB
// frame is encoded with libx264 through libavcodec at constant quality
// (crf 20, preset medium: offline work affords sharpness over speed, and
// unlike the stream no frame is a reduced interactive one), a keyframe every
// two seconds so that players can seek, and muxed by StreamRecorder.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/record/stream_recorder.hpp>

namespace crackvis::record {

struct MovieSettings {
  int width = 1280;  // even, the size of every frame
  int height = 720;
  int fps = 30;
  int bitrate = 0;  // bits per second; 0: constant quality (crf 20)
};

class MovieWriter {
 public:
  // Creates `path`; fails at once on odd sizes or a file that cannot be
  // written.
  static Result<std::unique_ptr<MovieWriter>> start(const std::string& path,
                                                    const MovieSettings& settings);
  ~MovieWriter();  // finishes the file; call finish() to see its Status

  // Encodes and writes the next frame (of the settings' size).
  Status add(const encode::RgbFrame& frame);
  // Writes the MP4 index and closes the file.
  Status finish();
  std::int64_t frames() const { return m_frames; }

 private:
  MovieWriter() = default;
  MovieSettings m_settings;
  std::unique_ptr<encode::FrameEncoder> m_encoder;
  std::unique_ptr<StreamRecorder> m_recorder;
  std::int64_t m_frames = 0;
};

}  // namespace crackvis::record
