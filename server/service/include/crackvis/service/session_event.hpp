// What a client asks of a render session, as the session sees it (no gRPC
// types: the render service converts a stream's messages into these), the
// limits a session works within, and the checks an event needs before it
// reaches a renderer. GL-free, so that the event fuzz target
// (tests/fuzz/render_events_fuzzer.cpp) runs them without a GL context.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <variant>

#include <crackvis/common/status.hpp>
#include <crackvis/dem_layout/layout.hpp>
#include <crackvis/render/camera_move.hpp>

namespace crackvis::service {

using Clock = std::chrono::steady_clock;

struct SessionLimits {
  int maxWidth = 3840;
  int maxHeight = 2160;
  double refineAfterMs = 50.0;       // full resolution this long after the last event
  double interactiveFrameMs = 35.0;  // budget of a reduced frame: turn wait + render
  int maxReduction = 8;
  std::size_t cacheSteps = 8;
  // Frames of all sessions rendered at once (render_turns.hpp); 0: the
  // hardware threads.
  int rendersAtOnce = 0;
  // Bounds of what waits for a slow or absent stream reader.
  std::size_t maxQueuedEvents = 256;  // beyond: an event is refused (RESOURCE_EXHAUSTED)
  std::size_t maxQueuedErrors = 64;   // beyond: event errors are dropped
  // A file declaring more is refused before its arrays are allocated
  // (RESOURCE_EXHAUSTED); ten million particles with 6-8 bonds each fit.
  dem::SizeLimits fileSizes{16'000'000, 80'000'000};
};

struct CameraEvent {
  render::CameraMove move = render::CameraMove::kRotate;
  double dx = 0.0;
  double dy = 0.0;
  bool still = false;  // answered by a full-resolution frame at once, not part of a drag
};
struct ResizeEvent {
  int width = 0;
  int height = 0;
};
struct SetStepEvent {
  int step = 0;         // -1: the last
  bool follow = false;  // the last step, then each new one of a live file
};
struct PlayEvent {
  bool playing = false;
  double fps = 0.0;  // 0: the description's stream fps
  bool loop = false;
};
struct ReplacePipelineEvent {
  std::string xml;
};
struct StillEvent {};
struct KeyframeEvent {};
struct PickEvent {
  double x = 0.0;  // fractions of the view from its top-left corner, 0..1
  double y = 0.0;
};

struct SessionEvent {
  std::uint64_t id = 0;
  Clock::time_point received = Clock::now();
  std::variant<CameraEvent, ResizeEvent, SetStepEvent, PlayEvent, ReplacePipelineEvent, StillEvent,
               KeyframeEvent, PickEvent>
      what;
};

// INVALID_ARGUMENT unless width and height are even and within
// 16x16..maxWidth x maxHeight.
Status checkViewSize(int width, int height, const SessionLimits& limits);

// What can be checked of an event without the session's data or renderer:
// a camera move's finite, bounded deltas, a resize's view size, a play's
// fps (0..240), a replacement's size (kMaxPipelineBytes), a pick's point
// (finite, within the view). INVALID_ARGUMENT
// naming the event; a step is checked against the file by the session.
Status checkEvent(const SessionEvent& event, const SessionLimits& limits);

}  // namespace crackvis::service
