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

namespace crackvis::client {

class RenderClient;

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

 public slots:
  void showFrame(const QImage& image);

 signals:
  void playToggled();
  void stepBy(int delta);

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
};

}  // namespace crackvis::client
