// What a stream sends its client: each rendered frame encoded as H.264 with
// its timings, the per-second statistics, and a session's notices as
// messages. Private to the service library.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "crackvis/v1/render.pb.h"
#include <crackvis/common/status.hpp>
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/service/session.hpp>

namespace crackvis::service {

// Encodes a stream's frames and keeps its per-second statistics. One per
// stream: a new stream starts a new encoder, so its first frame is a keyframe.
class StreamEncoder {
 public:
  Result<v1::Frame> encode(RenderedFrame& frame);

  // Makes an encoder of `width` x `height` and encodes one frame with it,
  // then drops it: libx264's first encoder in a process takes about 20 ms
  // more than later ones (its tables and set-up), which a server pays at
  // its start instead of in the first user's first picture.
  static void warmUp(int width, int height);

  // A stats message once a second.
  std::optional<v1::StreamStats> stats(std::uint64_t dropped);

 private:
  struct Window {
    double frames = 0;
    std::uint64_t bytes = 0;
    double renderMs = 0;
    double encodeMs = 0;
  };
  std::unique_ptr<encode::FrameEncoder> m_encoder;
  Window m_window;
  Clock::time_point m_windowStart = Clock::now();
};

// A session's notice as the stream's message: an event's error, a pick's
// answer or the session's state.
v1::ServerMessage toMessage(const SessionNotice& notice);

}  // namespace crackvis::service
