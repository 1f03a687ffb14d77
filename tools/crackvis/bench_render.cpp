// crackvis bench render: what a user of a remote session feels, measured in
// one run against a running crackvis-render. Opens a session on a file's
// step (particles as sphere impostors + crack surfaces) at a given size,
// drags the camera with rotate events at a mouse's rate, and reports from
// the frames that come back: event-to-frame latency percentiles (each event
// until the first frame that reflects it, as the client receives it), frame
// rate while interacting, render and encode times, the reduction factors
// used, and how long after the last event the full-resolution frame came.
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <numeric>
#include <thread>

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <nlohmann/json.hpp>

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
  std::string file;
  int step = -1;
  std::string size = "1280x720";
  std::string method = "local-voronoi";
  std::string pipelinePath;
  double seconds = 5.0;
  double eventRate = 60.0;  // events per second, a mouse drag's rate
  int stillFrames = 10;     // isolated camera moves answered at full resolution
  int firstPictures = 3;    // sessions opened and closed for the time to the first picture
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
  explicit FrameCollector(grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>* stream)
      : m_stream(stream), m_thread([this] { run(); }) {}
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
    return m_pictures;
  }
  static constexpr std::size_t kKeptPictures = 30;

 private:
  void run() {
    auto decoder = encode::FrameDecoder::create();
    v1::ServerMessage message;
    while (m_stream->Read(&message)) {
      const auto received = Clock::now();
      if (message.has_frame()) {
        FrameRecord record{received, message.frame(), message.frame().h264().size(), 0.0};
        if (decoder) {
          encode::EncodedFrame unit;
          unit.data.assign(message.frame().h264().begin(), message.frame().h264().end());
          const auto start = Clock::now();
          auto picture = (*decoder)->decode(unit);
          record.decodeMs = ms(Clock::now() - start);
          if (picture && picture->has_value()) {
            std::lock_guard lock(m_mutex);
            m_pictures.push_back(std::move(**picture));
            if (m_pictures.size() > kKeptPictures) {
              m_pictures.erase(m_pictures.begin());
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
  std::mutex m_mutex;
  std::condition_variable m_changed;
  std::vector<FrameRecord> m_frames;
  std::vector<std::string> m_errors;
  std::vector<encode::RgbFrame> m_pictures;
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
  LoadAverage loadBefore;
  LoadAverage loadAfter;
};

std::string particleDrawingName(const v1::Frame& frame) {
  return frame.particles().empty() ? "(particles not reported)" : frame.particles();
}

std::string frameKind(const v1::Frame& frame) {
  return fmt::format("1/{} {}", std::max(1, frame.reduction()), particleDrawingName(frame));
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
  return tls::createChannel(channel);
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

Result<Report> run(const RenderBenchOptions& options) {
  CRACKVIS_RETURN_IF_ERROR(checkHostPort("--server", options.server));
  auto material = tls::loadTlsMaterial(options.tls);
  if (!material) {
    return material.status();
  }
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
  d.file = options.file;
  d.step = options.step;
  d.view.width = size->first;
  d.view.height = size->second;
  if (options.pipelinePath.empty() || options.methodGiven) {
    d.cracks.method = *method;
  }
  auto created = makeChannel(options, *material);
  if (!created) {
    return created.status();
  }
  const auto channel = std::move(created).value();
  auto stub = v1::RenderService::NewStub(channel);
  const LoadAverage loadBefore = loadAverage();
  std::vector<FirstPicture> firstPictures;
  for (int k = 0; k < options.firstPictures; ++k) {
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

  // The drag: rotate events at the mouse's rate, a full turn per 4 s.
  std::vector<Clock::time_point> sent;
  const auto period = std::chrono::duration<double>(1.0 / options.eventRate);
  const auto start = Clock::now();
  auto next = start;
  while (ms(Clock::now() - start) < options.seconds * 1000.0) {
    v1::ClientEvent event;
    event.set_event_id(sent.size() + 1);
    event.mutable_camera()->set_kind(v1::CameraEvent::ROTATE);
    event.mutable_camera()->set_dx(1.8 / options.eventRate);  // 360 degrees / 200 per view / 4 s
    event.mutable_camera()->set_dy(0.0);
    sent.push_back(Clock::now());
    if (!stream->Write(event)) {
      return finish(Status(StatusCode::kUnavailable, "the stream ended during the drag"));
    }
    next += std::chrono::duration_cast<Clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  const auto lastEvent = sent.back();
  report.interactionSeconds = ms(lastEvent - start) / 1000.0;
  const std::uint64_t lastId = sent.size();
  if (!collector.waitFor(
          [&](const auto& frames) {
            return frames.back().frame.last_event_id() >= lastId &&
                   frames.back().frame.full_resolution();
          },
          30.0)) {
    return finish(Status(StatusCode::kUnavailable,
                         fmt::format("no full-resolution frame within 30 s of the last event{}",
                                     serverErrors(collector))));
  }
  const auto frames = collector.frames();
  report.events = sent.size();
  // Each event until the first frame that reflects it.
  std::size_t f = before;
  for (std::size_t e = 0; e < sent.size(); ++e) {
    while (f < frames.size() && frames[f].frame.last_event_id() < e + 1) {
      ++f;
    }
    if (f < frames.size()) {
      report.latencies.push_back(ms(frames[f].received - sent[e]));
    }
  }
  std::uint64_t bytes = 0;
  for (std::size_t k = before; k < frames.size(); ++k) {
    const auto& frame = frames[k].frame;
    if (frames[k].received <= lastEvent) {
      ++report.interactiveFrames;
      report.dragSpheresAtMost2x =
          report.dragSpheresAtMost2x && frame.reduction() <= 2 && frame.particles() == "spheres";
      bytes += frames[k].bytes;
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
    const std::uint64_t moveId = sent.size() + static_cast<std::uint64_t>(k) + 1;
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

nlohmann::json toJson(const Report& r) {
  std::vector<double> reductions(r.reductions.begin(), r.reductions.end());
  const double fps = r.interactionSeconds > 0
                         ? static_cast<double>(r.interactiveFrames) / r.interactionSeconds
                         : 0;
  return nlohmann::json{{"backend", r.backend},
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
                        {"encode_alone_ms", summaryJson(r.isolatedEncodeMs)},
                        {"client_decode_ms", summaryJson(r.decodeMs)},
                        {"reduction", summaryJson(reductions)},
                        {"full_frame_after_idle_ms", r.refineAfterIdleMs},
                        {"full_resolution_event_to_frame_ms", summaryJson(r.stillLatencies)},
                        {"full_resolution_render_ms", summaryJson(r.stillRenderMs)},
                        {"frame_kinds", r.frameKinds},
                        {"frames", r.frames},
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
}

void printFirstPicture(const nlohmann::json& first) {
  auto line = [](const char* what, const nlohmann::json& p) {
    const auto& s = p["server"];
    std::printf(
        "%s %8.1f ms = OpenSession %.1f + first frame %.1f; server: file opened %.1f, renderer "
        "%.1f, step read %.1f, extraction %.1f, scene %.1f, render %.1f, encode %.1f; other "
        "%.1f\n",
        what, p["total_ms"].get<double>(), p["open_session_ms"].get<double>(),
        p["first_frame_ms"].get<double>(), s["open_file_ms"].get<double>(),
        s["renderer_ms"].get<double>(), s["load_ms"].get<double>(), s["extract_ms"].get<double>(),
        s["scene_ms"].get<double>(), s["render_ms"].get<double>(), s["encode_ms"].get<double>(),
        p["other_ms"].get<double>());
  };
  if (first.contains("first")) {
    std::printf("time to first picture (OpenSession to the first full-resolution frame):\n");
    line("  first open  ", first["first"]);
  }
  if (first.contains("later_median")) {
    line("  later, p50  ", first["later_median"]);
  }
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

int runBenchRender(const RenderBenchOptions& options) {
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
      "latency, ParaView's still render). Prints latency percentiles, frames per second, render "
      "and encode times, how each frame was drawn (reduction factor, particles as spheres or "
      "flat points) and the load, as a table and as JSON.");
  command->add_option("--server", options->server, "crackvis-render address, HOST:PORT")
      ->required();
  command->add_option("--file", options->file, "crackvis-dem file under the data service's root")
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
