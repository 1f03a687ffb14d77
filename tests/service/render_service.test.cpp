// The render service end to end: a real crackvis-data and a real
// crackvis-render (in process, loopback ports, mutual TLS with certificates
// from certs/make-dev-certs.sh), real EGL rendering on llvmpipe, real H.264
// decoded on the test's side. The data is a scaled simulated cuboid A.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <thread>

#include <catch2/catch.hpp>
#include <grpcpp/grpcpp.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <unistd.h>

#include "crackvis/v1/render.grpc.pb.h"
#include "dataservice/service_fixture.hpp"
#include "grpc/health/v1/health.grpc.pb.h"
#include "service/render_fixture.hpp"
#include "support/process.hpp"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/encode/frame_codec.hpp>
#include <crackvis/importers/importer.hpp>
#include <crackvis/importers/step_source.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/render/egl_context.hpp>
#include <crackvis/rpc/grpc_status.hpp>
#include <crackvis/rpc_server/credentials.hpp>
#include <crackvis/service/render_server.hpp>
#include <crackvis/sim/presets.hpp>
#include <crackvis/sim/run.hpp>

using namespace crackvis;
using namespace crackvis::testing;
namespace v1 = crackvis::v1;

namespace {

std::unique_ptr<v1::RenderService::Stub> connect(const service::RenderServer& server,
                                                 const std::string& certificate = "client") {
  const auto tls = testing::clientTls(certificate);
  auto read = [](const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  grpc::SslCredentialsOptions ssl{read(tls.ca), read(tls.key), read(tls.cert)};
  return v1::RenderService::NewStub(
      grpc::CreateChannel(fmt::format("localhost:{}", server.port()), grpc::SslCredentials(ssl)));
}

std::string openSession(v1::RenderService::Stub& stub, const pipeline::PipelineDescription& d,
                        v1::OpenSessionResponse* response = nullptr) {
  grpc::ClientContext context;
  v1::OpenSessionRequest request;
  request.set_pipeline_xml(pipeline::toXml(d));
  v1::OpenSessionResponse local;
  auto* out = response != nullptr ? response : &local;
  const grpc::Status status = stub.OpenSession(&context, request, out);
  INFO(status.error_message());
  REQUIRE(status.ok());
  return out->session_id();
}

grpc::Status openStatus(v1::RenderService::Stub& stub, const std::string& xml) {
  grpc::ClientContext context;
  v1::OpenSessionRequest request;
  request.set_pipeline_xml(xml);
  v1::OpenSessionResponse response;
  return stub.OpenSession(&context, request, &response);
}

struct ReceivedFrame {
  v1::Frame frame;
  encode::RgbFrame picture;
};

// A stream attached to a session: a reader thread decodes every frame.
class StreamClient {
 public:
  StreamClient(v1::RenderService::Stub& stub, const std::string& session,
               const std::string& token = "") {
    if (!token.empty()) {
      m_context.AddMetadata("authorization", "Bearer " + token);
    }
    m_stream = stub.Stream(&m_context);
    v1::ClientEvent attach;
    attach.set_event_id(0);
    attach.set_attach_session_id(session);
    REQUIRE(m_stream->Write(attach));
    auto decoder = encode::FrameDecoder::create();
    REQUIRE(decoder.isOk());
    m_decoder = std::move(decoder).value();
    m_reader = std::thread([this] { readLoop(); });
  }
  ~StreamClient() {
    if (!m_finished) {
      m_context.TryCancel();
    }
    m_reader.join();
  }

  std::uint64_t send(v1::ClientEvent event) {
    event.set_event_id(++m_lastEvent);
    REQUIRE(m_stream->Write(event));
    return m_lastEvent;
  }
  std::uint64_t rotate(double dx, double dy = 0.0, bool still = false) {
    v1::ClientEvent event;
    event.mutable_camera()->set_kind(v1::CameraEvent::ROTATE);
    event.mutable_camera()->set_dx(dx);
    event.mutable_camera()->set_dy(dy);
    event.mutable_camera()->set_still(still);
    return send(event);
  }
  std::uint64_t setStep(int step) {
    v1::ClientEvent event;
    event.mutable_set_step()->set_step(step);
    return send(event);
  }

  // Waits until `done(frames, errors)` holds; false after `seconds`.
  template <typename Done>
  bool waitFor(Done done, double seconds = 30.0) {
    std::unique_lock lock(m_mutex);
    return m_changed.wait_for(lock, std::chrono::duration<double>(seconds), [&] {
      return done(m_frames, m_errors) || m_ended;
    }) && done(m_frames, m_errors);
  }
  std::vector<ReceivedFrame> frames() {
    std::lock_guard lock(m_mutex);
    return m_frames;
  }
  std::vector<v1::EventError> errors() {
    std::lock_guard lock(m_mutex);
    return m_errors;
  }
  std::vector<v1::SessionState> states() {
    std::lock_guard lock(m_mutex);
    return m_states;
  }
  // Ends the stream like a vanished client: no goodbye, the call just dies.
  void vanish() { m_context.TryCancel(); }
  grpc::Status finish() {
    m_stream->WritesDone();
    m_reader.join();
    m_reader = std::thread([] {});
    m_finished = true;
    return m_status;
  }

 private:
  void readLoop() {
    v1::ServerMessage message;
    while (m_stream->Read(&message)) {
      std::lock_guard lock(m_mutex);
      if (message.has_frame()) {
        ReceivedFrame received{message.frame(), {}};
        encode::EncodedFrame unit;
        const auto& bytes = message.frame().h264();
        unit.data.assign(bytes.begin(), bytes.end());
        unit.keyframe = message.frame().keyframe();
        auto picture = m_decoder->decode(unit);
        if (picture.isOk() && picture->has_value()) {
          received.picture = std::move(**picture);
        }
        m_frames.push_back(std::move(received));
      } else if (message.has_error()) {
        m_errors.push_back(message.error());
      } else if (message.has_state()) {
        m_states.push_back(message.state());
      }
      m_changed.notify_all();
    }
    std::lock_guard lock(m_mutex);
    m_status = m_stream->Finish();
    m_ended = true;
    m_changed.notify_all();
  }

  grpc::ClientContext m_context;
  std::unique_ptr<grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>> m_stream;
  std::unique_ptr<encode::FrameDecoder> m_decoder;
  std::thread m_reader;
  std::mutex m_mutex;
  std::condition_variable m_changed;
  std::vector<ReceivedFrame> m_frames;
  std::vector<v1::EventError> m_errors;
  std::vector<v1::SessionState> m_states;
  grpc::Status m_status;
  bool m_ended = false;
  bool m_finished = false;
  std::uint64_t m_lastEvent = 0;
};

bool reddish(const std::uint8_t* p) {
  return p[0] > 120 && p[1] < 80 && p[2] < 80;
}

int redPixels(const encode::RgbFrame& picture) {
  int n = 0;
  for (std::size_t i = 0; i + 2 < picture.rgb.size(); i += 3) {
    n += reddish(&picture.rgb[i]) ? 1 : 0;
  }
  return n;
}

double meanDifference(const encode::RgbFrame& a, const encode::RgbFrame& b) {
  if (a.rgb.size() != b.rgb.size() || a.rgb.empty()) {
    return 255.0;
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) {
    sum += std::abs(static_cast<int>(a.rgb[i]) - static_cast<int>(b.rgb[i]));
  }
  return sum / static_cast<double>(a.rgb.size());
}

}  // namespace

TEST_CASE("a session streams frames that follow the client's events",
          "[render][service][integration]") {
  auto services = startServices();
  auto stub = connect(*services.render);
  v1::OpenSessionResponse opened;
  const std::string id = openSession(*stub, crackView(), &opened);
  CHECK(opened.step_count() > 10);
  CHECK(opened.backend().find("EGL") != std::string::npos);
  StreamClient stream(*stub, id);

  // The first frame: a full-resolution keyframe of the cracks, in red.
  REQUIRE(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
  const ReceivedFrame first = stream.frames().front();
  CHECK(first.frame.keyframe());
  CHECK(first.frame.full_resolution());
  CHECK(first.frame.width() == 320);
  CHECK(first.frame.step() == opened.step_count() - 1);
  REQUIRE(first.picture.width == 320);
  CHECK(redPixels(first.picture) > 200);

  // A drag: 40 rotate events; every one is reflected by some frame, frames
  // come at reduced resolution while the drag goes on, then a full one.
  std::uint64_t last = 0;
  for (int k = 0; k < 40; ++k) {
    last = stream.rotate(0.01);
    std::this_thread::sleep_for(std::chrono::milliseconds(15));
  }
  REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
    return frames.size() >= 30 && frames.back().frame.last_event_id() == last &&
           frames.back().frame.full_resolution();
  }));
  const auto frames = stream.frames();
  CHECK(frames.size() >= 30);
  bool reduced = false;
  for (std::size_t k = 1; k < frames.size(); ++k) {
    CHECK(frames[k].frame.frame_id() > frames[k - 1].frame.frame_id());
    CHECK(frames[k].frame.last_event_id() >= frames[k - 1].frame.last_event_id());
    reduced = reduced || !frames[k].frame.full_resolution();
    CHECK(frames[k].picture.width == 320);  // every frame decodes
  }
  CHECK(reduced);
  // 40 x 0.01 of the view's width is 80 degrees of azimuth: another picture.
  CHECK(meanDifference(first.picture, frames.back().picture) > 2.0);
  CHECK(frames.back().frame.timings().render_ms() > 0.0);
  CHECK(frames.back().frame.timings().encode_ms() > 0.0);
  CHECK(stream.errors().empty());
}

