// crackvis bench render: what a user of a remote session feels, measured in
// one run against a running crackvis-render. Opens a session on a file's
// step (particles as sphere impostors + crack surfaces) at a given size,
// drags the camera with rotate events at a mouse's rate, and reports from
// the frames that come back: event-to-frame latency percentiles (each event
// until the first frame that reflects it, as the client receives it), frame
// rate while interacting, render and encode times, the reduction factors
// used, and how long after the last event the full-resolution frame came.
// Then jumps in time (SetStep to random steps, forwards and backwards) and
// playback at a given step rate, counting the steps that miss their slot.
#include <algorithm>
#include <barrier>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "bench_support.hpp"
#include "commands.hpp"
#include "crackvis/v1/render.grpc.pb.h"
#include "pipeline_file.hpp"
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/rpc/connection_advice.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/tls/channel.hpp>
#include <crackvis/tls/tls_material.hpp>

namespace crackvis::cli {
namespace {

using Clock = std::chrono::steady_clock;
namespace v1 = crackvis::v1;

struct RenderBenchOptions {
  std::string server;
  std::vector<std::string> files;  // the sessions' files, in turn
  int step = -1;
  std::string size = "1280x720";
  std::string method = "local-voronoi";
  std::string pipelinePath;
  double seconds = 5.0;
  double eventRate = 60.0;     // events per second, a mouse drag's rate
  int stillFrames = 10;        // isolated camera moves answered at full resolution
  int firstPictures = 3;       // sessions opened and closed for the time to the first picture
  double firstPictureGap = 0;  // seconds from one such session's close to the next open
  int jumps = 20;              // SetStep to random other steps, each until its full frame
  int playbackSteps = 50;      // steps played (ending at the last step); 0: none
  double playbackRate = 10.0;  // steps per second while playing
  unsigned seed = 1;           // of the random jumps, so runs compare step for step
  int sessions = 0;            // > 0: that many sessions drag at once, nothing else
  int serverPid = 0;           // the render server's process, sampled from /proc
  tls::TlsFiles tls = tls::defaultTlsFiles("client");
  std::string token;
  bool jsonOnly = false;
  bool methodGiven = false;
};

struct FrameRecord {
  Clock::time_point received;
  v1::Frame frame;  // without its bytes
  std::size_t bytes = 0;
  double decodeMs = 0.0;
};

double ms(Clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

// The session's frames as they arrive, decoded as a client would.
class FrameCollector {
 public:
  // `decode`: each frame is decoded as a client would (and timed); off where
  // the client would run on another machine and must not take this one's
  // cores from the server (--sessions).
  explicit FrameCollector(grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>* stream,
                          bool decode = true)
      : m_stream(stream), m_decode(decode), m_thread([this] { run(); }) {}
  ~FrameCollector() { m_thread.join(); }

  template <typename Done>
  bool waitFor(Done done, double seconds) {
    std::unique_lock lock(m_mutex);
    return m_changed.wait_for(lock, std::chrono::duration<double>(seconds), [&] {
      return m_ended || done(m_frames);
    }) && done(m_frames);
  }
  std::vector<FrameRecord> frames() {
    std::lock_guard lock(m_mutex);
    return m_frames;
  }
  std::vector<std::string> errors() {
    std::lock_guard lock(m_mutex);
    return m_errors;
  }
  // The last decoded pictures, for timing the encoder on real frames alone.
  std::vector<encode::RgbFrame> pictures() {
    std::lock_guard lock(m_mutex);
    return {m_pictures.begin(), m_pictures.end()};
  }
  static constexpr std::size_t kKeptPictures = 30;

 private:
  void run() {
    auto decoder = m_decode ? encode::FrameDecoder::create()
                            : Result<std::unique_ptr<encode::FrameDecoder>>(
                                  Status(StatusCode::kCancelled, "not decoding"));
    v1::ServerMessage message;
    // Decoded into again as a client would: the oldest kept picture's memory
    // is reused, not a fresh buffer zeroed and faulted in per frame, which
    // took this process's CPU from the server it measures.
    encode::RgbFrame picture;
    while (m_stream->Read(&message)) {
      const auto received = Clock::now();
      if (message.has_frame()) {
        FrameRecord record{received, message.frame(), message.frame().h264().size(), 0.0};
        if (decoder) {
          encode::EncodedFrame unit;
          unit.data.assign(message.frame().h264().begin(), message.frame().h264().end());
          const auto start = Clock::now();
          auto decoded = (*decoder)->decodeInto(unit, picture);
          record.decodeMs = ms(Clock::now() - start);
          if (decoded && *decoded) {
            std::lock_guard lock(m_mutex);
            m_pictures.push_back(std::move(picture));
            picture = {};
            if (m_pictures.size() > kKeptPictures) {
              picture = std::move(m_pictures.front());
              m_pictures.pop_front();
            }
          }
        }
        record.frame.clear_h264();
        std::lock_guard lock(m_mutex);
        m_frames.push_back(std::move(record));
      } else if (message.has_error()) {
        std::lock_guard lock(m_mutex);
        m_errors.push_back(message.error().message());
      }
      m_changed.notify_all();
    }
    std::lock_guard lock(m_mutex);
    m_ended = true;
    m_changed.notify_all();
  }

  grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>* m_stream;
  bool m_decode;
  std::mutex m_mutex;
  std::condition_variable m_changed;
  std::vector<FrameRecord> m_frames;
  std::vector<std::string> m_errors;
  std::deque<encode::RgbFrame> m_pictures;
  bool m_ended = false;
  std::thread m_thread;
};

// One open of the file as a user's first look at it: OpenSession, attach,
// until the first full-resolution frame is received; then the session closes.
struct FirstPicture {
  double openSessionMs = 0.0;  // the OpenSession call, as the client waits for it
  double firstFrameMs = 0.0;   // attaching until the first full-resolution frame is received
  v1::FrameTimings server;     // that frame's timings, as the server measured them
  double totalMs() const { return openSessionMs + firstFrameMs; }
};

// A step change as a user's jump in time: SetStep to another step, until
// the frame that shows it, first at any resolution, then at full resolution.
struct Jump {
  int from = 0;
  int to = 0;
  double firstFrameMs = 0.0;
  double fullFrameMs = 0.0;
  double loadMs = 0.0;     // the server reading the step (0 from its cache)
  double extractMs = 0.0;  // the crack method on the step
};

// Play from `firstStep` to the last step at `rate` steps per second. A step
// misses its slot when its frame comes more than 1.5 periods after the
// previous step's: the viewer sees the previous step held too long.
struct Playback {
  double rate = 0.0;
  int firstStep = 0;
  int steps = 0;
  std::vector<double> gapsMs;  // between the first frames of successive steps
  int missedSlots = 0;
  int stepsNotShown = 0;  // steps the server skipped (it should show every one)
  double seconds = 0.0;   // Play sent until the last step's frame
};

struct Report {
  std::string backend;
  std::vector<FirstPicture> firstPictures;
  int width = 0;
  int height = 0;
  std::int64_t particles = 0;
  int step = 0;
  double firstFrameMs = 0.0;
  std::size_t events = 0;
  std::vector<double> latencies;  // per event
  std::size_t interactiveFrames = 0;
  double interactionSeconds = 0.0;
  std::vector<double> reducedRenderMs;
  std::vector<double> fullRenderMs;
  std::vector<double> encodeMs;
  // The server's part of a drag frame's latency: from receiving the last
  // event the frame reflects to handing the frame to gRPC.
  std::vector<double> serverEventToSendMs;
  std::vector<double> isolatedEncodeMs;  // the same frames encoded here, nothing else running
  std::vector<double> decodeMs;
  std::vector<int> reductions;
  double refineAfterIdleMs = -1.0;
  double bitsPerSecond = 0.0;
  // Isolated camera moves, each with a request for a full-resolution frame:
  // the event-to-frame latency of a still render (ParaView's Render()).
  std::vector<double> stillLatencies;
  std::vector<double> stillRenderMs;
  // How each frame after the first was drawn: reduction factor and the
  // particles' drawing ("1/2 spheres"), counted.
  std::map<std::string, int> frameKinds;
  nlohmann::json frames = nlohmann::json::array();  // every frame: id, event, reduction, particles
  // Every frame of the drag drew true spheres at no more than 2x reduction.
  bool dragSpheresAtMost2x = true;
  std::vector<Jump> jumps;
  std::optional<Playback> playback;
  LoadAverage loadBefore;
  LoadAverage loadAfter;
};

std::string particleDrawingName(const v1::Frame& frame) {
  return frame.particles().empty() ? "(particles not reported)" : frame.particles();
}

std::string frameKind(const v1::Frame& frame) {
  return fmt::format("1/{} {}{}", std::max(1, frame.reduction()), particleDrawingName(frame),
                     frame.coarse() ? " coarse" : "");
}

// The errors the session sent, for a failure message: "; the server said: ...".
std::string serverErrors(FrameCollector& collector) {
  const auto errors = collector.errors();
  if (errors.empty()) {
    return {};
  }
  std::string text = "; the server said:";
  for (const std::string& error : errors) {
    text += " " + error;
  }
  return text;
}

// The material was read (and checked) before the run starts.
Result<std::shared_ptr<grpc::Channel>> makeChannel(const RenderBenchOptions& options,
                                                   const tls::TlsMaterial& material) {
  tls::ChannelOptions channel;
  channel.target = options.server;
  channel.material = material;
  auto created = tls::createChannel(channel);
  if (created) {
    // Its first call meets a connection (gRPC 1.51 can fail an attempt in
    // progress: rpc::awaitConnection).
    rpc::awaitConnection(**created, options.server,
                         std::chrono::system_clock::now() + std::chrono::seconds(10));
  }
  return created;
}

void authorize(grpc::ClientContext& context, const RenderBenchOptions& options) {
  if (!options.token.empty()) {
    context.AddMetadata("authorization", "Bearer " + options.token);
  }
}

Result<v1::OpenSessionResponse> openSession(v1::RenderService::Stub& stub,
                                            const RenderBenchOptions& options,
                                            const pipeline::PipelineDescription& d,
                                            const std::shared_ptr<grpc::Channel>& channel) {
  grpc::ClientContext context;
  authorize(context, options);
  v1::OpenSessionRequest open;
  open.set_pipeline_xml(pipeline::toXml(d));
  v1::OpenSessionResponse opened;
  CRACKVIS_RETURN_IF_ERROR(
      rpc::fromGrpcStatus(stub.OpenSession(&context, open, &opened), "OpenSession",
                          {rpc::ServerKind::kRender, options.server}, channel));
  return opened;
}

void closeSession(v1::RenderService::Stub& stub, const RenderBenchOptions& options,
                  const std::string& sessionId) {
  grpc::ClientContext context;
  authorize(context, options);
  v1::CloseSessionRequest close;
  close.set_session_id(sessionId);
  v1::CloseSessionResponse closed;
  (void)stub.CloseSession(&context, close, &closed);
}

Result<FirstPicture> timeFirstPicture(v1::RenderService::Stub& stub,
                                      const RenderBenchOptions& options,
                                      const pipeline::PipelineDescription& d,
                                      const std::shared_ptr<grpc::Channel>& channel) {
  FirstPicture picture;
  const auto start = Clock::now();
  auto opened = openSession(stub, options, d, channel);
  if (!opened) {
    return opened.status();
  }
  const auto attached = Clock::now();
  picture.openSessionMs = ms(attached - start);
  Status status;
  {
    grpc::ClientContext streamContext;
    authorize(streamContext, options);
    auto stream = stub.Stream(&streamContext);
    v1::ClientEvent attach;
    attach.set_attach_session_id(opened->session_id());
    stream->Write(attach);
    FrameCollector collector(stream.get());
    const auto full = [](const auto& frames) {
      return std::any_of(frames.begin(), frames.end(),
                         [](const FrameRecord& f) { return f.frame.full_resolution(); });
    };
    if (collector.waitFor(full, 120.0)) {
      for (const FrameRecord& record : collector.frames()) {
        if (record.frame.full_resolution()) {
          picture.firstFrameMs = ms(record.received - attached);
          picture.server = record.frame.timings();
          break;
        }
      }
    } else {
      status = Status(StatusCode::kUnavailable,
                      fmt::format("no first frame within 120 s{}", serverErrors(collector)));
    }
    stream->WritesDone();
    streamContext.TryCancel();
  }
  closeSession(stub, options, opened->session_id());
  if (!status) {
    return status;
  }
  return picture;
}

using SessionStream = grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>;

// The first frame from `from` on that reflects event `id` and shows `step`,
// at full resolution when `full`.
const FrameRecord* frameShowing(const std::vector<FrameRecord>& frames, std::size_t from,
                                std::uint64_t id, int step, bool full) {
  for (std::size_t k = from; k < frames.size(); ++k) {
    const v1::Frame& frame = frames[k].frame;
    if (frame.last_event_id() >= id && frame.step() == step && (!full || frame.full_resolution())) {
      return &frames[k];
    }
  }
  return nullptr;
}

// Sends SetStep `step` as event `id` and waits for its full-resolution frame.
Result<Jump> jumpTo(SessionStream& stream, FrameCollector& collector, std::uint64_t id, int from,
                    int step) {
  v1::ClientEvent event;
  event.set_event_id(id);
  event.mutable_set_step()->set_step(step);
  const std::size_t seen = collector.frames().size();
  const auto sentAt = Clock::now();
  if (!stream.Write(event)) {
    return Status(StatusCode::kUnavailable, "the stream ended during a step change");
  }
  const bool shown = collector.waitFor(
      [&](const auto& frames) { return frameShowing(frames, seen, id, step, true) != nullptr; },
      120.0);
  if (!shown) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("no full-resolution frame of step {} within 120 s of SetStep{}", step,
                              serverErrors(collector)));
  }
  const auto frames = collector.frames();
  const FrameRecord* first = frameShowing(frames, seen, id, step, false);
  const FrameRecord* full = frameShowing(frames, seen, id, step, true);
  return Jump{from,
              step,
              ms(first->received - sentAt),
              ms(full->received - sentAt),
              first->frame.timings().load_ms(),  // the step's own work comes with its first frame
              first->frame.timings().extract_ms()};
}

// The server's refine delay grows when events follow its full frames
// closely, and is back to its configured value after a second without
// events (session_worker.cpp, kNewDrag): each measurement starts fresh.
constexpr auto kNewInteraction = std::chrono::milliseconds(1100);
// Between jumps: longer than the server's premature-refine window (250 ms),
// so each jump's full frame comes after the configured delay.
constexpr auto kBetweenJumps = std::chrono::milliseconds(300);

// Jumps to random other steps (forwards and backwards alike), one at a
// time, each waited for at full resolution: a user clicking on the Steps
// plot or typing a step.
Status measureJumps(SessionStream& stream, FrameCollector& collector, std::uint64_t& nextId,
                    int stepCount, int current, const RenderBenchOptions& options,
                    std::vector<Jump>& jumps) {
  if (options.jumps == 0 || stepCount < 2) {
    return Status::ok();
  }
  std::mt19937 random(options.seed);
  std::uniform_int_distribution<int> other(0, stepCount - 2);
  std::this_thread::sleep_for(kNewInteraction);
  for (int k = 0; k < options.jumps; ++k) {
    int to = other(random);
    to += to >= current ? 1 : 0;
    auto jump = jumpTo(stream, collector, nextId++, current, to);
    if (!jump) {
      return jump.status();
    }
    jumps.push_back(*jump);
    current = to;
    std::this_thread::sleep_for(kBetweenJumps);
  }
  return Status::ok();
}

// Play at options.playbackRate from playbackSteps before the last step to
// the last, where the server stops by itself with a full-resolution frame.
Status measurePlayback(SessionStream& stream, FrameCollector& collector, std::uint64_t& nextId,
                       int stepCount, int current, const RenderBenchOptions& options,
                       std::optional<Playback>& out) {
  if (options.playbackSteps == 0 || stepCount < 2) {
    return Status::ok();
  }
  Playback playback;
  playback.rate = options.playbackRate;
  playback.steps = std::min(options.playbackSteps, stepCount - 1);
  playback.firstStep = stepCount - 1 - playback.steps;
  const int last = stepCount - 1;
  std::this_thread::sleep_for(kNewInteraction);
  if (auto start = jumpTo(stream, collector, nextId++, current, playback.firstStep); !start) {
    return start.status();
  }
  std::this_thread::sleep_for(kNewInteraction);
  const std::uint64_t id = nextId++;
  v1::ClientEvent play;
  play.set_event_id(id);
  play.mutable_play()->set_playing(true);
  play.mutable_play()->set_fps(options.playbackRate);
  play.mutable_play()->set_loop(false);
  const std::size_t seen = collector.frames().size();
  const auto sentAt = Clock::now();
  if (!stream.Write(play)) {
    return Status(StatusCode::kUnavailable, "the stream ended during playback");
  }
  const double expected = playback.steps / options.playbackRate;
  if (!collector.waitFor(
          [&](const auto& frames) { return frameShowing(frames, seen, id, last, true) != nullptr; },
          4.0 * expected + 60.0)) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("playback did not reach step {} within {:.0f} s{}", last,
                              4.0 * expected + 60.0, serverErrors(collector)));
  }
  const auto frames = collector.frames();
  const double period = 1000.0 / options.playbackRate;
  auto previous = sentAt;
  for (int step = playback.firstStep + 1; step <= last; ++step) {
    const FrameRecord* shown = frameShowing(frames, seen, id, step, false);
    if (shown == nullptr) {
      ++playback.stepsNotShown;
      continue;
    }
    const double gap = ms(shown->received - previous);
    playback.gapsMs.push_back(gap);
    playback.missedSlots += gap > 1.5 * period ? 1 : 0;
    previous = shown->received;
  }
  playback.seconds = ms(previous - sentAt) / 1000.0;
  out = std::move(playback);
  return Status::ok();
}

