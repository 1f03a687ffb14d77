// The course of a file over its steps (what `crackvis info --steps`
// prints), drawn with QPainter: the broken bonds against the step on the
// left axis and one chosen step scalar (load, displacement, ...) on a right
// axis of its own, with a marker at the step shown; a click or drag goes to
// the step under the pointer.
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
  // The step under widget column `x` (the nearest, clamped); -1 without
  // steps.
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
  int xOf(int step) const;

  StepHistory m_history;
  int m_step = -1;
  int m_scalar = -1;  // index into m_history.scalars
};

}  // namespace crackvis::client
