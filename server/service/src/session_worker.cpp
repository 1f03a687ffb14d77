#include "session_worker.hpp"

#include <algorithm>
#include <chrono>
#include <future>

#include <fmt/format.h>

#include "session_guard.hpp"
#include <crackvis/common/elapsed.hpp>
#include <crackvis/common/log.hpp>
#include <crackvis/render/probe_scene.hpp>
#include <crackvis/scene/scene_pipeline.hpp>

namespace crackvis::service {
namespace {
// How long a new session waits, beside its file's open, for a renderer of
// its size that a closing session is clearing (RendererShelf::take): about
// what making one costs (100-140 ms of a core on llvmpipe at 1280x720; 50-80
// ms measured on an H200 with the rehearsal).
constexpr auto kWaitForKeptRenderer = std::chrono::milliseconds(200);
}  // namespace

Status Session::Worker::ensureRenderer(int w, int h) {
  if (renderer && renderer->capacityWidth() >= w && renderer->capacityHeight() >= h) {
    return Status::ok();
  }
  std::optional<pipeline::CameraDescription> camera;
  int oldWidth = 0;
  int oldHeight = 0;
  if (renderer) {
    camera = renderer->camera();
    oldWidth = renderer->capacityWidth();
    oldHeight = renderer->capacityHeight();
  }
  renderer.reset();  // one GL context per session at a time
  noteRenderer();
  auto created = render::SceneRenderer::create(w, h);
  if (!created) {
    // Back to a context of the old size, so that the session keeps its view
    // (without one, frames and camera moves answer "no rendering context").
    if (oldWidth > 0) {
      if (auto again = render::SceneRenderer::create(oldWidth, oldHeight)) {
        renderer = std::move(again).value();
        noteRenderer();
        (void)restoreScene(camera);  // the creation error is the one to report
      }
    }
    return created.status();
  }
  renderer = std::move(created).value();
  noteRenderer();
  return restoreScene(camera);
}

void Session::Worker::noteRenderer() {
  std::lock_guard lock(session.m_mutex);
  if (renderer && rendererSound) {
    session.m_shelfSize = std::pair{renderer->capacityWidth(), renderer->capacityHeight()};
  } else {
    session.m_shelfSize.reset();
  }
}

Status Session::Worker::restoreScene(const std::optional<pipeline::CameraDescription>& camera) {
  if (camera) {
    renderer->setCamera(*camera);
  }
  return scene ? buildScene(false) : Status::ok();
}

Status Session::Worker::needRenderer() const {
  if (!renderer) {
    return internalError(
        fmt::format("session {}: no rendering context (creating one failed)", session.m_id));
  }
  return Status::ok();
}

void Session::Worker::noteStepTimings() {
  stepTimings = {};
  stepTimings.openMs = scene->timings().openMs;
  stepTimings.describeMs = scene->timings().describeMs;
  stepTimings.loadMs = scene->timings().loadMs;
  stepTimings.extractMs = scene->timings().extractMs;
}

Status Session::Worker::buildScene(bool resetCamera) {
  CRACKVIS_RETURN_IF_ERROR(needRenderer());
  const auto start = Clock::now();
  CRACKVIS_RETURN_IF_ERROR(renderer->setScene(description(), scene->input(), resetCamera));
  stepTimings.sceneMs = millisecondsSince(start);
  dirty = true;
  return Status::ok();
}

Status Session::Worker::showStep(int step) {
  CRACKVIS_RETURN_IF_ERROR(scene->showStep(step));
  noteStepTimings();
  return buildScene(false);
}

Status Session::Worker::start() {
  const auto& d = session.m_initial;
  CRACKVIS_RETURN_IF_ERROR(checkViewSize(d.view.width, d.view.height, session.m_limits));
  width = d.view.width;
  height = d.view.height;
  // The GL context is made while the file opens: each takes about 100 ms
  // of the first picture (EGL, llvmpipe and VTK's first frame; the file's
  // lattice and first step through crackvis-data and the bond graph), and
  // they need different cores, not one after the other.
  // The thread also draws the session's description once on a small
  // specimen: the first frame then finds its shader programs compiled
  // (about 30 ms in VTK and Mesa, and llvmpipe's code for them). A
  // rehearsal that fails costs nothing but its time: the first frame
  // compiles what it needs, as before.
  // A renderer left by an earlier session is taken when one of this size
  // waits (RendererShelf).
  auto making = std::async(std::launch::async, [d, shelf = session.m_renderers] {
    Result<std::unique_ptr<render::SceneRenderer>> created =
        shelf ? shelf->take(d.view.width, d.view.height, kWaitForKeptRenderer) : nullptr;
    if (!*created) {
      created = render::SceneRenderer::create(d.view.width, d.view.height);
    }
    if (created) {
      try {
        (void)render::rehearseOnProbe(**created, d);
      } catch (...) {
        // A renderer that a throw left inside a frame draws nothing more.
        created->reset();
        created = render::SceneRenderer::create(d.view.width, d.view.height);
      }
    }
    if (created) {
      (*created)->releaseContext();
    }
    return created;
  });
  auto opened = scene::ScenePipeline::open(d, session.m_opener, session.m_limits.cacheSteps);
  // Waited for whatever the file did: the thread must not outlive the call.
  const auto rendererWait = Clock::now();
  auto created = making.get();
  const double rendererMs = millisecondsSince(rendererWait);
  if (!opened) {
    if (created) {
      renderer = std::move(created).value();
      shelveRenderer();
    }
    return opened.status();
  }
  scene = std::move(opened).value();
  noteStepTimings();
  if (!created) {
    return created.status();
  }
  renderer = std::move(created).value();
  noteRenderer();
  CRACKVIS_RETURN_IF_ERROR(buildScene(false));
  stepTimings.rendererMs = rendererMs;
  const dem::Lattice& lattice = scene->source().lattice();
  session.m_info.stepCount = stepCount();
  session.m_info.particleCount = static_cast<std::int64_t>(lattice.particleCount());
  session.m_info.bondCount = static_cast<std::int64_t>(lattice.bondCount());
  session.m_info.backend = renderer->backend();
  session.m_info.file = d.file;
  // Opening a live file at its last step follows it.
  following = scene->source().beingWritten() && d.step == -1;
  scheduleLook();
  return Status::ok();
}

void Session::Worker::shelveRenderer() {
  if (!session.m_renderers || !renderer || !rendererSound) {
    return;
  }
  // One that cannot be cleared, or a throw on the way, and the renderer goes
  // with the worker instead.
  (void)guarded(session.m_id, "keeping its renderer", [&] {
    CRACKVIS_RETURN_IF_ERROR(renderer->clearScene());
    renderer->releaseContext();
    session.m_renderers->put(std::move(renderer));
    return Status::ok();
  });
}

Status Session::Worker::drawFrame(int w, int h, render::Image& image,
                                  render::SceneRenderer::FrameDetail detail) {
  // Unsound until the frame has come back well: a throw out of it leaves
  // the renderer unfit for another session.
  const bool sound = rendererSound;
  rendererSound = false;
  const Status drawn = renderer->renderFrame(w, h, image, detail);
  rendererSound = sound && drawn.isOk();
  if (sound && !rendererSound) {
    noteRenderer();  // it will not be shelved: a close announces nothing
  }
  return drawn;
}

void Session::Worker::scheduleLook() {
  const source::StepSource& source = scene->source();
  if (source.appendable() && source.beingWritten()) {
    nextLook = Clock::now() + kLookEvery;
  } else {
    nextLook.reset();
    following = false;
  }
}

void Session::Worker::follow() {
  if (!nextLook || Clock::now() < *nextLook) {
    return;
  }
  auto grew = scene->refreshSteps();
  if (!grew) {
    // Replaced under its name, or unreadable: the session keeps what it
    // shows and stops looking; the stream hears why.
    nextLook.reset();
    following = false;
    session.notify({0, grew.status(), state()});
    return;
  }
  const bool ended = !scene->source().beingWritten();
  if (*grew && following && !playing) {
    if (Status status = showStep(stepCount() - 1); !status) {
      following = false;
      session.notify({0, status, state()});
      return;
    }
  }
  scheduleLook();  // after the last step is shown: a run that ended stops the following
  if (*grew || ended) {
    session.notify({0, Status::ok(), state()});
  }
}

SessionState Session::Worker::state() const {
  const scene::ScenePipeline::CrackMapping& mapping = scene->crackMapping();
  const source::StepSource& source = scene->source();
  SessionState out{scene->step(), stepCount(), playing,          width,
                   height,        viewXml(),   mapping.fraction, mapping.warning};
  out.live = source.appendable() && source.beingWritten();
  out.following = following;
  out.runEnded = source.appendable() && !source.beingWritten();
  return out;
}

std::string Session::Worker::viewXml() const {
  pipeline::PipelineDescription d = description();
  d.step = scene->step();
  d.view.width = width;
  d.view.height = height;
  if (renderer) {
    d.view.camera = renderer->camera();
  }
  return pipeline::toXml(d);
}

// Input that arrives in bunches (a browser whose main thread is busy
// painting, a network that holds packets back) leaves gaps longer than
// refine_after_ms inside one drag. A full-resolution frame started in such a
// gap holds the next move up for its whole render time, and a drag then
// alternates between reduced and full frames. So a refinement that a move
// follows within kPrematureRefine was premature: the wait doubles, up to 8
// times the configured one. A move after a second's rest starts a new drag
// with the configured wait.
namespace {
constexpr auto kPrematureRefine = std::chrono::milliseconds(250);
constexpr auto kNewDrag = std::chrono::seconds(1);
constexpr double kMaxRefineStretch = 8.0;
// A step change with no other step change or camera move for this long is
// a jump (a click on the Steps plot, a typed step), not a slider being
// dragged: the user waits for the picture of that step, so it is rendered
// at full resolution at once instead of a reduced frame and a refinement
// after refine_after_ms (issue 34 point 2: 114 -> ~80 ms on cuboid A). The
// first step of a slider drag pays one full render; the rest are reduced.
constexpr auto kJumpAfterRest = std::chrono::milliseconds(250);
}  // namespace

void Session::Worker::interacted(const SessionEvent& event) {
  const double configured = session.m_limits.refineAfterMs;
  if (event.received - lastInteraction > kNewDrag) {
    refineDelayMs = configured;
    reduction.newDrag();
  } else if (refinedAt && event.received - *refinedAt < kPrematureRefine) {
    refineDelayMs = std::min(2.0 * refineDelayMs, kMaxRefineStretch * configured);
  }
  refinedAt.reset();
  // A refinement planned after the last reduced frame is superseded: the
  // next reduced frame plans it anew from this event. Without this, a
  // session that waited long for its render turn found the old plan due and
  // drew a full-resolution frame in the middle of a drag, the dearest frame
  // at the worst time (issue 34 point 3).
  refineAt.reset();
  lastInteraction = event.received;
  lastEventReceived = event.received;
  dirty = true;
}

void Session::Worker::reject(const SessionEvent& event, const Status& status) {
  session.notify({event.id, status, std::nullopt});
}

void Session::Worker::apply(const SessionEvent& event) {
  lastEventId = std::max(lastEventId, event.id);
  if (Status status = checkEvent(event, session.m_limits); !status) {
    reject(event, status);
    return;
  }
  std::visit([&](const auto& what) { handle(event, what); }, event.what);
}

void Session::Worker::handle(const SessionEvent& event, const CameraEvent& camera) {
  if (Status status = needRenderer(); !status) {
    session.notify({event.id, status, std::nullopt});
    return;
  }
  renderer->moveCamera(camera.move, camera.dx, camera.dy);
  stateDue = true;
  if (camera.still) {
    stillFrame(event);
    return;
  }
  interacted(event);
}

void Session::Worker::handle(const SessionEvent& event, const ResizeEvent& resize) {
  if (Status status = ensureRenderer(resize.width, resize.height); !status) {
    reject(event, status);
    return;
  }
  width = resize.width;
  height = resize.height;
  scene->setViewSize(width, height);
  interacted(event);
  session.notify({event.id, Status::ok(), state()});
}

void Session::Worker::handle(const SessionEvent& event, const SetStepEvent& set) {
  following = set.follow && nextLook.has_value();
  const int step = set.step == -1 || set.follow ? stepCount() - 1 : set.step;
  if (Status status = showStep(step); !status) {
    reject(event, status);
    return;
  }
  scene->prefetch(step + 1);
  const bool jump = event.received - lastStepChange > kJumpAfterRest &&
                    event.received - lastInteraction > kJumpAfterRest;
  lastStepChange = event.received;
  if (jump) {
    stillFrame(event);
  } else {
    interacted(event);
  }
  session.notify({event.id, Status::ok(), state()});
}

void Session::Worker::handle(const SessionEvent& event, const PlayEvent& play) {
  following = false;
  playing = play.playing;
  loop = play.loop;
  playFps = play.fps > 0.0 ? play.fps : description().stream.fps;
  nextTick = Clock::now();
  if (playing) {
    scene->prefetch(scene->step() + 1);
  }
  lastEventReceived = event.received;
  dirty = true;
  session.notify({event.id, Status::ok(), state()});
}

void Session::Worker::handle(const SessionEvent& event, const ReplacePipelineEvent& replace) {
  auto parsed = pipeline::parsePipeline(replace.xml);
  if (!parsed) {
    reject(event, parsed.status());
    return;
  }
  if (Status status = replaceDescription(std::move(parsed).value()); !status) {
    reject(event, status);
    return;
  }
  interacted(event);
  session.notify({event.id, Status::ok(), state()});
}

Status Session::Worker::replaceDescription(pipeline::PipelineDescription next) {
  CRACKVIS_RETURN_IF_ERROR(checkViewSize(next.view.width, next.view.height, session.m_limits));
  const bool newFile = next.file != description().file;
  const bool cameraGiven =
      next.view.camera.has_value() && next.view.camera != description().view.camera;
  CRACKVIS_RETURN_IF_ERROR(scene->replace(std::move(next)));
  noteStepTimings();
  Status status = ensureRenderer(description().view.width, description().view.height);
  if (status) {
    status = buildScene(false);
  }
  if (!status) {
    scene->revert();
    // Same data as before the replacement: a failure here would be new.
    if (Status rebuilt = buildScene(false); !rebuilt) {
      log::event(stderr, "crackvis-render", "restore_failed",
                 {{"session", session.m_id}, {"detail", rebuilt.message()}});
    }
    dirty = true;
    return status;
  }
  scene->commit();
  width = description().view.width;
  height = description().view.height;
  if (newFile) {
    following = scene->source().beingWritten() && description().step == -1;
    scheduleLook();
  }
  if (cameraGiven) {
    renderer->setCamera(*description().view.camera);
  } else if (newFile) {
    renderer->moveCamera(render::CameraMove::kReset, 0, 0);
  }
  return Status::ok();
}

void Session::Worker::handle(const SessionEvent& event, const PickEvent& at) {
  if (Status status = needRenderer(); !status) {
    reject(event, status);
    return;
  }
  const scene::Ray ray = renderer->viewRay(at.x, at.y, width, height);
  SessionNotice notice{event.id, Status::ok(), std::nullopt};
  notice.pick = scene::pick(description(), scene->input(), ray);
  session.notify(std::move(notice));
}

void Session::Worker::stillFrame(const SessionEvent& event) {
  forceFull = true;
  lastEventReceived = event.received;
  dirty = true;
}

void Session::Worker::handle(const SessionEvent& event, const KeyframeEvent&) {
  keyframe = true;
  lastEventReceived = event.received;
  dirty = true;
}

void Session::Worker::tick() {
  if (!playing || Clock::now() < nextTick) {
    return;
  }
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / std::max(playFps, 0.1)));
  nextTick = std::max(nextTick + period, Clock::now());
  int step = scene->step() + 1;
  if (step >= stepCount()) {
    if (!loop) {
      playing = false;
      session.notify({0, Status::ok(), state()});
      forceFull = true;
      dirty = true;
      return;
    }
    step = 0;
  }
  if (Status status = showStep(step); !status) {
    playing = false;
    session.notify({0, status, state()});
    return;
  }
  scene->prefetch(step + 1 < stepCount() ? step + 1 : 0);
}

