#include <QMetaObject>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include "crackvis/v1/render.grpc.pb.h"
#include <crackvis/client/render_client.hpp>
#include <crackvis/common/certificates.hpp>
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/record/movie_writer.hpp>
#include <crackvis/record/stream_recorder.hpp>
#include <crackvis/rpc/connection_advice.hpp>
#include <crackvis/rpc/grpc_status.hpp>

namespace crackvis::client {
namespace {

namespace v1 = crackvis::v1;
using Clock = std::chrono::steady_clock;

// A TLS file of the connection, with the defaults' fallback to the
// installed certificates and a message naming the option that sets it.
Result<std::string> readTlsFile(const QString& path, const char* what, const char* flag) {
  return readCertificateFile(path.toStdString(), what,
                             fmt::format("{} or in File > Connect", flag));
}

// crackvis-render as the user named it, for connection_advice's messages;
// this client has no plaintext mode.
rpc::Peer renderPeer(const QString& address) {
  return {rpc::ServerKind::kRender, address.toStdString(), false, "--", false};
}

// A Snapshot's PNG as the movie's next frame; the server must have rendered
// the size asked for (the movie's every frame has one size).
Status rgbFromPng(const QByteArray& png, int width, int height, encode::RgbFrame& frame) {
  const QImage image = QImage::fromData(png, "PNG").convertToFormat(QImage::Format_RGB888);
  if (image.width() != width || image.height() != height) {
    return internalError(fmt::format("the server's snapshot is {}x{}, not the movie's {}x{}",
                                     image.width(), image.height(), width, height));
  }
  frame.width = width;
  frame.height = height;
  frame.rgb.resize(static_cast<std::size_t>(width) * height * 3);
  const auto rowBytes = static_cast<std::size_t>(width) * 3;
  for (int row = 0; row < height; ++row) {
    std::memcpy(frame.rgb.data() + row * rowBytes, image.constScanLine(row), rowBytes);
  }
  return Status::ok();
}

double ms(Clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

struct EncodedUnit {
  encode::EncodedFrame frame;
  FrameInfo info;
  std::uint64_t generation = 0;  // the stream it came from: a new one starts a new decoder
  Clock::time_point received;
};

QImage toImage(const encode::RgbFrame& frame) {
  QImage image(frame.width, frame.height, QImage::Format_RGB888);
  const std::size_t row = static_cast<std::size_t>(frame.width) * 3;
  for (int y = 0; y < frame.height; ++y) {
    std::memcpy(image.scanLine(y), frame.rgb.data() + static_cast<std::size_t>(y) * row, row);
  }
  return image;
}

}  // namespace

struct RenderClient::Impl {
  RenderClient* owner = nullptr;
  ConnectionSettings settings;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::RenderService::Stub> stub;

  // Session state, under `mutex`.
  mutable std::mutex mutex;
  std::string sessionId;
  std::string pipelineXml;
  int stepCount = 0;
  int step = 0;
  bool playing = false;

  // Events for the writer, under `mutex`.
  std::condition_variable eventsChanged;
  std::deque<v1::ClientEvent> events;
  std::uint64_t nextEventId = 1;
  std::map<std::uint64_t, Clock::time_point> sentAt;

  // The stream currently attached, under `mutex`.
  grpc::ClientContext* streamContext = nullptr;
  std::uint64_t streamGeneration = 0;  // counts attached streams

  // Frames for the decoder, under `mutex`.
  std::condition_variable unitsChanged;
  std::deque<EncodedUnit> units;

  // The newest decoded frame for the GUI thread (older ones are dropped).
  std::mutex deliveryMutex;
  std::optional<std::pair<QImage, FrameInfo>> latest;
  bool deliveryPending = false;

  // Statistics, under `mutex`.
  std::deque<Clock::time_point> frameTimes;
  std::deque<std::pair<Clock::time_point, std::size_t>> byteTimes;
  std::deque<double> latencies;
  quint64 framesDecoded = 0;
  quint64 reconnects = 0;

  std::unique_ptr<record::StreamRecorder> recorder;  // under `mutex`
  Clock::time_point recordingStart;
  qint64 recordedFrames = 0;
  int frameWidth = 0;  // of the stream's pictures, under `mutex`
  int frameHeight = 0;

  std::atomic<bool> stopping{false};
  std::thread supervisor;
  std::thread decoder;

  Status failure(const grpc::Status& status, const char* call) const {
    return rpc::fromGrpcStatus(status, call, renderPeer(settings.address), channel);
  }

