// crackvis-client --measure-latency: the window timed as a user drives it,
// with the figures the browser page reports (tools/bench/browser_latency.mjs)
// so that tools/bench/browser-vs-client.sh sets the two side by side. The
// view is sized to exactly WxH; once its full-resolution frame is painted, a
// drag of rotate moves at `rate` Hz goes to the viewport as mouse events
// (press, moves, release: the handlers a user's mouse reaches), then
// isolated still camera moves (CameraEvent.still) each wait for their
// full-resolution frame. Every event's latency runs from its send to the
// first painted frame that reflects it: the decode, the conversion and the
// paint included.
#pragma once

#include <QElapsedTimer>
#include <QJsonObject>
#include <QObject>
#include <QPointF>
#include <QSize>
#include <QString>
#include <QTimer>
#include <vector>

#include <crackvis/client_core/render_client.hpp>

namespace crackvis::client {

class MainWindow;

struct LatencyRunOptions {
  QSize view{1280, 720};
  double seconds = 5.0;  // the drag's length
  double rate = 60.0;    // its moves per second
  int stills = 10;
  QString jsonPath;  // where the figures go ("-": standard output)
};

class LatencyRun : public QObject {
  Q_OBJECT

 public:
  LatencyRun(MainWindow& window, LatencyRunOptions options);
  // Once connected, right before the file is opened: the first frame is
  // timed from here.
  void start();
  // Ends the run with `why` (a lost connection, a refused event).
  void fail(const QString& why);

 signals:
  // The run ended: 0 and the figures written, or 1 and why not.
  void finished(int exitCode, const QString& message);

 private:
  enum class Phase { kFirstFrame, kSettle, kDrag, kAfterDrag, kStills, kDone };

  void framePainted(const std::vector<double>& latencies, const FrameInfo& info);
  void sizeView();
  void startDrag();
  void moveMouse();
  void endDrag();
  void closeDrag();
  void nextStill();
  void finish();
  double cpuMs() const;

  MainWindow& m_window;
  LatencyRunOptions m_options;
  Phase m_phase = Phase::kFirstFrame;
  QElapsedTimer m_clock;  // from start()
  double m_firstFrameMs = -1.0;
  QTimer m_timeout;
  // The drag.
  int m_move = 0;
  QPointF m_at;  // where the mouse is
  qint64 m_dragStartMs = 0;
  double m_dragCpuStartMs = 0.0;
  int m_dragFrames = 0;
  std::vector<double> m_dragLatencies;
  std::vector<double> m_decodeMs;
  std::vector<double> m_serverMs;
  QJsonObject m_reductions;
  double m_bitrateBps = 0.0;
  double m_dragFps = 0.0;
  double m_cpuPerFrameMs = 0.0;
  quint64 m_releaseEvent = 0;      // the drag's last event: its release
  bool m_releasePainted = false;   // a frame reflecting it was painted
  bool m_afterDragWaited = false;  // the rest after the drag is over
  // The still moves.
  int m_still = 0;
  quint64 m_stillEvent = 0;  // the newest still move's event, until answered
  std::vector<double> m_stillLatencies;
};

}  // namespace crackvis::client
