// The render server's sessions take turns at rendering. Each session's
// thread renders its frames with llvmpipe (or a GPU driver) that spreads one
// frame over the cores itself; N sessions rendering at once only time-slice
// the cores, so every frame's wall time grows N-fold and each session's
// latency with it. Taking turns, at most `atOnce` frames render together,
// while the sessions' encoders and event handling run beside them.
//
// Turns go in the order they were asked for, and a session asks for one
// frame at a time, so with N sessions each waits for at most N - 1 others:
// fair, bounded, and a busy session cannot starve the rest. Events that
// arrive while a session waits are coalesced into its next frame, so a
// loaded server lowers each session's frame rate instead of queueing frames.
//
// Measured on 2 cores with llvmpipe (docs/benchmarks.md, "Many users on one
// render node"): 2 at once beat 1 (a frame does not keep both cores busy) and
// 8 (time slicing): at N = 8, a p95 of 417 ms against 525 and 696 ms.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace crackvis::service {

class RenderTurns {
 public:
  // atOnce <= 0: the hardware threads, at least 1.
  explicit RenderTurns(int atOnce);
  RenderTurns(const RenderTurns&) = delete;
  RenderTurns& operator=(const RenderTurns&) = delete;

  int atOnce() const { return m_atOnce; }

  // A turn, held while rendering; its end lets the next one in.
  class Turn {
   public:
    Turn() = default;
    Turn(RenderTurns* turns, bool crowded) : m_turns(turns), m_crowded(crowded) {}
    Turn(Turn&& other) noexcept : m_turns(other.m_turns), m_crowded(other.m_crowded) {
      other.m_turns = nullptr;
    }
    Turn& operator=(Turn&&) = delete;
    Turn(const Turn&) = delete;
    ~Turn();
    // Whether another frame was rendering or waiting when this one asked:
    // frames that render at the same time slow each other down even with
    // turns to spare (llvmpipe rasterises every context's frames in turn).
    bool crowded() const { return m_crowded; }

   private:
    RenderTurns* m_turns = nullptr;
    bool m_crowded = false;
  };
  // Blocks until it is this caller's turn.
  Turn take();

 private:
  void release();

  const int m_atOnce;
  std::mutex m_mutex;
  std::condition_variable m_changed;
  int m_rendering = 0;
  std::uint64_t m_nextTicket = 0;  // the next caller's place in line
  std::uint64_t m_serving = 0;     // the first place not yet let in
};

}  // namespace crackvis::service
