// ParaView's image reduction factor, adapted so that a reduced frame fits
// the budget. Part of a frame's cost does not shrink with its pixels
// (vertex and geometry work), so a larger factor is taken only while the
// last larger one paid off, and a smaller one as soon as it fits: the
// sharpest picture that holds the frame rate.
//
// A session's worker renders its reduced (interactive) frames at factor()
// and reports each one's render time to adaptReduction(); full-resolution
// frames are neither rendered at factor() nor reported. Private to the
// service library.
#pragma once

#include <array>
#include <cstddef>

#include <crackvis/service/session_event.hpp>

namespace crackvis::service {

class ReductionPolicy {
 public:
  static constexpr int kMaxReduction = 8;

  // The budget is limits.interactiveFrameMs, the largest factor
  // limits.maxReduction (at most kMaxReduction).
  explicit ReductionPolicy(const SessionLimits& limits);

  // The factor the next reduced frame is rendered at (1: full resolution).
  int factor() const { return m_reduction; }
  int mostReduction() const { return m_mostReduction; }

  // A reduced frame at factor() took `renderMs`: the factor of the next one.
  void adaptReduction(double renderMs);

 private:
  int m_mostReduction;
  double m_budgetMs;
  int m_reduction = 2;
  std::array<double, kMaxReduction + 1> m_timeAt{};  // render ms by factor (moving average)
};

}  // namespace crackvis::service
