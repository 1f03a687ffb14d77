// What a RenderClient keeps of a session: full-resolution snapshots, movies
// re-rendered on the server (recordMovie) and the received stream remuxed
// into an MP4 (startRecording/stopRecording).
#include <QImage>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <utility>

#include <fmt/format.h>

#include "render_client_impl.hpp"
#include <crackvis/record/movie_writer.hpp>

namespace crackvis::client {
namespace {

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

}  // namespace

void RenderClient::Impl::record(const EncodedUnit& unit) {
  if (!recorder) {
    return;
  }
  (void)recorder->add(unit.frame,
                      std::chrono::duration<double>(unit.received - recordingStart).count());
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

}  // namespace crackvis::client