  // One unary call of the connection's file calls: authorized, its failure
  // worded by connection_advice. `call(context, response)` makes the call.
  template <typename Response, typename Call>
  Status unary(const char* name, Response& response, Call&& call) {
    if (!stub) {
      return failedPrecondition("not connected");
    }
    grpc::ClientContext context;
    authorize(context);
    return failure(call(context, response), name);
  }

  void authorize(grpc::ClientContext& context) const {
    if (!settings.token.isEmpty()) {
      context.AddMetadata("authorization", "Bearer " + settings.token.toStdString());
    }
  }

  std::uint64_t queue(v1::ClientEvent event) {
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

  Status openOnServer(const std::string& xml) {
    grpc::ClientContext context;
    authorize(context);
    v1::OpenSessionRequest request;
    request.set_pipeline_xml(xml);
    v1::OpenSessionResponse response;
    CRACKVIS_RETURN_IF_ERROR(
        failure(stub->OpenSession(&context, request, &response), "OpenSession"));
    std::lock_guard lock(mutex);
    sessionId = response.session_id();
    pipelineXml = xml;
    stepCount = response.step_count();
    return Status::ok();
  }

  // One attached stream: writes the attach message, runs the writer thread,
  // reads until the stream ends; returns how it ended.
  grpc::Status runStream(bool askKeyframe) {
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

  void writeLoop(grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>& stream,
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

  void handle(const v1::ServerMessage& message, std::uint64_t generation) {
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
           f = state.mapped_fraction(), w = QString::fromStdString(state.crack_warning())] {
            emit o->stateChanged(s, n, p);
            emit o->crackMappingChanged(f, w);
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

  // Under `mutex`: the received access unit into the MP4, if recording.
  void record(const EncodedUnit& unit) {
    if (!recorder) {
      return;
    }
    (void)recorder->add(unit.frame,
                        std::chrono::duration<double>(unit.received - recordingStart).count());
  }

  // Re-attaches (or re-opens) until it works or the client stops.
  void supervise() {
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

  void decodeLoop() {
    std::unique_ptr<encode::FrameDecoder> frameDecoder;
    std::uint64_t decoderGeneration = 0;
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
      if (frameDecoder) {
        auto decoded = frameDecoder->decode(unit.frame);
        if (decoded && decoded->has_value()) {
          image = toImage(**decoded);
        }
      }
      lock.lock();
      if (image) {
        const auto now = Clock::now();
        ++framesDecoded;
        frameTimes.push_back(now);
        for (auto it = sentAt.begin(); it != sentAt.end() && it->first <= unit.info.lastEventId;) {
          const double latency = ms(now - it->second);
          latencies.push_back(latency);
          unit.info.latencyMs = latency;
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

  // Hands the newest frame to the GUI thread; frames it has not taken yet
  // are replaced (a slow GUI never falls behind the stream).
  void deliver(QImage image, const FrameInfo& info) {
    bool post = false;
    {
      std::lock_guard lock(deliveryMutex);
      latest = std::make_pair(std::move(image), info);
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

  void stopSession() {
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
};

RenderClient::RenderClient(QObject* parent) : QObject(parent), m_impl(std::make_unique<Impl>()) {
  qRegisterMetaType<crackvis::client::FrameInfo>();
  m_impl->owner = this;
}

RenderClient::~RenderClient() {
  closeSession();
}

Status RenderClient::connectTo(const ConnectionSettings& settings) {
  closeSession();
  CRACKVIS_RETURN_IF_ERROR(rpc::checkHostPort("address", settings.address.toStdString()));
  auto ca = readTlsFile(settings.caPath, "CA certificate", "--ca");
  auto cert = readTlsFile(settings.certPath, "client certificate", "--cert");
  auto key = readTlsFile(settings.keyPath, "client key", "--key");
  for (const auto* file : {&ca, &cert, &key}) {
    if (!*file) {
      return file->status();
    }
  }
  grpc::SslCredentialsOptions ssl{*ca, *key, *cert};
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(64 << 20);
  arguments.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
  arguments.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  auto channel = grpc::CreateCustomChannel(settings.address.toStdString(),
                                           grpc::SslCredentials(ssl), arguments);
  auto stub = v1::RenderService::NewStub(channel);
  // One round trip that needs the server and our certificate: ListFiles.
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  if (!settings.token.isEmpty()) {
    context.AddMetadata("authorization", "Bearer " + settings.token.toStdString());
  }
  v1::ListFilesResponse files;
  CRACKVIS_RETURN_IF_ERROR(
      rpc::fromGrpcStatus(stub->ListFiles(&context, v1::ListFilesRequest(), &files),
                          fmt::format("connecting to {}", settings.address.toStdString()),
                          renderPeer(settings.address), channel));
  m_impl->settings = settings;
  m_impl->channel = std::move(channel);
  m_impl->stub = std::move(stub);
  return Status::ok();
}

bool RenderClient::connected() const {
  return m_impl->stub != nullptr;
}
const ConnectionSettings& RenderClient::settings() const {
  return m_impl->settings;
}

Result<std::vector<FileEntry>> RenderClient::listFiles() {
  v1::ListFilesRequest request;
  request.set_recursive(true);
  v1::ListFilesResponse response;
  CRACKVIS_RETURN_IF_ERROR(
      m_impl->unary("ListFiles", response, [&](grpc::ClientContext& context, auto& out) {
        return m_impl->stub->ListFiles(&context, request, &out);
      }));
  std::vector<FileEntry> out;
  for (const auto& file : response.files()) {
    out.push_back({QString::fromStdString(file.path()), static_cast<qint64>(file.size_bytes()),
                   file.is_hdf5()});
  }
  return out;
}

Result<StepHistory> RenderClient::stepHistory(const QString& file) {
  v1::StepHistoryRequest request;
  request.set_file(file.toStdString());
  v1::StepHistoryResponse response;
  CRACKVIS_RETURN_IF_ERROR(
      m_impl->unary("StepHistory", response, [&](grpc::ClientContext& context, auto& out) {
        return m_impl->stub->StepHistory(&context, request, &out);
      }));
  StepHistory history;
  history.time.assign(response.time().begin(), response.time().end());
  history.brokenBonds.assign(response.broken_bonds().begin(), response.broken_bonds().end());
  history.bondCount = response.bond_count();
  for (const v1::StepSeries& series : response.scalars()) {
    history.scalarNames << QString::fromStdString(series.name());
    history.scalars.emplace_back(series.values().begin(), series.values().end());
  }
  return history;
}

Result<FileSummary> RenderClient::describe(const QString& file) {
  v1::DescribeRequest request;
  request.set_file(file.toStdString());
  v1::DescribeResponse response;
  CRACKVIS_RETURN_IF_ERROR(
      m_impl->unary("Describe", response, [&](grpc::ClientContext& context, auto& out) {
        return m_impl->stub->Describe(&context, request, &out);
      }));
  FileSummary summary;
  summary.file = file;
  summary.format = QString::fromStdString(response.format());
  summary.sizeBytes = static_cast<qint64>(response.size_bytes());
  summary.steps = response.steps_size();
  if (summary.steps > 0) {
    summary.firstTime = response.steps(0).time();
    summary.lastTime = response.steps(summary.steps - 1).time();
  }
  for (const auto& dataset : response.datasets()) {
    QStringList shape;
    for (auto extent : dataset.shape()) {
      shape << QString::number(extent);
    }
    if (dataset.path() == "/particles/radius" && dataset.shape_size() == 1) {
      summary.particles = static_cast<qint64>(dataset.shape(0));
    }
    if (dataset.path() == "/bonds/pairs" && dataset.shape_size() >= 1) {
      summary.bonds = static_cast<qint64>(dataset.shape(0));
    }
    for (const auto& [folder, names] :
         {std::pair{"/extra/particles/", &summary.particleExtras},
          std::pair{"/steps/000000/extra/particles/", &summary.particleExtras},
          std::pair{"/extra/bonds/", &summary.bondExtras},
          std::pair{"/steps/000000/extra/bonds/", &summary.bondExtras}}) {
      const std::string_view path = dataset.path();
      if (path.rfind(folder, 0) == 0) {
        const QString name = QString::fromStdString(std::string(path.substr(std::strlen(folder))));
        if (!names->contains(name)) {
          *names << name;
        }
      }
    }
    // Per-step arrays repeat in every step: list the first step's only.
    const bool laterStep =
        dataset.path().rfind("/steps/", 0) == 0 && dataset.path().rfind("/steps/000000/", 0) != 0;
    if (!laterStep) {
      summary.arrays << QStringLiteral("%1 %2 [%3]")
                            .arg(QString::fromStdString(dataset.path()),
                                 QString::fromStdString(dataset.dtype_name()), shape.join(", "));
    }
  }
  return summary;
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
v1::ClientEvent cameraEvent(v1::CameraEvent::Kind kind, double dx, double dy) {
  v1::ClientEvent event;
  event.mutable_camera()->set_kind(kind);
  event.mutable_camera()->set_dx(dx);
  event.mutable_camera()->set_dy(dy);
  return event;
}
}  // namespace

quint64 RenderClient::rotate(double dx, double dy) {
  return m_impl->queue(cameraEvent(v1::CameraEvent::ROTATE, dx, dy));
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

Result<QByteArray> RenderClient::snapshotPng(int width, int height, std::optional<int> step) {
  std::string id;
  {
    std::lock_guard lock(m_impl->mutex);
    id = m_impl->sessionId;
  }
  if (id.empty()) {
    return failedPrecondition("no session");
  }
  grpc::ClientContext context;
  m_impl->authorize(context);
  v1::SnapshotRequest request;
  request.set_session_id(id);
  request.set_width(width);
  request.set_height(height);
  if (step) {
    request.set_step(*step);
  }
  v1::SnapshotResponse response;
  CRACKVIS_RETURN_IF_ERROR(
      m_impl->failure(m_impl->stub->Snapshot(&context, request, &response), "Snapshot"));
  return QByteArray::fromStdString(response.png());
}

Status RenderClient::recordMovie(const QString& path, const std::vector<int>& steps, int width,
                                 int height, int fps,
                                 const std::function<bool(int, int)>& progress) {
  if (!hasSession()) {
    return failedPrecondition("no session to record");
  }
  if (steps.empty()) {
    return invalidArgument("a movie needs at least one step");
  }
  auto movie = record::MovieWriter::start(path.toStdString(), {width, height, fps, 0});
  if (!movie) {
    return movie.status();
  }
  encode::RgbFrame frame;
  const auto total = static_cast<int>(steps.size());
  for (int k = 0; k < total; ++k) {
    auto png = snapshotPng(width, height, steps[static_cast<std::size_t>(k)]);
    Status status = png.status();
    if (status) {
      status = rgbFromPng(*png, width, height, frame);
    }
    if (status) {
      status = (*movie)->add(frame);
    }
    if (status && progress && !progress(k + 1, total)) {
      status = cancelled(fmt::format("recording {} cancelled", path.toStdString()));
    }
    if (!status) {
      movie->reset();
      std::filesystem::remove(path.toStdString());
      return status;
    }
  }
  return (*movie)->finish();
}

QSize RenderClient::frameSize() const {
  std::lock_guard lock(m_impl->mutex);
  return {m_impl->frameWidth, m_impl->frameHeight};
}

Status RenderClient::startRecording(const QString& path) {
  int width = 0;
  int height = 0;
  {
    std::lock_guard lock(m_impl->mutex);
    if (m_impl->sessionId.empty()) {
      return failedPrecondition("no session to record");
    }
    if (m_impl->recorder) {
      return failedPrecondition("already recording");
    }
    width = m_impl->frameWidth;
    height = m_impl->frameHeight;
  }
  if (width == 0) {
    return failedPrecondition("no frame received yet: the recording takes the stream's size");
  }
  // The recording starts at the next keyframe, asked for here.
  auto recorder = record::StreamRecorder::start(path.toStdString(), width, height, 30);
  if (!recorder) {
    return recorder.status();
  }
  {
    std::lock_guard lock(m_impl->mutex);
    m_impl->recorder = std::move(recorder).value();
    m_impl->recordingStart = Clock::now();
  }
  v1::ClientEvent keyframe;
  keyframe.set_request_keyframe(true);
  m_impl->queue(keyframe);
  return Status::ok();
}

Status RenderClient::stopRecording() {
  std::unique_ptr<record::StreamRecorder> recorder;
  {
    std::lock_guard lock(m_impl->mutex);
    recorder = std::move(m_impl->recorder);
  }
  if (!recorder) {
    return Status::ok();
  }
  Status finished = recorder->finish();
  std::lock_guard lock(m_impl->mutex);
  m_impl->recordedFrames = recorder->framesWritten();
  return finished;
}

qint64 RenderClient::recordedFrames() const {
  std::lock_guard lock(m_impl->mutex);
  return m_impl->recordedFrames;
}

bool RenderClient::recording() const {
  std::lock_guard lock(m_impl->mutex);
  return m_impl->recorder != nullptr;
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
