// crackvis-client as a user starts it (issue 18, errors that say what to
// do): without a display, with a misspelt option, and --window-screenshot
// runs that cannot succeed, which print the reason at once and exit 1
// instead of waiting out their 60 s. The services run in this process.
#include <QByteArray>
#include <QJsonDocument>
#include <QJsonObject>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "client/client_process.hpp"
#include "dataservice/service_fixture.hpp"
#include "service/render_fixture.hpp"
#include "support/network.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>

using namespace crackvis;
using namespace crackvis::testing;

namespace {

std::vector<std::string> connection(const std::string& address) {
  const auto tls = clientTls("client");
  return {"--connect", address, "--ca", tls.ca, "--cert", tls.cert, "--key", tls.key};
}

struct TimedRun {
  ProcessResult result;
  double seconds = 0.0;
};

TimedRun screenshotRun(const std::vector<std::string>& args) {
  const auto start = std::chrono::steady_clock::now();
  TimedRun run{runClient(kOffscreen, args), 0.0};
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace

TEST_CASE(
    "with --window-screenshot the client prints why it cannot take the picture and exits at once",
    "[client][integration]") {
  auto services = startServices();
  TempDir out;
  const std::string png = out.file("shot.png");
  SECTION("a file the server refuses") {
    auto args = connection(services.render->address());
    args.insert(args.end(), {"--file", "missing.h5", "--window-screenshot", png});
    const TimedRun run = screenshotRun(args);
    INFO(run.result.err);
    CHECK(run.result.exitCode == 1);
    const auto own = clientLines(run.result.err);
    REQUIRE(own.size() == 1);
    CHECK_THAT(own[0], Catch::StartsWith("crackvis-client: cannot open missing.h5: ") &&
                           Catch::Contains("missing.h5"));
    CHECK(run.seconds < 20.0);
  }
  SECTION("a --pipeline step the file lacks") {
    auto view = crackView();
    view.file = "cuboidA.h5";
    view.step = 100000;
    const std::string xml = out.file("view.xml");
    std::ofstream(xml) << pipeline::toXml(view);
    auto args = connection(services.render->address());
    args.insert(args.end(),
                {"--file", "cuboidA.h5", "--pipeline", xml, "--window-screenshot", png});
    const TimedRun run = screenshotRun(args);
    INFO(run.result.err);
    CHECK(run.result.exitCode == 1);
    const auto own = clientLines(run.result.err);
    REQUIRE(own.size() == 1);
    CHECK_THAT(own[0], Catch::Contains("step 100000 out of range (the file has steps 0.."));
    CHECK(run.seconds < 20.0);
  }
  SECTION("no render server") {
    const std::string address = fmt::format("localhost:{}", closedPort());
    auto args = connection(address);
    args.insert(args.end(), {"--file", "cuboidA.h5", "--window-screenshot", png});
    const TimedRun run = screenshotRun(args);
    CHECK(run.result.exitCode == 1);
    CHECK(clientLines(run.result.err) ==
          std::vector<std::string>{fmt::format(
              "crackvis-client: cannot connect: no crackvis-render at {} (connection refused): "
              "is it running? see docs/deploy.md",
              address)});
    CHECK(run.seconds < 20.0);
  }
  SECTION("no file to show") {
    auto args = connection(services.render->address());
    args.insert(args.end(), {"--window-screenshot", png});
    const auto result = runClient(kOffscreen, args);
    CHECK(result.exitCode == 2);
    CHECK(clientLines(result.err) ==
          std::vector<std::string>{"crackvis-client: --window-screenshot needs --connect "
                                   "and --file (or a --pipeline view that names a file)"});
  }
  CHECK_FALSE(std::filesystem::exists(png));
}

TEST_CASE(
    "crackvis-client --measure-latency drags the window's view and times each event to its paint",
    "[client][integration]") {
  auto services = startServices();
  TempDir out;
  const std::string json = out.file("latency.json");
  auto args = connection(services.render->address());
  args.insert(args.end(), {"--file", "cuboidA.h5", "--measure-latency", json, "--view-size",
                           "640x480", "--drag-seconds", "1", "--still-moves", "3"});
  const TimedRun run = screenshotRun(args);
  INFO(run.result.err);
  REQUIRE(run.result.exitCode == 0);
  CHECK(clientLines(run.result.err).empty());
  std::ifstream in(json);
  std::stringstream text;
  text << in.rdbuf();
  const QJsonObject figures =
      QJsonDocument::fromJson(QByteArray::fromStdString(text.str())).object();
  INFO(text.str());
  CHECK(figures["size"].toString() == "640x480");
  CHECK(figures["platform"].toString() == "offscreen");
  CHECK(figures["first_frame_ms"].toDouble() > 0.0);
  // The drag's 60 moves: every one reached the server as an event and was
  // reflected by a painted frame, the release's still request too.
  const QJsonObject drag = figures["drag_event_to_paint_ms"].toObject();
  CHECK(drag["n"].toInt() == 61);
  CHECK(drag["p50"].toDouble() > 0.0);
  CHECK(drag["p95"].toDouble() >= drag["p50"].toDouble());
  const int frames = figures["drag_frames"].toInt();
  CHECK(frames > 0);
  CHECK(figures["decode_ms"].toObject()["n"].toInt() == frames);
  CHECK(figures["drag_fps"].toDouble() > 0.0);
  CHECK(figures["client_cpu_ms_per_frame"].toDouble() > 0.0);
  CHECK(figures["bitrate_mbps"].toDouble() > 0.0);
  // Each still move is one event, answered by one painted frame.
  const QJsonObject still = figures["still_event_to_paint_ms"].toObject();
  CHECK(still["n"].toInt() == 3);
  CHECK(still["p50"].toDouble() > 0.0);
  // The server's part of a frame's latency is inside the whole.
  const QJsonObject server = figures["server_event_to_send_ms"].toObject();
  CHECK(server["n"].toInt() > 0);
  CHECK(server["p50"].toDouble() > 0.0);
  CHECK(server["p50"].toDouble() < drag["p95"].toDouble());
}
