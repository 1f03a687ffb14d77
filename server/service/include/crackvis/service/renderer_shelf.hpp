// Renderers kept between sessions. Making one (an EGL context, and VTK's
// frame buffers, which llvmpipe allocates and clears: 100-140 ms of one core
// at 1280x720 on the 2-core development machine, most of it page faults) is
// work every session's first picture shared its cores with. A session that
// ends puts its renderer here, its scene dropped (SceneRenderer::clearScene:
// no actor, array or camera of its user stays); the next session of the same
// view size takes it instead of making one. crackvis-render also stocks one
// at start-up, so that its first session finds one.
//
// Only renderers none of whose frames failed come back, so a context that
// failed is not handed on. At most `capacity` wait here: each holds its
// context and frame buffers (crackvis-render idle: 181 MB resident with one
// kept at 1280x720, 147 MB without).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include <crackvis/render/scene_renderer.hpp>

namespace crackvis::service {

class RendererShelf {
 public:
  explicit RendererShelf(std::size_t capacity = 1) : m_capacity(capacity) {}
  RendererShelf(const RendererShelf&) = delete;
  RendererShelf& operator=(const RendererShelf&) = delete;
  ~RendererShelf();  // waits for a renderer being stocked

  // Makes one renderer of width x height on a thread of its own and puts it
  // here; once per shelf (later calls do nothing), and nothing if making it
  // fails (the first session then makes its own, and reports why).
  void stock(int width, int height);
  // A renderer of exactly width x height, its context released; null when
  // none waits. While one of that size is on its way back (expect, not yet
  // arrived), waits up to `wait` for it: a client that closes a session and
  // opens the next at once (the browser page choosing another file) would
  // otherwise make a renderer while its last one is being cleared.
  std::unique_ptr<render::SceneRenderer> take(
      int width, int height, std::chrono::milliseconds wait = std::chrono::milliseconds(0));
  // A session that closes will put its renderer of width x height here
  // (expect), and has put it or given up (arrived; exactly once for each
  // expect).
  void expect(int width, int height);
  void arrived(int width, int height);
  int expected(int width, int height) const;
  // `renderer`'s scene cleared and its context released by the caller. A
  // full shelf drops its oldest (on this thread): the newest is likelier to
  // fit the next session (the same user again, the same window). A renderer
  // of a size a take is waiting for is dropped last: the waiter was woken
  // for it and has not yet had the lock (should every one kept be awaited,
  // the one put goes, unless it is awaited too).
  void put(std::unique_ptr<render::SceneRenderer> renderer);
  std::size_t size() const;
  // Takes waiting now for a renderer of width x height (for tests).
  int waiting(int width, int height) const;

 private:
  std::unique_ptr<render::SceneRenderer> takeLocked(int width, int height);
  bool awaited(const render::SceneRenderer& renderer) const;

  const std::size_t m_capacity;
  mutable std::mutex m_mutex;
  std::condition_variable m_changed;  // a renderer put, or one not coming
  std::vector<std::unique_ptr<render::SceneRenderer>> m_kept;
  std::map<std::pair<int, int>, int> m_incoming;  // size -> renderers on their way
  std::map<std::pair<int, int>, int> m_waiting;   // size -> takes waiting for one
  std::thread m_stocking;
};

}  // namespace crackvis::service
