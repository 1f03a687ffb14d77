#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>
#include <malloc.h>

#include <crackvis/common/exception_boundary.hpp>
#include <crackvis/common/log.hpp>
#include <crackvis/scene/scene_pipeline.hpp>
#include <crackvis/service/session.hpp>

namespace crackvis::service {
namespace {

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// What an event is, for the log and error messages.
const char* eventName(const SessionEvent& event) {
  static constexpr const char* kNames[] = {"camera",           "resize", "set_step", "play",
                                           "replace_pipeline", "still",  "keyframe", "pick"};
  static_assert(std::size(kNames) == std::variant_size_v<decltype(event.what)>);
  return kNames[event.what.index()];
}

// Runs `work` on a session's thread. An exception (a bug, or a library that
// throws on data it should have refused) fails only this piece of work with
// an INTERNAL error and an event line; it never escapes the thread, which
// would end the process for every user.
template <typename Work>
Status guarded(const std::string& session, std::string_view during, Work&& work) noexcept {
  return guardedCall(work, [&](std::string_view detail) {
    log::event(
        stderr, "crackvis-render", "session_exception",
        {{"session", session}, {"during", std::string(during)}, {"detail", std::string(detail)}});
    return failedOnException(fmt::format("session {}: {}", session, during), detail);
  });
}

}  // namespace

// Everything the session's thread owns: the scene's data (ScenePipeline), the
// renderer with its GL context, and the interaction state (view size,
// playing, resolution).
struct Session::Worker {
  Session& session;
  std::unique_ptr<scene::ScenePipeline> scene;
  std::unique_ptr<render::SceneRenderer> renderer;
  FrameTimings stepTimings;  // of the last step change (reported with the next frame)

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
  Clock::time_point lastInteraction = Clock::now() - std::chrono::hours(1);
  int reduction = 2;
  static constexpr int kMaxReduction = 8;
  std::array<double, kMaxReduction + 1> timeAt{};  // render ms by factor (moving average)
  std::uint64_t lastEventId = 0;
  std::optional<Clock::time_point> lastEventReceived;
  std::uint64_t frameId = 0;
  // The next full-resolution frame is followed by a state message: the
  // camera moved since the last one, or a new stream has not had one (the
  // camera fitted to a newly opened file is known only after a render).
  bool stateDue = false;

  explicit Worker(Session& owner) : session(owner) {}

  int stepCount() const { return scene->stepCount(); }
  const pipeline::PipelineDescription& description() const { return scene->description(); }

  Status ensureRenderer(int w, int h) {
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
    auto created = render::SceneRenderer::create(w, h);
    if (!created) {
      // Back to a context of the old size, so that the session keeps its view
      // (without one, frames and camera moves answer "no rendering context").
      if (oldWidth > 0) {
        if (auto again = render::SceneRenderer::create(oldWidth, oldHeight)) {
          renderer = std::move(again).value();
          (void)restoreScene(camera);  // the creation error is the one to report
        }
      }
      return created.status();
    }
    renderer = std::move(created).value();
    return restoreScene(camera);
  }

  Status restoreScene(const std::optional<pipeline::CameraDescription>& camera) {
    if (camera) {
      renderer->setCamera(*camera);
    }
    return scene ? buildScene(false) : Status::ok();
  }

  Status needRenderer() const {
    if (!renderer) {
      return internalError(
          fmt::format("session {}: no rendering context (creating one failed)", session.m_id));
    }
    return Status::ok();
  }

  // What the pipeline's last step change cost, reported with the next frame.
  void noteStepTimings() {
    stepTimings = {};
    stepTimings.loadMs = scene->timings().loadMs;
    stepTimings.extractMs = scene->timings().extractMs;
  }

  Status buildScene(bool resetCamera) {
    CRACKVIS_RETURN_IF_ERROR(needRenderer());
    const auto start = Clock::now();
    CRACKVIS_RETURN_IF_ERROR(renderer->setScene(description(), scene->input(), resetCamera));
    stepTimings.sceneMs = millisecondsSince(start);
    dirty = true;
    return Status::ok();
  }

