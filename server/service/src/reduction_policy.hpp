// How a drag's frames are drawn, adapted frame by frame: ParaView's image
// reduction factor, and coarse stand-ins for the particles and the crack
// surfaces while the server is crowded.
//
// The factor is chosen so that a reduced frame fits the budget, counting the
// wait for its render turn (the user waits for both). Part of a frame's cost
// does not shrink with its pixels (vertex and geometry work), so a larger
// factor is taken only while the last larger one paid off, and a smaller one
// as soon as it fits: the sharpest picture that holds the frame rate.
//
// Coarse stand-ins (render::SceneRenderer::FrameDetail::kCoarse) are drawn
// while most of the session's recent frames met other sessions' frames
// rendering or waiting (RenderTurns::Turn::crowded): llvmpipe rasterises
// the frames of all sessions in turn, and each frame's cost follows its
// primitives, not its pixels, so only fewer primitives give every session
// more frames (docs/benchmarks.md, "Many users on one render node"). A
// session alone keeps every primitive.
//
// A session's worker renders its reduced (interactive) frames at factor()
// and, while dragging, coarse(), and reports each one to adapt();
// full-resolution frames are neither rendered at factor() nor reported.
// Private to the service library.
#pragma once

#include <array>
#include <cstddef>
#include <optional>

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
  // Whether the next reduced frame draws coarse stand-ins.
  bool coarse() const { return m_coarse; }

  // A reduced frame at factor(), drawn `coarse` or not, waited `turnWaitMs`
  // for its render turn and rendered in `renderMs`: the factor of the next
  // one. `crowded` (a drag's frame: whether it met other frames rendering
  // or waiting; none for playback, which is never drawn coarse): its detail.
  void adapt(double renderMs, double turnWaitMs, bool coarse, std::optional<bool> crowded);
  // A drag after a rest starts in full detail: the crowd of the last drag
  // may have gone, and shows again within two frames if not.
  void newDrag();

 private:
  void adaptDetail(bool crowded);
  void adaptFactor(double frameMs, bool coarse);

  int m_mostReduction;
  double m_budgetMs;
  int m_reduction = 2;
  bool m_coarse = false;
  double m_crowdedShare = 0.0;  // of the recent frames (moving average)
  // Wait and render ms by factor (moving average), in full detail and
  // coarse.
  std::array<std::array<double, kMaxReduction + 1>, 2> m_timeAt{};
};

}  // namespace crackvis::service
