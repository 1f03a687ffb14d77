// The picture: paints the newest decoded frame and turns mouse, wheel, keys
// and resizes into session events, with ParaView's conventions: left drag
// rotates, middle (or shift + left) pans, right drag or the wheel zooms;
// r resets the camera, space plays or pauses, the arrow keys step.
#pragma once

#include <QImage>
#include <QPoint>
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
