#include <QElapsedTimer>
#include <QEventLoop>
#include <QFile>
#include <QTimer>

#include <fmt/format.h>

#include <crackvis/client_core/demo_script.hpp>

namespace crackvis::client {
namespace {

// The frames the demo has been shown, watched from the session's opening:
// a frame can arrive while the script pauses between events (its pause
// runs the event loop), before the script starts waiting for it.
class FrameWatch {
 public:
  explicit FrameWatch(RenderClient& client)
      : m_connection(QObject::connect(
            &client, &RenderClient::frameReady, [this](const QImage&, const FrameInfo& info) {
              ++m_shown;
              if (info.fullResolution) {
                m_fullResolution = true;
                m_lastFullEvent = std::max(m_lastFullEvent, info.lastEventId);
              }
            })) {}
  ~FrameWatch() { QObject::disconnect(m_connection); }
  FrameWatch(const FrameWatch&) = delete;
  FrameWatch& operator=(const FrameWatch&) = delete;

  // A full-resolution frame reflecting `eventId` has been shown.
  bool shows(quint64 eventId) const { return m_fullResolution && m_lastFullEvent >= eventId; }
  int shown() const { return m_shown; }

 private:
  QMetaObject::Connection m_connection;
  int m_shown = 0;
  bool m_fullResolution = false;
  quint64 m_lastFullEvent = 0;
};

// Runs the event loop until a full-resolution frame reflects `eventId`
// (at once when one already has).
Status awaitFrame(RenderClient& client, const FrameWatch& watch, quint64 eventId, double seconds) {
  if (watch.shows(eventId)) {
    return Status::ok();
  }
  QEventLoop loop;
  auto connection = QObject::connect(&client, &RenderClient::frameReady, &loop,
                                     [&](const QImage&, const FrameInfo&) {
                                       if (watch.shows(eventId)) {
                                         loop.quit();
                                       }
                                     });
  QTimer::singleShot(static_cast<int>(seconds * 1000), &loop, &QEventLoop::quit);
  loop.exec();
  QObject::disconnect(connection);
  if (!watch.shows(eventId)) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("no frame for event {} within {} s", eventId, seconds));
  }
  return Status::ok();
}

}  // namespace

Result<DemoResult> runDemo(RenderClient& client, const DemoOptions& options,
                           const std::function<void(const QString&)>& say) {
  DemoResult result;
  auto view = options.view;
  view.file = options.file.toStdString();
  view.step = 0;
  const FrameWatch watch(client);
  CRACKVIS_RETURN_IF_ERROR(client.openSession(QString::fromStdString(pipeline::toXml(view))));
  const int steps = client.stepCount();
  say(QStringLiteral("session open: %1, %2 steps, %3x%4")
          .arg(options.file)
          .arg(steps)
          .arg(view.view.width)
          .arg(view.view.height));
  CRACKVIS_RETURN_IF_ERROR(awaitFrame(client, watch, 0, options.timeoutSeconds));
  CRACKVIS_RETURN_IF_ERROR(client.startRecording(options.moviePath));

  say(QStringLiteral("rotating the specimen"));
  quint64 last = 0;
  for (int k = 0; k < options.rotateEvents; ++k) {
    last = client.rotate(0.5 / options.rotateEvents, 0.0);
    QEventLoop pause;
    QTimer::singleShot(33, &pause, &QEventLoop::quit);  // a mouse drag's pace
    pause.exec();
  }
  CRACKVIS_RETURN_IF_ERROR(awaitFrame(client, watch, last, options.timeoutSeconds));

  say(QStringLiteral("stepping through the fracture"));
  for (int step = 0; step < steps; step += std::max(1, options.stepStride)) {
    CRACKVIS_RETURN_IF_ERROR(
        awaitFrame(client, watch, client.setStep(step), options.timeoutSeconds));
  }
  CRACKVIS_RETURN_IF_ERROR(
      awaitFrame(client, watch, client.setStep(steps - 1), options.timeoutSeconds));

  view.step = steps - 1;
  for (cracks::Method method : {cracks::Method::kCellAttribute, cracks::Method::kCellCut,
                                cracks::Method::kCellCentre, cracks::Method::kLocalVoronoi}) {
    say(QStringLiteral("crack method: %1").arg(QString::fromUtf8(cracks::toString(method).data())));
    view.cracks.method = method;
    const quint64 event = client.replacePipeline(QString::fromStdString(pipeline::toXml(view)));
    CRACKVIS_RETURN_IF_ERROR(awaitFrame(client, watch, event, options.timeoutSeconds));
  }

  CRACKVIS_RETURN_IF_ERROR(client.stopRecording());
  result.framesRecorded = client.recordedFrames();
  result.framesShown = watch.shown();
  auto png = client.snapshotPng();
  if (!png) {
    return png.status();
  }
  QFile picture(options.picturePath);
  if (!picture.open(QIODevice::WriteOnly) || picture.write(*png) != png->size()) {
    return failedPrecondition(fmt::format("cannot write {}: {}", options.picturePath.toStdString(),
                                          picture.errorString().toStdString()));
  }
  say(QStringLiteral("wrote %1 (%2 frames) and %3")
          .arg(options.moviePath)
          .arg(result.framesRecorded)
          .arg(options.picturePath));
  client.closeSession();
  return result;
}

}  // namespace crackvis::client
