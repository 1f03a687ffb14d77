// Deployment as an operator and a new user meet it: both services started
// from their systemd-style command lines (`--config FILE`), checked through
// grpc.health.v1, stopped with SIGTERM while a session streams; and the
// README's main command, shortened, producing demo.mp4 and demo.png.
#include <QImage>
#include <chrono>
#include <csignal>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include <catch2/catch.hpp>
#include <fcntl.h>
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>
#include <sys/wait.h>
#include <unistd.h>

#include "crackvis/v1/render.grpc.pb.h"
#include "dataservice/service_fixture.hpp"
#include "server/render_fixture.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"

using namespace crackvis;
using namespace crackvis::testing;
using Clock = std::chrono::steady_clock;

namespace {

// A service started like systemd starts it, its output in a file.
class Service {
 public:
  Service(const std::vector<std::string>& argv, const std::string& log) : m_log(log) {
    m_pid = fork();
    if (m_pid == 0) {
      const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      std::vector<char*> args;
      for (const auto& a : argv) {
        args.push_back(const_cast<char*>(a.c_str()));
      }
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
  }
  ~Service() {
    if (m_pid > 0 && !m_reaped) {
      kill(m_pid, SIGKILL);
      waitpid(m_pid, nullptr, 0);
    }
  }
  std::string output() const {
    std::ifstream in(m_log);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  // The port from the line 'event=serving address="HOST:PORT"', once printed.
  int awaitPort(double seconds = 30.0) const {
    const std::regex serving(R"re(event=serving address="[0-9.]+:([0-9]+)")re");
    const auto end = Clock::now() + std::chrono::duration<double>(seconds);
    while (Clock::now() < end) {
      std::smatch match;
      const std::string text = output();
      if (std::regex_search(text, match, serving)) {
        return std::stoi(match[1]);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return 0;
  }
  // SIGTERM; the exit status if the process ended within `seconds`, else -1.
  int terminate(double seconds) {
    kill(m_pid, SIGTERM);
    const auto end = Clock::now() + std::chrono::duration<double>(seconds);
    while (Clock::now() < end) {
      int status = 0;
      if (waitpid(m_pid, &status, WNOHANG) == m_pid) {
        m_reaped = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }

 private:
  std::string m_log;
  pid_t m_pid = -1;
  bool m_reaped = false;
};

std::string write(const TempDir& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir.file(name)) << text;
  return dir.file(name);
}

std::string healthOf(int port) {
  const auto tls = clientTls("client");
  const auto result = runProcess({CRACKVIS_CLI, "health", fmt::format("127.0.0.1:{}", port), "--ca",
                                  tls.ca, "--cert", tls.cert, "--key", tls.key});
  return result.exitCode == 0 ? result.out : "exit " + std::to_string(result.exitCode) + result.err;
}

}  // namespace

TEST_CASE("both services run from config files, answer health and stop on SIGTERM",
          "[deploy][integration]") {
  TempDir dir;
  const auto server = serverTls();
  const auto render = clientTls("crackvis-render");
  const std::string dataConfig =
      write(dir, "data.json",
            fmt::format(R"({{"listen": "127.0.0.1:0", "data_root": "{}",
  "tls": {{"ca": "{}", "cert": "{}", "key": "{}"}}, "access_log": "{}"}})",
                        crackRoot().path().string(), server.ca, server.cert, server.key,
                        dir.file("data-access.log")));
  Service data({CRACKVIS_DATA, "--config", dataConfig}, dir.file("data.log"));
  const int dataPort = data.awaitPort();
  INFO(data.output());
  REQUIRE(dataPort > 0);
  const std::string renderConfig = write(dir, "render.json",
                                         fmt::format(R"({{"listen": "127.0.0.1:0",
  "tls": {{"ca": "{}", "cert": "{}", "key": "{}"}},
  "data_service": {{"target": "localhost:{}", "ca": "{}", "cert": "{}", "key": "{}"}},
  "limits": {{"max_sessions": 4, "session_grace_seconds": 30}}, "access_log": "-"}})",
                                                     server.ca, server.cert, server.key, dataPort,
                                                     render.ca, render.cert, render.key));
  Service renderer({CRACKVIS_RENDER, "--config", renderConfig}, dir.file("render.log"));
  const int renderPort = renderer.awaitPort();
  INFO(renderer.output());
  REQUIRE(renderPort > 0);
  // Versions and the rendering backend at start-up.
  CHECK(renderer.output().find("event=start version=\"0.") != std::string::npos);
  CHECK(renderer.output().find("backend=\"EGL") != std::string::npos);
  CHECK(data.output().find("crackvis-data event=start version=\"0.") != std::string::npos);
  CHECK(healthOf(dataPort).find("SERVING") != std::string::npos);
  CHECK(healthOf(renderPort).find("SERVING") != std::string::npos);

  // A session streams while the render server is told to stop.
  const auto tls = clientTls("client");
  auto read = [](const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  auto stub = v1::RenderService::NewStub(
      grpc::CreateChannel(fmt::format("localhost:{}", renderPort),
                          grpc::SslCredentials({read(tls.ca), read(tls.key), read(tls.cert)})));
  grpc::ClientContext openContext;
  v1::OpenSessionRequest open;
  open.set_pipeline_xml(pipeline::toXml(crackView()));
  v1::OpenSessionResponse opened;
  REQUIRE(stub->OpenSession(&openContext, open, &opened).ok());
  grpc::ClientContext streamContext;
  auto stream = stub->Stream(&streamContext);
  v1::ClientEvent attach;
  attach.set_attach_session_id(opened.session_id());
  REQUIRE(stream->Write(attach));
  v1::ServerMessage message;
  bool framed = false;
  while (!framed && stream->Read(&message)) {
    framed = message.has_frame();
  }
  REQUIRE(framed);

  const auto start = Clock::now();
  CHECK(renderer.terminate(5.0) == 0);
  CHECK(data.terminate(5.0) == 0);
  CHECK(std::chrono::duration<double>(Clock::now() - start).count() < 5.0);
  // The stream ended with the session closed, not hanging.
  while (stream->Read(&message)) {
  }
  const grpc::Status ended = stream->Finish();
  CHECK(!ended.ok());
  CHECK(renderer.output().find("event=stop signal=\"15\" sessions_closed=\"1\"") !=
        std::string::npos);
}

