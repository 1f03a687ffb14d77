// One render session: a pipeline description's scene data (a
// scene::ScenePipeline: the data source with a step cache, the crack
// extractor, incremental across steps) and an off-screen renderer with its
// own GL context, all owned by the session's own thread (a GL context is
// current on one thread). No gRPC types: the render service
// turns a stream's messages into SessionEvents and RenderedFrames into
// encoded frames.
//
// Interactivity first: while events arrive (or while playing) frames are
// rendered at a reduced resolution chosen to hold a frame-time budget and
// scaled up; a full-resolution frame follows `refineAfterMs` after the last
// event. Rendering never waits for the network: the outbox holds the newest
// frame only, and a frame the stream has not taken yet is replaced (dropped).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/scene/scene_pipeline.hpp>
#include <crackvis/scene_model/scene_pick.hpp>
#include <crackvis/service/heap_trimmer.hpp>
#include <crackvis/service/render_turns.hpp>
#include <crackvis/service/renderer_shelf.hpp>
#include <crackvis/service/session_event.hpp>
#include <crackvis/source/step_source.hpp>

namespace crackvis::service {

struct FrameTimings {
  double openMs = 0.0;      // the file opened for this frame (summary, lattice, first step)
  double describeMs = 0.0;  // of openMs: the summary (crackvis-data's Describe)
  double rendererMs = 0.0;  // the EGL context and renderer made for this frame
  double loadMs = 0.0;
  double extractMs = 0.0;
  double sceneMs = 0.0;
  double renderMs = 0.0;
  double turnWaitMs = 0.0;  // waiting for the server's render turn (render_turns.hpp)
};

struct RenderedFrame {
  std::uint64_t frameId = 0;
  std::uint64_t lastEventId = 0;
  std::optional<Clock::time_point> lastEventReceived;  // set when it reflects a new event
  int step = 0;
  bool fullResolution = true;
  int reduction = 1;
  bool coarse = false;    // the particles and cracks drawn by coarse stand-ins
  bool keyframe = false;  // the client asked for one
  int bitrate = 0;        // the description's stream bitrate
  int fps = 30;
  // How the particles were drawn: "spheres" (impostors as point sprites or,
  // for spheres wider than the largest point, VTK's geometry shader),
  // "points", or "none".
  std::string particles;
  int width = 0;  // the view's size, the stream's
  int height = 0;
  // The view's pixels, or fewer: a reduced frame (`reduction` > 1), which the
  // encoder enlarges to width x height by pixel replication.
  render::Image image;
  FrameTimings timings;
};

struct SessionState {
  int step = 0;
  int stepCount = 0;
  bool playing = false;
  int width = 0;
  int height = 0;
  std::string pipelineXml;
  double mappedFraction = 1.0;  // of the step's broken bonds, as surface elements
  std::string crackWarning;     // when below 95 %, naming the likely cause
  bool live = false;            // a live file: steps may be added
  bool following = false;       // showing each new step as it arrives
  bool runEnded = false;        // a live file whose writer closed it
};

// What a stream sends besides frames: an event the session could not apply,
// or its state after a change.
struct SessionNotice {
  std::uint64_t eventId = 0;
  Status error;                                          // not OK: an event error
  std::optional<SessionState> state;                     // set: a state message
  std::optional<scene::PickResult> pick = std::nullopt;  // set: the answer to a pick event
};

struct SessionInfo {
  int stepCount = 0;
  std::int64_t particleCount = 0;
  std::int64_t bondCount = 0;
  std::string backend;
  std::string file;
};

class Session {
 public:
  // Opens the data source of a file (the render server's: through
  // crackvis-data, with the caller's folder rules applied).
  using SourceOpener = scene::SourceOpener;

  // Starts the session's thread, which creates the GL context, opens the
  // file, loads and extracts the description's step and builds the scene;
  // returns once that has succeeded or with its error (NOT_FOUND for an
  // unknown file, OUT_OF_RANGE for a step outside the file, ...).
  // `turns`: the server's, shared by its sessions so that their frames take
  // turns (none: this session renders whenever it has a frame to draw).
  // `renderers`: where the session takes its renderer from if one of its
  // view size waits there, and puts it when it ends (none: it makes its own).
  // `trimmer`: asked to trim the heap once the session has ended (none: the
  // session trims it itself as it ends).
  static Result<std::shared_ptr<Session>> open(std::string id,
                                               pipeline::PipelineDescription description,
                                               SourceOpener opener, SessionLimits limits,
                                               std::shared_ptr<RenderTurns> turns = nullptr,
                                               std::shared_ptr<RendererShelf> renderers = nullptr,
                                               std::shared_ptr<HeapTrimmer> trimmer = nullptr);
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  ~Session();  // closes and joins the thread (the GL context goes with it)