// Pixels a red-on-black crack view never has: viridis's greens, blues and
// yellows (green well above red).
int viridisPixels(const encode::RgbFrame& picture) {
  int n = 0;
  for (std::size_t i = 0; i + 2 < picture.rgb.size(); i += 3) {
    n += picture.rgb[i + 1] > picture.rgb[i] + 40 ? 1 : 0;
  }
  return n;
}

TEST_CASE("a still camera move is answered at full resolution, and --max-reduction caps a drag's",
          "[render][service][integration]") {
  auto services = startServices();
  auto view = crackView();
  view.particles.visible = true;  // the spheres: frames that cost something

  SECTION("a still move: its first frame is full resolution") {
    auto stub = connect(*services.render);
    StreamClient stream(*stub, openSession(*stub, view));
    REQUIRE(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t id = stream.rotate(0.05, 0.0, true);
      REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
        return frames.back().frame.last_event_id() >= id;
      }));
      for (const auto& frame : stream.frames()) {
        if (frame.frame.last_event_id() == id) {
          CHECK(frame.frame.full_resolution());
          CHECK(frame.frame.reduction() == 1);
          CHECK(frame.frame.particles() == "spheres");
        }
      }
    }
  }
  SECTION("max_reduction 1: a drag is drawn at full resolution throughout") {
    auto config = renderConfig(*services.data);
    config.limits.maxReduction = 1;
    config.limits.interactiveFrameMs = 1.0;  // every frame over budget: it would reduce
    auto server = startRenderServer(config);
    auto stub = connect(*server);
    StreamClient stream(*stub, openSession(*stub, view));
    REQUIRE(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
    std::uint64_t last = 0;
    for (int k = 0; k < 20; ++k) {
      last = stream.rotate(0.01);
      std::this_thread::sleep_for(std::chrono::milliseconds(15));
    }
    REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
      return frames.back().frame.last_event_id() == last;
    }));
    const auto frames = stream.frames();
    CHECK(frames.size() >= 5);
    for (const auto& frame : frames) {
      CHECK(frame.frame.reduction() == 1);
    }
  }
}

TEST_CASE("a session reads the arrays its view colours by: break step, bond force, velocity",
          "[render][service][integration]") {
  auto services = startServices();
  auto stub = connect(*services.render);
  const std::string id = openSession(*stub, crackView());
  StreamClient stream(*stub, id);
  REQUIRE(stream.waitFor([](const auto& frames, const auto&) {
    return !frames.empty() && frames.back().frame.full_resolution();
  }));
  CHECK(redPixels(stream.frames().back().picture) > 100);
  CHECK(viridisPixels(stream.frames().back().picture) < 20);
  // A replaced pipeline that colours by another array; the frame after it.
  auto colouredBy = [&](const pipeline::PipelineDescription& view) {
    const std::size_t errorsBefore = stream.errors().size();
    v1::ClientEvent replace;
    replace.mutable_replace_pipeline()->set_pipeline_xml(pipeline::toXml(view));
    const auto event = stream.send(replace);
    REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
      return frames.back().frame.last_event_id() == event && frames.back().frame.full_resolution();
    }));
    INFO(pipeline::toXml(view));
    CHECK(stream.errors().size() == errorsBefore);
    return stream.frames().back().picture;
  };
  // Without the arrays these were drawn in the solid colour (the red crack
  // colour, or one colour-map end for every particle).
  auto view = crackView();
  view.cracks.colourBy = pipeline::CrackColourBy::kBreakStep;
  const int byBreakStep = viridisPixels(colouredBy(view));
  CHECK(byBreakStep > 100);
  // Broken bonds carry no force: the intact bonds show it.
  view.cracks.colourBy = pipeline::CrackColourBy::kSolid;
  view.cracks.visible = false;
  view.bonds.show = pipeline::BondSelection::kAll;
  view.bonds.colourBy = pipeline::BondColourBy::kForce;
  const int byForce = viridisPixels(colouredBy(view));
  CHECK(byForce > 100);
  view.bonds.show = pipeline::BondSelection::kNone;
  view.cracks.visible = true;
  view.particles.visible = true;
  view.particles.colourBy = pipeline::ParticleColourBy::kVelocity;
  const int byVelocity = viridisPixels(colouredBy(view));
  CHECK(byVelocity > 100);
  view.particles.colourBy = pipeline::ParticleColourBy::kSolid;
  CHECK(viridisPixels(colouredBy(view)) < 20);

  // A replacement that fails after the file was re-read for it (the step is
  // not there) is an event error and leaves the session as it was: it goes on
  // streaming the previous view, not a half-switched one.
  auto missingStep = view;
  missingStep.particles.colourBy = pipeline::ParticleColourBy::kVelocity;
  missingStep.step = 1'000'000;
  v1::ClientEvent replace;
  replace.mutable_replace_pipeline()->set_pipeline_xml(pipeline::toXml(missingStep));
  stream.send(replace);
  REQUIRE(stream.waitFor([](const auto&, const auto& errors) { return !errors.empty(); }));
  CHECK(stream.errors().front().code() == static_cast<int>(grpc::StatusCode::OUT_OF_RANGE));
  const auto event = stream.rotate(0.02);
  REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
    return frames.back().frame.last_event_id() == event && frames.back().frame.full_resolution();
  }));
  CHECK(viridisPixels(stream.frames().back().picture) < 20);  // solid grey particles still
  CHECK(colouredBy(view).rgb.size() > 0);                     // and it takes the next replacement
}

TEST_CASE("a session's annotations name the step it shows", "[render][service][integration]") {
  auto services = startServices();
  auto stub = connect(*services.render);
  auto view = crackView();
  view.annotations.show = true;
  view.step = 0;
  StreamClient stream(*stub, openSession(*stub, view));
  // The annotation text at the top left, in a full-resolution frame after `event`.
  auto textAfter = [&](std::uint64_t event) {
    REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
      return !frames.empty() && frames.back().frame.last_event_id() == event &&
             frames.back().frame.full_resolution();
    }));
    const auto picture = stream.frames().back().picture;
    std::vector<std::uint8_t> corner;
    int bright = 0;
    for (int y = 0; y < picture.height / 8; ++y) {
      for (int x = 0; x < picture.width / 2; ++x) {
        const auto* p = &picture.rgb[3 * (static_cast<std::size_t>(y) * picture.width + x)];
        corner.push_back(p[0]);
        bright += p[0] > 150 && p[1] > 150 && p[2] > 150 ? 1 : 0;
      }
    }
    CHECK(bright > 30);
    return corner;
  };
  const auto atZero = textAfter(0);
  const auto atLast = textAfter(stream.setStep(7));
  // "step 0 of ..." became "step 7 of ...".
  CHECK(atZero != atLast);
  CHECK(stream.errors().empty());
}

TEST_CASE("a session steps and plays through the fracture", "[render][service][integration]") {
  auto services = startServices();
  auto stub = connect(*services.render);
  auto view = crackView();
  view.step = 0;
  const std::string id = openSession(*stub, view);
  StreamClient stream(*stub, id);
  REQUIRE(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
  // Step 0 shows only the notch (pre-broken bonds); the fracture grows from it.
  const int notch = redPixels(stream.frames().front().picture);

  SECTION("set step shows the step's cracks") {
    const auto event = stream.setStep(-1);
    REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
      return frames.back().frame.last_event_id() == event && frames.back().frame.full_resolution();
    }));
    CHECK(redPixels(stream.frames().back().picture) > notch * 3 / 2);
    CHECK(stream.frames().back().frame.step() > 0);
  }
  SECTION("play advances the steps") {
    v1::ClientEvent play;
    play.mutable_play()->set_playing(true);
    play.mutable_play()->set_fps(25);
    stream.send(play);
    REQUIRE(stream.waitFor(
        [](const auto& frames, const auto&) { return frames.back().frame.step() >= 5; }));
    const auto frames = stream.frames();
    for (std::size_t k = 1; k < frames.size(); ++k) {
      CHECK(frames[k].frame.step() >= frames[k - 1].frame.step());
    }
    CHECK(!stream.states().empty());
    CHECK(stream.states().back().playing());
  }
}

TEST_CASE("a session's state says when few broken bonds became crack surfaces",
          "[render][service][integration]") {
  // A random packing with a planted crack, beside the cuboid in the data root.
  const std::string file = "random-planted.h5";
  testing::writePlantedRandomPacking(crackRoot().file(file), 2);
  auto services = startServices();
  auto stub = connect(*services.render);
  auto view = crackView();
  view.file = file;
  view.cracks.method = cracks::Method::kCellCut;
  view.cracks.decomposition = cracks::Decomposition::kLattice;
  StreamClient stream(*stub, openSession(*stub, crackView()));
  // Each replacement is answered with the session's state, then a frame.
  auto stateAfter = [&](const pipeline::PipelineDescription& next) {
    v1::ClientEvent replace;
    replace.mutable_replace_pipeline()->set_pipeline_xml(pipeline::toXml(next));
    const auto id = stream.send(replace);
    REQUIRE(stream.waitFor([&](const auto& frames, const auto& errors) {
      return !errors.empty() || (!frames.empty() && frames.back().frame.last_event_id() == id);
    }));
    REQUIRE(stream.errors().empty());
    REQUIRE(!stream.states().empty());
    return stream.states().back();
  };
  const v1::SessionState lattice = stateAfter(view);
  CHECK(lattice.mapped_fraction() < 0.95);
  CHECK_THAT(lattice.crack_warning(), Catch::Contains("span no lattice"));
  // The triangulation: no warning.
  view.cracks.decomposition = cracks::Decomposition::kAuto;
  const v1::SessionState triangulated = stateAfter(view);
  CHECK(triangulated.mapped_fraction() >= 0.95);
  CHECK(triangulated.crack_warning().empty());
}

