#include "stream_encoder.hpp"

#include <algorithm>
#include <chrono>
#include <utility>

#include <crackvis/rpc/grpc_status.hpp>

namespace crackvis::service {
namespace {

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

Result<v1::Frame> StreamEncoder::encode(RenderedFrame& frame) {
  // A reduced frame's image is smaller than the stream: the encoder enlarges it.
  if (!m_encoder || m_encoder->settings().width != frame.width ||
      m_encoder->settings().height != frame.height ||
      m_encoder->settings().bitrate != frame.bitrate) {
    auto created = encode::FrameEncoder::create(
        {frame.width, frame.height, std::max(1, frame.fps), frame.bitrate});
    if (!created) {
      return created.status();
    }
    m_encoder = std::move(created).value();
    frame.keyframe = true;
  }
  const auto start = Clock::now();
  encode::RgbFrame rgb{frame.image.width, frame.image.height, std::move(frame.image.rgb)};
  auto encoded = m_encoder->encode(rgb, frame.keyframe);
  if (!encoded) {
    return encoded.status();
  }
  const double encodeMs = secondsSince(start) * 1000.0;
  v1::Frame out;
  out.set_frame_id(frame.frameId);
  out.set_last_event_id(frame.lastEventId);
  out.set_width(frame.width);
  out.set_height(frame.height);
  out.set_keyframe(encoded->keyframe);
  out.set_full_resolution(frame.fullResolution);
  out.set_reduction(frame.reduction);
  out.set_particles(frame.particles);
  out.set_coarse(frame.coarse);
  out.set_step(frame.step);
  out.set_h264(encoded->data.data(), encoded->data.size());
  auto* timings = out.mutable_timings();
  timings->set_open_ms(frame.timings.openMs);
  timings->set_describe_ms(frame.timings.describeMs);
  timings->set_renderer_ms(frame.timings.rendererMs);
  timings->set_load_ms(frame.timings.loadMs);
  timings->set_extract_ms(frame.timings.extractMs);
  timings->set_scene_ms(frame.timings.sceneMs);
  timings->set_render_ms(frame.timings.renderMs);
  timings->set_turn_wait_ms(frame.timings.turnWaitMs);
  timings->set_encode_ms(encodeMs);
  if (frame.lastEventReceived) {
    timings->set_event_to_send_ms(secondsSince(*frame.lastEventReceived) * 1000.0);
  }
  m_window.frames += 1;
  m_window.bytes += encoded->data.size();
  m_window.renderMs += frame.timings.renderMs;
  m_window.encodeMs += encodeMs;
  return out;
}

void StreamEncoder::warmUp(int width, int height) {
  auto created = encode::FrameEncoder::create({width, height, 30, 4'000'000});
  if (!created) {
    return;  // the first stream reports why
  }
  constexpr std::uint8_t kGrey = 128;
  encode::RgbFrame grey{
      width, height,
      std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height * 3, kGrey)};
  (void)(*created)->encode(grey, true);
}

std::optional<v1::StreamStats> StreamEncoder::stats(std::uint64_t dropped) {
  const double seconds = secondsSince(m_windowStart);
  if (seconds < 1.0) {
    return std::nullopt;
  }
  v1::StreamStats out;
  out.set_fps(m_window.frames / seconds);
  out.set_bitrate_bps(8.0 * static_cast<double>(m_window.bytes) / seconds);
  out.set_frames_dropped(dropped);
  if (m_window.frames > 0) {
    out.set_render_ms_mean(m_window.renderMs / m_window.frames);
    out.set_encode_ms_mean(m_window.encodeMs / m_window.frames);
  }
  m_window = {};
  m_windowStart = Clock::now();
  return out;
}

v1::ServerMessage toMessage(const SessionNotice& notice) {
  v1::ServerMessage message;
  if (!notice.error.isOk()) {
    auto* error = message.mutable_error();
    error->set_event_id(notice.eventId);
    error->set_code(static_cast<int>(rpc::toGrpcStatus(notice.error).error_code()));
    error->set_message(notice.error.message());
    return message;
  }
  if (notice.pick) {
    const scene::PickResult& picked = *notice.pick;
    auto* pick = message.mutable_pick();
    pick->set_event_id(notice.eventId);
    pick->set_kind(scene::pickedKindName(picked.kind));
    pick->set_index(picked.index);
    pick->set_x(picked.point.x);
    pick->set_y(picked.point.y);
    pick->set_z(picked.point.z);
    for (const scene::PickedValue& v : picked.values) {
      auto* value = pick->add_values();
      value->set_name(v.name);
      value->set_value(v.value);
      value->set_unit(v.unit);
    }
    pick->set_text(scene::describePick(picked));
    return message;
  }
  if (notice.state) {
    auto* state = message.mutable_state();
    state->set_step(notice.state->step);
    state->set_step_count(notice.state->stepCount);
    state->set_playing(notice.state->playing);
    state->set_width(notice.state->width);
    state->set_height(notice.state->height);
    state->set_pipeline_xml(notice.state->pipelineXml);
    state->set_mapped_fraction(notice.state->mappedFraction);
    state->set_crack_warning(notice.state->crackWarning);
    state->set_live(notice.state->live);
    state->set_following(notice.state->following);
    state->set_run_ended(notice.state->runEnded);
  }
  return message;
}

}  // namespace crackvis::service