  const std::string& id() const { return m_id; }
  const SessionInfo& info() const { return m_info; }

  void post(SessionEvent event);
  // An event the stream could not even turn into a SessionEvent.
  void reportEventError(std::uint64_t eventId, Status error);

  // A stream attaches: the previous one (if any) is superseded, the next
  // frame is rendered at once and is a keyframe. Returns the attachment.
  std::uint64_t attach();
  void detach(std::uint64_t attachment);
  // Since when no stream is attached (the open time if none ever was);
  // nullopt while one is.
  std::optional<Clock::time_point> detachedSince() const;

  enum class Next { kFrame, kNotice, kTimeout, kSuperseded, kClosed };
  // What `attachment`'s stream sends next: notices first, then the newest frame.
  Next next(std::uint64_t attachment, std::chrono::milliseconds timeout, RenderedFrame& frame,
            SessionNotice& notice);

  // A full-resolution picture of the current state (width/height 0: the
  // view's), rendered on the session's thread.
  Result<render::Image> snapshot(int width, int height, int* step = nullptr,
                                 std::optional<int> atStep = std::nullopt);

  // What waits in the session's queues, and what bounded them so far.
  struct QueueStats {
    std::size_t events = 0;   // queued for the session's thread
    std::size_t notices = 0;  // queued for the stream
    std::uint64_t coalesced = 0;
    std::uint64_t refused = 0;
    std::uint64_t errorsDropped = 0;
  };
  QueueStats queueStats() const;

  // `reason`, when given, is what the session's stream tells its client
  // ("reclaimed for another user ...").
  void close(std::string reason = {});
  bool closed() const;
  std::string closeReason() const;
  std::uint64_t framesDropped() const;
  // When a client last did something here: an event, or a stream attaching.
  Clock::time_point lastActive() const;

 private:
  Session(std::string id, pipeline::PipelineDescription description, SourceOpener opener,
          SessionLimits limits, std::shared_ptr<RenderTurns> turns,
          std::shared_ptr<RendererShelf> renderers, std::shared_ptr<HeapTrimmer> trimmer);
  struct Worker;  // the thread's state: scene pipeline, renderer, view

  void run(std::promise<Status> started);
  void runWorker(std::promise<Status>& started);
  // Settles what a close announced to the shelf (RendererShelf::arrived).
  void settleShelving();
  Status serve(Worker& worker);        // the event loop; an error ends the session
  Status renderEarly(Worker& worker);  // the first frame, before a stream attaches
  void fail(const Status& status);
  void publish(RenderedFrame frame);
  void notify(SessionNotice notice);

  const std::string m_id;
  const SessionLimits m_limits;
  SessionInfo m_info;
  pipeline::PipelineDescription m_initial;
  SourceOpener m_opener;
  std::shared_ptr<RenderTurns> m_turns;
  std::shared_ptr<RendererShelf> m_renderers;
  std::shared_ptr<HeapTrimmer> m_trimmer;

  mutable std::mutex m_mutex;
  std::condition_variable m_wake;      // the session thread
  std::condition_variable m_outgoing;  // the attached stream
  std::deque<SessionEvent> m_events;
  std::deque<std::function<void(Worker&)>> m_tasks;
  std::optional<RenderedFrame> m_latest;
  // The first frame, drawn before any stream attached; the first attach
  // takes it (renderEarly).
  std::optional<RenderedFrame> m_early;
  std::deque<SessionNotice> m_notices;
  std::uint64_t m_attachment = 0;  // current; 0: none
  std::uint64_t m_nextAttachment = 1;
  std::optional<Clock::time_point> m_detachedSince;
  bool m_needFrame = false;  // a stream attached and wants a keyframe now
  bool m_closing = false;
  // The capacity of the renderer the worker would shelve, and the one a
  // close announced to the shelf (settled once the worker has ended).
  std::optional<std::pair<int, int>> m_shelfSize;
  std::optional<std::pair<int, int>> m_announced;
  std::string m_closeReason;
  Clock::time_point m_lastActive = Clock::now();
  std::uint64_t m_dropped = 0;
  QueueStats m_queue;  // the counters
  std::thread m_thread;
};

}  // namespace crackvis::service