TEST_CASE("bad requests get a clear status and the server keeps serving",
          "[render][service][integration]") {
  auto services = startServices();
  auto stub = connect(*services.render);

  SECTION("an invalid pipeline names the line and the element") {
    const grpc::Status status = openStatus(*stub, "<pipeline>\n  <data/>\n</pipeline>");
    CHECK(status.error_code() == grpc::StatusCode::INVALID_ARGUMENT);
    CHECK(status.error_message().find("line") != std::string::npos);
  }
  SECTION("an unknown file") {
    auto view = crackView();
    view.file = "missing.h5";
    const grpc::Status status = openStatus(*stub, pipeline::toXml(view));
    CHECK(status.error_code() == grpc::StatusCode::NOT_FOUND);
    CHECK(status.error_message().find("missing.h5") != std::string::npos);
  }
  SECTION("a file that is not HDF5, and a path out of the root") {
    auto view = crackView();
    view.file = "notes.txt";
    CHECK(openStatus(*stub, pipeline::toXml(view)).error_code() ==
          grpc::StatusCode::FAILED_PRECONDITION);
    view.file = "../etc/passwd";
    CHECK(openStatus(*stub, pipeline::toXml(view)).error_code() ==
          grpc::StatusCode::INVALID_ARGUMENT);
  }
  SECTION("a step out of range, when opening and in a stream") {
    auto view = crackView();
    view.step = 100000;
    const grpc::Status status = openStatus(*stub, pipeline::toXml(view));
    CHECK(status.error_code() == grpc::StatusCode::OUT_OF_RANGE);
    CHECK(status.error_message().find("step 100000 out of range") != std::string::npos);

    StreamClient stream(*stub, openSession(*stub, crackView()));
    const auto bad = stream.setStep(100000);
    REQUIRE(stream.waitFor([](const auto&, const auto& errors) { return !errors.empty(); }));
    CHECK(stream.errors().front().event_id() == bad);
    CHECK(stream.errors().front().code() == static_cast<int>(grpc::StatusCode::OUT_OF_RANGE));
    // The session goes on: the next event is reflected by a frame.
    const auto good = stream.rotate(0.05);
    REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
      return !frames.empty() && frames.back().frame.last_event_id() == good;
    }));
  }
  SECTION("an invalid replacement pipeline and an invalid resize are event errors") {
    StreamClient stream(*stub, openSession(*stub, crackView()));
    v1::ClientEvent replace;
    replace.mutable_replace_pipeline()->set_pipeline_xml("<pipeline><nonsense/></pipeline>");
    const auto replaceId = stream.send(replace);
    v1::ClientEvent resize;
    resize.mutable_resize()->set_width(7);
    resize.mutable_resize()->set_height(100000);
    const auto resizeId = stream.send(resize);
    REQUIRE(stream.waitFor([](const auto&, const auto& errors) { return errors.size() >= 2; }));
    // The resize is refused where it is queued, the pipeline on the session's
    // thread: their errors may come in either order.
    const auto errors = stream.errors();
    auto errorOf = [&](auto id) {
      const auto found = std::find_if(errors.begin(), errors.end(),
                                      [&](const auto& error) { return error.event_id() == id; });
      REQUIRE(found != errors.end());
      return *found;
    };
    CHECK(errorOf(replaceId).code() == static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
    CHECK(errorOf(resizeId).code() == static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
    CHECK(errorOf(resizeId).message().find("7x100000") != std::string::npos);
  }
  SECTION("a stream to an unknown session, and one that does not attach first") {
    StreamClient unknown(*stub, "no-such-session");
    const grpc::Status status = unknown.finish();
    CHECK(status.error_code() == grpc::StatusCode::NOT_FOUND);
    // A stream whose first message is an event, not attach_session_id.
    grpc::ClientContext context;
    auto unattached = stub->Stream(&context);
    v1::ClientEvent still;
    still.set_event_id(1);
    still.mutable_still();
    REQUIRE(unattached->Write(still));
    unattached->WritesDone();
    v1::ServerMessage ignored;
    while (unattached->Read(&ignored)) {
    }
    const grpc::Status first = unattached->Finish();
    CHECK(first.error_code() == grpc::StatusCode::INVALID_ARGUMENT);
    CHECK_THAT(first.error_message(), Catch::Contains("attach_session_id"));
  }
  SECTION("a client certificate from another CA is refused") {
    auto other = connect(*services.render, "other-client");
    CHECK(openStatus(*other, pipeline::toXml(crackView())).error_code() ==
          grpc::StatusCode::UNAVAILABLE);
  }
  // Whatever happened, a new session opens and streams.
  StreamClient stream(*stub, openSession(*stub, crackView()));
  CHECK(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
}

TEST_CASE("a vanished client's session and GL context are freed",
          "[render][service][integration]") {
  // A grace short enough to see sessions expire, long enough that a loaded
  // machine attaches the stream in time (0.3 s failed once under load).
  auto services = startServices(1.5);
  auto stub = connect(*services.render);
  {
    StreamClient stream(*stub, openSession(*stub, crackView()));
    REQUIRE(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
    CHECK(services.render->sessionCount() == 1);
    // Its own context, and one kept for a next session if the session did
    // not take the one crackvis-render made at start.
    CHECK(waitUntil(
        [&] { return render::EglContext::liveCount() == 1 + services.render->keptRenderers(); },
        10.0));
    stream.rotate(0.1);
    stream.vanish();
  }
  CHECK(waitUntil([&] { return services.render->sessionCount() == 0; }, 10.0));
  // Its context is freed, or kept for the next session: one waits.
  CHECK(waitUntil(
      [&] { return render::EglContext::liveCount() == services.render->keptRenderers(); }, 10.0));
  CHECK(services.render->keptRenderers() == 1);
  // A session opened and never streamed expires too.
  openSession(*stub, crackView());
  CHECK(waitUntil([&] { return services.render->sessionCount() == 0; }, 10.0));
  CHECK(waitUntil(
      [&] { return render::EglContext::liveCount() == services.render->keptRenderers(); }, 10.0));
  CHECK(services.render->keptRenderers() == 1);
}

TEST_CASE("snapshots, several sessions, close, and the data service passed through",
          "[render][service][integration]") {
  auto services = startServices(30.0, 2);
  auto stub = connect(*services.render);
  const std::string a = openSession(*stub, crackView());
  auto other = crackView();
  other.cracks.method = cracks::Method::kCellCut;
  const std::string b = openSession(*stub, other);
  CHECK(services.render->sessionCount() == 2);
  // The limit is two sessions.
  CHECK(openStatus(*stub, pipeline::toXml(crackView())).error_code() ==
        grpc::StatusCode::RESOURCE_EXHAUSTED);
  {
    StreamClient first(*stub, a);
    StreamClient second(*stub, b);
    for (auto* stream : {&first, &second}) {
      // Frames superseded before the stream took them are dropped: wait for
      // the one that reflects the event.
      const auto event = stream->rotate(0.02);
      CHECK(stream->waitFor([&](const auto& frames, const auto&) {
        return !frames.empty() && frames.back().frame.last_event_id() == event;
      }));
      CHECK(redPixels(stream->frames().back().picture) > 100);
    }
  }
  grpc::ClientContext snapshotContext;
  v1::SnapshotRequest request;
  request.set_session_id(a);
  request.set_width(640);
  request.set_height(480);
  v1::SnapshotResponse png;
  const grpc::Status snapshot = stub->Snapshot(&snapshotContext, request, &png);
  INFO(snapshot.error_message());
  REQUIRE(snapshot.ok());
  CHECK(png.width() == 640);
  CHECK(png.png().substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8));
  // Only 0 means the view's size: a negative one is refused, not replaced.
  for (const auto& [width, height] : {std::pair{-5, -5}, std::pair{640, -2}, std::pair{-640, 0}}) {
    grpc::ClientContext badContext;
    request.set_width(width);
    request.set_height(height);
    const grpc::Status bad = stub->Snapshot(&badContext, request, &png);
    INFO(width << "x" << height << ": " << bad.error_message());
    CHECK(bad.error_code() == grpc::StatusCode::INVALID_ARGUMENT);
  }

  grpc::ClientContext listContext;
  v1::ListFilesRequest list;
  v1::ListFilesResponse files;
  REQUIRE(stub->ListFiles(&listContext, list, &files).ok());
  bool listed = false;
  for (const auto& file : files.files()) {
    listed = listed || file.path() == "cuboidA.h5";
  }
  CHECK(listed);
  grpc::ClientContext describeContext;
  v1::DescribeRequest describe;
  describe.set_file("cuboidA.h5");
  v1::DescribeResponse description;
  REQUIRE(stub->Describe(&describeContext, describe, &description).ok());
  CHECK(description.steps_size() > 10);
  grpc::ClientContext missingContext;
  describe.set_file("../outside.h5");
  CHECK(stub->Describe(&missingContext, describe, &description).error_code() ==
        grpc::StatusCode::INVALID_ARGUMENT);
  // A file that is no crackvis-dem and a missing one: a clear refusal.
  for (const auto& [file, code] :
       {std::pair{"notes.txt", grpc::StatusCode::FAILED_PRECONDITION},
        std::pair{"nosuch.h5", grpc::StatusCode::NOT_FOUND},
        std::pair{"../outside.h5", grpc::StatusCode::INVALID_ARGUMENT}}) {
    grpc::ClientContext historyContext;
    v1::StepHistoryRequest history;
    history.set_file(file);
    v1::StepHistoryResponse steps;
    const grpc::Status refused = stub->StepHistory(&historyContext, history, &steps);
    INFO(file << ": " << refused.error_message());
    CHECK(refused.error_code() == code);
  }

  for (const std::string& id : {a, b}) {
    grpc::ClientContext context;
    v1::CloseSessionRequest close;
    close.set_session_id(id);
    v1::CloseSessionResponse closed;
    CHECK(stub->CloseSession(&context, close, &closed).ok());
  }
  CHECK(services.render->sessionCount() == 0);
  grpc::ClientContext again;
  v1::CloseSessionRequest close;
  close.set_session_id(a);
  v1::CloseSessionResponse closed;
  CHECK(stub->CloseSession(&again, close, &closed).error_code() == grpc::StatusCode::NOT_FOUND);
}

// Yade's JCFpm notched bar (tests/data) imported into the served root as a
// user would (crackvis import yade), once.
void importYadeBar(const std::string& name) {
  const std::string imported = crackRoot().file(name);
  if (!std::filesystem::exists(imported)) {
    auto source = importers::openYade({std::string(CRACKVIS_TEST_DATA) + "/yade/notched_bar"});
    REQUIRE(source);
    importers::ImportOptions options;
    options.output = imported;
    options.progress = false;
    REQUIRE(importers::importSeries(**source, options));
  }
}

// The series of a StepHistory answer by name; empty when it has none.
std::vector<double> seriesOf(const v1::StepHistoryResponse& history, const std::string& name) {
  for (const auto& series : history.scalars()) {
    if (series.name() == name) {
      return {series.values().begin(), series.values().end()};
    }
  }
  return {};
}

// StepHistory of `file` with the crack numbers of `method`; the call must
// succeed.
v1::StepHistoryResponse crackHistory(v1::RenderService::Stub& stub, const std::string& file,
                                     const std::string& method) {
  grpc::ClientContext context;
  v1::StepHistoryRequest request;
  request.set_file(file);
  request.set_cracks(method);
  v1::StepHistoryResponse response;
  const grpc::Status status = stub.StepHistory(&context, request, &response);
  INFO(status.error_message());
  REQUIRE(status.ok());
  return response;
}

TEST_CASE("StepHistory with a crack method adds the crack's numbers per step",
          "[render][service][integration]") {
  // A planted through crack: at the last step the right half has moved one
  // bond length, 2 mm, away from the left.
  const std::string file = "planted-history.h5";
  testing::writePlantedLattice(crackRoot().file(file), 8);
  auto services = startServices();
  auto stub = connect(*services.render);
  for (const char* method : {"local-voronoi", "cell-centre"}) {
    INFO(method);
    const v1::StepHistoryResponse history = crackHistory(*stub, file, method);
    const auto steps = static_cast<std::size_t>(history.broken_bonds_size());
    REQUIRE(steps == 9);  // the intact block and 8 steps
    for (const char* name :
         {"total_area", "main_area", "front_extent", "front_speed", "main_mean_opening",
          "fragments", "largest_fragment_share", "tension_breaks", "shear_breaks"}) {
      INFO(name);
      CHECK(seriesOf(history, name).size() == steps);
    }
    const auto area = seriesOf(history, "total_area");
    const auto main = seriesOf(history, "main_area");
    const auto fragments = seriesOf(history, "fragments");
    const auto opening = seriesOf(history, "main_mean_opening");
    const auto tension = seriesOf(history, "tension_breaks");
    const auto shear = seriesOf(history, "shear_breaks");
    REQUIRE((area.size() == steps && fragments.size() == steps && opening.size() == steps));
    CHECK(area.front() == 0.0);
    CHECK(area.back() > area[3]);
    CHECK(main.back() <= area.back());
    CHECK(fragments.front() == 1.0);
    CHECK(fragments.back() == 2.0);
    CHECK(opening.back() == Approx(2e-3).epsilon(0.01));
    CHECK(tension.back() + shear.back() ==
          static_cast<double>(history.broken_bonds(8) - history.broken_bonds(0)));
  }

  // An imported Yade run: the modes JCFpm recorded (27 tensile breaks)
  // come from the file's bonds/break_mode.
  importYadeBar("yade-history.h5");
  grpc::ClientContext yadeContext;
  v1::StepHistoryRequest yade;
  yade.set_file("yade-history.h5");
  yade.set_cracks("cell-cut");
  v1::StepHistoryResponse yadeHistory;
  const grpc::Status yadeStatus = stub->StepHistory(&yadeContext, yade, &yadeHistory);
  INFO(yadeStatus.error_message());
  REQUIRE(yadeStatus.ok());
  CHECK(seriesOf(yadeHistory, "tension_breaks").back() == 27.0);
  CHECK(seriesOf(yadeHistory, "shear_breaks").back() == 0.0);
  CHECK(seriesOf(yadeHistory, "jcfpm_tensile_cracks").back() == 27.0);

  grpc::ClientContext badContext;
  v1::StepHistoryRequest bad;
  bad.set_file(file);
  bad.set_cracks("voronoi-everywhere");
  v1::StepHistoryResponse refused;
  const grpc::Status status = stub->StepHistory(&badContext, bad, &refused);
  CHECK(status.error_code() == grpc::StatusCode::INVALID_ARGUMENT);
  CHECK_THAT(status.error_message(), Catch::Contains("voronoi-everywhere"));
  // A deadline too short for the whole file: the server stops at its next
  // step (the client has its DEADLINE_EXCEEDED already), and the user may
  // then ask again: one at a time, not none.
  grpc::ClientContext hurried;
  hurried.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(1));
  bad.set_cracks("local-voronoi");
  const grpc::Status late = stub->StepHistory(&hurried, bad, &refused);
  CHECK(late.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED);
  grpc::Status again;
  for (int attempt = 0; attempt < 50; ++attempt) {
    grpc::ClientContext context;
    refused.Clear();
    again = stub->StepHistory(&context, bad, &refused);
    if (again.error_code() != grpc::StatusCode::RESOURCE_EXHAUSTED) {
      break;
    }
    CHECK_THAT(again.error_message(), Catch::Contains("one at a time per user"));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  INFO(again.error_message());
  CHECK(again.ok());
}

TEST_CASE("StepHistory's crack numbers of a live file go on from the caller's last step",
          "[render][service][integration][live]") {
  // The same planted crack written at once, and step by step as a running
  // code writes it.
  const std::string whole = "history-whole.h5";
  const auto sample = testing::writePlantedLattice(crackRoot().file(whole), 8);
  REQUIRE(sample.steps.size() == 9);
  const std::string live = "history-live.h5";
  std::filesystem::remove(crackRoot().file(live));
  dem::DemMetadata metadata = dem::metadataFrom("render_service test");
  metadata.stepLayout = dem::StepLayout::kAppendable;
  auto writer = dem::DemFileWriter::create(crackRoot().file(live), sample.lattice, metadata);
  REQUIRE(writer.isOk());
  auto append = [&](std::size_t from, std::size_t to) {
    for (std::size_t k = from; k < to; ++k) {
      REQUIRE(writer->appendStep(sample.steps[k]).isOk());
    }
  };
  auto services = startServices();
  auto stub = connect(*services.render);
  auto history = [&](const std::string& file) {
    return crackHistory(*stub, file, "local-voronoi");
  };
  // The whole file first: a user's kept run is of one file, and a call on
  // another file lets it go.
  const v1::StepHistoryResponse reference = history(whole);
  CHECK(reference.crack_steps_computed() == 9);
  append(0, 5);
  const v1::StepHistoryResponse early = history(live);
  CHECK(early.time_size() == 5);
  CHECK(early.crack_steps_computed() == 5);
  CHECK(seriesOf(early, "total_area").size() == 5);
  // The run goes on: only the 4 new steps are extracted and analysed.
  append(5, 9);
  const v1::StepHistoryResponse later = history(live);
  CHECK(later.time_size() == 9);
  CHECK(later.crack_steps_computed() == 4);
  // And its numbers are those of the whole file run at once, bit for bit
  // (NaN where a step has no crack).
  REQUIRE(reference.scalars_size() > 5);
  for (const auto& series : reference.scalars()) {
    INFO(series.name());
    CHECK(testing::sameBytes(seriesOf(later, series.name()),
                             std::vector<double>(series.values().begin(), series.values().end())));
  }
  // The writer is done: the kept run finds no new step and is let go, so
  // the next call runs on every step again.
  REQUIRE(writer->close().isOk());
  CHECK(history(live).crack_steps_computed() == 0);
  CHECK(history(live).crack_steps_computed() == 9);
}

TEST_CASE("StepHistory keeps a finished file's crack numbers until the file changes",
          "[render][service][integration]") {
  const std::string file = "history-finished.h5";
  const std::string path = crackRoot().file(file);
  // A file counts as finished once it has been left alone for 2 s: its
  // modification time is set back rather than waited for.
  auto writeSettled = [&](int steps, std::chrono::minutes age) {
    testing::writePlantedLattice(path, steps);
    std::filesystem::last_write_time(path, std::filesystem::file_time_type::clock::now() - age);
  };
  auto services = startServices();
  auto stub = connect(*services.render);
  auto history = [&](const char* method) { return crackHistory(*stub, file, method); };
  auto revision = [&] {
    grpc::ClientContext context;
    v1::DescribeRequest request;
    request.set_file(file);
    v1::DescribeResponse response;
    REQUIRE(stub->Describe(&context, request, &response).ok());
    return response.revision();
  };
  auto sameSeries = [](const v1::StepHistoryResponse& a, const v1::StepHistoryResponse& b) {
    REQUIRE(a.scalars_size() == b.scalars_size());
    for (const auto& series : a.scalars()) {
      INFO(series.name());
      CHECK(
          testing::sameBytes(seriesOf(b, series.name()),
                             std::vector<double>(series.values().begin(), series.values().end())));
    }
  };

  // A file being written has no revision: its numbers are not kept. (Its
  // modification time is put in the future, so that the file cannot settle
  // while a slow machine runs the test.)
  testing::writePlantedLattice(path, 8);
  std::filesystem::last_write_time(
      path, std::filesystem::file_time_type::clock::now() + std::chrono::hours(1));
  CHECK(revision().empty());
  CHECK(history("local-voronoi").crack_steps_computed() == 9);
  CHECK(history("local-voronoi").crack_steps_computed() == 9);

  writeSettled(8, std::chrono::minutes(60));
  const std::string first = revision();
  CHECK(first.size() == 32);
  CHECK(revision() == first);
  const v1::StepHistoryResponse computed = history("local-voronoi");
  CHECK(computed.crack_steps_computed() == 9);
  // Asked again: no step is run, and the numbers are the same.
  const v1::StepHistoryResponse kept = history("local-voronoi");
  CHECK(kept.crack_steps_computed() == 0);
  CHECK(kept.time_size() == 9);
  sameSeries(computed, kept);
  REQUIRE(seriesOf(kept, "total_area").size() == 9);
  // Another method is another entry.
  CHECK(history("cell-centre").crack_steps_computed() == 9);
  CHECK(history("cell-centre").crack_steps_computed() == 0);

  // The file is written again, with fewer steps: a new revision, new numbers.
  writeSettled(5, std::chrono::minutes(30));
  CHECK(revision() != first);
  const v1::StepHistoryResponse rewritten = history("local-voronoi");
  CHECK(rewritten.crack_steps_computed() == 6);
  CHECK(seriesOf(rewritten, "total_area").size() == 6);
  CHECK(history("local-voronoi").crack_steps_computed() == 0);
}

TEST_CASE("crackvis-render --snapshot draws the cracks of a generated series",
          "[render][service][integration]") {
  testing::TempDir out;
  auto view = crackView();
  std::ofstream(out.file("view.xml")) << pipeline::toXml(view);
  const auto result =
      testing::runProcess({CRACKVIS_RENDER, "--snapshot", out.file("view.xml"), "--data-root",
                           crackRoot().path().string(), "-o", out.file("cracks.png")});
  INFO(result.err);
  REQUIRE(result.exitCode == 0);
  CHECK(result.out.find("cuboidA.h5 step") != std::string::npos);
  CHECK(std::filesystem::file_size(out.file("cracks.png")) > 1000);

  const auto bad =
      testing::runProcess({CRACKVIS_RENDER, "--snapshot", out.file("view.xml"), "--data-root",
                           crackRoot().path().string(), "--step", "9999", "-o", out.file("x.png")});
  CHECK(bad.exitCode == 1);
  CHECK(bad.err.find("step 9999 out of range") != std::string::npos);
}

// Requests as a user: the token travels as "authorization: Bearer".
class AsUser {
 public:
  AsUser(v1::RenderService::Stub& stub, std::string token)
      : m_stub(stub), m_token(std::move(token)) {}

  grpc::Status open(const pipeline::PipelineDescription& d,
                    v1::OpenSessionResponse* response = nullptr) {
    grpc::ClientContext context;
    prepare(context);
    v1::OpenSessionRequest request;
    request.set_pipeline_xml(pipeline::toXml(d));
    v1::OpenSessionResponse local;
    return m_stub.OpenSession(&context, request, response != nullptr ? response : &local);
  }
  grpc::Status list(const std::string& folder, std::vector<std::string>* paths = nullptr) {
    grpc::ClientContext context;
    prepare(context);
    v1::ListFilesRequest request;
    request.set_folder(folder);
    request.set_recursive(true);
    v1::ListFilesResponse response;
    const grpc::Status status = m_stub.ListFiles(&context, request, &response);
    for (const auto& file : response.files()) {
      if (paths != nullptr) {
        paths->push_back(file.path());
      }
    }
    return status;
  }
  grpc::Status describe(const std::string& file) {
    grpc::ClientContext context;
    prepare(context);
    v1::DescribeRequest request;
    request.set_file(file);
    v1::DescribeResponse response;
    return m_stub.Describe(&context, request, &response);
  }
  grpc::Status stepHistory(const std::string& file) {
    grpc::ClientContext context;
    prepare(context);
    v1::StepHistoryRequest request;
    request.set_file(file);
    v1::StepHistoryResponse response;
    return m_stub.StepHistory(&context, request, &response);
  }
  grpc::Status snapshot(const std::string& session) {
    grpc::ClientContext context;
    prepare(context);
    v1::SnapshotRequest request;
    request.set_session_id(session);
    request.set_width(64);
    request.set_height(48);
    v1::SnapshotResponse response;
    return m_stub.Snapshot(&context, request, &response);
  }

 private:
  void prepare(grpc::ClientContext& context) const {
    if (!m_token.empty()) {
      context.AddMetadata("authorization", "Bearer " + m_token);
    }
  }
  v1::RenderService::Stub& m_stub;
  std::string m_token;
};

pipeline::PipelineDescription viewOf(const std::string& file) {
  auto d = crackView();
  d.file = file;
  return d;
}

TEST_CASE("the render server applies crackvis-data's users: tokens and folders",
          "[render][service][integration]") {
  dataservice::UserEntry carol{"carol", rpc::hashToken("carol-token").value(), "", "", {"*"}};
  dataservice::UserEntry alice{"alice", rpc::hashToken("alice-token").value(), "", "", {"alice"}};
  dataservice::UserEntry bob{"bob", rpc::hashSecret("bob-token", 1000).value(), "", "", {"bob"}};
  auto services = startServices(30.0, 8, {carol, alice, bob});
  auto stub = connect(*services.render);
  AsUser anonymous(*stub, "");
  AsUser wrong(*stub, "wrong");
  AsUser asCarol(*stub, "carol-token");
  AsUser asAlice(*stub, "alice-token");
  AsUser asBob(*stub, "bob-token");

  SECTION("tokens, and the folder rule on the file as named") {
    CHECK(anonymous.open(crackView()).error_code() == grpc::StatusCode::UNAUTHENTICATED);
    CHECK(wrong.open(crackView()).error_code() == grpc::StatusCode::UNAUTHENTICATED);
    const grpc::Status denied = asBob.open(crackView());
    CHECK(denied.error_code() == grpc::StatusCode::PERMISSION_DENIED);
    CHECK_THAT(denied.error_message(), Catch::Contains("user 'bob' may not read 'cuboidA.h5'"));
    CHECK(asCarol.open(crackView()).ok());
    CHECK(asBob.open(viewOf("bob/b.h5")).ok());
  }
  SECTION("listings show each user exactly their files, never a link into another's folder") {
    std::vector<std::string> bobs;
    REQUIRE(asBob.list("", &bobs).ok());
    CHECK(bobs == std::vector<std::string>{"bob/b.h5"});
    std::vector<std::string> alices;
    REQUIRE(asAlice.list("", &alices).ok());
    CHECK(alices == std::vector<std::string>{"alice/a.h5", "alice/swap.h5"});
    std::vector<std::string> all;
    REQUIRE(asCarol.list("", &all).ok());
    CHECK(std::find(all.begin(), all.end(), "alice/link.h5") != all.end());
    CHECK(std::find(all.begin(), all.end(), "cuboidA.h5") != all.end());
  }
  SECTION("another user's folder answers exactly as a missing one") {
    const grpc::Status foreign = asAlice.list("bob");
    const grpc::Status missing = asAlice.list("nosuch");
    CHECK(foreign.error_code() == grpc::StatusCode::NOT_FOUND);
    CHECK(missing.error_code() == grpc::StatusCode::NOT_FOUND);
    CHECK(foreign.error_message() == "folder 'bob' not found under the data root");
    CHECK(missing.error_message() == "folder 'nosuch' not found under the data root");
  }
  SECTION("a symlink in alice's folder to bob's file: Describe, OpenSession, replacement") {
    CHECK(asAlice.describe("alice/a.h5").ok());
    CHECK(asAlice.stepHistory("alice/a.h5").ok());
    CHECK(asAlice.stepHistory("alice/link.h5").error_code() == grpc::StatusCode::PERMISSION_DENIED);
    CHECK(asBob.stepHistory("cuboidA.h5").error_code() == grpc::StatusCode::PERMISSION_DENIED);
    CHECK(anonymous.stepHistory("alice/a.h5").error_code() == grpc::StatusCode::UNAUTHENTICATED);
    const grpc::Status described = asAlice.describe("alice/link.h5");
    CHECK(described.error_code() == grpc::StatusCode::PERMISSION_DENIED);
    CHECK_THAT(described.error_message(), Catch::Contains("links to 'bob/b.h5'"));
    const grpc::Status opened = asAlice.open(viewOf("alice/link.h5"));
    CHECK(opened.error_code() == grpc::StatusCode::PERMISSION_DENIED);
    CHECK_THAT(opened.error_message(), Catch::Contains("links to 'bob/b.h5'"));

    v1::OpenSessionResponse response;
    REQUIRE(asAlice.open(viewOf("alice/a.h5"), &response).ok());
    StreamClient stream(*stub, response.session_id(), "alice-token");
    REQUIRE(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
    v1::ClientEvent replace;
    replace.mutable_replace_pipeline()->set_pipeline_xml(pipeline::toXml(viewOf("alice/link.h5")));
    stream.send(replace);
    REQUIRE(stream.waitFor([](const auto&, const auto& errors) { return !errors.empty(); }));
    CHECK(stream.errors()[0].code() == static_cast<int>(grpc::StatusCode::PERMISSION_DENIED));
    CHECK_THAT(stream.errors()[0].message(), Catch::Contains("bob/b.h5"));
  }
  SECTION("a snapshot after the link was re-pointed at bob's file") {
    v1::OpenSessionResponse response;
    REQUIRE(asAlice.open(viewOf("alice/swap.h5"), &response).ok());
    REQUIRE(asAlice.snapshot(response.session_id()).ok());
    const auto swap = crackRoot().path() / "alice" / "swap.h5";
    std::filesystem::remove(swap);
    std::filesystem::create_symlink("../bob/b.h5", swap);
    const grpc::Status snapshot = asAlice.snapshot(response.session_id());
    std::filesystem::remove(swap);
    std::filesystem::create_symlink("a.h5", swap);
    CHECK(snapshot.error_code() == grpc::StatusCode::PERMISSION_DENIED);
    CHECK_THAT(snapshot.error_message(), Catch::Contains("links to 'bob/b.h5'"));
  }
  SECTION("sessions are capped per user beside the server-wide cap") {
    std::vector<v1::OpenSessionResponse> sessions(5);
    for (int i = 0; i < 4; ++i) {
      REQUIRE(asBob.open(viewOf("bob/b.h5"), &sessions[i]).ok());
    }
    const grpc::Status fifth = asBob.open(viewOf("bob/b.h5"), &sessions[4]);
    CHECK(fifth.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED);
    CHECK_THAT(fifth.error_message(), Catch::Contains("per user"));
    CHECK(asCarol.open(crackView()).ok());  // another user still opens one
  }
  SECTION(
      "a full server lets a new user in by reclaiming from the user furthest above a fair "
      "share, sessions without a stream first") {
    std::vector<v1::OpenSessionResponse> bobs(4);
    std::vector<v1::OpenSessionResponse> carols(4);
    for (int i = 0; i < 4; ++i) {
      REQUIRE(asBob.open(viewOf("bob/b.h5"), &bobs[i]).ok());
      REQUIRE(asCarol.open(viewOf("bob/b.h5"), &carols[i]).ok());
    }
    REQUIRE(services.render->sessionCount() == 8);
    // bob watches his first session; the other seven have no stream.
    StreamClient watched(*stub, bobs[0].session_id(), "bob-token");
    REQUIRE(watched.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
    // Two users hold all 8; alice gets in twice (a fair share of 8 among 3 is 2), taking
    // sessions nobody watches, and is refused a third.
    CHECK(asAlice.open(viewOf("alice/a.h5")).ok());
    CHECK(asAlice.open(viewOf("alice/a.h5")).ok());
    const grpc::Status third = asAlice.open(viewOf("alice/a.h5"));
    CHECK(third.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED);
    CHECK_THAT(third.error_message(), Catch::Contains("a fair share is 2"));
    CHECK(services.render->sessionCount() == 8);
    // bob's watched session survived; each of bob and carol gave one.
    CHECK(asBob.snapshot(bobs[0].session_id()).ok());
    int bobsLeft = 0;
    int carolsLeft = 0;
    for (int i = 0; i < 4; ++i) {
      bobsLeft += asBob.snapshot(bobs[i].session_id()).ok() ? 1 : 0;
      carolsLeft += asCarol.snapshot(carols[i].session_id()).ok() ? 1 : 0;
    }
    CHECK(bobsLeft == 3);
    CHECK(carolsLeft == 3);
  }
}

TEST_CASE("a number no parser can hold fails only that call, with an access-log line",
          "[render][service][integration]") {
  TempDir logs;
  auto services = startServices(30.0, 8, {}, logs.file("render-access.log"));
  auto stub = connect(*services.render);
  std::string xml = pipeline::toXml(crackView());
  const std::string step = "step=\"-1\"";
  REQUIRE(xml.find(step) != std::string::npos);
  xml.replace(xml.find(step), step.size(), "step=\"99999999999999999999\"");
  const grpc::Status status = openStatus(*stub, xml);
  INFO(status.error_message());
  // Before the range-checked conversions this was UNKNOWN, from an escaped
  // std::stoll exception.
  CHECK(status.error_code() == grpc::StatusCode::INVALID_ARGUMENT);
  CHECK_THAT(status.error_message(), Catch::Contains("line ") && Catch::Contains("data") &&
                                         Catch::Contains("step") &&
                                         Catch::Contains("99999999999999999999"));
  std::ifstream in(logs.file("render-access.log"));
  const std::string log((std::istreambuf_iterator<char>(in)), {});
  CHECK_THAT(log, Catch::Contains("method=OpenSession"));
  CHECK_THAT(log,
             Catch::Contains(fmt::format("status={}", rpc::grpcCodeName(status.error_code()))));
  // The same numbers in a pipeline replacement fail only that event; the
  // session goes on.
  StreamClient stream(*stub, openSession(*stub, crackView()));
  std::string opacity = pipeline::toXml(crackView());
  const std::string key = "opacity=\"";
  const size_t at = opacity.find(key, opacity.find("<particles"));
  REQUIRE(at != std::string::npos);
  const size_t value = at + key.size();
  opacity.replace(value, opacity.find('"', value) - value, "1e-400");
  for (const std::string& bad : {xml, opacity}) {
    v1::ClientEvent replace;
    replace.mutable_replace_pipeline()->set_pipeline_xml(bad);
    stream.send(replace);
  }
  REQUIRE(stream.waitFor([](const auto&, const auto& errors) { return errors.size() >= 2; }));
  for (const auto& error : stream.errors()) {
    INFO(error.message());
    CHECK(error.code() == static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
    CHECK_THAT(error.message(), Catch::Contains("line "));
  }
  CHECK_THAT(stream.errors()[1].message(),
             Catch::Contains("particles") && Catch::Contains("opacity"));
  const auto good = stream.rotate(0.05);
  CHECK(stream.waitFor([&](const auto& frames, const auto&) {
    return !frames.empty() && frames.back().frame.last_event_id() == good;
  }));
}

TEST_CASE("the render server starts and stops like the data server",
          "[render][service][integration]") {
  auto services = startServices();
  SECTION("its health status is SERVING") {
    const auto tls = testing::clientTls("client");
    auto read = [](const std::string& path) {
      std::ifstream in(path);
      return std::string(std::istreambuf_iterator<char>(in), {});
    };
    grpc::SslCredentialsOptions ssl{read(tls.ca), read(tls.key), read(tls.cert)};
    auto health = grpc::health::v1::Health::NewStub(grpc::CreateChannel(
        fmt::format("localhost:{}", services.render->port()), grpc::SslCredentials(ssl)));
    grpc::ClientContext context;
    grpc::health::v1::HealthCheckRequest request;
    grpc::health::v1::HealthCheckResponse response;
    REQUIRE(health->Check(&context, request, &response).ok());
    CHECK(response.status() == grpc::health::v1::HealthCheckResponse::SERVING);
  }
  SECTION("a second render server on its port fails with 'address in use'") {
    service::RenderServerConfig config;
    config.listen = fmt::format("127.0.0.1:{}", services.render->port());
    config.tls = serverTls();
    config.data.target = services.data->address();
    config.data.tls = clientTls("crackvis-render");
    config.accessLog = "";
    auto second = service::RenderServer::start(config);
    REQUIRE_FALSE(second.isOk());
    CHECK_THAT(second.status().message(), Catch::Contains("in use"));
  }
  SECTION("an IPv6 loopback address is bracketed") {
    auto v6 = startRenderServer(*services.data, "[::1]:0");
    CHECK(v6->address() == fmt::format("[::1]:{}", v6->port()));
  }
  SECTION("--data-insecure only to a loopback address") {
    service::RenderServerConfig config;
    config.listen = "127.0.0.1:0";
    config.tls = serverTls();
    config.data.target = "192.0.2.1:50051";
    config.data.insecure = true;
    config.accessLog = "";
    auto refused = service::RenderServer::start(config);
    REQUIRE_FALSE(refused.isOk());
    CHECK(refused.status().code() == StatusCode::kFailedPrecondition);
    CHECK_THAT(refused.status().message(), Catch::Contains("--data-insecure"));
  }
  SECTION("wait() returns once shutdown() has stopped the server") {
    std::atomic<bool> returned{false};
    std::thread waiter([&] {
      services.render->wait();
      returned = true;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    CHECK_FALSE(returned);
    services.render->shutdown(0.5);
    waiter.join();
    CHECK(returned);
    auto stub = connect(*services.render);
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
    v1::ListFilesResponse files;
    CHECK_FALSE(stub->ListFiles(&context, v1::ListFilesRequest(), &files).ok());
  }
}

TEST_CASE("streams that never attach are cancelled, and cannot pin a thread each",
          "[render][service][integration]") {
  auto services = startServices();
  TempDir logs;
  auto config = renderConfig(*services.data);
  config.attachSeconds = 2.0;
  config.accessLog = logs.file("render-access.log");
  auto render = startRenderServer(config);
  auto stub = connect(*render);
  const int before = threadCount();
  constexpr int kStreams = 150;
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientReaderWriter<v1::ClientEvent, v1::ServerMessage>>>
      streams;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < kStreams; ++i) {
    contexts.push_back(std::make_unique<grpc::ClientContext>());
    streams.push_back(stub->Stream(contexts.back().get()));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  // Before, each waiting stream held a thread of its own (500 streams, 517).
  const int during = threadCount();
  INFO("threads before " << before << ", while waiting " << during);
  CHECK(during - before < 100);
  int timedOut = 0;
  for (auto& stream : streams) {
    v1::ServerMessage ignored;
    while (stream->Read(&ignored)) {
    }
    const grpc::Status status = stream->Finish();
    INFO(status.error_message());
    if (status.error_code() == grpc::StatusCode::CANCELLED) {
      ++timedOut;  // the server cancelled it; its access-log line says why
    } else {
      // Beyond the handler threads gRPC refuses the call outright.
      CHECK(status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED);
    }
  }
  CHECK(timedOut > 0);
  // The server logs a call after the client has seen it end: wait for the line.
  const auto logged = [&] {
    std::ifstream in(logs.file("render-access.log"));
    const std::string log((std::istreambuf_iterator<char>(in)), {});
    return log.find("within 2 s (attach_seconds)") != std::string::npos ? log : std::string{};
  };
  std::string log = logged();
  for (int wait = 0; wait < 50 && log.empty(); ++wait) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    log = logged();
  }
  CHECK_THAT(log, Catch::Contains("method=Stream") && Catch::Contains("status=DEADLINE_EXCEEDED") &&
                      Catch::Contains("within 2 s (attach_seconds)"));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK(seconds < 10.0);
  // The server still opens a session and streams it, once gRPC has taken
  // back the handler threads of the ended streams (under load that can
  // take a moment: "Server Threadpool Exhausted" meanwhile).
  CHECK(waitUntil([&] { return openStatus(*stub, pipeline::toXml(crackView())).ok(); }, 10.0));
  StreamClient stream(*stub, openSession(*stub, crackView()));
  CHECK(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
}

TEST_CASE("an imported Yade run goes through the data service into a render session",
          "[render][service][integration][importers]") {
  importYadeBar("yade-import.h5");
  auto services = startServices();
  auto stub = connect(*services.render);
  auto view = crackView();
  view.file = "yade-import.h5";
  view.cracks.method = cracks::Method::kCellCut;
  v1::OpenSessionResponse opened;
  const std::string id = openSession(*stub, view, &opened);
  CHECK(opened.step_count() == 11);
  StreamClient stream(*stub, id);
  REQUIRE(stream.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
  CHECK(stream.frames().front().frame.step() == 10);
  CHECK(redPixels(stream.frames().front().picture) > 50);  // the crack the JCFpm run made

  // Its particles coloured by Yade's own per-sphere 'damage' array (an extra
  // array, read through the data service), viridis; an array the file does
  // not have is refused naming those it has.
  auto damage = view;
  damage.cracks.visible = false;
  damage.particles.visible = true;
  damage.particles.colourBy = pipeline::ParticleColourBy::kExtra;
  damage.particles.colourByExtra = "damage";
  StreamClient coloured(*stub, openSession(*stub, damage));
  REQUIRE(coloured.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
  CHECK(viridisPixels(coloured.frames().front().picture) > 100);
  damage.particles.colourByExtra = "nope";
  const grpc::Status missing = openStatus(*stub, pipeline::toXml(damage));
  CHECK(missing.error_code() == grpc::StatusCode::FAILED_PRECONDITION);
  CHECK_THAT(missing.error_message(),
             Catch::Contains("no per-particle extra array 'nope'") && Catch::Contains("damage"));

  // Its bonds coloured by Yade's normal force (the per-bond extra 'forceN').
  auto force = view;
  force.cracks.visible = false;
  force.bonds.show = pipeline::BondSelection::kAll;
  force.bonds.colourBy = pipeline::BondColourBy::kExtra;
  force.bonds.colourByExtra = "forceN";
  StreamClient bonds(*stub, openSession(*stub, force));
  REQUIRE(bonds.waitFor([](const auto& frames, const auto&) { return !frames.empty(); }));
  CHECK(viridisPixels(bonds.frames().front().picture) > 100);
  force.bonds.colourByExtra = "nope";
  const grpc::Status noBondArray = openStatus(*stub, pipeline::toXml(force));
  CHECK(noBondArray.error_code() == grpc::StatusCode::FAILED_PRECONDITION);
  CHECK_THAT(noBondArray.error_message(),
             Catch::Contains("no per-bond extra array 'nope'") && Catch::Contains("forceN"));
}

TEST_CASE(
    "crackvis bench render reports interactive and full-resolution latency, and how each "
    "frame was drawn",
    "[render][service][integration][bench]") {
  auto services = startServices();
  const auto tls = testing::clientTls("client");
  const auto run = testing::runProcess({CRACKVIS_CLI,
                                        "bench",
                                        "render",
                                        "--server",
                                        fmt::format("localhost:{}", services.render->port()),
                                        "--file",
                                        "cuboidA.h5",
                                        "--size",
                                        "320x240",
                                        "--seconds",
                                        "1",
                                        "--still-frames",
                                        "3",
                                        "--jumps",
                                        "4",
                                        "--playback-steps",
                                        "5",
                                        "--playback-rate",
                                        "10",
                                        "--ca",
                                        tls.ca,
                                        "--cert",
                                        tls.cert,
                                        "--key",
                                        tls.key,
                                        "--json"});
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  const auto json = nlohmann::json::parse(run.out.substr(run.out.find('{')));
  CHECK(json.at("size") == "320x240");
  CHECK(json.at("event_to_frame_ms").at("count").get<int>() > 10);
  // Each still request answered by a full-resolution frame, timed from the
  // camera move to its arrival.
  const auto& still = json.at("full_resolution_event_to_frame_ms");
  CHECK(still.at("count") == 3);
  CHECK(still.at("p50").get<double>() > 0.0);
  CHECK(json.at("full_resolution_render_ms").at("count") == 3);
  CHECK(json.at("full_resolution_render_ms").at("p50").get<double>() <=
        still.at("p50").get<double>());
  // The default view draws its particles as spheres in every frame, reduced or not.
  const auto& kinds = json.at("frame_kinds");
  REQUIRE(!kinds.empty());
  int frames = 0;
  for (const auto& [kind, count] : kinds.items()) {
    INFO(kind);
    CHECK_THAT(kind, Catch::EndsWith(" spheres"));
    frames += count.get<int>();
  }
  CHECK(kinds.contains("1/1 spheres"));
  CHECK(frames >= 3 + 1);
  // Every frame listed, as counted.
  REQUIRE(json.at("frames").size() == static_cast<std::size_t>(frames));
  for (const auto& frame : json.at("frames")) {
    CHECK(frame.at("particles") == "spheres");
    CHECK(frame.at("reduction").get<int>() >= 1);
  }
  CHECK(json.at("targets").at("interactive_spheres_at_most_2x_reduction").is_boolean());
  // The server's part of the drag frames' latency, from their timings.
  const auto& serverPart = json.at("server_event_to_send_ms");
  CHECK(serverPart.at("count").get<int>() >= 1);
  CHECK(serverPart.at("p50").get<double>() > 0.0);
  CHECK(json.at("load_before").size() == 3);
  // The time to the first picture (issue 34 point 1): three sessions opened
  // and closed, each timed from OpenSession to its first full-resolution
  // frame, with the server's parts, which happen inside that time.
  const auto& first = json.at("first_picture");
  REQUIRE(first.at("opens").size() == 3);
  for (const auto& open : first.at("opens")) {
    const auto& server = open.at("server");
    CHECK(open.at("total_ms").get<double>() == Approx(open.at("open_session_ms").get<double>() +
                                                      open.at("first_frame_ms").get<double>()));
    CHECK(server.at("open_file_ms").get<double>() > 0.0);  // each session opens the file
    // The file's Describe is part of the open (a Describe through
    // crackvis-data takes a round trip, however warm its cache).
    CHECK(server.at("describe_ms").get<double>() > 0.0);
    CHECK(server.at("describe_ms").get<double>() <= server.at("open_file_ms").get<double>());
    CHECK(server.at("renderer_ms").get<double>() > 0.0);
    CHECK(server.at("extract_ms").get<double>() > 0.0);
    CHECK(server.at("render_ms").get<double>() > 0.0);
    CHECK(server.at("encode_ms").get<double>() > 0.0);
    CHECK(open.at("other_ms").get<double>() >= 0.0);
  }
  CHECK(first.at("first") == first.at("opens").front());
  CHECK(first.at("later_median").at("total_ms").get<double>() > 0.0);
  // Jumps in time (issue 34 point 2): each to another step, its full frame
  // no earlier than its first, forwards and backwards counted apart.
  const auto& jumps = json.at("jumps");
  REQUIRE(jumps.at("list").size() == 4);
  for (const auto& jump : jumps.at("list")) {
    CHECK(jump.at("from") != jump.at("to"));
    CHECK(jump.at("first_frame_ms").get<double>() > 0.0);
    CHECK(jump.at("full_frame_ms").get<double>() >= jump.at("first_frame_ms").get<double>());
  }
  CHECK(jumps.at("forward_full_frame_ms").at("count").get<int>() +
            jumps.at("backward_full_frame_ms").at("count").get<int>() ==
        4);
  CHECK(json.at("targets").contains("jump_full_frame_p95_le_100ms"));
  // Playback: 5 steps ending at the last, each shown, paced by the server at
  // the asked rate (never faster: 4 periods at least between the first and
  // the last step's frames).
  const auto& playback = json.at("playback");
  CHECK(playback.at("steps").get<int>() == 5);
  CHECK(playback.at("steps_not_shown").get<int>() == 0);
  CHECK(playback.at("gap_ms").at("count").get<int>() == 5);
  CHECK(playback.at("seconds").get<double>() >= 0.39);
  CHECK(playback.at("achieved_rate").get<double>() > 0.0);
  CHECK(json.at("targets").contains("playback_no_missed_slots"));
}

TEST_CASE("crackvis bench render --sessions drags several sessions at once, each measured",
          "[render][service][integration][bench]") {
  // issue 34 point 3: N users on one node, each with its own connection,
  // session and file, dragging together; the server here runs in this
  // process, whose CPU time and memory the benchmark samples.
  auto services = startServices();
  const auto tls = testing::clientTls("client");
  const auto run = testing::runProcess({CRACKVIS_CLI,
                                        "bench",
                                        "render",
                                        "--server",
                                        fmt::format("localhost:{}", services.render->port()),
                                        "--file",
                                        "cuboidA.h5",
                                        "--file",
                                        "alice/a.h5",
                                        "--sessions",
                                        "3",
                                        "--server-pid",
                                        std::to_string(getpid()),
                                        "--size",
                                        "320x240",
                                        "--seconds",
                                        "1",
                                        "--ca",
                                        tls.ca,
                                        "--cert",
                                        tls.cert,
                                        "--key",
                                        tls.key,
                                        "--json"});
  INFO(run.out << run.err);
  REQUIRE(run.exitCode == 0);
  const auto json = nlohmann::json::parse(run.out.substr(run.out.find('{')));
  CHECK(json.at("sessions") == 3);
  CHECK(json.at("failed") == 0);
  const auto& each = json.at("per_session");
  REQUIRE(each.size() == 3);
  CHECK(each[0].at("file") == "cuboidA.h5");
  CHECK(each[1].at("file") == "alice/a.h5");
  CHECK(each[2].at("file") == "cuboidA.h5");
  for (const auto& session : each) {
    CHECK(session.at("events").get<int>() > 10);
    CHECK(session.at("event_to_frame_ms").at("count").get<int>() > 10);
    CHECK(session.at("event_to_frame_ms").at("p50").get<double>() > 0.0);
    CHECK(session.at("fps").get<double>() > 0.0);
    CHECK(session.at("reduction_mean").get<double>() >= 1.0);
  }
  CHECK(json.at("p95_max_ms").get<double>() >= json.at("p50_max_ms").get<double>());
  const auto& server = json.at("server");
  REQUIRE(server.is_object());
  CHECK(server.at("cpu_cores").get<double>() > 0.0);
  CHECK(server.at("rss_peak_mib").get<double>() > 0.0);
}

TEST_CASE("a session at the largest view stays within its memory bound, and closing frees it",
          "[render][service][integration]") {
  // issue 29 point 5: 8 sessions at 3840x2160 took 3.2 GiB. What one session
  // at the largest view (limits.max_width x max_height) costs this process,
  // the render server, is bounded here; docs/security.md states the bound.
  auto services = startServices();
  // The heap trimmed a second after the last close, not after the default
  // ten: what closing frees is read back within the wait below.
  service::RenderServerConfig config = renderConfig(*services.data);
  config.heapTrimAfterMs = 1000;
  services.render = startRenderServer(config);
  auto stub = connect(*services.render);
  auto snapshotOf = [&](const std::string& id, int width, int height) {
    grpc::ClientContext context;
    v1::SnapshotRequest request;
    request.set_session_id(id);
    request.set_width(width);
    request.set_height(height);
    v1::SnapshotResponse png;
    return stub->Snapshot(&context, request, &png).ok();
  };
  auto closeOf = [&](const std::string& id) {
    grpc::ClientContext context;
    v1::CloseSessionRequest close;
    close.set_session_id(id);
    v1::CloseSessionResponse closed;
    return stub->CloseSession(&context, close, &closed).ok();
  };
  // Once first, so that libraries, caches and the file's description are
  // not counted.
  auto view = crackView();
  view.view.width = 3840;
  view.view.height = 2160;
  const std::string warm = openSession(*stub, view);
  REQUIRE(snapshotOf(warm, 3840, 2160));
  REQUIRE(closeOf(warm));
  const std::uint64_t before = residentBytes();
  std::vector<std::string> ids;
  for (int i = 0; i < 2; ++i) {
    ids.push_back(openSession(*stub, view));
    REQUIRE(snapshotOf(ids.back(), 3840, 2160));
  }
  const std::uint64_t loaded = residentBytes();
  const double perSessionMiB =
      static_cast<double>(loaded - std::min(loaded, before)) / 2 / (1 << 20);
  for (const std::string& id : ids) {
    CHECK(closeOf(id));
  }
  REQUIRE(waitUntil([&] { return services.render->sessionCount() == 0; }, 10.0));
  // The server trims its heap once no session has ended for a second (as
  // configured above; HeapTrimmer): what is left is read until then.
  double leftMiB = 0.0;
  waitUntil(
      [&] {
        const std::uint64_t now = residentBytes();
        leftMiB = static_cast<double>(now - std::min(now, before)) / (1 << 20);
        return leftMiB < 256.0;
      },
      10.0);
  std::printf(
      "a session of cuboid A at 3840x2160: %.0f MiB resident; %.0f MiB left after closing "
      "two\n",
      perSessionMiB, leftMiB);
  CHECK(perSessionMiB < 512.0);
  CHECK(leftMiB < 256.0);
}

TEST_CASE("a session follows a live file as the writer adds steps",
          "[render][service][integration][live]") {
  auto services = startServices();
  auto stub = connect(*services.render);
  const std::string name = "following.h5";
  const std::string path = crackRoot().file(name);
  std::filesystem::remove(path);
  constexpr int kSteps = 60;
  pid_t writer =
      startProcess({CRACKVIS_CLI, "sim", "plate2d", "--scale", "0.3", "--steps",
                    std::to_string(kSteps), "--pace", "0.15", "--live", "-q", "-o", path});
  REQUIRE(writer > 0);
  REQUIRE(waitUntil([&] { return std::filesystem::exists(path); }, 60.0));
  auto view = crackView();
  view.file = name;
  view.step = -1;  // the last step of a live file: the session follows it
  const std::string id = openSession(*stub, view);
  StreamClient stream(*stub, id);
  auto lastState = [&] {
    const auto states = stream.states();
    return states.empty() ? v1::SessionState() : states.back();
  };

  SECTION("each new step is told and shown, in order, until the run ends") {
    REQUIRE(waitUntil([&] { return lastState().run_ended(); }, 120.0));
    CHECK(waitProcess(writer) == 0);
    const auto states = stream.states();
    std::set<int> counts;
    int previousCount = 0;
    int followedLive = 0;
    for (const v1::SessionState& state : states) {
      CHECK(state.step_count() >= previousCount);  // steps are never taken back
      previousCount = state.step_count();
      counts.insert(state.step_count());
      if (state.live() && state.following()) {
        ++followedLive;
        CHECK(state.step() == state.step_count() - 1);  // following shows the newest
      }
    }
    CHECK(counts.size() >= 3);  // the stream heard of new steps while the run went on
    CHECK(followedLive >= 2);
    const v1::SessionState last = states.back();
    CHECK(last.step_count() == kSteps);
    CHECK(last.step() == kSteps - 1);
    CHECK_FALSE(last.live());
    REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
      return !frames.empty() && frames.back().frame.step() == kSteps - 1;
    }));
    const auto frames = stream.frames();
    for (std::size_t k = 1; k < frames.size(); ++k) {
      CHECK(frames[k].frame.step() >= frames[k - 1].frame.step());
    }
    CHECK(stream.errors().empty());
    // A screenshot of the live file's session, at a step of one's own (as a
    // movie takes them): the PNG comes, and the session stops following.
    grpc::ClientContext snapshotContext;
    v1::SnapshotRequest request;
    request.set_session_id(id);
    request.set_step(kSteps / 2);
    v1::SnapshotResponse png;
    const grpc::Status snapshot = stub->Snapshot(&snapshotContext, request, &png);
    INFO(snapshot.error_message());
    REQUIRE(snapshot.ok());
    CHECK(png.png().size() > 100);
    CHECK(png.step() == kSteps / 2);
  }

  SECTION("stepping back leaves follow mode, and follow returns to the newest step") {
    REQUIRE(waitUntil([&] { return lastState().step_count() >= 5; }, 60.0));
    stream.setStep(1);
    REQUIRE(waitUntil([&] { return !lastState().following() && lastState().step() == 1; }, 30.0));
    const int seen = lastState().step_count();
    REQUIRE(waitUntil([&] { return lastState().step_count() > seen; }, 60.0));
    CHECK(lastState().step() == 1);  // new steps are told, the view stays
    v1::ClientEvent follow;
    follow.mutable_set_step()->set_follow(true);
    stream.send(follow);
    REQUIRE(waitUntil(
        [&] {
          const auto state = lastState();
          return state.following() && state.step() == state.step_count() - 1;
        },
        30.0));
    kill(writer, SIGTERM);
    waitProcess(writer);
  }

  SECTION("a writer killed mid-run leaves the session at its last complete step") {
    REQUIRE(waitUntil([&] { return lastState().step_count() >= 4; }, 60.0));
    kill(writer, SIGKILL);
    waitProcess(writer);
    const auto count = [&] { return lastState().step_count(); };
    std::this_thread::sleep_for(std::chrono::seconds(1));
    const int settled = count();
    std::this_thread::sleep_for(std::chrono::seconds(1));
    CHECK(count() == settled);
    CHECK(lastState().live());  // the writer never said it ended
    const auto event = stream.setStep(-1);
    REQUIRE(stream.waitFor([&](const auto& frames, const auto&) {
      return !frames.empty() && frames.back().frame.last_event_id() == event &&
             frames.back().frame.full_resolution();
    }));
    CHECK(stream.frames().back().frame.step() == settled - 1);

    SECTION("and a new run under the same name is refused, never mixed in") {
      const pid_t again = startProcess({CRACKVIS_CLI, "sim", "plate2d", "--scale", "0.3", "--steps",
                                        "3", "--live", "-q", "-o", path});
      REQUIRE(waitProcess(again) == 0);
      REQUIRE(stream.waitFor([](const auto&, const auto& errors) { return !errors.empty(); }));
      CHECK(stream.errors().back().message().find("was replaced") != std::string::npos);
      CHECK(lastState().step_count() == settled);  // the session kept the first run
    }
  }
  std::filesystem::remove(path);
}
