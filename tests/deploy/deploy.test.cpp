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
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "crackvis/v1/render.grpc.pb.h"
#include "dataservice/service_fixture.hpp"
#include "service/render_fixture.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/common/huge_pages.hpp>
#include <crackvis/common/service_manager.hpp>

using namespace crackvis;
using namespace crackvis::testing;
using Clock = std::chrono::steady_clock;

namespace {

// A service started like systemd starts it (NOTIFY_SOCKET among `extraEnv`
// for a Type=notify unit), its output in a file.
class Service {
 public:
  Service(const std::vector<std::string>& argv, const std::string& log,
          const std::vector<std::string>& extraEnv = {})
      : m_log(log) {
    // Arguments and environment are built before fork: the child only execs.
    std::vector<char*> args;
    for (const auto& a : argv) {
      args.push_back(const_cast<char*>(a.c_str()));
    }
    args.push_back(nullptr);
    std::vector<char*> env;
    for (char** variable = environ; *variable != nullptr; ++variable) {
      env.push_back(*variable);
    }
    for (const auto& variable : extraEnv) {
      env.push_back(const_cast<char*>(variable.c_str()));
    }
    env.push_back(nullptr);
    m_pid = fork();
    if (m_pid == 0) {
      const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      execve(args[0], args.data(), env.data());
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

// The receiving end of $NOTIFY_SOCKET, as systemd holds it for a Type=notify
// unit: a datagram socket bound to a path, or with a leading '@' to a name in
// the abstract namespace.
class NotifySocket {
 public:
  explicit NotifySocket(const std::string& path) : m_path(path) {
    m_fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::snprintf(address.sun_path, sizeof(address.sun_path), "%s", path.c_str());
    if (path.front() == '@') {
      address.sun_path[0] = '\0';
    }
    const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size());
    m_bound = bind(m_fd, reinterpret_cast<const sockaddr*>(&address), length) == 0;
  }
  ~NotifySocket() { close(m_fd); }
  bool bound() const { return m_bound; }
  std::string environment() const { return "NOTIFY_SOCKET=" + m_path; }
  // The next message, or "" after `seconds` without one.
  std::string receive(double seconds) const {
    pollfd waiting{m_fd, POLLIN, 0};
    if (poll(&waiting, 1, static_cast<int>(seconds * 1000)) != 1) {
      return {};
    }
    char buffer[4096];
    const ssize_t size = recv(m_fd, buffer, sizeof(buffer), 0);
    return size > 0 ? std::string(buffer, static_cast<std::size_t>(size)) : std::string();
  }

 private:
  std::string m_path;
  int m_fd = -1;
  bool m_bound = false;
};

std::string healthOf(int port) {
  const auto tls = clientTls("client");
  const auto result = runProcess({CRACKVIS_CLI, "health", fmt::format("127.0.0.1:{}", port), "--ca",
                                  tls.ca, "--cert", tls.cert, "--key", tls.key});
  return result.exitCode == 0 ? result.out : "exit " + std::to_string(result.exitCode) + result.err;
}

}  // namespace

TEST_CASE("readiness reaches systemd's notify socket, a path or an abstract name", "[deploy]") {
  CHECK(unsetenv("NOTIFY_SOCKET") == 0);
  CHECK_FALSE(service_manager::notify("READY=1"));  // not under systemd: nothing sent
  const NotifySocket abstract(fmt::format("@crackvis-notify-test-{}", getpid()));
  REQUIRE(abstract.bound());
  CHECK(setenv("NOTIFY_SOCKET", abstract.environment().substr(14).c_str(), 1) == 0);
  CHECK(service_manager::notify("STATUS=testing"));
  CHECK(abstract.receive(5.0) == "STATUS=testing");
  CHECK(setenv("NOTIFY_SOCKET", "relative/path", 1) == 0);
  CHECK_FALSE(service_manager::notify("READY=1"));  // not an address systemd gives
  CHECK(unsetenv("NOTIFY_SOCKET") == 0);
}

TEST_CASE("the services and the CLI say their versions", "[deploy]") {
  for (const std::string program : {CRACKVIS_DATA, CRACKVIS_RENDER, CRACKVIS_CLI}) {
    const auto result = runProcess({program, "--version"});
    INFO(program << ": " << result.out << result.err);
    CHECK(result.exitCode == 0);
    CHECK_THAT(result.out, Catch::Contains(" 0.") && Catch::StartsWith("crackvis"));
  }
  CHECK_THAT(runProcess({CRACKVIS_DATA, "--version"}).out, Catch::Contains("HDF5 1."));
  CHECK_THAT(runProcess({CRACKVIS_RENDER, "--version"}).out, Catch::Contains("libavcodec "));
}

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
  // Type=notify: READY=1 once it serves, so `systemctl start` returns then.
  const NotifySocket dataNotify(dir.file("data.notify"));
  REQUIRE(dataNotify.bound());
  Service data({CRACKVIS_DATA, "--config", dataConfig}, dir.file("data.log"),
               {dataNotify.environment()});
  const std::string dataReady = dataNotify.receive(30.0);
  const int dataPort = data.awaitPort();
  INFO(data.output());
  REQUIRE(dataPort > 0);
  CHECK(dataReady.rfind("READY=1\nSTATUS=serving 127.0.0.1:", 0) == 0);
  CHECK(healthOf(dataPort).find("SERVING") != std::string::npos);
  const std::string renderConfig = write(dir, "render.json",
                                         fmt::format(R"({{"listen": "127.0.0.1:0",
  "tls": {{"ca": "{}", "cert": "{}", "key": "{}"}},
  "data_service": {{"target": "localhost:{}", "ca": "{}", "cert": "{}", "key": "{}"}},
  "limits": {{"max_sessions": 4, "session_grace_seconds": 30}}, "access_log": "-"}})",
                                                     server.ca, server.cert, server.key, dataPort,
                                                     render.ca, render.cert, render.key));
  const NotifySocket renderNotify(dir.file("render.notify"));
  REQUIRE(renderNotify.bound());
  Service renderer({CRACKVIS_RENDER, "--config", renderConfig}, dir.file("render.log"),
                   {renderNotify.environment()});
  CHECK(renderNotify.receive(30.0).rfind("READY=1\n", 0) == 0);
  const int renderPort = renderer.awaitPort();
  INFO(renderer.output());
  REQUIRE(renderPort > 0);
  // Versions and the rendering backend at start-up.
  CHECK(renderer.output().find("event=start version=\"0.") != std::string::npos);
  CHECK(renderer.output().find("backend=\"EGL") != std::string::npos);
  // The heap kept touched for first pictures (160 MiB unless set): where the
  // service re-executes itself onto one malloc arena (common/huge_pages.hpp),
  // which the reserve needs; elsewhere it reports why it keeps none. Under
  // AddressSanitizer malloc is its own, never the main heap.
  std::ifstream thp("/sys/kernel/mm/transparent_hugepage/enabled");
  const std::string thpMode(std::istreambuf_iterator<char>(thp), {});
  const auto tunables = crackvis::hugePageTunables(thpMode, std::getenv("GLIBC_TUNABLES"),
                                                   std::getenv(crackvis::kHugePagesVariable));
  bool oneArena = tunables && tunables->find("arena_max=1") != std::string::npos;
#ifdef __SANITIZE_ADDRESS__
  oneArena = false;
#endif
  CHECK(renderer.output().find(oneArena
                                   ? "heap_reserve=\"160 MiB\""
                                   : "heap_reserve=\"none (threads have heaps of their own)\"") !=
        std::string::npos);
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
  CHECK(renderNotify.receive(1.0) == "STOPPING=1");
  CHECK(dataNotify.receive(1.0) == "STOPPING=1");
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