void Session::Worker::renderIfDirty(std::optional<RenderedFrame>* hold) {
  const auto now = Clock::now();
  if (refineAt && now >= *refineAt) {
    refineAt.reset();
    refinedAt = now;
    forceFull = true;
    dirty = true;
  }
  if (!dirty) {
    return;
  }
  const bool interacting =
      playing ||
      std::chrono::duration<double, std::milli>(now - lastInteraction).count() < refineDelayMs;
  const bool reduced = interacting && !forceFull;  // as the policy says
  const int factor = reduced ? reduction.factor() : 1;
  // Playback shows each step once: stand-ins made for one frame would cost
  // more than they save.
  const bool coarse = reduced && !playing && reduction.coarse();
  RenderedFrame frame;
  frame.step = scene->step();
  frame.reduction = factor;
  frame.keyframe = keyframe;
  frame.bitrate = description().stream.bitrate;
  frame.fps = description().stream.fps;
  frame.lastEventId = lastEventId;
  frame.lastEventReceived = lastEventReceived;
  frame.timings = stepTimings;
  render::Image image;
  const int w = std::max(16, width / factor);
  const int h = std::max(16, height / factor);
  Status rendered = needRenderer();
  auto start = Clock::now();
  bool crowded = false;
  if (rendered && coarse) {
    renderer->prepareCoarse();  // outside the render turn: the others need not wait for it
    start = Clock::now();
  }
  if (rendered) {
    const auto asked = start;
    const RenderTurns::Turn turn = session.m_turns ? session.m_turns->take() : RenderTurns::Turn();
    start = Clock::now();
    frame.timings.turnWaitMs = millisecondsSince(asked);
    crowded = turn.crowded();
    rendered = drawFrame(w, h, image,
                         coarse ? render::SceneRenderer::FrameDetail::kCoarse
                                : render::SceneRenderer::FrameDetail::kFull);
  }
  if (Status status = rendered; !status) {
    session.notify({lastEventId, status, std::nullopt});
    dirty = false;
    return;
  }
  frame.timings.renderMs = millisecondsSince(start);
  // Coarse only where something stood in; a coarse frame is refined as a
  // reduced one is, even at factor 1.
  frame.coarse = coarse && renderer->drewStandIns();
  frame.fullResolution = factor == 1 && !frame.coarse;
  frame.particles = particleDrawing();
  frame.width = width;
  frame.height = height;
  frame.image = std::move(image);
  if (!frame.fullResolution) {
    refineAt = lastInteraction + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double, std::milli>(refineDelayMs));
  }
  if (reduced) {
    reduction.adapt(frame.timings.renderMs, frame.timings.turnWaitMs, frame.coarse,
                    playing ? std::nullopt : std::optional<bool>(crowded));
  }
  frame.frameId = ++frameId;
  const bool settled = frame.fullResolution && stateDue;
  if (hold != nullptr) {
    *hold = std::move(frame);
  } else {
    session.publish(std::move(frame));
  }
  if (settled) {  // the camera came to rest, or a new stream: the state carries it
    stateDue = false;
    session.notify({0, Status::ok(), state()});
  }
  stepTimings = {};
  lastEventReceived.reset();
  dirty = false;
  forceFull = false;
  keyframe = false;
}

