// libFuzzer target: the events a render stream's client sends. The input is
// cut into length-prefixed pieces, each parsed as a crackvis.v1.ClientEvent
// (protobuf's parser on hostile bytes), converted to a SessionEvent
// (toSessionEvent) and checked as the render service checks it before it
// queues it (checkEvent). Every event must be converted and accepted or
// refused with INVALID_ARGUMENT, never crash; and what is accepted must be
// what a renderer can take: finite camera deltas of at most 100 views, an
// even view size within the limits, 0..240 fps, a pipeline within its size.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <variant>

#include <fuzzer/FuzzedDataProvider.h>

#include "client_events.hpp"
#include "fuzz_require.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>

const char* const kFuzzTargetName = "render events fuzzer";

namespace {

using namespace crackvis;
using namespace crackvis::service;

struct AcceptedCheck {
  const SessionLimits& limits;
  void operator()(const CameraEvent& camera) const {
    require(std::isfinite(camera.dx) && std::isfinite(camera.dy) && std::abs(camera.dx) <= 100 &&
                std::abs(camera.dy) <= 100,
            "a camera move the renderer cannot take was accepted");
  }
  void operator()(const ResizeEvent& resize) const {
    require(resize.width >= 16 && resize.height >= 16 && resize.width <= limits.maxWidth &&
                resize.height <= limits.maxHeight && resize.width % 2 == 0 &&
                resize.height % 2 == 0,
            "a view size outside the limits was accepted");
  }
  void operator()(const PlayEvent& play) const {
    require(std::isfinite(play.fps) && play.fps >= 0.0 && play.fps <= 240.0,
            "a play rate outside 0..240 was accepted");
  }
  void operator()(const ReplacePipelineEvent& replace) const {
    require(replace.xml.size() <= pipeline::kMaxPipelineBytes,
            "a pipeline over the size limit was accepted");
  }
  void operator()(const SetStepEvent&) const {}
  void operator()(const StillEvent&) const {}
  void operator()(const KeyframeEvent&) const {}
  void operator()(const PickEvent& pick) const {
    require(pick.x >= 0.0 && pick.x <= 1.0 && pick.y >= 0.0 && pick.y <= 1.0,
            "a pick outside the view was accepted");
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider input(data, size);
  const SessionLimits limits;
  while (input.remaining_bytes() > 0) {
    const std::string bytes =
        input.ConsumeBytesAsString(input.ConsumeIntegralInRange<std::size_t>(0, 512));
    crackvis::v1::ClientEvent event;
    if (!event.ParseFromString(bytes)) {
      continue;  // gRPC refuses what does not parse before a handler sees it
    }
    auto converted = toSessionEvent(event);
    if (!converted) {
      require(converted.status().code() == StatusCode::kInvalidArgument,
              "a refused event is not INVALID_ARGUMENT");
      continue;
    }
    require(converted->id == event.event_id(), "the event id was not kept");
    const Status checked = checkEvent(*converted, limits);
    if (!checked) {
      require(checked.code() == StatusCode::kInvalidArgument,
              "a refused event is not INVALID_ARGUMENT");
      require(checked.message().size() < 1024, "a refusal echoes too much");
      continue;
    }
    std::visit(AcceptedCheck{limits}, converted->what);
  }
  return 0;
}
