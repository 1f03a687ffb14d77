// The course of a file over its steps (what `crackvis info --steps`
// prints), drawn with QPainter: the broken bonds on the left axis and one
// chosen series (a step scalar such as the load, or a crack number such as
// the crack area) on a right axis of its own, against the step or against
// any other series (crack area against load or displacement), with a marker
// at the step shown; a click or drag goes to the step under the pointer.
#pragma once

#include <QWidget>

#include <crackvis/client_core/render_client.hpp>

namespace crackvis::client {

class StepPlot : public QWidget {
  Q_OBJECT

 public:
  explicit StepPlot(QWidget* parent = nullptr);

  void setHistory(const StepHistory& history);
  const StepHistory& history() const { return m_history; }
  void setCurrentStep(int step);
  // The step scalar drawn beside the broken bonds; false (none drawn) for a
  // name the file lacks or an empty one.
  bool setScalar(const QString& name);
  QString scalar() const;
  // What the horizontal axis shows: "step" (also for an empty name), "time",
  // "broken bonds" or a series' name; false (the step) for a name the
  // history lacks.
  bool setAxis(const QString& name);
  QString axis() const;
  // The names setAxis() takes for the history shown.
  QStringList axisNames() const;
  // The step under widget column `x`: the step whose value on the
  // horizontal axis is nearest (clamped); -1 without steps.
  int stepAt(int x) const;
  QRect plotArea() const;
  QSize sizeHint() const override { return {420, 170}; }

 signals:
  void stepClicked(int step);

 protected:
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;

 private:
  // Each step's value on the horizontal axis (NaN where it has none).
  std::vector<double> axisValues() const;
  void drawAxis(QPainter& painter, const QRect& area);

  StepHistory m_history;
  int m_step = -1;
  int m_scalar = -1;  // index into m_history.scalars
  QString m_axis;     // "" the step
};

}  // namespace crackvis::client