  Status showStep(int step) {
    CRACKVIS_RETURN_IF_ERROR(scene->showStep(step));
    noteStepTimings();
    return buildScene(false);
  }

  Status start() {
    const auto& d = session.m_initial;
    CRACKVIS_RETURN_IF_ERROR(checkViewSize(d.view.width, d.view.height, session.m_limits));
    auto opened = scene::ScenePipeline::open(d, session.m_opener, session.m_limits.cacheSteps);
    if (!opened) {
      return opened.status();
    }
    scene = std::move(opened).value();
    noteStepTimings();
    width = d.view.width;
    height = d.view.height;
    auto created = render::SceneRenderer::create(width, height);
    if (!created) {
      return created.status();
    }
    renderer = std::move(created).value();
    CRACKVIS_RETURN_IF_ERROR(buildScene(false));
    const dem::Lattice& lattice = scene->source().lattice();
    session.m_info.stepCount = stepCount();
    session.m_info.particleCount = static_cast<std::int64_t>(lattice.particleCount());
    session.m_info.bondCount = static_cast<std::int64_t>(lattice.bondCount());
    session.m_info.backend = renderer->backend();
    session.m_info.file = d.file;
    return Status::ok();
  }

  SessionState state() const {
    const scene::ScenePipeline::CrackMapping& mapping = scene->crackMapping();
    return {scene->step(), stepCount(), playing,          width,
            height,        viewXml(),   mapping.fraction, mapping.warning};
  }

  // The description in force as a saved view holds it: the step shown, the
  // stream's size and the camera where the user left it, so that the client
  // can save the view and reopen it as it was.
  std::string viewXml() const {
    pipeline::PipelineDescription d = description();
    d.step = scene->step();
    d.view.width = width;
    d.view.height = height;
    if (renderer) {
      d.view.camera = renderer->camera();
    }
    return pipeline::toXml(d);
  }

  void interacted(const SessionEvent& event) {
    lastInteraction = event.received;
    lastEventReceived = event.received;
    dirty = true;
  }

  void reject(const SessionEvent& event, const Status& status) {
    session.notify({event.id, status, std::nullopt});
  }

  void apply(const SessionEvent& event) {
    lastEventId = std::max(lastEventId, event.id);
    if (Status status = checkEvent(event, session.m_limits); !status) {
      reject(event, status);
      return;
    }
    std::visit([&](const auto& what) { handle(event, what); }, event.what);
  }

