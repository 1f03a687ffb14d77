#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <algorithm>
#include <cmath>
#include <limits>

#include <crackvis/client_ui/step_plot.hpp>

namespace crackvis::client {
namespace {

const QColor kBrokenColour(0xff, 0x9f, 0x1c);
const QColor kScalarColour(0x4c, 0xc9, 0xf0);
// The horizontal axis's names beside the series'.
const char* const kStepAxis = "step";
const char* const kTimeAxis = "time";
const char* const kBrokenAxis = "broken bonds";

// The finite values' range (0..1 without any).
std::pair<double, double> rangeOf(const std::vector<double>& values) {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (const double v : values) {
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (!(lo <= hi)) {
    return {0.0, 1.0};
  }
  return lo == hi ? std::pair{lo - 0.5, hi + 0.5} : std::pair{lo, hi};
}

// Counts in full ("17653", not "1.765e+04"); other values with four digits.
QString label(double value) {
  if (value == std::round(value) && std::abs(value) < 1e7) {
    return QString::number(static_cast<qint64>(value));
  }
  return QString::number(value, 'g', 4);
}

}  // namespace

StepPlot::StepPlot(QWidget* parent) : QWidget(parent) {
  setMinimumHeight(120);
  setToolTip(tr("Click or drag to go to a step"));
}

void StepPlot::setHistory(const StepHistory& history) {
  const QString chosen = scalar();
  const QString against = axis();
  m_history = history;
  m_scalar = -1;
  if (!chosen.isEmpty()) {
    setScalar(chosen);
  }
  setAxis(against);
  update();
}

void StepPlot::setCurrentStep(int step) {
  m_step = step;
  update();
}

bool StepPlot::setScalar(const QString& name) {
  m_scalar = static_cast<int>(m_history.scalarNames.indexOf(name));
  update();
  return m_scalar >= 0;
}

QString StepPlot::scalar() const {
  return m_scalar >= 0 ? m_history.scalarNames.at(m_scalar) : QString();
}

bool StepPlot::setAxis(const QString& name) {
  const bool known = axisNames().contains(name) && name != kStepAxis;
  m_axis = known ? name : QString();
  update();
  return known || name.isEmpty() || name == kStepAxis;
}

QString StepPlot::axis() const {
  return m_axis.isEmpty() ? QString(kStepAxis) : m_axis;
}

QStringList StepPlot::axisNames() const {
  QStringList names{kStepAxis};
  if (!m_history.time.empty()) {
    names << kTimeAxis;
  }
  names << kBrokenAxis;
  names << m_history.scalarNames;
  return names;
}

std::vector<double> StepPlot::axisValues() const {
  const std::size_t steps = m_history.brokenBonds.size();
  std::vector<double> values(steps, std::nan(""));
  const auto scalar = m_history.scalarNames.indexOf(m_axis);
  for (std::size_t k = 0; k < steps; ++k) {
    if (m_axis.isEmpty()) {
      values[k] = static_cast<double>(k);
    } else if (m_axis == kTimeAxis) {
      values[k] = k < m_history.time.size() ? m_history.time[k] : values[k];
    } else if (m_axis == kBrokenAxis) {
      values[k] = static_cast<double>(m_history.brokenBonds[k]);
    } else if (scalar >= 0 && k < m_history.scalars[static_cast<std::size_t>(scalar)].size()) {
      values[k] = m_history.scalars[static_cast<std::size_t>(scalar)][k];
    }
  }
  return values;
}

QRect StepPlot::plotArea() const {
  return rect().adjusted(64, 22, -64, -26);
}

int StepPlot::stepAt(int x) const {
  const auto steps = static_cast<int>(m_history.brokenBonds.size());
  if (steps == 0) {
    return -1;
  }
  const QRect area = plotArea();
  if (steps == 1 || area.width() <= 0) {
    return 0;
  }
  // The nearest step along the axis; of equally near ones (a load that
  // falls back to a value it had), the one nearest the step shown.
  const std::vector<double> values = axisValues();
  const auto [lo, hi] = rangeOf(values);
  const double wanted =
      lo + std::clamp(static_cast<double>(x - area.left()) / area.width(), 0.0, 1.0) * (hi - lo);
  int best = -1;
  for (int k = 0; k < steps; ++k) {
    const double v = values[static_cast<std::size_t>(k)];
    if (!std::isfinite(v)) {
      continue;
    }
    const double distance = std::abs(v - wanted);
    const double bestDistance = best < 0
                                    ? std::numeric_limits<double>::infinity()
                                    : std::abs(values[static_cast<std::size_t>(best)] - wanted);
    if (distance < bestDistance ||
        (distance == bestDistance && std::abs(k - m_step) < std::abs(best - m_step))) {
      best = k;
    }
  }
  return std::max(best, 0);
}

void StepPlot::mousePressEvent(QMouseEvent* event) {
  if (const int step = stepAt(event->position().toPoint().x()); step >= 0) {
    emit stepClicked(step);
  }
}

void StepPlot::mouseMoveEvent(QMouseEvent* event) {
  if (event->buttons() & Qt::LeftButton) {
    mousePressEvent(event);
  }
}

void StepPlot::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.fillRect(rect(), QColor(30, 30, 40));
  const QRect area = plotArea();
  const auto steps = static_cast<int>(m_history.brokenBonds.size());
  painter.setPen(Qt::lightGray);
  if (steps == 0 || area.width() <= 0 || area.height() <= 0) {
    painter.drawText(rect(), Qt::AlignCenter, tr("Open a file to see its steps"));
    return;
  }
  painter.drawRect(area);
  // Axes: the chosen one below, broken bonds on the left, the scalar on the
  // right.
  drawAxis(painter, area);
  const std::vector<double> along = axisValues();
  const auto [first, last] = rangeOf(along);
  const auto xAt = [&](int k) {
    return area.left() +
           (along[static_cast<std::size_t>(k)] - first) / (last - first) * area.width();
  };
  std::vector<double> broken(m_history.brokenBonds.begin(), m_history.brokenBonds.end());
  auto curve = [&](const std::vector<double>& values, const QColor& colour, bool left) {
    const auto [lo, hi] = rangeOf(values);
    QPainterPath path;
    bool open = false;
    for (int k = 0; k < steps && k < static_cast<int>(values.size()); ++k) {
      const double v = values[static_cast<std::size_t>(k)];
      if (!std::isfinite(v) || !std::isfinite(along[static_cast<std::size_t>(k)])) {
        open = false;  // a step without the value breaks the line
        continue;
      }
      const QPointF p(xAt(k), area.bottom() - (v - lo) / (hi - lo) * area.height());
      open ? path.lineTo(p) : path.moveTo(p);
      open = true;
    }
    painter.setPen(QPen(colour, 2));
    painter.drawPath(path);
    const QRect labels = left ? QRect(0, area.top() - 8, area.left() - 4, area.height() + 16)
                              : QRect(area.right() + 4, area.top() - 8, 60, area.height() + 16);
    const auto align = left ? Qt::AlignRight : Qt::AlignLeft;
    painter.drawText(labels, align | Qt::AlignTop, label(hi));
    painter.drawText(labels, align | Qt::AlignBottom, label(lo));
  };
  curve(broken, kBrokenColour, true);
  QString title = tr("broken bonds (of %1)").arg(m_history.bondCount);
  if (m_scalar >= 0) {
    curve(m_history.scalars[static_cast<std::size_t>(m_scalar)], kScalarColour, false);
  }
  painter.setPen(kBrokenColour);
  painter.drawText(QRect(area.left(), 2, area.width(), 18), Qt::AlignLeft, title);
  if (m_scalar >= 0) {
    painter.setPen(kScalarColour);
    painter.drawText(QRect(area.left(), 2, area.width(), 18), Qt::AlignRight, scalar());
  }
  if (m_step >= 0 && m_step < steps && std::isfinite(along[static_cast<std::size_t>(m_step)])) {
    painter.setPen(QPen(Qt::white, 1, Qt::DashLine));
    const QPointF top(xAt(m_step), area.top());
    painter.drawLine(top, QPointF(top.x(), area.bottom()));
  }
}

// Below the plot: the step axis's ends with their simulated times, or
// another axis's range and name.
void StepPlot::drawAxis(QPainter& painter, const QRect& area) {
  const QRect below(area.left(), area.bottom() + 4, area.width(), 20);
  const auto steps = static_cast<int>(m_history.brokenBonds.size());
  if (m_axis.isEmpty()) {
    auto end = [&](int step) {
      const auto k = static_cast<std::size_t>(step);
      return k < m_history.time.size() ? tr("%1 (t = %2 s)").arg(step).arg(label(m_history.time[k]))
                                       : QString::number(step);
    };
    painter.drawText(below, Qt::AlignLeft, end(0));
    painter.drawText(below, Qt::AlignCenter, tr("step"));
    painter.drawText(below, Qt::AlignRight, end(steps - 1));
    return;
  }
  const auto [lo, hi] = rangeOf(axisValues());
  painter.drawText(below, Qt::AlignLeft, label(lo));
  painter.drawText(below, Qt::AlignCenter, m_axis);
  painter.drawText(below, Qt::AlignRight, label(hi));
}

}  // namespace crackvis::client