std::string Session::Worker::particleDrawing() const {
  const auto& particles = description().particles;
  if (!particles.visible) {
    return "none";
  }
  return particles.representation == pipeline::ParticleRepresentation::kImpostors ? "spheres"
                                                                                  : "points";
}

Result<render::Image> Session::Worker::snapshot(int w, int h, int& step,
                                                std::optional<int> atStep) {
  // Only 0 means the view's size: a negative size is refused by the check.
  w = w == 0 ? width : w;
  h = h == 0 ? height : h;
  CRACKVIS_RETURN_IF_ERROR(checkViewSize(w, h, session.m_limits));
  CRACKVIS_RETURN_IF_ERROR(ensureRenderer(w, h));
  if (atStep) {
    const int shown = *atStep == -1 ? stepCount() - 1 : *atStep;
    CRACKVIS_RETURN_IF_ERROR(dem::checkStepInRange(description().file, shown, stepCount()));
    following = following && *atStep == -1;
    if (shown != scene->step()) {
      CRACKVIS_RETURN_IF_ERROR(showStep(shown));
      scene->prefetch(shown + 1);
      session.notify({0, Status::ok(), state()});
    }
  }
  render::Image image;
  CRACKVIS_RETURN_IF_ERROR(drawFrame(w, h, image, render::SceneRenderer::FrameDetail::kFull));
  step = scene->step();
  dirty = true;  // the stream's next frame is rendered again at its own size
  return image;
}

Status Session::Worker::recover() {
  playing = false;
  dirty = true;
  forceFull = true;
  return guarded(session.m_id, "recovery", [&] {
    scene->revert();
    return buildScene(false);
  });
}

std::optional<Clock::time_point> Session::Worker::wakeTime() const {
  std::optional<Clock::time_point> at = refineAt;
  if (playing && (!at || nextTick < *at)) {
    at = nextTick;
  }
  if (nextLook && (!at || *nextLook < *at)) {
    at = nextLook;
  }
  return at;
}

}  // namespace crackvis::service