// The pipeline the benchmark renders: --pipeline's (or the default
// particles + cracks) on `file` at --step and --size, with --method.
Result<pipeline::PipelineDescription> benchDescription(const RenderBenchOptions& options,
                                                       const std::string& file) {
  auto size = cli::parseFrameSize(options.size);
  if (!size) {
    return size.status();
  }
  auto method = cracks::parseMethod(options.method);
  if (!method) {
    return method.status();
  }
  auto described = cli::readPipelineFile(options.pipelinePath);
  if (!described) {
    return described.status();
  }
  pipeline::PipelineDescription d = std::move(described).value();
  d.view.camera.reset();
  d.file = file;
  d.step = options.step;
  d.view.width = size->first;
  d.view.height = size->second;
  if (options.pipelinePath.empty() || options.methodGiven) {
    d.cracks.method = *method;
  }
  return d;
}

// The drag's events as sent: rotate events at the mouse's rate, a full turn
// per 4 s, numbered from `firstId`.
struct Drag {
  std::uint64_t firstId = 1;
  Clock::time_point start;
  std::vector<Clock::time_point> sent;
  std::uint64_t lastId() const { return firstId + sent.size() - 1; }
};

// Drags for options.seconds, then waits for the full-resolution frame that
// reflects the last event (the drag's end as the user sees it).
Result<Drag> dragCamera(SessionStream& stream, FrameCollector& collector,
                        const RenderBenchOptions& options, std::uint64_t firstId) {
  Drag drag;
  drag.firstId = firstId;
  const auto period = std::chrono::duration<double>(1.0 / options.eventRate);
  drag.start = Clock::now();
  auto next = drag.start;
  while (ms(Clock::now() - drag.start) < options.seconds * 1000.0) {
    v1::ClientEvent event;
    event.set_event_id(firstId + drag.sent.size());
    event.mutable_camera()->set_kind(v1::CameraEvent::ROTATE);
    event.mutable_camera()->set_dx(1.8 / options.eventRate);  // 360 degrees / 200 per view / 4 s
    event.mutable_camera()->set_dy(0.0);
    drag.sent.push_back(Clock::now());
    if (!stream.Write(event)) {
      return Status(StatusCode::kUnavailable, "the stream ended during the drag");
    }
    next += std::chrono::duration_cast<Clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  const std::uint64_t lastId = drag.lastId();
  if (!collector.waitFor(
          [&](const auto& frames) {
            return !frames.empty() && frames.back().frame.last_event_id() >= lastId &&
                   frames.back().frame.full_resolution();
          },
          30.0)) {
    return Status(StatusCode::kUnavailable,
                  fmt::format("no full-resolution frame within 30 s of the last event{}",
                              serverErrors(collector)));
  }
  return drag;
}

// Each event until the first frame (from `from` on) that reflects it.
std::vector<double> eventLatencies(const std::vector<FrameRecord>& frames, std::size_t from,
                                   const Drag& drag) {
  std::vector<double> latencies;
  std::size_t f = from;
  for (std::size_t e = 0; e < drag.sent.size(); ++e) {
    const std::uint64_t id = drag.firstId + e;
    while (f < frames.size() && frames[f].frame.last_event_id() < id) {
      ++f;
    }
    if (f < frames.size()) {
      latencies.push_back(ms(frames[f].received - drag.sent[e]));
    }
  }
  return latencies;
}

Result<Report> run(const RenderBenchOptions& options) {
  CRACKVIS_RETURN_IF_ERROR(checkHostPort("--server", options.server));
  auto material = tls::loadTlsMaterial(options.tls);
  if (!material) {
    return material.status();
  }
  auto described = benchDescription(options, options.files.front());
  if (!described) {
    return described.status();
  }
  const pipeline::PipelineDescription d = std::move(described).value();
  auto created = makeChannel(options, *material);
  if (!created) {
    return created.status();
  }
  const auto channel = std::move(created).value();
  // makeChannel awaited the connection: a client is connected before its
  // user chooses a file (it listed the files first), so the TCP and TLS
  // handshakes are not part of the first picture. A server that cannot be
  // reached is reported by the first call, with gRPC's reason.
  auto stub = v1::RenderService::NewStub(channel);
  const LoadAverage loadBefore = loadAverage();
  std::vector<FirstPicture> firstPictures;
  for (int k = 0; k < options.firstPictures; ++k) {
    if (k > 0 && options.firstPictureGap > 0) {
      std::this_thread::sleep_for(std::chrono::duration<double>(options.firstPictureGap));
    }
    auto picture = timeFirstPicture(*stub, options, d, channel);
    if (!picture) {
      return picture.status();
    }
    firstPictures.push_back(*picture);
  }

  auto session = openSession(*stub, options, d, channel);
  if (!session) {
    return session.status();
  }
  const v1::OpenSessionResponse& opened = *session;
  Report report;
  report.firstPictures = std::move(firstPictures);
  report.backend = opened.backend();
  report.loadBefore = loadBefore;
  report.width = d.view.width;
  report.height = d.view.height;
  report.particles = opened.particle_count();

  grpc::ClientContext streamContext;
  authorize(streamContext, options);
  auto stream = stub->Stream(&streamContext);
  v1::ClientEvent attach;
  attach.set_attach_session_id(opened.session_id());
  const auto attached = Clock::now();
  stream->Write(attach);
  FrameCollector collector(stream.get());
  auto finish = [&](Status status) -> Result<Report> {
    stream->WritesDone();
    (void)stream->Finish();
    closeSession(*stub, options, opened.session_id());
    if (!status) {
      return status;
    }
    return report;
  };
  if (!collector.waitFor([](const auto& frames) { return !frames.empty(); }, 120.0)) {
    return finish(Status(StatusCode::kUnavailable, "no first frame within 120 s"));
  }
  const auto firstFrames = collector.frames();
  report.firstFrameMs = ms(firstFrames.front().received - attached);
  report.step = firstFrames.front().frame.step();
  const std::size_t before = firstFrames.size();

  auto dragged = dragCamera(*stream, collector, options, 1);
  if (!dragged) {
    return finish(dragged.status());
  }
  const Drag& drag = *dragged;
  const auto lastEvent = drag.sent.back();
  report.interactionSeconds = ms(lastEvent - drag.start) / 1000.0;
  const std::uint64_t lastId = drag.lastId();
  const auto frames = collector.frames();
  report.events = drag.sent.size();
  report.latencies = eventLatencies(frames, before, drag);
  std::uint64_t bytes = 0;
  for (std::size_t k = before; k < frames.size(); ++k) {
    const auto& frame = frames[k].frame;
    if (frames[k].received <= lastEvent) {
      ++report.interactiveFrames;
      report.dragSpheresAtMost2x =
          report.dragSpheresAtMost2x && frame.reduction() <= 2 && frame.particles() == "spheres";
      bytes += frames[k].bytes;
      if (frame.timings().event_to_send_ms() > 0.0) {
        report.serverEventToSendMs.push_back(frame.timings().event_to_send_ms());
      }
    }
    (frame.full_resolution() ? report.fullRenderMs : report.reducedRenderMs)
        .push_back(frame.timings().render_ms());
    report.encodeMs.push_back(frame.timings().encode_ms());
    report.decodeMs.push_back(frames[k].decodeMs);
    report.reductions.push_back(frame.reduction());
    if (frame.full_resolution() && frame.last_event_id() >= lastId &&
        report.refineAfterIdleMs < 0.0) {
      report.refineAfterIdleMs = ms(frames[k].received - lastEvent);
    }
  }
  // Still renders: a small camera move that is not part of a drag
  // (CameraEvent.still), answered by a full-resolution frame, one at a time,
  // each waited for (and a pause after it, so the next one starts from an
  // idle session): ParaView's still render, a camera change and Render().
  for (int k = 0; k < options.stillFrames; ++k) {
    const std::uint64_t moveId = lastId + static_cast<std::uint64_t>(k) + 1;
    v1::ClientEvent move;
    move.set_event_id(moveId);
    move.mutable_camera()->set_kind(v1::CameraEvent::ROTATE);
    move.mutable_camera()->set_dx(1.8 / options.eventRate);
    move.mutable_camera()->set_still(true);
    const std::size_t seen = collector.frames().size();
    const auto sentAt = Clock::now();
    if (!stream->Write(move)) {
      return finish(Status(StatusCode::kUnavailable, "the stream ended during the still renders"));
    }
    if (!collector.waitFor(
            [&](const auto& arrived) {
              return arrived.size() > seen && arrived.back().frame.last_event_id() >= moveId &&
                     arrived.back().frame.full_resolution();
            },
            30.0)) {
      return finish(Status(StatusCode::kUnavailable,
                           fmt::format("no full-resolution frame within 30 s of a still camera "
                                       "move{}",
                                       serverErrors(collector))));
    }
    const auto answered = collector.frames();
    for (std::size_t a = seen; a < answered.size(); ++a) {
      if (answered[a].frame.last_event_id() >= moveId && answered[a].frame.full_resolution()) {
        report.stillLatencies.push_back(ms(answered[a].received - sentAt));
        report.stillRenderMs.push_back(answered[a].frame.timings().render_ms());
        break;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  for (const FrameRecord& record : collector.frames()) {
    ++report.frameKinds[frameKind(record.frame)];
    report.frames.push_back({{"frame", record.frame.frame_id()},
                             {"last_event", record.frame.last_event_id()},
                             {"reduction", record.frame.reduction()},
                             {"particles", record.frame.particles()},
                             {"render_ms", record.frame.timings().render_ms()}});
  }
  // The session's encoder shares the cores with its renderer; the same
  // frames encoded here with the same settings, alone, time the encoder.
  const auto pictures = collector.pictures();
  if (!pictures.empty()) {
    auto encoder = encode::FrameEncoder::create(
        {pictures.front().width, pictures.front().height, d.stream.fps, d.stream.bitrate});
    if (encoder) {
      for (std::size_t k = 0; k < pictures.size(); ++k) {
        const auto encodeStart = Clock::now();
        if ((*encoder)->encode(pictures[k], k == 0)) {
          report.isolatedEncodeMs.push_back(ms(Clock::now() - encodeStart));
        }
      }
    }
  }
  // Jumps and playback last: their frames are not part of the drag's figures.
  std::uint64_t nextId = lastId + static_cast<std::uint64_t>(options.stillFrames) + 1;
  if (Status status = measureJumps(*stream, collector, nextId, opened.step_count(), report.step,
                                   options, report.jumps);
      !status) {
    return finish(status);
  }
  const int shown = report.jumps.empty() ? report.step : report.jumps.back().to;
  if (Status status = measurePlayback(*stream, collector, nextId, opened.step_count(), shown,
                                      options, report.playback);
      !status) {
    return finish(status);
  }
  report.loadAfter = loadAverage();
  report.bitsPerSecond = report.interactionSeconds > 0
                             ? 8.0 * static_cast<double>(bytes) / report.interactionSeconds
                             : 0.0;
  return finish(Status::ok());
}

nlohmann::json toJson(const FirstPicture& p) {
  const v1::FrameTimings& s = p.server;
  const double server = s.open_ms() + s.renderer_ms() + s.load_ms() + s.extract_ms() +
                        s.scene_ms() + s.render_ms() + s.encode_ms();
  return {{"total_ms", p.totalMs()},
          {"open_session_ms", p.openSessionMs},
          {"first_frame_ms", p.firstFrameMs},
          {"server",
           {{"open_file_ms", s.open_ms()},
            {"describe_ms", s.describe_ms()},
            {"renderer_ms", s.renderer_ms()},
            {"load_ms", s.load_ms()},
            {"extract_ms", s.extract_ms()},
            {"scene_ms", s.scene_ms()},
            {"render_ms", s.render_ms()},
            {"encode_ms", s.encode_ms()}}},
          {"other_ms", p.totalMs() - server}};
}

// The first open, and the median of the later ones by their total.
nlohmann::json firstPictureJson(const std::vector<FirstPicture>& opens) {
  nlohmann::json all = nlohmann::json::array();
  for (const FirstPicture& p : opens) {
    all.push_back(toJson(p));
  }
  nlohmann::json out{{"opens", all}};
  if (!opens.empty()) {
    out["first"] = all.front();
  }
  if (opens.size() > 1) {
    std::vector<std::size_t> later(opens.size() - 1);
    std::iota(later.begin(), later.end(), std::size_t{1});
    std::sort(later.begin(), later.end(), [&](std::size_t a, std::size_t b) {
      return opens[a].totalMs() < opens[b].totalMs();
    });
    out["later_median"] = all[later[later.size() / 2]];
  }
  return out;
}

nlohmann::json jumpsJson(const std::vector<Jump>& jumps) {
  std::vector<double> full;
  std::vector<double> first;
  std::vector<double> forward;
  std::vector<double> backward;
  std::vector<double> load;
  std::vector<double> extract;
  nlohmann::json list = nlohmann::json::array();
  for (const Jump& j : jumps) {
    full.push_back(j.fullFrameMs);
    first.push_back(j.firstFrameMs);
    (j.to > j.from ? forward : backward).push_back(j.fullFrameMs);
    load.push_back(j.loadMs);
    extract.push_back(j.extractMs);
    list.push_back({{"from", j.from},
                    {"to", j.to},
                    {"first_frame_ms", j.firstFrameMs},
                    {"full_frame_ms", j.fullFrameMs},
                    {"load_ms", j.loadMs},
                    {"extract_ms", j.extractMs}});
  }
  return {{"count", jumps.size()},
          {"full_frame_ms", summaryJson(full)},
          {"forward_full_frame_ms", summaryJson(forward)},
          {"backward_full_frame_ms", summaryJson(backward)},
          {"first_frame_ms", summaryJson(first)},
          {"server_load_ms", summaryJson(load)},
          {"server_extract_ms", summaryJson(extract)},
          {"list", list}};
}

nlohmann::json playbackJson(const std::optional<Playback>& p) {
  if (!p) {
    return nullptr;
  }
  const double largest =
      p->gapsMs.empty() ? 0.0 : *std::max_element(p->gapsMs.begin(), p->gapsMs.end());
  return {{"rate", p->rate},
          {"first_step", p->firstStep},
          {"steps", p->steps},
          {"seconds", p->seconds},
          {"achieved_rate", p->seconds > 0.0 ? p->steps / p->seconds : 0.0},
          {"gap_ms", summaryJson(p->gapsMs)},
          {"gap_max_ms", largest},
          {"missed_slots", p->missedSlots},
          {"steps_not_shown", p->stepsNotShown}};
}

// Issue 34's goals for jumps and playback, where they were measured.
void addTimeTargets(const Report& r, nlohmann::json& targets) {
  if (!r.jumps.empty()) {
    std::vector<double> full;
    for (const Jump& j : r.jumps) {
      full.push_back(j.fullFrameMs);
    }
    targets["jump_full_frame_p95_le_100ms"] = percentile(full, 95) <= 100.0;
  }
  if (r.playback) {
    targets["playback_no_missed_slots"] =
        r.playback->missedSlots == 0 && r.playback->stepsNotShown == 0;
  }
}

nlohmann::json toJson(const Report& r) {
  std::vector<double> reductions(r.reductions.begin(), r.reductions.end());
  const double fps = r.interactionSeconds > 0
                         ? static_cast<double>(r.interactiveFrames) / r.interactionSeconds
                         : 0;
  nlohmann::json out{{"backend", r.backend},
                     {"size", fmt::format("{}x{}", r.width, r.height)},
                     {"particles", r.particles},
                     {"step", r.step},
                     {"first_frame_ms", r.firstFrameMs},
                     {"first_picture", firstPictureJson(r.firstPictures)},
                     {"events", r.events},
                     {"event_to_frame_ms", summaryJson(r.latencies)},
                     {"interactive_fps", fps},
                     {"interactive_bitrate_mbps", r.bitsPerSecond / 1e6},
                     {"render_reduced_ms", summaryJson(r.reducedRenderMs)},
                     {"render_full_ms", summaryJson(r.fullRenderMs)},
                     {"encode_ms", summaryJson(r.encodeMs)},
                     {"server_event_to_send_ms", summaryJson(r.serverEventToSendMs)},
                     {"encode_alone_ms", summaryJson(r.isolatedEncodeMs)},
                     {"client_decode_ms", summaryJson(r.decodeMs)},
                     {"reduction", summaryJson(reductions)},
                     {"full_frame_after_idle_ms", r.refineAfterIdleMs},
                     {"full_resolution_event_to_frame_ms", summaryJson(r.stillLatencies)},
                     {"full_resolution_render_ms", summaryJson(r.stillRenderMs)},
                     {"frame_kinds", r.frameKinds},
                     {"frames", r.frames},
                     {"jumps", jumpsJson(r.jumps)},
                     {"playback", playbackJson(r.playback)},
                     {"machine", machineDescription()},
                     {"load_before", toJson(r.loadBefore)},
                     {"load_after", toJson(r.loadAfter)},
                     {"targets",
                      {{"event_to_frame_p50_le_60ms", percentile(r.latencies, 50) <= 60.0},
                       {"interactive_fps_ge_15", fps >= 15.0},
                       {"encode_p50_le_5ms", percentile(r.encodeMs, 50) <= 5.0},
                       {"full_frame_within_300ms_of_idle",
                        r.refineAfterIdleMs >= 0.0 && r.refineAfterIdleMs <= 300.0},
                       {"interactive_p50_le_40ms", percentile(r.latencies, 50) <= 40.0},
                       {"interactive_spheres_at_most_2x_reduction",
                        r.interactiveFrames > 0 && r.dragSpheresAtMost2x}}}};
  addTimeTargets(r, out["targets"]);
  return out;
}

void printFirstPicture(const nlohmann::json& first) {
  auto line = [](const char* what, const nlohmann::json& p) {
    const auto& s = p["server"];
    std::printf(
        "%s %8.1f ms = OpenSession %.1f + first frame %.1f; server: file opened %.1f (of it "
        "Describe %.1f), renderer %.1f, step read %.1f, extraction %.1f, scene %.1f, render %.1f, "
        "encode %.1f; other %.1f\n",
        what, p["total_ms"].get<double>(), p["open_session_ms"].get<double>(),
        p["first_frame_ms"].get<double>(), s["open_file_ms"].get<double>(),
        s["describe_ms"].get<double>(), s["renderer_ms"].get<double>(), s["load_ms"].get<double>(),
        s["extract_ms"].get<double>(), s["scene_ms"].get<double>(), s["render_ms"].get<double>(),
        s["encode_ms"].get<double>(), p["other_ms"].get<double>());
  };
  if (first.contains("first")) {
    std::printf("time to first picture (OpenSession to the first full-resolution frame):\n");
    line("  first open  ", first["first"]);
  }
  if (first.contains("later_median")) {
    line("  later, p50  ", first["later_median"]);
  }
}

void printJumps(const nlohmann::json& jumps) {
  if (jumps["count"].get<int>() == 0) {
    return;
  }
  auto line = [&](const char* what, const char* key) {
    const auto& s = jumps[key];
    std::printf("  %-26s %4d  p50 %8.1f  p95 %8.1f ms\n", what, s["count"].get<int>(),
                s["p50"].get<double>(), s["p95"].get<double>());
  };
  std::printf("jumps to random steps (SetStep until the frame showing the step):\n");
  line("full-resolution frame", "full_frame_ms");
  line("  forwards", "forward_full_frame_ms");
  line("  backwards", "backward_full_frame_ms");
  line("first frame (any size)", "first_frame_ms");
  line("server: step read", "server_load_ms");
  line("server: extraction", "server_extract_ms");
}

void printPlayback(const nlohmann::json& p) {
  if (p.is_null()) {
    return;
  }
  std::printf(
      "playback of steps %d..%d at %.1f steps/s: %.1f steps/s achieved, gap between steps p50 "
      "%.1f p95 %.1f max %.1f ms, %d of %d steps missed their slot (gap > 1.5 periods), %d not "
      "shown\n",
      p["first_step"].get<int>(), p["first_step"].get<int>() + p["steps"].get<int>(),
      p["rate"].get<double>(), p["achieved_rate"].get<double>(), p["gap_ms"]["p50"].get<double>(),
      p["gap_ms"]["p95"].get<double>(), p["gap_max_ms"].get<double>(), p["missed_slots"].get<int>(),
      p["steps"].get<int>(), p["steps_not_shown"].get<int>());
}

void printTable(const nlohmann::json& j) {
  std::printf(
      "crackvis bench render: %s, %lld particles, step %d\n%s\nmachine: %s; load before %s, after "
      "%s\n\n",
      j["size"].get<std::string>().c_str(), j["particles"].get<long long>(), j["step"].get<int>(),
      j["backend"].get<std::string>().c_str(), j["machine"].get<std::string>().c_str(),
      loadText(j["load_before"]).c_str(), loadText(j["load_after"]).c_str());
  std::printf("%-34s %10s %10s %10s %10s\n", "", "mean", "p50", "p90", "p99");
  for (const char* key : {"event_to_frame_ms", "full_resolution_event_to_frame_ms",
                          "render_reduced_ms", "render_full_ms", "full_resolution_render_ms",
                          "encode_ms", "encode_alone_ms", "client_decode_ms", "reduction"}) {
    const auto& s = j[key];
    std::printf("%-34s %10.2f %10.2f %10.2f %10.2f\n", key, s["mean"].get<double>(),
                s["p50"].get<double>(), s["p90"].get<double>(), s["p99"].get<double>());
  }
  printFirstPicture(j["first_picture"]);
  printJumps(j["jumps"]);
  printPlayback(j["playback"]);
  std::printf("\nfirst frame after attaching       %10.1f ms\n", j["first_frame_ms"].get<double>());
  std::printf("frames per second while dragging  %10.1f\n", j["interactive_fps"].get<double>());
  std::printf("bitrate while dragging            %10.2f Mbit/s\n",
              j["interactive_bitrate_mbps"].get<double>());
  std::printf("full-resolution frame after idle  %10.1f ms\n",
              j["full_frame_after_idle_ms"].get<double>());
  std::printf("frames drawn as (reduction, particles):");
  for (const auto& [kind, count] : j["frame_kinds"].items()) {
    std::printf(" %s x%d", kind.c_str(), count.get<int>());
  }
  std::printf("\n");
  std::printf("targets:");
  for (const auto& [name, met] : j["targets"].items()) {
    std::printf(" %s=%s", name.c_str(), met.get<bool>() ? "met" : "MISSED");
  }
  std::printf("\n\n");
}

// --sessions N: N users at once, each with its own connection, session,
// file (the --file list in turn) and view (turned k/N of a full turn), all
// dragging together. What each one feels, and what the server spends.
struct SessionFeel {
  std::string file;
  std::size_t events = 0;
  std::vector<double> latencies;
  std::size_t frames = 0;  // received during the drag
  double seconds = 0.0;
  std::vector<double> reductions;
  std::size_t coarseFrames = 0;    // drawn with coarse stand-ins (a crowded server)
  std::vector<double> turnWaitMs;  // the server's wait for its render turn, per frame
  std::vector<double> renderMs;
  std::string error;
};

// A process's CPU time and resident memory from /proc: the render server's,
// when it runs on this machine (--server-pid), sampled while sessions drag.
class ProcessSampler {
 public:
  explicit ProcessSampler(int pid) : m_pid(pid) {}
  ~ProcessSampler() { stop(); }
  void start() {
    if (m_pid <= 0) {
      return;
    }
    m_startTicks = cpuTicks();
    m_started = Clock::now();
    m_rssStartKib = rssKib();
    m_thread = std::thread([this] {
      std::unique_lock lock(m_mutex);
      while (!m_stopping) {
        m_rssPeakKib = std::max(m_rssPeakKib, rssKib());
        m_wake.wait_for(lock, std::chrono::milliseconds(100));
      }
    });
  }
  void stop() {
    if (!m_thread.joinable()) {
      return;
    }
    {
      std::lock_guard lock(m_mutex);
      m_stopping = true;
    }
    m_wake.notify_all();
    m_thread.join();
    m_cpuSeconds =
        static_cast<double>(cpuTicks() - m_startTicks) / static_cast<double>(sysconf(_SC_CLK_TCK));
    m_seconds = ms(Clock::now() - m_started) / 1000.0;
  }
  nlohmann::json json() const {
    if (m_pid <= 0 || m_seconds <= 0.0) {
      return nullptr;
    }
    return {{"pid", m_pid},
            {"cpu_cores", m_cpuSeconds / m_seconds},
            {"rss_start_mib", static_cast<double>(m_rssStartKib) / 1024.0},
            {"rss_peak_mib", static_cast<double>(m_rssPeakKib) / 1024.0}};
  }

 private:
  // utime + stime, the 14th and 15th fields of /proc/PID/stat, in ticks.
  long long cpuTicks() const {
    std::ifstream in(fmt::format("/proc/{}/stat", m_pid));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto name = text.rfind(')');  // the command name may hold spaces
    if (name == std::string::npos) {
      return 0;
    }
    std::istringstream fields(text.substr(name + 2));
    std::string field;
    long long ticks = 0;
    for (int k = 3; k <= 15 && fields >> field; ++k) {
      ticks += k >= 14 ? std::stoll(field) : 0;
    }
    return ticks;
  }
  long long rssKib() const {
    std::ifstream in(fmt::format("/proc/{}/status", m_pid));
    std::string key;
    long long value = 0;
    while (in >> key) {
      if (key == "VmRSS:" && in >> value) {
        return value;
      }
    }
    return 0;
  }

  int m_pid;
  std::thread m_thread;
  std::mutex m_mutex;
  std::condition_variable m_wake;
  bool m_stopping = false;
  long long m_startTicks = 0;
  Clock::time_point m_started;
  long long m_rssStartKib = 0;
  long long m_rssPeakKib = 0;
  double m_cpuSeconds = 0.0;
  double m_seconds = 0.0;
};

// Ends a session's stream before its collector (declared earlier) joins.
struct StreamEnd {
  grpc::ClientContext& context;
  SessionStream& stream;
  ~StreamEnd() {
    stream.WritesDone();
    context.TryCancel();
  }
};

Status dragAlongside(const RenderBenchOptions& options, const tls::TlsMaterial& material, int k,
                     std::barrier<>& together, bool& arrived, SessionFeel& feel) {
  auto described = benchDescription(options, feel.file);
  if (!described) {
    return described.status();
  }
  auto created = makeChannel(options, material);
  if (!created) {
    return created.status();
  }
  const auto channel = std::move(created).value();
  auto stub = v1::RenderService::NewStub(channel);
  auto opened = openSession(*stub, options, *described, channel);
  if (!opened) {
    return opened.status();
  }
  Status status;
  {
    grpc::ClientContext streamContext;
    authorize(streamContext, options);
    auto stream = stub->Stream(&streamContext);
    v1::ClientEvent attach;
    attach.set_attach_session_id(opened->session_id());
    stream->Write(attach);
    FrameCollector collector(stream.get(), false);
    StreamEnd end{streamContext, *stream};
    // Its own view: turned k/N of a full turn, as a still move (event 1).
    v1::ClientEvent turn;
    turn.set_event_id(1);
    turn.mutable_camera()->set_kind(v1::CameraEvent::ROTATE);
    turn.mutable_camera()->set_dx(1.8 * k / options.sessions);
    turn.mutable_camera()->set_still(true);
    stream->Write(turn);
    const bool ready = collector.waitFor(
        [](const auto& frames) {
          return !frames.empty() && frames.back().frame.last_event_id() >= 1 &&
                 frames.back().frame.full_resolution();
        },
        120.0);
    if (!ready) {
      return Status(StatusCode::kUnavailable,
                    fmt::format("no first frame within 120 s{}", serverErrors(collector)));
    }
    together.arrive_and_wait();
    arrived = true;
    const std::size_t before = collector.frames().size();
    auto drag = dragCamera(*stream, collector, options, 2);
    if (!drag) {
      status = drag.status();
    } else {
      const auto frames = collector.frames();
      feel.events = drag->sent.size();
      feel.latencies = eventLatencies(frames, before, *drag);
      feel.seconds = ms(drag->sent.back() - drag->start) / 1000.0;
      for (std::size_t f = before; f < frames.size(); ++f) {
        if (frames[f].received <= drag->sent.back()) {
          ++feel.frames;
          feel.reductions.push_back(std::max(1, frames[f].frame.reduction()));
          feel.coarseFrames += frames[f].frame.coarse() ? 1 : 0;
          feel.turnWaitMs.push_back(frames[f].frame.timings().turn_wait_ms());
          feel.renderMs.push_back(frames[f].frame.timings().render_ms());
        }
      }
    }
  }
  closeSession(*stub, options, opened->session_id());
  return status;
}

nlohmann::json toJson(const SessionFeel& feel) {
  return {{"file", feel.file},
          {"events", feel.events},
          {"event_to_frame_ms", summaryJson(feel.latencies)},
          {"fps", feel.seconds > 0.0 ? static_cast<double>(feel.frames) / feel.seconds : 0.0},
          {"reduction_mean", mean(feel.reductions)},
          {"coarse_share", feel.frames > 0 ? static_cast<double>(feel.coarseFrames) /
                                                 static_cast<double>(feel.frames)
                                           : 0.0},
          {"server_turn_wait_ms", summaryJson(feel.turnWaitMs)},
          {"server_render_ms", summaryJson(feel.renderMs)},
          {"error", feel.error}};
}

Result<nlohmann::json> runSessions(const RenderBenchOptions& options) {
  CRACKVIS_RETURN_IF_ERROR(checkHostPort("--server", options.server));
  auto material = tls::loadTlsMaterial(options.tls);
  if (!material) {
    return material.status();
  }
  const int n = options.sessions;
  std::vector<SessionFeel> feels(static_cast<std::size_t>(n));
  std::barrier together(n + 1);  // the sessions, and this thread to start the sampler
  ProcessSampler server(options.serverPid);
  const LoadAverage loadBefore = loadAverage();
  std::vector<std::thread> users;
  for (int k = 0; k < n; ++k) {
    users.emplace_back([&, k] {
      SessionFeel& feel = feels[static_cast<std::size_t>(k)];
      feel.file = options.files[static_cast<std::size_t>(k) % options.files.size()];
      bool arrived = false;
      if (Status status = dragAlongside(options, *material, k, together, arrived, feel); !status) {
        feel.error = status.message();
      }
      if (!arrived) {
        together.arrive_and_drop();
      }
    });
  }
  together.arrive_and_wait();
  server.start();
  for (std::thread& user : users) {
    user.join();
  }
  server.stop();
  nlohmann::json each = nlohmann::json::array();
  std::vector<double> p50s;
  std::vector<double> p95s;
  int failed = 0;
  for (const SessionFeel& feel : feels) {
    each.push_back(toJson(feel));
    failed += feel.error.empty() ? 0 : 1;
    if (feel.error.empty()) {
      p50s.push_back(percentile(feel.latencies, 50));
      p95s.push_back(percentile(feel.latencies, 95));
    }
  }
  return nlohmann::json{
      {"sessions", n},
      {"size", options.size},
      {"seconds", options.seconds},
      {"event_rate", options.eventRate},
      {"per_session", each},
      {"failed", failed},
      {"p50_max_ms", p50s.empty() ? 0.0 : *std::max_element(p50s.begin(), p50s.end())},
      {"p50_median_ms", median(p50s)},
      {"p95_max_ms", p95s.empty() ? 0.0 : *std::max_element(p95s.begin(), p95s.end())},
      {"server", server.json()},
      {"machine", machineDescription()},
      {"load_before", toJson(loadBefore)},
      {"load_after", toJson(loadAverage())}};
}

void printSessions(const nlohmann::json& j) {
  std::printf(
      "crackvis bench render --sessions %d: %s, each dragging %.1f s at %.0f events/s\nmachine: "
      "%s; load before %s, after %s\n\n",
      j["sessions"].get<int>(), j["size"].get<std::string>().c_str(), j["seconds"].get<double>(),
      j["event_rate"].get<double>(), j["machine"].get<std::string>().c_str(),
      loadText(j["load_before"]).c_str(), loadText(j["load_after"]).c_str());
  std::printf("%-8s %-24s %7s %9s %9s %7s %9s %7s %10s %10s\n", "session", "file", "events",
              "p50 ms", "p95 ms", "fps", "reduction", "coarse", "turn wait", "render");
  int k = 0;
  for (const auto& s : j["per_session"]) {
    const auto& latency = s["event_to_frame_ms"];
    std::printf("%-8d %-24s %7zu %9.1f %9.1f %7.1f %9.2f %6.0f%% %10.1f %10.1f %s\n", ++k,
                s["file"].get<std::string>().c_str(), s["events"].get<std::size_t>(),
                latency["p50"].get<double>(), latency["p95"].get<double>(), s["fps"].get<double>(),
                s["reduction_mean"].get<double>(), 100.0 * s["coarse_share"].get<double>(),
                s["server_turn_wait_ms"]["p50"].get<double>(),
                s["server_render_ms"]["p50"].get<double>(), s["error"].get<std::string>().c_str());
  }
  std::printf("worst session: p50 %.1f ms, p95 %.1f ms; median session p50 %.1f ms\n",
              j["p50_max_ms"].get<double>(), j["p95_max_ms"].get<double>(),
              j["p50_median_ms"].get<double>());
  const auto& server = j["server"];
  if (server.is_null()) {
    std::printf("server: not sampled (--server-pid for a server on this machine)\n\n");
  } else {
    std::printf(
        "server (pid %d): %.2f cores busy, resident %.0f MiB at the start, %.0f MiB peak\n\n",
        server["pid"].get<int>(), server["cpu_cores"].get<double>(),
        server["rss_start_mib"].get<double>(), server["rss_peak_mib"].get<double>());
  }
}

int runBenchSessions(const RenderBenchOptions& options) {
  auto report = runSessions(options);
  if (!report) {
    printError("bench render", report.status().message());
    return kExitFailure;
  }
  if (!options.jsonOnly) {
    printSessions(*report);
  }
  std::printf("%s\n", report->dump(2).c_str());
  return (*report)["failed"].get<int>() == 0 ? kExitOk : kExitFailure;
}

int runBenchRender(const RenderBenchOptions& options) {
  if (options.sessions > 0) {
    return runBenchSessions(options);
  }
  auto report = run(options);
  if (!report) {
    printError("bench render", report.status().message());
    return kExitFailure;
  }
  const auto json = toJson(*report);
  if (!options.jsonOnly) {
    printTable(json);
  }
  std::printf("%s\n", json.dump(2).c_str());
  return kExitOk;
}

}  // namespace

Command addBenchRenderCommand(CLI::App& bench) {
  auto options = std::make_shared<RenderBenchOptions>();
  auto* command = bench.add_subcommand(
      "render",
      "Interactive and still rendering against a running crackvis-render: first the time to "
      "the first picture (--first-pictures sessions, each timed from OpenSession to its first "
      "full-resolution frame, split into the server's parts), then opens a session "
      "(particles as sphere impostors + crack surfaces), drags the camera with rotate events "
      "(the interactive event-to-frame latency), then makes --still-frames isolated still camera "
      "moves, each answered by a full-resolution frame (the full-resolution event-to-frame "
      "latency, ParaView's still render), then --jumps step changes to random steps and a "
      "playback of --playback-steps steps. Prints latency percentiles, frames per second, render "
      "and encode times, how each frame was drawn (reduction factor, particles as spheres or "
      "flat points) and the load, as a table and as JSON.");
  command->add_option("--server", options->server, "crackvis-render address, HOST:PORT")
      ->required();
  command
      ->add_option("--file", options->files,
                   "crackvis-dem file under the data service's root; with --sessions, several "
                   "(repeat --file), taken in turn by the sessions")
      ->required();
  command->add_option("--step", options->step, "step to show (default: the last)");
  command->add_option("--size", options->size, "view size WIDTHxHEIGHT")->capture_default_str();
  command->add_option("-p,--pipeline", options->pipelinePath,
                      "pipeline description to render (its file, step and size are replaced by "
                      "--file, --step and --size; default: particles as impostors + cracks)");
  command->add_option("-m,--method", options->method, "crack method")
      ->capture_default_str()
      ->check(CLI::IsMember({"cell-attribute", "cell-cut", "local-voronoi", "cell-centre"}));
  command->add_option("--seconds", options->seconds, "length of the drag")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 600.0));
  command->add_option("--event-rate", options->eventRate, "rotate events per second")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  command
      ->add_option("--still-frames", options->stillFrames,
                   "isolated camera moves answered at full resolution (0: none)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  command
      ->add_option("--first-pictures", options->firstPictures,
                   "sessions opened, each until its first full-resolution frame, and closed "
                   "before the drag: the time to the first picture, the first open (cold on "
                   "services started fresh) and the median of the others (warm)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100));
  command
      ->add_option("--first-picture-gap", options->firstPictureGap,
                   "seconds between a first-picture session's close and the next open (0: at "
                   "once, the browser's pattern; over a second: the render server's heap "
                   "trimmed meanwhile)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 60.0));
  command
      ->add_option("--jumps", options->jumps,
                   "step changes to random other steps after the still moves, forwards and "
                   "backwards, each timed until its full-resolution frame (0: none)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000));
  command
      ->add_option("--sessions", options->sessions,
                   "instead of the single-session run: N sessions at once, each with its own "
                   "connection, file (the --file list in turn) and view, all dragging together "
                   "for --seconds; prints each one's event-to-frame p50 and p95, frame rate, "
                   "reduction and share of coarse frames, and the server's CPU and memory with "
                   "--server-pid")
      ->check(CLI::Range(1, 64));
  command
      ->add_option("--server-pid", options->serverPid,
                   "with --sessions: the render server's process on this machine, whose CPU time "
                   "and resident memory are sampled from /proc during the drag")
      ->check(CLI::PositiveNumber);
  command->add_option("--seed", options->seed, "seed of the random jumps")->capture_default_str();
  command
      ->add_option("--playback-steps", options->playbackSteps,
                   "steps played at --playback-rate, ending at the last step, counting the steps "
                   "that miss their slot (0: no playback)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000000));
  command->add_option("--playback-rate", options->playbackRate, "steps per second when playing")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  command->add_option("--ca", options->tls.ca, "CA certificate that signed the server's (PEM)")
      ->capture_default_str();
  command->add_option("--cert", options->tls.cert, "client certificate (PEM)")
      ->capture_default_str();
  command->add_option("--key", options->tls.key, "client private key (PEM)")->capture_default_str();
  command->add_option("--token", options->token, "bearer token, when the server has users");
  command->add_flag("--json", options->jsonOnly, "print only the JSON");
  command->footer(
      "Example: crackvis bench render --server localhost:50052 --file cuboidA.h5 --size 1280x720");
  return {command, [options, command] {
            options->methodGiven = command->count("--method") > 0;
            return runBenchRender(*options);
          }};
}

}  // namespace crackvis::cli
