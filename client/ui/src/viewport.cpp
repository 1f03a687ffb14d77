#include <QKeyEvent>
#include <QMouseEvent>
#include <QPainter>
#include <QWheelEvent>
#include <algorithm>

#include <crackvis/client_core/render_client.hpp>
#include <crackvis/client_ui/viewport.hpp>

namespace crackvis::client {

Viewport::Viewport(RenderClient& client, QWidget* parent) : QWidget(parent), m_client(client) {
  setFocusPolicy(Qt::StrongFocus);
  setMinimumSize(320, 240);
  setAttribute(Qt::WA_OpaquePaintEvent);
  m_resizeTimer.setSingleShot(true);
  m_resizeTimer.setInterval(150);
  connect(&m_resizeTimer, &QTimer::timeout, this, [this] {
    if (m_client.hasSession()) {
      m_client.resize(std::max(16, width()), std::max(16, height()));
    }
  });
}

void Viewport::showFrame(const QImage& image, const FrameInfo& info) {
  m_image = image;
  ++m_framesShown;
  // update() paints once for the frames shown meanwhile: the events of
  // those not painted are reflected first by the one that is.
  std::vector<std::chrono::steady_clock::time_point> unpainted = std::move(m_info.eventsSentAt);
  m_info = info;
  m_info.eventsSentAt.insert(m_info.eventsSentAt.begin(), unpainted.begin(), unpainted.end());
  // A window that is not painted (minimised, hidden) keeps only the newest
  // events' times: they are what its next paint will time.
  constexpr std::size_t kMostUnpainted = 256;
  if (m_info.eventsSentAt.size() > kMostUnpainted) {
    m_info.eventsSentAt.erase(m_info.eventsSentAt.begin(),
                              m_info.eventsSentAt.end() - kMostUnpainted);
  }
  m_framePending = true;
  update();
}

void Viewport::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.fillRect(rect(), QColor(30, 30, 40));
  if (m_image.isNull()) {
    painter.setPen(Qt::lightGray);
    painter.drawText(rect(), Qt::AlignCenter, tr("Connect and open a file (File menu)"));
    return;
  }
  painter.drawImage(pictureRect(), m_image);
  painter.end();
  if (!m_framePending) {
    return;  // a repaint (exposed, resized) of a frame painted before
  }
  m_framePending = false;
  const auto now = std::chrono::steady_clock::now();
  std::vector<double> latencies;
  for (const auto sent : m_info.eventsSentAt) {
    latencies.push_back(std::chrono::duration<double, std::milli>(now - sent).count());
    m_paintLatencies.push_back(latencies.back());
  }
  m_info.eventsSentAt.clear();
  while (m_paintLatencies.size() > 30) {
    m_paintLatencies.pop_front();
  }
  emit painted(latencies, m_info);
}

double Viewport::paintLatencyMs() const {
  if (m_paintLatencies.empty()) {
    return -1.0;
  }
  std::vector<double> sorted(m_paintLatencies.begin(), m_paintLatencies.end());
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  return sorted[sorted.size() / 2];
}

// The stream has the window's size once a resize went through; until then
// the picture is scaled, keeping its aspect ratio.
QRect Viewport::pictureRect() const {
  if (m_image.isNull()) {
    return rect();
  }
  const QSize size = m_image.size().scaled(this->size(), Qt::KeepAspectRatio);
  return {QPoint((width() - size.width()) / 2, (height() - size.height()) / 2), size};
}

bool Viewport::pickAt(QPoint point) {
  const QRect picture = pictureRect();
  if (!m_client.hasSession() || !picture.contains(point) || picture.isEmpty()) {
    return false;
  }
  m_lastEventSent = m_client.pick((point.x() - picture.left() + 0.5) / picture.width(),
                                  (point.y() - picture.top() + 0.5) / picture.height());
  return true;
}

void Viewport::mouseDoubleClickEvent(QMouseEvent* event) {
  if (event->button() == Qt::LeftButton) {
    pickAt(event->position().toPoint());
  }
}

void Viewport::mousePressEvent(QMouseEvent* event) {
  m_last = event->position().toPoint();
  if (event->button() == Qt::LeftButton) {
    m_drag = event->modifiers() & Qt::ShiftModifier ? Drag::kPan : Drag::kRotate;
  } else if (event->button() == Qt::MiddleButton) {
    m_drag = Drag::kPan;
  } else if (event->button() == Qt::RightButton) {
    m_drag = Drag::kZoom;
  }
}

void Viewport::mouseMoveEvent(QMouseEvent* event) {
  const QPoint now = event->position().toPoint();
  const double dx = static_cast<double>(now.x() - m_last.x()) / std::max(1, width());
  const double dy = static_cast<double>(now.y() - m_last.y()) / std::max(1, height());
  m_last = now;
  switch (m_drag) {
    case Drag::kRotate:
      m_lastEventSent = m_client.rotate(dx, dy);
      break;
    case Drag::kPan:
      m_lastEventSent = m_client.pan(dx, dy);
      break;
    case Drag::kZoom:
      m_lastEventSent = m_client.zoom(-2.0 * dy);  // drag up to zoom in
      break;
    case Drag::kNone:
      break;
  }
}

void Viewport::mouseReleaseEvent(QMouseEvent*) {
  if (m_drag != Drag::kNone) {
    m_lastEventSent = m_client.requestStill();  // the full-resolution picture at once
  }
  m_drag = Drag::kNone;
}

void Viewport::wheelEvent(QWheelEvent* event) {
  m_lastEventSent = m_client.zoom(event->angleDelta().y() / 1200.0);
}

void Viewport::keyPressEvent(QKeyEvent* event) {
  switch (event->key()) {
    case Qt::Key_R:
      m_lastEventSent = m_client.resetCamera();
      break;
    case Qt::Key_Space:
      emit playToggled();
      break;
    case Qt::Key_Right:
    case Qt::Key_Up:
      emit stepBy(1);
      break;
    case Qt::Key_Left:
    case Qt::Key_Down:
      emit stepBy(-1);
      break;
    default:
      QWidget::keyPressEvent(event);
  }
}

void Viewport::resizeEvent(QResizeEvent* event) {
  QWidget::resizeEvent(event);
  m_resizeTimer.start();
}

}  // namespace crackvis::client