  void handle(const SessionEvent& event, const CameraEvent& camera) {
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

  void handle(const SessionEvent& event, const ResizeEvent& resize) {
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

  void handle(const SessionEvent& event, const SetStepEvent& set) {
    const int step = set.step == -1 ? stepCount() - 1 : set.step;
    if (Status status = showStep(step); !status) {
      reject(event, status);
      return;
    }
    scene->prefetch(step + 1);
    interacted(event);
    session.notify({event.id, Status::ok(), state()});
  }

  void handle(const SessionEvent& event, const PlayEvent& play) {
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

  void handle(const SessionEvent& event, const ReplacePipelineEvent& replace) {
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

  // A replacement that fails part-way (a new file that opens but lacks the
  // step, a read that fails, a rendering context that cannot grow) leaves
  // the session showing what it showed rather than half-switched.
  Status replaceDescription(pipeline::PipelineDescription next) {
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
    if (cameraGiven) {
      renderer->setCamera(*description().view.camera);
    } else if (newFile) {
      renderer->moveCamera(render::CameraMove::kReset, 0, 0);
    }
    return Status::ok();
  }

  void handle(const SessionEvent& event, const StillEvent&) { stillFrame(event); }

  void handle(const SessionEvent& event, const PickEvent& at) {
    if (Status status = needRenderer(); !status) {
      reject(event, status);
      return;
    }
    const scene::Ray ray = renderer->viewRay(at.x, at.y, width, height);
    SessionNotice notice{event.id, Status::ok(), std::nullopt};
    notice.pick = scene::pick(description(), scene->input(), ray);
    session.notify(std::move(notice));
  }

  void stillFrame(const SessionEvent& event) {
    forceFull = true;
    lastEventReceived = event.received;
    dirty = true;
  }

  void handle(const SessionEvent& event, const KeyframeEvent&) {
    keyframe = true;
    lastEventReceived = event.received;
    dirty = true;
  }

  // Advances a playing session by one step when its tick is due.
  void tick() {
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

  // Renders a frame when something changed: reduced while interacting or
  // playing, full resolution otherwise.
  void renderIfDirty() {
    const auto now = Clock::now();
    if (refineAt && now >= *refineAt) {
      refineAt.reset();
      forceFull = true;
      dirty = true;
    }
    if (!dirty) {
      return;
    }
    const bool interacting =
        playing || std::chrono::duration<double, std::milli>(now - lastInteraction).count() <
                       session.m_limits.refineAfterMs;
    reduction = std::min(reduction, mostReduction());  // the start value may exceed a low limit
    const int factor = interacting && !forceFull ? reduction : 1;
    RenderedFrame frame;
    frame.step = scene->step();
    frame.reduction = factor;
    frame.fullResolution = factor == 1;
    frame.keyframe = keyframe;
    frame.bitrate = description().stream.bitrate;
    frame.fps = description().stream.fps;
    frame.lastEventId = lastEventId;
    frame.lastEventReceived = lastEventReceived;
    frame.timings = stepTimings;
    render::Image image;
    const int w = std::max(16, width / factor);
    const int h = std::max(16, height / factor);
    const auto start = Clock::now();
    Status rendered = needRenderer();
    if (rendered) {
      rendered = renderer->renderFrame(w, h, image, factor > 1);
    }
    if (Status status = rendered; !status) {
      session.notify({lastEventId, status, std::nullopt});
      dirty = false;
      return;
    }
    frame.timings.renderMs = millisecondsSince(start);
    frame.particles = particleDrawing();
    if (factor > 1) {
      render::resample(image, width, height, frame.image);
      refineAt = lastInteraction +
                 std::chrono::duration_cast<Clock::duration>(
                     std::chrono::duration<double, std::milli>(session.m_limits.refineAfterMs));
    } else {
      frame.image = std::move(image);
    }
    if (interacting && !forceFull) {
      adaptReduction(frame.timings.renderMs);
    }
    frame.frameId = ++frameId;
    const bool settled = frame.fullResolution && stateDue;
    session.publish(std::move(frame));
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

  std::string particleDrawing() const {
    const auto& particles = description().particles;
    if (!particles.visible) {
      return "none";
    }
    return particles.representation == pipeline::ParticleRepresentation::kImpostors ? "spheres"
                                                                                    : "points";
  }

  int mostReduction() const { return std::min(session.m_limits.maxReduction, kMaxReduction); }

  // ParaView's image reduction factor, adapted so that a reduced frame fits
  // the budget. Part of a frame's cost does not shrink with its pixels
  // (vertex and geometry work), so a larger factor is taken only while the
  // last larger one paid off, and a smaller one as soon as it fits: the
  // sharpest picture that holds the frame rate.
  void adaptReduction(double renderMs) {
    auto& known = timeAt[static_cast<std::size_t>(reduction)];
    known = known > 0.0 ? 0.7 * known + 0.3 * renderMs : renderMs;
    const double budget = session.m_limits.interactiveFrameMs;
    const int most = mostReduction();
    const double larger = reduction < most ? timeAt[static_cast<std::size_t>(reduction + 1)] : 0.0;
    const double smaller = reduction > 1 ? timeAt[static_cast<std::size_t>(reduction - 1)] : 0.0;
    if (known > budget && reduction < most && (larger == 0.0 || larger < 0.95 * known)) {
      ++reduction;
    } else if (reduction > 1 && ((smaller > 0.0 && (smaller <= budget || smaller < 1.15 * known)) ||
                                 (smaller == 0.0 && known < 0.5 * budget))) {
      --reduction;
    }
  }

  // A full-resolution picture of the current state (0: the view's size).
  Result<render::Image> snapshot(int w, int h, int& step, std::optional<int> atStep) {
    // Only 0 means the view's size: a negative size is refused by the check.
    w = w == 0 ? width : w;
    h = h == 0 ? height : h;
    CRACKVIS_RETURN_IF_ERROR(checkViewSize(w, h, session.m_limits));
    CRACKVIS_RETURN_IF_ERROR(ensureRenderer(w, h));
    if (atStep) {
      const int shown = *atStep == -1 ? stepCount() - 1 : *atStep;
      CRACKVIS_RETURN_IF_ERROR(dem::checkStepInRange(description().file, shown, stepCount()));
      if (shown != scene->step()) {
        CRACKVIS_RETURN_IF_ERROR(showStep(shown));
        scene->prefetch(shown + 1);
        session.notify({0, Status::ok(), state()});
      }
    }
    render::Image image;
    CRACKVIS_RETURN_IF_ERROR(renderer->renderFrame(w, h, image));
    step = scene->step();
    dirty = true;  // the stream's next frame is rendered again at its own size
    return image;
  }

  // After work that threw: back to the last complete scene (a replacement
  // not yet committed is undone) and to a still picture. Fails when even
  // that throws; the session is then unusable.
  Status recover() {
    playing = false;
    dirty = true;
    forceFull = true;
    return guarded(session.m_id, "recovery", [&] {
      scene->revert();
      return buildScene(false);
    });
  }

  std::optional<Clock::time_point> wakeTime() const {
    std::optional<Clock::time_point> at = refineAt;
    if (playing && (!at || nextTick < *at)) {
      at = nextTick;
    }
    return at;
  }
};

Session::Session(std::string id, pipeline::PipelineDescription description, SourceOpener opener,
                 SessionLimits limits)
    : m_id(std::move(id)),
      m_limits(limits),
      m_initial(std::move(description)),
      m_opener(std::move(opener)),
      m_detachedSince(Clock::now()) {}

Result<std::shared_ptr<Session>> Session::open(std::string id,
                                               pipeline::PipelineDescription description,
                                               SourceOpener opener, SessionLimits limits) {
  std::shared_ptr<Session> session(
      new Session(std::move(id), std::move(description), std::move(opener), limits));
  std::promise<Status> started;
  auto result = started.get_future();
  session->m_thread = std::thread(
      [raw = session.get(), p = std::move(started)]() mutable { raw->run(std::move(p)); });
  Status status = result.get();
  if (!status) {
    session->close();
    session->m_thread.join();
    return status;
  }
  return session;
}

Session::~Session() {
  close();
  if (m_thread.joinable()) {
    m_thread.join();
  }
}

void Session::run(std::promise<Status> started) {
  runWorker(started);
  // The worker's scene, step cache, GL context and encoder are gone: hand the
  // freed pages back to the system. glibc keeps them in its arenas
  // otherwise, and crackvis-render grew by ~150 MB per closed cuboid-A
  // session (117 MB idle, 461 MB after three; 186 MB once trimmed).
  malloc_trim(0);
}

void Session::runWorker(std::promise<Status>& started) {
  Worker worker(*this);
  if (Status status = guarded(m_id, "open", [&] { return worker.start(); }); !status) {
    started.set_value(status);
    return;
  }
  started.set_value(Status::ok());
  if (Status status = guarded(m_id, "the session loop", [&] { return serve(worker); }); !status) {
    fail(status);
  }
  // Tasks that will not run break their promises: a waiting snapshot
  // returns UNAVAILABLE.
  std::lock_guard lock(m_mutex);
  m_tasks.clear();
}

Status Session::serve(Worker& worker) {
  std::unique_lock lock(m_mutex);
  while (!m_closing) {
    auto ready = [&] {
      return m_closing || !m_events.empty() || !m_tasks.empty() ||
             (m_attachment != 0 && (worker.dirty || m_needFrame));
    };
    if (auto at = worker.wakeTime()) {
      m_wake.wait_until(lock, *at, ready);
    } else {
      m_wake.wait(lock, ready);
    }
    if (m_closing) {
      break;
    }
    auto events = std::move(m_events);
    m_events.clear();
    auto tasks = std::move(m_tasks);
    m_tasks.clear();
    if (m_needFrame) {
      m_needFrame = false;
      worker.keyframe = true;
      worker.forceFull = true;
      worker.dirty = true;
      worker.stateDue = true;
    }
    const bool attached = m_attachment != 0;
    lock.unlock();
    for (const SessionEvent& event : events) {
      const Status status = guarded(m_id, eventName(event), [&] {
        worker.apply(event);
        return Status::ok();
      });
      if (!status) {
        notify({event.id, status, std::nullopt});
        CRACKVIS_RETURN_IF_ERROR(worker.recover());
      }
    }
    for (auto& task : tasks) {
      task(worker);  // guards itself: it owns the promise to answer
    }
    Status status = guarded(m_id, "playing", [&] {
      worker.tick();
      return Status::ok();
    });
    if (status && attached) {
      status = guarded(m_id, "rendering", [&] {
        worker.renderIfDirty();
        return Status::ok();
      });
    }
    if (!status) {
      notify({worker.lastEventId, status, std::nullopt});
      CRACKVIS_RETURN_IF_ERROR(worker.recover());
      worker.dirty = false;  // no frame until the next event: it may throw again
    }
    lock.lock();
  }
  return Status::ok();
}

// The session cannot go on: its stream gets the error, then the end.
void Session::fail(const Status& status) {
  log::event(stderr, "crackvis-render", "session_failed",
             {{"session", m_id}, {"detail", status.message()}});
  notify({0, status, std::nullopt});
  close();
}

// A client that sends faster than the session applies (or a stream whose
// reader stopped) must not grow the queue without bound: camera moves of one
// kind queued back to back add up into one, and beyond maxQueuedEvents an
// event is refused with an error notice (itself bounded, see notify).
void Session::post(SessionEvent event) {
  std::optional<std::uint64_t> refused;
  {
    std::lock_guard lock(m_mutex);
    m_lastActive = Clock::now();
    auto* camera = std::get_if<CameraEvent>(&event.what);
    auto* last = m_events.empty() ? nullptr : std::get_if<CameraEvent>(&m_events.back().what);
    if (camera != nullptr && last != nullptr && camera->move == last->move &&
        camera->move != render::CameraMove::kReset) {
      last->dx += camera->dx;
      last->dy += camera->dy;
      m_events.back().id = event.id;
      m_events.back().received = event.received;
      ++m_queue.coalesced;
    } else if (m_events.size() >= m_limits.maxQueuedEvents) {
      ++m_queue.refused;
      refused = event.id;
    } else {
      m_events.push_back(std::move(event));
    }
  }
  if (refused) {
    notify({*refused,
            Status(StatusCode::kResourceExhausted,
                   fmt::format("session {}: {} events are queued already; event refused", m_id,
                               m_limits.maxQueuedEvents)),
            std::nullopt});
    return;
  }
  m_wake.notify_one();
}

Session::QueueStats Session::queueStats() const {
  std::lock_guard lock(m_mutex);
  QueueStats stats = m_queue;
  stats.events = m_events.size();
  stats.notices = m_notices.size();
  return stats;
}

std::uint64_t Session::attach() {
  std::uint64_t attachment = 0;
  {
    std::lock_guard lock(m_mutex);
    attachment = m_nextAttachment++;
    m_attachment = attachment;
    m_lastActive = Clock::now();
    m_detachedSince.reset();
    m_latest.reset();  // a frame encoded for another stream's decoder
    m_needFrame = true;
  }
  m_wake.notify_one();
  m_outgoing.notify_all();  // the superseded stream ends
  return attachment;
}

void Session::detach(std::uint64_t attachment) {
  std::lock_guard lock(m_mutex);
  if (m_attachment == attachment) {
    m_attachment = 0;
    m_detachedSince = Clock::now();
    m_latest.reset();
  }
}

std::optional<Clock::time_point> Session::detachedSince() const {
  std::lock_guard lock(m_mutex);
  return m_detachedSince;
}

Session::Next Session::next(std::uint64_t attachment, std::chrono::milliseconds timeout,
                            RenderedFrame& frame, SessionNotice& notice) {
  std::unique_lock lock(m_mutex);
  m_outgoing.wait_for(lock, timeout, [&] {
    return m_closing || m_attachment != attachment || !m_notices.empty() || m_latest.has_value();
  });
  if (m_attachment != attachment) {
    return Next::kSuperseded;
  }
  // Notices first, even from a closing session: the error that ended it.
  if (!m_notices.empty()) {
    notice = std::move(m_notices.front());
    m_notices.pop_front();
    return Next::kNotice;
  }
  if (m_closing) {
    return Next::kClosed;
  }
  if (m_latest) {
    frame = std::move(*m_latest);
    m_latest.reset();
    return Next::kFrame;
  }
  return Next::kTimeout;
}

void Session::publish(RenderedFrame frame) {
  {
    std::lock_guard lock(m_mutex);
    if (m_latest) {
      ++m_dropped;  // the stream has not taken the previous frame: stale
      // A dropped frame's keyframe request and newer event id carry over.
      frame.keyframe = frame.keyframe || m_latest->keyframe;
    }
    m_latest = std::move(frame);
  }
  m_outgoing.notify_all();
}

void Session::reportEventError(std::uint64_t eventId, Status error) {
  notify({eventId, std::move(error), std::nullopt});
}

// Notices wait for a stream that may never read them: a newer state
// supersedes the queued ones (a state says everything), and beyond
// maxQueuedErrors an event error is dropped (its state, if any, still goes).
void Session::notify(SessionNotice notice) {
  {
    std::lock_guard lock(m_mutex);
    if (notice.state) {
      std::erase_if(m_notices, [](const SessionNotice& queued) {
        return queued.error.isOk() && queued.state.has_value();
      });
    }
    if (!notice.error.isOk()) {
      const auto errors = std::count_if(m_notices.begin(), m_notices.end(),
                                        [](const SessionNotice& n) { return !n.error.isOk(); });
      if (static_cast<std::size_t>(errors) >= m_limits.maxQueuedErrors) {
        ++m_queue.errorsDropped;
        if (!notice.state) {
          return;
        }
        notice.error = Status::ok();
      }
    }
    m_notices.push_back(std::move(notice));
  }
  m_outgoing.notify_all();
}

Result<render::Image> Session::snapshot(int width, int height, int* step,
                                        std::optional<int> atStep) {
  auto promise = std::make_shared<std::promise<Result<render::Image>>>();
  auto future = promise->get_future();
  auto stepOut = std::make_shared<int>(0);
  {
    std::lock_guard lock(m_mutex);
    if (m_closing) {
      return failedPrecondition(fmt::format("session {} is closed", m_id));
    }
    m_tasks.push_back([promise, width, height, stepOut, atStep, this](Worker& worker) {
      Result<render::Image> result = Status(StatusCode::kInternal, "");
      const Status status = guarded(m_id, "snapshot", [&] {
        result = worker.snapshot(width, height, *stepOut, atStep);
        return result.status();
      });
      promise->set_value(status ? std::move(result) : Result<render::Image>(status));
    });
  }
  m_wake.notify_one();
  if (future.wait_for(std::chrono::seconds(60)) != std::future_status::ready) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("session {}: the snapshot did not finish within 60 s", m_id));
  }
  Result<render::Image> result = Status(StatusCode::kUnavailable, "");
  try {
    result = future.get();
  } catch (const std::future_error&) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("session {} closed before the snapshot was rendered", m_id));
  }
  if (result && step != nullptr) {
    *step = *stepOut;
  }
  return result;
}

void Session::close(std::string reason) {
  {
    std::lock_guard lock(m_mutex);
    m_closing = true;
    if (!reason.empty() && m_closeReason.empty()) {
      m_closeReason = std::move(reason);
    }
  }
  m_wake.notify_all();
  m_outgoing.notify_all();
}

bool Session::closed() const {
  std::lock_guard lock(m_mutex);
  return m_closing;
}

std::string Session::closeReason() const {
  std::lock_guard lock(m_mutex);
  return m_closeReason;
}

Clock::time_point Session::lastActive() const {
  std::lock_guard lock(m_mutex);
  return m_lastActive;
}

std::uint64_t Session::framesDropped() const {
  std::lock_guard lock(m_mutex);
  return m_dropped;
}

}  // namespace crackvis::service
