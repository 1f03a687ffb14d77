// The picture: paints the newest decoded frame and turns mouse, wheel, keys
// and resizes into session events, with ParaView's conventions: left drag
// rotates, middle (or shift + left) pans, right drag or the wheel zooms;
// r fits the whole specimen, space plays or pauses, the arrow keys step; a
// double click asks what is drawn there (a particle's or crack element's
// values, answered through RenderClient::picked).
#pragma once

#include <QImage>
#include <QPoint>
#include <QRect>
#include <QTimer>
#include <QWidget>
#include <chrono>
#include <deque>
#include <vector>

#include <crackvis/client_core/render_client.hpp>

namespace crackvis::client {

class Viewport : public QWidget {
  Q_OBJECT

 public:
  Viewport(RenderClient& client, QWidget* parent = nullptr);
  const QImage& image() const { return m_image; }
  int framesShown() const { return m_framesShown; }
  // Where the frame is painted (scaled into the widget, aspect kept).
  QRect pictureRect() const;
  // Asks what is drawn at a widget point; false outside the picture.
  bool pickAt(QPoint point);
  // The median of the last 30 events' latencies from their send to the
  // first painted frame that reflects them (what the user sees wait); -1
  // before the first.
  double paintLatencyMs() const;
  // The id of the newest event the mouse, wheel or keys sent (0: none yet).
  quint64 lastEventSent() const { return m_lastEventSent; }

 public slots:
  void showFrame(const QImage& image, const crackvis::client::FrameInfo& info = {});

 signals:
  void playToggled();
  void stepBy(int delta);
  // A new frame was painted: the latencies (ms, from send to this paint) of the
  // events it is the first painted frame to reflect, and the frame's info.
  void painted(const std::vector<double>& eventToPaintMs, const crackvis::client::FrameInfo& info);

 protected:
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void mouseDoubleClickEvent(QMouseEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;
  void keyPressEvent(QKeyEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;

 private:
  enum class Drag { kNone, kRotate, kPan, kZoom };
  RenderClient& m_client;
  QImage m_image;
  QPoint m_last;
  Drag m_drag = Drag::kNone;
  QTimer m_resizeTimer;  // a resize is sent once the window stops changing
  int m_framesShown = 0;
  // The newest frame's info, with the send times of every event that no
  // painted frame has reflected yet (frames shown between two paints
  // collect theirs here).
  FrameInfo m_info;
  bool m_framePending = false;  // a frame shown and not painted yet
  quint64 m_lastEventSent = 0;
  std::deque<double> m_paintLatencies;  // the last 30, for paintLatencyMs
};

}  // namespace crackvis::client
