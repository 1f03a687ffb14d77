#include <QElapsedTimer>
#include <QEventLoop>
#include <QFile>
#include <QTimer>

#include <fmt/format.h>

#include <crackvis/client/demo_script.hpp>

namespace crackvis::client {
namespace {

// Runs the event loop until a full-resolution frame reflects `eventId`.
Status awaitFrame(RenderClient& client, quint64 eventId, double seconds, int& shown) {
  QEventLoop loop;
  bool done = false;
  auto connection = QObject::connect(&client, &RenderClient::frameReady, &loop,
                                     [&](const QImage&, const FrameInfo& info) {
                                       ++shown;
                                       if (info.lastEventId >= eventId && info.fullResolution) {
                                         done = true;
                                         loop.quit();
                                       }
                                     });
  QTimer::singleShot(static_cast<int>(seconds * 1000), &loop, &QEventLoop::quit);
  loop.exec();
  QObject::disconnect(connection);
  if (!done) {
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
  CRACKVIS_RETURN_IF_ERROR(client.openSession(QString::fromStdString(pipeline::toXml(view))));
  const int steps = client.stepCount();
  say(QStringLiteral("session open: %1, %2 steps, %3x%4")
          .arg(options.file)
          .arg(steps)
          .arg(view.view.width)
          .arg(view.view.height));
  CRACKVIS_RETURN_IF_ERROR(awaitFrame(client, 0, options.timeoutSeconds, result.framesShown));
  CRACKVIS_RETURN_IF_ERROR(client.startRecording(options.moviePath));

  say(QStringLiteral("rotating the specimen"));
  quint64 last = 0;
  for (int k = 0; k < options.rotateEvents; ++k) {
    last = client.rotate(0.5 / options.rotateEvents, 0.0);
    QEventLoop pause;
    QTimer::singleShot(33, &pause, &QEventLoop::quit);  // a mouse drag's pace
    pause.exec();
  }
  CRACKVIS_RETURN_IF_ERROR(awaitFrame(client, last, options.timeoutSeconds, result.framesShown));

  say(QStringLiteral("stepping through the fracture"));
  for (int step = 0; step < steps; step += std::max(1, options.stepStride)) {
    CRACKVIS_RETURN_IF_ERROR(
        awaitFrame(client, client.setStep(step), options.timeoutSeconds, result.framesShown));
  }
  CRACKVIS_RETURN_IF_ERROR(
      awaitFrame(client, client.setStep(steps - 1), options.timeoutSeconds, result.framesShown));

  view.step = steps - 1;
  for (cracks::Method method : {cracks::Method::kCellAttribute, cracks::Method::kCellCut,
                                cracks::Method::kCellCentre, cracks::Method::kLocalVoronoi}) {
    say(QStringLiteral("crack method: %1").arg(QString::fromUtf8(cracks::toString(method).data())));
    view.cracks.method = method;
    const quint64 event = client.replacePipeline(QString::fromStdString(pipeline::toXml(view)));
    CRACKVIS_RETURN_IF_ERROR(awaitFrame(client, event, options.timeoutSeconds, result.framesShown));
  }

  CRACKVIS_RETURN_IF_ERROR(client.stopRecording());
  result.framesRecorded = client.recordedFrames();
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
