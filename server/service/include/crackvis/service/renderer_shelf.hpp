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

#include <cstddef>
#include <memory>
#include <mutex>
#include <thread>
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
  // none waits.
  std::unique_ptr<render::SceneRenderer> take(int width, int height);
  // `renderer`'s scene cleared and its context released by the caller. A
  // full shelf drops its oldest (on this thread): the newest is likelier to
  // fit the next session (the same user again, the same window).
  void put(std::unique_ptr<render::SceneRenderer> renderer);
  std::size_t size() const;

 private:
  const std::size_t m_capacity;
  mutable std::mutex m_mutex;
  std::vector<std::unique_ptr<render::SceneRenderer>> m_kept;
  std::thread m_stocking;
};

}  // namespace crackvis::service
