// Recording of the received stream to MP4: StreamRecorder remuxes the H.264
// access units that the client receives (Annex B, as
// crackvis::encode::FrameEncoder produces them) into an MP4 file with
// libavformat. Nothing is decoded or re-encoded, so recording costs no more
// than writing the bytes.
//
// The file starts at the first keyframe: frames before it cannot be decoded
// without their reference frames, so they are skipped and counted. The SPS and
// PPS of that keyframe become the track's avcC; later keyframes keep theirs
// in-band. Every FFmpeg error is in the Status with the file's path and its
// av_strerror text.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/encode/frame_codec.hpp>

namespace crackvis::record {

class StreamRecorder {
 public:
  // Creates `path` (an .mp4) for a stream of width x height at about `fps`
  // frames per second; fails at once when the file cannot be written.
  static Result<std::unique_ptr<StreamRecorder>> start(const std::string& path, int width,
                                                       int height, int fps);
  StreamRecorder(const StreamRecorder&) = delete;
  StreamRecorder& operator=(const StreamRecorder&) = delete;
  ~StreamRecorder();  // finishes the file; call finish() to see its Status

  // Adds one access unit presented `seconds` after the recording began.
  // Times that do not increase are nudged forward by one tick. A frame of
  // another size than the recording's is refused (INVALID_ARGUMENT).
  Status add(const encode::EncodedFrame& frame, double seconds);

  // Writes the MP4 index and closes the file; later calls return the first
  // call's Status. Without a keyframe nothing could be recorded: the empty
  // file is removed and the Status says so.
  Status finish();

  std::int64_t framesWritten() const { return m_written; }
  std::int64_t framesSkipped() const { return m_skipped; }  // before the first keyframe
  const std::string& path() const { return m_path; }

 private:
  StreamRecorder() = default;
  Status loadPacket(const encode::EncodedFrame& frame);
  Status checkSize(const encode::EncodedFrame& frame);
  Status writeHeader(const encode::EncodedFrame& keyframe, double seconds);
  Status writePacket(const encode::EncodedFrame& frame, double seconds);
  Status closeFile();

  struct Impl;
  std::unique_ptr<Impl> m_impl;
  std::string m_path;
  int m_width = 0;
  int m_height = 0;
  int m_fps = 0;
  std::int64_t m_written = 0;
  std::int64_t m_skipped = 0;
};

}  // namespace crackvis::record
