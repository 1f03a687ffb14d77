#include "client_events.hpp"

#include <fmt/format.h>

namespace crackvis::service {
namespace v1 = crackvis::v1;

Result<SessionEvent> toSessionEvent(const v1::ClientEvent& in) {
  SessionEvent out;
  out.id = in.event_id();
  out.received = Clock::now();
  switch (in.event_case()) {
    case v1::ClientEvent::kCamera: {
      const auto& camera = in.camera();
      CameraEvent event{render::CameraMove::kRotate, camera.dx(), camera.dy(), camera.still()};
      switch (camera.kind()) {
        case v1::CameraEvent::ROTATE:
          break;
        case v1::CameraEvent::PAN:
          event.move = render::CameraMove::kPan;
          break;
        case v1::CameraEvent::ZOOM:
          event.move = render::CameraMove::kZoom;
          break;
        case v1::CameraEvent::RESET:
          event.move = render::CameraMove::kReset;
          break;
        default:
          return invalidArgument(fmt::format(
              "camera event {}: kind must be ROTATE, PAN, ZOOM or RESET", in.event_id()));
      }
      out.what = event;
      return out;
    }
    case v1::ClientEvent::kResize:
      out.what = ResizeEvent{in.resize().width(), in.resize().height()};
      return out;
    case v1::ClientEvent::kSetStep:
      out.what = SetStepEvent{in.set_step().step(), in.set_step().follow()};
      return out;
    case v1::ClientEvent::kPlay:
      out.what = PlayEvent{in.play().playing(), in.play().fps(), in.play().loop()};
      return out;
    case v1::ClientEvent::kReplacePipeline:
      out.what = ReplacePipelineEvent{in.replace_pipeline().pipeline_xml()};
      return out;
    case v1::ClientEvent::kStill:
      out.what = StillEvent{};
      return out;
    case v1::ClientEvent::kRequestKeyframe:
      out.what = KeyframeEvent{};
      return out;
    case v1::ClientEvent::kPick:
      out.what = PickEvent{in.pick().x(), in.pick().y()};
      return out;
    case v1::ClientEvent::kAttachSessionId:
      return invalidArgument(
          fmt::format("event {}: a stream attaches once, in its first message", in.event_id()));
    case v1::ClientEvent::EVENT_NOT_SET:
      break;
  }
  return invalidArgument(fmt::format("event {}: no event set", in.event_id()));
}

}  // namespace crackvis::service
