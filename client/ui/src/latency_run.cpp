#include <QCoreApplication>
#include <QFile>
#include <QGuiApplication>
#include <QJsonArray>
#include <QJsonDocument>
#include <QMouseEvent>
#include <algorithm>
#include <cmath>
#include <ctime>
#include <numbers>

#include <crackvis/client_ui/latency_run.hpp>
#include <crackvis/client_ui/main_window.hpp>

namespace crackvis::client {
namespace {

// Overall bound, beyond the drag and the still moves: a run that has not
// ended by then reports why.
constexpr int kRunSlackMs = 60'000;
constexpr int kPerStillMs = 3'000;
// The drag's frames are counted until the frame answering its release is
// painted (at least kAfterDragMs, at most this).
constexpr int kMostAfterDragMs = 10'000;
// As browser_latency.mjs: a second's rest before the drag, half a second
// after it (its last frames), half a second before the still moves, and
// 200 ms after each still move's frame.
constexpr int kSettleMs = 1000;
constexpr int kAfterDragMs = 500;
constexpr int kBeforeStillsMs = 500;
constexpr int kBetweenStillsMs = 200;
constexpr double kStillRotate = 0.05;

// The browser benchmark's percentile: the value at floor(p * n) of the
// sorted values, so that the two clients' figures are taken alike.
QJsonValue percentile(std::vector<double> values, double p) {
  if (values.empty()) {
    return QJsonValue::Null;
  }
  std::sort(values.begin(), values.end());
  const auto at =
      static_cast<std::size_t>(std::floor(p / 100.0 * static_cast<double>(values.size())));
  return values[std::min(values.size() - 1, at)];
}

QJsonObject summary(const std::vector<double>& values) {
  return {{"n", static_cast<qint64>(values.size())},
          {"p50", percentile(values, 50)},
          {"p95", percentile(values, 95)}};
}

void sendMouse(QWidget& target, QEvent::Type type, QPointF at, Qt::MouseButton button,
               Qt::MouseButtons held) {
  QMouseEvent event(type, at, target.mapToGlobal(at), button, held, Qt::NoModifier);
  QCoreApplication::sendEvent(&target, &event);
}

}  // namespace

LatencyRun::LatencyRun(MainWindow& window, LatencyRunOptions options)
    : QObject(&window), m_window(window), m_options(std::move(options)) {
  const int bound =
      kRunSlackMs + static_cast<int>(1000.0 * m_options.seconds) + kPerStillMs * m_options.stills;
  m_timeout.setSingleShot(true);
  m_timeout.setInterval(bound);
  connect(&m_timeout, &QTimer::timeout, this, [this, bound] {
    fail(QStringLiteral("the latency run did not end within %1 s").arg(bound / 1000));
  });
  connect(&m_window.viewport(), &Viewport::painted, this, &LatencyRun::framePainted);
}

void LatencyRun::start() {
  m_clock.start();
  m_timeout.start();
  sizeView();
}

// The window grows or shrinks by what the view lacks or has over WxH; the
// viewport sends the resize to the server once it stops changing.
void LatencyRun::sizeView() {
  const QSize have = m_window.viewport().size();
  if (have != m_options.view) {
    m_window.resize(m_window.size() + (m_options.view - have));
  }
}

void LatencyRun::framePainted(const std::vector<double>& latencies, const FrameInfo& info) {
  switch (m_phase) {
    case Phase::kFirstFrame: {
      if (m_firstFrameMs < 0.0) {
        m_firstFrameMs = static_cast<double>(m_clock.nsecsElapsed()) / 1e6;
      }
      // Not from inside the viewport's paint: after it.
      QTimer::singleShot(0, this, [this] {
        if (m_phase == Phase::kFirstFrame) {
          sizeView();
        }
      });
      const Viewport& view = m_window.viewport();
      if (info.fullResolution && view.size() == m_options.view &&
          view.image().size() == m_options.view) {
        m_phase = Phase::kSettle;
        QTimer::singleShot(kSettleMs, this, &LatencyRun::startDrag);
      }
      break;
    }
    case Phase::kDrag:
    case Phase::kAfterDrag: {
      ++m_dragFrames;
      m_dragLatencies.insert(m_dragLatencies.end(), latencies.begin(), latencies.end());
      m_decodeMs.push_back(info.decodeMs);
      // The server's part while dragging, as the page counts it.
      if (m_phase == Phase::kDrag && info.serverEventToSendMs > 0.0) {
        m_serverMs.push_back(info.serverEventToSendMs);
      }
      const QString reduction = QString::number(info.reduction);
      m_reductions[reduction] = m_reductions.value(reduction).toInt() + 1;
      if (m_phase == Phase::kAfterDrag && info.lastEventId >= m_releaseEvent) {
        m_releasePainted = true;
        closeDrag();
      }
      break;
    }
    case Phase::kStills:
      // The still move's own frame: the newest event it reflects is the move.
      if (m_stillEvent != 0 && info.lastEventId >= m_stillEvent && !latencies.empty()) {
        m_stillEvent = 0;
        m_stillLatencies.push_back(latencies.back());
        QTimer::singleShot(kBetweenStillsMs, this, &LatencyRun::nextStill);
      }
      break;
    case Phase::kSettle:
    case Phase::kDone:
      break;
  }
}

void LatencyRun::startDrag() {
  if (m_phase == Phase::kDone) {
    return;
  }
  Viewport& view = m_window.viewport();
  m_phase = Phase::kDrag;
  m_dragCpuStartMs = cpuMs();
  m_dragStartMs = m_clock.elapsed();
  m_at = QPointF(view.width() / 2.0, view.height() / 2.0);
  sendMouse(view, QEvent::MouseButtonPress, m_at, Qt::LeftButton, Qt::LeftButton);
  m_move = 0;
  moveMouse();
}

// Move i at i / rate seconds into the drag, on the browser benchmark's path:
// a figure eight about the view's centre.
void LatencyRun::moveMouse() {
  if (m_phase != Phase::kDrag) {
    return;  // the run failed meanwhile
  }
  const int moves = static_cast<int>(std::lround(m_options.seconds * m_options.rate));
  if (m_move >= moves) {
    endDrag();
    return;
  }
  ++m_move;
  Viewport& view = m_window.viewport();
  const double angle = 2.0 * std::numbers::pi * m_move / (m_options.rate * 2.0);
  m_at = QPointF(view.width() / 2.0 + 0.2 * view.width() * std::sin(angle),
                 view.height() / 2.0 + 0.1 * view.height() * std::sin(2.0 * angle));
  sendMouse(view, QEvent::MouseMove, m_at, Qt::NoButton, Qt::LeftButton);
  const double due = static_cast<double>(m_dragStartMs) + 1000.0 * m_move / m_options.rate;
  const auto wait = static_cast<int>(std::max(0.0, due - static_cast<double>(m_clock.elapsed())));
  QTimer::singleShot(wait, Qt::PreciseTimer, this, &LatencyRun::moveMouse);
}

void LatencyRun::endDrag() {
  Viewport& view = m_window.viewport();
  sendMouse(view, QEvent::MouseButtonRelease, m_at, Qt::LeftButton, Qt::NoButton);
  m_releaseEvent = view.lastEventSent();
  m_bitrateBps = m_window.client().statistics().bitrateBps;  // over the drag's last second
  m_phase = Phase::kAfterDrag;
  QTimer::singleShot(kAfterDragMs, this, [this] {
    m_afterDragWaited = true;
    closeDrag();
  });
  QTimer::singleShot(kMostAfterDragMs, this, [this] {
    m_releasePainted = true;  // no frame answered the release: the drag ends anyway
    closeDrag();
  });
}

// The drag's figures, once its release has been answered and the rest after
// it is over.
void LatencyRun::closeDrag() {
  if (m_phase != Phase::kAfterDrag || !m_releasePainted || !m_afterDragWaited) {
    return;
  }
  const double dragMs = static_cast<double>(m_clock.elapsed() - m_dragStartMs);
  m_dragFps = 1000.0 * m_dragFrames / dragMs;
  m_cpuPerFrameMs = m_dragFrames > 0 ? (cpuMs() - m_dragCpuStartMs) / m_dragFrames : 0.0;
  m_phase = Phase::kSettle;
  QTimer::singleShot(kBeforeStillsMs, this, [this] {
    if (m_phase == Phase::kSettle) {
      m_phase = Phase::kStills;
      nextStill();
    }
  });
}

void LatencyRun::nextStill() {
  if (m_phase != Phase::kStills) {
    return;  // the run failed meanwhile
  }
  if (m_still == m_options.stills) {
    finish();
    return;
  }
  ++m_still;
  m_stillEvent = m_window.client().rotate(kStillRotate, 0.0, /*still=*/true);
}

void LatencyRun::finish() {
  m_phase = Phase::kDone;
  m_timeout.stop();
  const QJsonObject result{
      {"size", QStringLiteral("%1x%2").arg(m_options.view.width()).arg(m_options.view.height())},
      {"first_frame_ms", m_firstFrameMs},
      {"drag_event_to_paint_ms", summary(m_dragLatencies)},
      {"still_event_to_paint_ms", summary(m_stillLatencies)},
      {"drag_fps", m_dragFps},
      {"drag_frames", m_dragFrames},
      {"reductions_painted", m_reductions},
      {"decode_ms", summary(m_decodeMs)},
      {"server_event_to_send_ms", summary(m_serverMs)},
      {"bitrate_mbps", m_bitrateBps / 1e6},
      {"client_cpu_ms_per_frame", m_cpuPerFrameMs},
      {"platform", QGuiApplication::platformName()},
  };
  const QByteArray json = QJsonDocument(result).toJson(QJsonDocument::Compact) + '\n';
  QFile out(m_options.jsonPath);
  const bool opened = m_options.jsonPath == QStringLiteral("-")
                          ? out.open(stdout, QIODevice::WriteOnly)
                          : out.open(QIODevice::WriteOnly | QIODevice::Truncate);
  if (!opened || out.write(json) != json.size()) {
    emit finished(1, QStringLiteral("cannot write %1").arg(m_options.jsonPath));
    return;
  }
  out.close();
  emit finished(0, {});
}

void LatencyRun::fail(const QString& why) {
  if (m_phase == Phase::kDone) {
    return;
  }
  m_phase = Phase::kDone;
  m_timeout.stop();
  emit finished(1, why);
}

double LatencyRun::cpuMs() const {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) / 1e6;
}

}  // namespace crackvis::client
