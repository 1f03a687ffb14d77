#include <cmath>

#include <fmt/format.h>

#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/service/session_event.hpp>

namespace crackvis::service {
namespace {

// A camera delta is a fraction of the view; a hundred views in one event is
// no drag, and a non-finite one would poison the camera.
constexpr double kMaxCameraDelta = 100.0;
constexpr double kMaxPlayFps = 240.0;

struct EventCheck {
  const SessionEvent& event;
  const SessionLimits& limits;

  Status operator()(const CameraEvent& camera) const {
    if (!std::isfinite(camera.dx) || !std::isfinite(camera.dy) ||
        std::abs(camera.dx) > kMaxCameraDelta || std::abs(camera.dy) > kMaxCameraDelta) {
      return invalidArgument(
          fmt::format("camera event {}: dx, dy must be finite view fractions", event.id));
    }
    return Status::ok();
  }
  Status operator()(const ResizeEvent& resize) const {
    return checkViewSize(resize.width, resize.height, limits);
  }
  Status operator()(const PlayEvent& play) const {
    if (!std::isfinite(play.fps) || play.fps < 0.0 || play.fps > kMaxPlayFps) {
      return invalidArgument(fmt::format("play fps {} outside 0..240", play.fps));
    }
    return Status::ok();
  }
  Status operator()(const ReplacePipelineEvent& replace) const {
    if (replace.xml.size() > pipeline::kMaxPipelineBytes) {
      return invalidArgument(fmt::format("event {}: the pipeline is over {} bytes", event.id,
                                         pipeline::kMaxPipelineBytes));
    }
    return Status::ok();
  }
  Status operator()(const SetStepEvent&) const { return Status::ok(); }
  Status operator()(const StillEvent&) const { return Status::ok(); }
  Status operator()(const KeyframeEvent&) const { return Status::ok(); }
  Status operator()(const PickEvent& pick) const {
    if (!(pick.x >= 0.0 && pick.x <= 1.0 && pick.y >= 0.0 && pick.y <= 1.0)) {
      return invalidArgument(
          fmt::format("pick event {}: x, y must be fractions of the view (0..1), not {}, {}",
                      event.id, pick.x, pick.y));
    }
    return Status::ok();
  }
};

}  // namespace

Status checkViewSize(int width, int height, const SessionLimits& limits) {
  if (width < 16 || height < 16 || width > limits.maxWidth || height > limits.maxHeight ||
      width % 2 != 0 || height % 2 != 0) {
    return invalidArgument(
        fmt::format("view size {}x{}: width and height must be even and within "
                    "16x16..{}x{}",
                    width, height, limits.maxWidth, limits.maxHeight));
  }
  return Status::ok();
}

Status checkEvent(const SessionEvent& event, const SessionLimits& limits) {
  return std::visit(EventCheck{event, limits}, event.what);
}

}  // namespace crackvis::service
