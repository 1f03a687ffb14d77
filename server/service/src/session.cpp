#include <algorithm>
#include <iterator>

#include <fmt/format.h>
#include <malloc.h>

#include "session_guard.hpp"
#include "session_worker.hpp"
#include <crackvis/common/log.hpp>
#include <crackvis/service/session.hpp>

namespace crackvis::service {
namespace {

// What an event is, for the log and error messages.
const char* eventName(const SessionEvent& event) {
  static constexpr const char* kNames[] = {"camera",           "resize", "set_step", "play",
                                           "replace_pipeline", "still",  "keyframe", "pick"};
  static_assert(std::size(kNames) == std::variant_size_v<decltype(event.what)>);
  return kNames[event.what.index()];
}

}  // namespace

Session::Session(std::string id, pipeline::PipelineDescription description, SourceOpener opener,
                 SessionLimits limits, std::shared_ptr<RenderTurns> turns,
                 std::shared_ptr<RendererShelf> renderers, std::shared_ptr<HeapTrimmer> trimmer)
    : m_id(std::move(id)),
      m_limits(limits),
      m_initial(std::move(description)),
      m_opener(std::move(opener)),
      m_turns(std::move(turns)),
      m_renderers(std::move(renderers)),
      m_trimmer(std::move(trimmer)),
      m_detachedSince(Clock::now()) {}

Result<std::shared_ptr<Session>> Session::open(std::string id,
                                               pipeline::PipelineDescription description,
                                               SourceOpener opener, SessionLimits limits,
                                               std::shared_ptr<RenderTurns> turns,
                                               std::shared_ptr<RendererShelf> renderers,
                                               std::shared_ptr<HeapTrimmer> trimmer) {
  std::shared_ptr<Session> session(new Session(std::move(id), std::move(description),
                                               std::move(opener), limits, std::move(turns),
                                               std::move(renderers), std::move(trimmer)));
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
  settleShelving();  // settled in runWorker; again here should it have thrown
  // The worker's scene, step cache, GL context and encoder are gone: hand the
  // freed pages back to the system. glibc keeps them in its arenas
  // otherwise, and crackvis-render grew by ~150 MB per closed cuboid-A
  // session (117 MB idle, 461 MB after three; 186 MB once trimmed). The
  // server's trimmer waits until no session has ended for a while, so that
  // the next session reuses them (HeapTrimmer).
  if (m_trimmer) {
    m_trimmer->request();
  } else {
    malloc_trim(0);
  }
}

void Session::settleShelving() {
  // The renderer a close announced is on the shelf now, or will not come;
  // and a close from here on announces nothing.
  std::lock_guard lock(m_mutex);
  m_shelfSize.reset();
  if (m_announced && m_renderers) {
    m_renderers->arrived(m_announced->first, m_announced->second);
  }
  m_announced.reset();
}

void Session::runWorker(std::promise<Status>& started) {
  Worker worker(*this);
  if (Status status = guarded(m_id, "open", [&] { return worker.start(); }); !status) {
    settleShelving();  // before Session::open's close, which would announce
    started.set_value(status);
    return;
  }
  started.set_value(Status::ok());
  if (Status status = guarded(m_id, "the session loop", [&] { return serve(worker); }); !status) {
    fail(status);
  }
  {
    // From here on a close announces nothing: the renderer is on its way.
    std::lock_guard lock(m_mutex);
    m_shelfSize.reset();
  }
  worker.shelveRenderer();
  settleShelving();  // now, not after the worker's teardown: a taker waits
  // Tasks that will not run break their promises: a waiting snapshot
  // returns UNAVAILABLE.
  std::lock_guard lock(m_mutex);
  m_tasks.clear();
}

// The first frame is drawn as soon as the session has opened, before its
// stream attaches, and waits for it: the client's answer to OpenSession and
// its stream's set-up (a browser's WebSocket: a TLS handshake and the
// upgrade) overlap the first render instead of preceding it. Its state
// notice waits in the queue like any other.
Status Session::renderEarly(Worker& worker) {
  {
    std::lock_guard lock(m_mutex);
    if (m_closing) {
      return Status::ok();  // closed before it was seen (an overtaken open)
    }
  }
  std::optional<RenderedFrame> early;
  worker.stateDue = true;  // the fitted camera, known after the render
  const Status status = guarded(m_id, "the first frame", [&] {
    worker.renderIfDirty(&early);
    return Status::ok();
  });
  if (!status) {
    notify({worker.lastEventId, status, std::nullopt});
    return worker.recover();  // the stream's attach asks for a frame again
  }
  if (!early) {
    return Status::ok();  // it failed and said so; the attach asks again
  }
  std::lock_guard lock(m_mutex);
  if (m_attachment != 0) {
    // Attached during the render: this is the keyframe the stream asked
    // for (drawing another would also make the first move's frame a full one).
    m_latest = std::move(early);
    m_needFrame = false;
    m_outgoing.notify_all();
  } else {
    m_early = std::move(early);
  }
  return Status::ok();
}

Status Session::serve(Worker& worker) {
  CRACKVIS_RETURN_IF_ERROR(renderEarly(worker));
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
    if (!events.empty()) {
      m_early.reset();  // drawn before these events changed the view
    }
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
    Status status = guarded(m_id, "following", [&] {
      worker.follow();
      return Status::ok();
    });
    if (status) {
      status = guarded(m_id, "playing", [&] {
        worker.tick();
        return Status::ok();
      });
    }
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
    if (worker.dirty) {
      m_early.reset();  // a live file's new step, a snapshot's step: drawn anew
    }
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
    if (m_early) {
      // The first frame, drawn while the client connected; its state
      // notice is queued already. A new stream's encoder starts with a
      // keyframe.
      m_latest = std::move(m_early);
      m_early.reset();
      m_needFrame = false;  // an attach that left during the render asked for it
    } else {
      m_needFrame = true;
    }
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
    if (!m_closing && m_shelfSize && m_renderers) {
      // Under the session's lock, so that run() settles only what was
      // announced (the shelf's lock is taken inside it, never the reverse).
      m_renderers->expect(m_shelfSize->first, m_shelfSize->second);
      m_announced = m_shelfSize;
    }
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
