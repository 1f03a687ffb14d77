// The render session's worker (Session::Worker): the state its thread owns
// and what the thread does with it: apply events, advance a playing
// session, render frames (reduced while interacting, see
// reduction_policy.hpp), take snapshots, recover after work that threw.
// Session (session.cpp) runs its loop around one Worker. Private to the
// service library.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "reduction_policy.hpp"
#include <crackvis/common/status.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/scene/scene_pipeline.hpp>
#include <crackvis/service/session.hpp>
#include <crackvis/service/session_event.hpp>

namespace crackvis::service {

// Everything the session's thread owns: the scene's data (ScenePipeline), the
// renderer with its GL context, and the interaction state (view size,
// playing, resolution).
struct Session::Worker {
  Session& session;
  std::unique_ptr<scene::ScenePipeline> scene;
  std::unique_ptr<render::SceneRenderer> renderer;
  bool rendererSound = true;  // no frame of it failed: it may serve another session
  FrameTimings stepTimings;   // of the last step change (reported with the next frame)

  int width = 0;
  int height = 0;
  bool playing = false;
  bool loop = false;
  double playFps = 0.0;
  Clock::time_point nextTick;
  bool dirty = true;
  bool forceFull = true;
  bool keyframe = true;
  std::optional<Clock::time_point> refineAt;
  // The wait for the full-resolution frame after the last move, adapted to
  // the client's input (refineDelay() in session_worker.cpp): from the
  // configured refine_after_ms up to 8 times it.
  double refineDelayMs = 0.0;
  std::optional<Clock::time_point> refinedAt;  // the last refinement the wait led to
  Clock::time_point lastInteraction = Clock::now() - std::chrono::hours(1);
  Clock::time_point lastStepChange = Clock::now() - std::chrono::hours(1);  // SetStep
  ReductionPolicy reduction;  // of the frames rendered while interacting or playing
  std::uint64_t lastEventId = 0;
  std::optional<Clock::time_point> lastEventReceived;
  std::uint64_t frameId = 0;
  // The next full-resolution frame is followed by a state message: the
  // camera moved since the last one, or a new stream has not had one (the
  // camera fitted to a newly opened file is known only after a render).
  bool stateDue = false;
  // A live file: the session looks for new steps every kLookEvery while its
  // writer has it open, and shows each as it arrives while following.
  static constexpr std::chrono::milliseconds kLookEvery{250};
  bool following = false;
  std::optional<Clock::time_point> nextLook;

  explicit Worker(Session& owner)
      : session(owner), refineDelayMs(owner.m_limits.refineAfterMs), reduction(owner.m_limits) {}

  int stepCount() const { return scene->stepCount(); }
  const pipeline::PipelineDescription& description() const { return scene->description(); }

  Status ensureRenderer(int w, int h);
  Status restoreScene(const std::optional<pipeline::CameraDescription>& camera);
  Status needRenderer() const;
  // What the pipeline's last step change cost, reported with the next frame.
  void noteStepTimings();
  Status buildScene(bool resetCamera);
  Status showStep(int step);
  Status start();
  // Puts a sound renderer on the server's shelf for the next session, its
  // scene dropped (on this thread, whose the context is).
  void shelveRenderer();
  // Tells the session the size of the renderer it would shelve (none while
  // it has no sound renderer), so that a close announces it to the shelf
  // (RendererShelf::expect).
  void noteRenderer();
  // The renderer's frame, noting whether the renderer stays sound.
  Status drawFrame(int w, int h, render::Image& image, render::SceneRenderer::FrameDetail detail);
  // Looks for a live file's new steps when due; shows the last while
  // following, and tells the stream of every change.
  void follow();
  // When the next look is due: never for a file that cannot grow.
  void scheduleLook();

  SessionState state() const;
  // The description in force as a saved view holds it: the step shown, the
  // stream's size and the camera where the user left it, so that the client
  // can save the view and reopen it as it was.
  std::string viewXml() const;

  void interacted(const SessionEvent& event);
  void reject(const SessionEvent& event, const Status& status);
  void apply(const SessionEvent& event);
  void handle(const SessionEvent& event, const CameraEvent& camera);
  void handle(const SessionEvent& event, const ResizeEvent& resize);
  void handle(const SessionEvent& event, const SetStepEvent& set);
  void handle(const SessionEvent& event, const PlayEvent& play);
  void handle(const SessionEvent& event, const ReplacePipelineEvent& replace);
  // A replacement that fails part-way (a new file that opens but lacks the
  // step, a read that fails, a rendering context that cannot grow) leaves
  // the session showing what it showed rather than half-switched.
  Status replaceDescription(pipeline::PipelineDescription next);
  void handle(const SessionEvent& event, const StillEvent&) { stillFrame(event); }
  void handle(const SessionEvent& event, const PickEvent& at);
  void stillFrame(const SessionEvent& event);
  void handle(const SessionEvent& event, const KeyframeEvent&);

  // Advances a playing session by one step when its tick is due.
  void tick();
  // Renders a frame when something changed: reduced while interacting or
  // playing, full resolution otherwise. Published for the stream, or kept
  // in `hold` (the first frame, drawn before a stream attached).
  void renderIfDirty(std::optional<RenderedFrame>* hold = nullptr);
  std::string particleDrawing() const;

  // A full-resolution picture of the current state (0: the view's size).
  Result<render::Image> snapshot(int w, int h, int& step, std::optional<int> atStep);
  // After work that threw: back to the last complete scene (a replacement
  // not yet committed is undone) and to a still picture. Fails when even
  // that throws; the session is then unusable.
  Status recover();
  std::optional<Clock::time_point> wakeTime() const;
};

}  // namespace crackvis::service