TEST_CASE("the README's main command, shortened, writes demo.mp4 and demo.png",
          "[deploy][integration]") {
  TempDir dir;
  const std::string out = dir.file("out");
  const auto result =
      runProcess({"env", "DEMO_SKIP_INSTALL=1", "DEMO_SCALE=0.3", "DEMO_HEADLESS=1",
                  "CRACKVIS_DEMO_SHORT=1", fmt::format("DEMO_BUILD={}", CRACKVIS_BUILD_DIR),
                  fmt::format("DEMO_DATA={}", dir.file("data")), "DEMO_PORT=0", "bash",
                  CRACKVIS_RUN_DEMO, out});
  INFO(result.out << result.err);
  REQUIRE(result.exitCode == 0);
  const std::regex wrote(R"(wrote .*demo\.mp4 \(([0-9]+) frames\))");
  std::smatch match;
  REQUIRE(std::regex_search(result.out, match, wrote));
  const int frames = std::stoi(match[1]);
  CHECK(frames >= 5);
  const auto probe = runProcess({"ffprobe", "-v", "error", "-count_frames", "-select_streams",
                                 "v:0", "-show_entries", "stream=codec_name,nb_read_frames", "-of",
                                 "csv=p=0", out + "/demo.mp4"});
  CHECK(probe.out == fmt::format("h264,{}\n", frames));
  QImage picture(QString::fromStdString(out + "/demo.png"));
  REQUIRE(!picture.isNull());
  int crack = 0;
  int lit = 0;
  for (int y = 0; y < picture.height(); ++y) {
    for (int x = 0; x < picture.width(); ++x) {
      const QColor c = picture.pixelColor(x, y);
      crack += c.red() > 150 && c.green() < 90 && c.blue() < 90 ? 1 : 0;
      lit += c.red() + c.green() + c.blue() > 150 ? 1 : 0;
    }
  }
  CHECK(lit > picture.width() * picture.height() / 50);  // not blank
  CHECK(crack > 500);  // the crack surfaces' red, which the damage colour map does not have
}
