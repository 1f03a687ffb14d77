// A RenderClient's session and its stream: opening and closing the session,
// the events queued for the writer thread, the reader that takes the
// server's messages, the decoder thread that turns access units into
// QImages for the GUI thread, reconnection with backoff, and the stream's
// statistics.
#include <QMetaObject>
#include <algorithm>
#include <chrono>
#include <cstring>
#include <thread>
#include <utility>
#include <vector>

#include "render_client_impl.hpp"

namespace crackvis::client {
namespace {

double ms(Clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

QImage toImage(const encode::RgbFrame& frame) {
  QImage image(frame.width, frame.height, QImage::Format_RGB888);
  const std::size_t row = static_cast<std::size_t>(frame.width) * 3;
  for (int y = 0; y < frame.height; ++y) {
    std::memcpy(image.scanLine(y), frame.rgb.data() + static_cast<std::size_t>(y) * row, row);
  }
  return image;
}

}  // namespace

std::uint64_t RenderClient::Impl::queue(v1::ClientEvent event) {
  std::uint64_t id = 0;
  {
    std::lock_guard lock(mutex);
    if (sessionId.empty()) {
      return 0;
    }
    id = nextEventId++;
    event.set_event_id(id);
    sentAt[id] = Clock::now();
    events.push_back(std::move(event));
  }
  eventsChanged.notify_all();
  return id;
}

Status RenderClient::Impl::openOnServer(const std::string& xml) {
  awaitConnection();
  grpc::ClientContext context;
  authorize(context);
  v1::OpenSessionRequest request;
  request.set_pipeline_xml(xml);
  v1::OpenSessionResponse response;
  CRACKVIS_RETURN_IF_ERROR(failure(stub->OpenSession(&context, request, &response), "OpenSession"));
  std::lock_guard lock(mutex);
  sessionId = response.session_id();
  pipelineXml = xml;
  stepCount = response.step_count();
  return Status::ok();
}

grpc::Status RenderClient::Impl::runStream(bool askKeyframe) {
  grpc::ClientContext context;
  authorize(context);
  auto stream = stub->Stream(&context);
  std::uint64_t generation = 0;
  {
    std::lock_guard lock(mutex);
    streamContext = &context;
    generation = ++streamGeneration;
    v1::ClientEvent attach;
    attach.set_attach_session_id(sessionId);
    if (!stream->Write(attach)) {
      streamContext = nullptr;
      return stream->Finish();
    }
    if (askKeyframe) {
      v1::ClientEvent keyframe;
      keyframe.set_event_id(nextEventId++);
      keyframe.set_request_keyframe(true);
      events.push_front(keyframe);
    }
  }
  std::atomic<bool> ended{false};
  std::thread writer([&] { writeLoop(*stream, ended); });
  v1::ServerMessage message;
  bool first = true;
  while (stream->Read(&message)) {
    if (first) {
      first = false;
      if (askKeyframe) {
        QMetaObject::invokeMethod(
            owner, [o = owner] { emit o->reconnected(); }, Qt::QueuedConnection);
      }
    }
    handle(message, generation);
  }
  {
    std::lock_guard lock(mutex);
    ended = true;
    streamContext = nullptr;
  }
  eventsChanged.notify_all();
  writer.join();
  return stream->Finish();
}

void RenderClient::Impl::writeLoop(
    grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>& stream,
    std::atomic<bool>& ended) {
  std::unique_lock lock(mutex);
  while (true) {
    eventsChanged.wait(lock, [&] { return ended || stopping || !events.empty(); });
    if (ended || stopping) {
      return;
    }
    v1::ClientEvent event = std::move(events.front());
    events.pop_front();
    lock.unlock();
    const bool written = stream.Write(event);
    lock.lock();
    if (!written) {
      return;  // the reader sees the stream end
    }
  }
}

void RenderClient::Impl::handle(const v1::ServerMessage& message, std::uint64_t generation) {
  if (message.has_frame()) {
    const v1::Frame& frame = message.frame();
    EncodedUnit unit;
    unit.frame.data.assign(frame.h264().begin(), frame.h264().end());
    unit.frame.keyframe = frame.keyframe();
    unit.frame.index = static_cast<std::int64_t>(frame.frame_id());
    unit.info.frameId = frame.frame_id();
    unit.info.lastEventId = frame.last_event_id();
    unit.info.step = frame.step();
    unit.info.keyframe = frame.keyframe();
    unit.info.fullResolution = frame.full_resolution();
    unit.info.reduction = frame.reduction();
    unit.info.renderMs = frame.timings().render_ms();
    unit.info.encodeMs = frame.timings().encode_ms();
    unit.info.serverEventToSendMs = frame.timings().event_to_send_ms();
    unit.generation = generation;
    unit.received = Clock::now();
    {
      std::lock_guard lock(mutex);
      byteTimes.emplace_back(unit.received, frame.h264().size());
      frameWidth = frame.width();
      frameHeight = frame.height();
      record(unit);
      step = frame.step();
      units.push_back(std::move(unit));
    }
    unitsChanged.notify_all();
  } else if (message.has_state()) {
    const auto& state = message.state();
    {
      std::lock_guard lock(mutex);
      step = state.step();
      stepCount = state.step_count();
      playing = state.playing();
      pipelineXml = state.pipeline_xml();
    }
    QMetaObject::invokeMethod(
        owner,
        [o = owner, s = state.step(), n = state.step_count(), p = state.playing(),
         f = state.mapped_fraction(), w = QString::fromStdString(state.crack_warning()),
         live = state.live(), following = state.following(), ended = state.run_ended()] {
          emit o->stateChanged(s, n, p);
          emit o->crackMappingChanged(f, w);
          emit o->liveChanged(live, following, ended);
        },
        Qt::QueuedConnection);
  } else if (message.has_pick()) {
    const auto& pick = message.pick();
    QMetaObject::invokeMethod(
        owner,
        [o = owner, id = pick.event_id(), text = QString::fromStdString(pick.text()),
         kind = QString::fromStdString(pick.kind()),
         index = pick.index()] { emit o->picked(id, text, kind, index); },
        Qt::QueuedConnection);
  } else if (message.has_error()) {
    QMetaObject::invokeMethod(
        owner,
        [o = owner, id = message.error().event_id(),
         text = QString::fromStdString(message.error().message())] {
          emit o->eventFailed(id, text);
        },
        Qt::QueuedConnection);
  }
}

void RenderClient::Impl::supervise() {
  bool reattach = false;
  auto backoff = std::chrono::milliseconds(100);
  while (!stopping) {
    const grpc::Status ended = runStream(reattach);
    if (stopping) {
      return;
    }
    if (ended.error_code() == grpc::StatusCode::NOT_FOUND) {
      // The server lost the session (a restart): open it again as it was.
      std::string xml;
      int lastStep = 0;
      {
        std::lock_guard lock(mutex);
        xml = pipelineXml;
        lastStep = step;
      }
      if (Status opened = openOnServer(xml); opened) {
        v1::ClientEvent restore;
        restore.mutable_set_step()->set_step(lastStep);
        queue(restore);
        backoff = std::chrono::milliseconds(100);
      }
    }
    {
      std::lock_guard lock(mutex);
      ++reconnects;
    }
    QMetaObject::invokeMethod(
        owner,
        [o = owner, why = QString::fromStdString(failure(ended, "Stream").message())] {
          emit o->connectionLost(why);
        },
        Qt::QueuedConnection);
    reattach = true;
    const auto until = Clock::now() + backoff;
    while (!stopping && Clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    backoff = std::min(backoff * 2, std::chrono::milliseconds(3000));
  }
}

void RenderClient::Impl::decodeLoop() {
  std::unique_ptr<encode::FrameDecoder> frameDecoder;
  std::uint64_t decoderGeneration = 0;
  encode::RgbFrame picture;  // decoded into again: its memory stays faulted in
  std::unique_lock lock(mutex);
  while (true) {
    unitsChanged.wait(lock, [&] { return stopping || !units.empty(); });
    if (stopping) {
      return;
    }
    EncodedUnit unit = std::move(units.front());
    units.pop_front();
    lock.unlock();
    if (!frameDecoder || unit.generation != decoderGeneration) {
      auto created = encode::FrameDecoder::create();
      frameDecoder = created ? std::move(created).value() : nullptr;
      decoderGeneration = unit.generation;
    }
    std::optional<QImage> image;
    const auto decodeStart = Clock::now();
    if (frameDecoder) {
      auto decoded = frameDecoder->decodeInto(unit.frame, picture);
      if (decoded && *decoded) {
        image = toImage(picture);
      }
    }
    lock.lock();
    if (image) {
      const auto now = Clock::now();
      unit.info.decodeMs = ms(now - decodeStart);
      ++framesDecoded;
      frameTimes.push_back(now);
      for (auto it = sentAt.begin(); it != sentAt.end() && it->first <= unit.info.lastEventId;) {
        const double latency = ms(now - it->second);
        latencies.push_back(latency);
        unit.info.latencyMs = latency;
        unit.info.eventsSentAt.push_back(it->second);
        it = sentAt.erase(it);
      }
      while (latencies.size() > 30) {
        latencies.pop_front();
      }
      lock.unlock();
      deliver(std::move(*image), unit.info);
      lock.lock();
    }
  }
}

void RenderClient::Impl::deliver(QImage image, const FrameInfo& info) {
  bool post = false;
  {
    std::lock_guard lock(deliveryMutex);
    // A frame the GUI thread has not taken yet is replaced, and the events
    // it reflected first are reflected first by this one.
    std::vector<Clock::time_point> sent;
    if (latest) {
      sent = std::move(latest->second.eventsSentAt);
    }
    latest = std::make_pair(std::move(image), info);
    auto& reflected = latest->second.eventsSentAt;
    reflected.insert(reflected.begin(), sent.begin(), sent.end());
    post = !deliveryPending;
    deliveryPending = true;
  }
  if (post) {
    QMetaObject::invokeMethod(
        owner,
        [this] {
          std::optional<std::pair<QImage, FrameInfo>> frame;
          {
            std::lock_guard lock(deliveryMutex);
            frame = std::move(latest);
            latest.reset();
            deliveryPending = false;
          }
          if (frame) {
            emit owner->frameReady(frame->first, frame->second);
          }
        },
        Qt::QueuedConnection);
  }
}

void RenderClient::Impl::stopSession() {
  {
    std::lock_guard lock(mutex);
    stopping = true;
    if (streamContext != nullptr) {
      streamContext->TryCancel();
    }
  }
  eventsChanged.notify_all();
  unitsChanged.notify_all();
  if (supervisor.joinable()) {
    supervisor.join();
  }
  if (decoder.joinable()) {
    decoder.join();
  }
  std::lock_guard lock(mutex);
  units.clear();
  events.clear();
  sentAt.clear();
  stopping = false;
}

Status RenderClient::openSession(const QString& pipelineXml) {
  if (!connected()) {
    return failedPrecondition("not connected");
  }
  closeSession();
  CRACKVIS_RETURN_IF_ERROR(m_impl->openOnServer(pipelineXml.toStdString()));
  m_impl->decoder = std::thread([impl = m_impl.get()] { impl->decodeLoop(); });
  m_impl->supervisor = std::thread([impl = m_impl.get()] { impl->supervise(); });
  return Status::ok();
}

void RenderClient::closeSession() {
  std::string id;
  {
    std::lock_guard lock(m_impl->mutex);
    id = m_impl->sessionId;
  }
  if (id.empty()) {
    return;
  }
  (void)stopRecording();
  m_impl->stopSession();
  grpc::ClientContext context;
  m_impl->authorize(context);
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  v1::CloseSessionRequest request;
  request.set_session_id(id);
  v1::CloseSessionResponse response;
  (void)m_impl->stub->CloseSession(&context, request, &response);
  std::lock_guard lock(m_impl->mutex);
  m_impl->sessionId.clear();
}

bool RenderClient::hasSession() const {
  std::lock_guard lock(m_impl->mutex);
  return !m_impl->sessionId.empty();
}
int RenderClient::stepCount() const {
  std::lock_guard lock(m_impl->mutex);
  return m_impl->stepCount;
}
int RenderClient::step() const {
  std::lock_guard lock(m_impl->mutex);
  return m_impl->step;
}
bool RenderClient::playing() const {
  std::lock_guard lock(m_impl->mutex);
  return m_impl->playing;
}
QString RenderClient::pipelineXml() const {
  std::lock_guard lock(m_impl->mutex);
  return QString::fromStdString(m_impl->pipelineXml);
}

namespace {
v1::ClientEvent cameraEvent(v1::CameraEvent::Kind kind, double dx, double dy, bool still = false) {
  v1::ClientEvent event;
  event.mutable_camera()->set_kind(kind);
  event.mutable_camera()->set_dx(dx);
  event.mutable_camera()->set_dy(dy);
  event.mutable_camera()->set_still(still);
  return event;
}
}  // namespace

quint64 RenderClient::rotate(double dx, double dy, bool still) {
  return m_impl->queue(cameraEvent(v1::CameraEvent::ROTATE, dx, dy, still));
}
quint64 RenderClient::pan(double dx, double dy) {
  return m_impl->queue(cameraEvent(v1::CameraEvent::PAN, dx, dy));
}
quint64 RenderClient::zoom(double amount) {
  return m_impl->queue(cameraEvent(v1::CameraEvent::ZOOM, amount, 0.0));
}
quint64 RenderClient::resetCamera() {
  return m_impl->queue(cameraEvent(v1::CameraEvent::RESET, 0.0, 0.0));
}
quint64 RenderClient::setStep(int step) {
  v1::ClientEvent event;
  event.mutable_set_step()->set_step(step);
  return m_impl->queue(event);
}
quint64 RenderClient::follow() {
  v1::ClientEvent event;
  event.mutable_set_step()->set_follow(true);
  return m_impl->queue(event);
}
quint64 RenderClient::play(bool playing, double fps) {
  v1::ClientEvent event;
  event.mutable_play()->set_playing(playing);
  event.mutable_play()->set_fps(fps);
  event.mutable_play()->set_loop(true);
  return m_impl->queue(event);
}
quint64 RenderClient::resize(int width, int height) {
  v1::ClientEvent event;
  event.mutable_resize()->set_width(width & ~1);
  event.mutable_resize()->set_height(height & ~1);
  return m_impl->queue(event);
}
quint64 RenderClient::replacePipeline(const QString& xml) {
  v1::ClientEvent event;
  event.mutable_replace_pipeline()->set_pipeline_xml(xml.toStdString());
  return m_impl->queue(event);
}
quint64 RenderClient::requestStill() {
  v1::ClientEvent event;
  event.mutable_still();
  return m_impl->queue(event);
}

quint64 RenderClient::pick(double x, double y) {
  v1::ClientEvent event;
  event.mutable_pick()->set_x(x);
  event.mutable_pick()->set_y(y);
  return m_impl->queue(event);
}

QSize RenderClient::frameSize() const {
  std::lock_guard lock(m_impl->mutex);
  return {m_impl->frameWidth, m_impl->frameHeight};
}

StreamStatistics RenderClient::statistics() const {
  std::lock_guard lock(m_impl->mutex);
  const auto now = Clock::now();
  const auto second = std::chrono::seconds(1);
  while (!m_impl->frameTimes.empty() && now - m_impl->frameTimes.front() > second) {
    m_impl->frameTimes.pop_front();
  }
  while (!m_impl->byteTimes.empty() && now - m_impl->byteTimes.front().first > second) {
    m_impl->byteTimes.pop_front();
  }
  StreamStatistics out;
  out.fps = static_cast<double>(m_impl->frameTimes.size());
  double bytes = 0;
  for (const auto& [when, size] : m_impl->byteTimes) {
    bytes += static_cast<double>(size);
  }
  out.bitrateBps = 8.0 * bytes;
  std::vector<double> latencies(m_impl->latencies.begin(), m_impl->latencies.end());
  if (!latencies.empty()) {
    std::nth_element(latencies.begin(), latencies.begin() + latencies.size() / 2, latencies.end());
    out.latencyMs = latencies[latencies.size() / 2];
  }
  out.framesDecoded = m_impl->framesDecoded;
  out.reconnects = m_impl->reconnects;
  return out;
}

}  // namespace crackvis::client
