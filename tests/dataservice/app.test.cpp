// crackvis-data as a user runs it: a child process with flags or a config
// file, on a loopback port the OS chooses, stopped with SIGTERM; and the
// one-line errors it gives instead of starting.
#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "service_fixture.hpp"
#include "support/process.hpp"

extern char** environ;

namespace crackvis::testing {
namespace {

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A crackvis-data child with stdout and stderr in files; SIGTERM at the end.
class ServerProcess {
 public:
  // `environment`: the child's, default this process's.
  explicit ServerProcess(std::vector<std::string> args, char** environment = environ) {
    args.insert(args.begin(), CRACKVIS_DATA);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, out().c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0600);
    posix_spawn_file_actions_addopen(&actions, 2, err().c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0600);
    std::vector<char*> argv;
    for (auto& arg : args) {
      argv.push_back(arg.data());
    }
    argv.push_back(nullptr);
    const int spawned = posix_spawn(&m_pid, argv[0], &actions, nullptr, argv.data(), environment);
    posix_spawn_file_actions_destroy(&actions);
    REQUIRE(spawned == 0);
  }
  ~ServerProcess() {
    if (m_pid > 0) {
      ::kill(m_pid, SIGKILL);
      ::waitpid(m_pid, nullptr, 0);
    }
  }

  pid_t pid() const { return m_pid; }
  std::string out() const { return m_dir.file("stdout"); }
  std::string err() const { return m_dir.file("stderr"); }

  // The address from the line 'crackvis-data event=serving address="HOST:PORT" ...'.
  std::string waitForAddress() {
    constexpr std::string_view kServing = "event=serving address=\"";
    for (int i = 0; i < 500; ++i) {
      const std::string text = readText(out());
      const size_t at = text.find(kServing);
      const size_t end = text.find('"', at == std::string::npos ? 0 : at + kServing.size());
      if (at != std::string::npos && end != std::string::npos) {
        return text.substr(at + kServing.size(), end - at - kServing.size());
      }
      int status = 0;
      if (::waitpid(m_pid, &status, WNOHANG) == m_pid) {
        m_pid = 0;
        FAIL("crackvis-data exited: " << readText(err()));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    FAIL("crackvis-data did not report its address: " << readText(err()));
    return {};
  }

  int terminate() {
    ::kill(m_pid, SIGTERM);
    int status = 0;
    ::waitpid(m_pid, &status, 0);
    m_pid = 0;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  TempDir m_dir;
  pid_t m_pid = 0;
};

// Whether an --insecure server at `address` answers its health check.
bool healthyWithoutTls(const std::string& address) {
  dataservice::ClientOptions options;
  options.target = address;
  options.insecure = true;
  auto client = connect(options);
  return client.checkHealth().isOk();
}

TEST_CASE("crackvis-data explains itself and refuses bad setups in one line",
          "[dataservice][integration]") {
  const std::string root = sampleRoot().root.path().string();
  const auto tls = serverTls();
  SECTION("--help") {
    const ProcessResult help = runProcess({CRACKVIS_DATA, "--help"});
    CHECK(help.exitCode == 0);
    for (const std::string flag :
         {"--config", "--listen", "--root", "--ca", "--cert", "--key", "--insecure", "--access-log",
          "--raw-tls-listen", "--max-read-bytes", "--max-streams", "hash-secret"}) {
      CHECK_THAT(help.out, Catch::Contains(flag));
    }
  }
  struct Refusal {
    std::vector<std::string> args;
    std::string message;
  };
  for (const Refusal& refusal : std::vector<Refusal>{
           {{"--root", root, "--listen", "127.0.0.1:0", "--ca", "/nonexistent/ca.pem", "--cert",
             tls.cert, "--key", tls.key},
            "cannot read CA certificate '/nonexistent/ca.pem'"},
           {{"--root", root, "--insecure", "--listen", "0.0.0.0:0"}, "loopback"},
           {{"--listen", "127.0.0.1:0"}, "no data root"},
           {{"--root", root + "/absent", "--insecure", "--listen", "127.0.0.1:0"}, "data root"},
           {{"--config", root + "/notes.txt"}, "not valid JSON"},
           {{"--root", root, "--insecure", "--listen", "localhost"}, "host:port"}}) {
    std::vector<std::string> argv = {CRACKVIS_DATA};
    argv.insert(argv.end(), refusal.args.begin(), refusal.args.end());
    const ProcessResult result = runProcess(argv);
    INFO(result.err);
    CHECK(result.exitCode == 1);
    CHECK(lines(result.err).size() == 1);
    CHECK_THAT(result.err,
               Catch::StartsWith("crackvis-data: ") && Catch::Contains(refusal.message));
  }
  const ProcessResult usage = runProcess({CRACKVIS_DATA, "--no-such-flag"});
  CHECK(usage.exitCode == 2);
}

TEST_CASE("crackvis-data serves from a config file until SIGTERM", "[dataservice][integration]") {
  TempDir dir;
  const auto tls = serverTls();
  const std::string config = dir.file("data.json");
  std::ofstream(config) << fmt::format(
      R"({{"listen": "127.0.0.1:0", "data_root": "{}", "access_log": "{}",
          "tls": {{"ca": "{}", "cert": "{}", "key": "{}"}},
          "limits": {{"max_read_bytes": 1048576}}}})",
      sampleRoot().root.path().string(), dir.file("access.log"), tls.ca, tls.cert, tls.key);
  ServerProcess server({"--config", config});
  const std::string address = server.waitForAddress();
  CHECK_THAT(address, Catch::StartsWith("127.0.0.1:"));
  dataservice::ClientOptions options;
  options.target = address;
  options.tls = clientTls();
  auto client = connect(options);
  CHECK(client.checkHealth().isOk());
  auto arrays = client.read("run.h5", {dataservice::Hyperslab::whole("/bonds/pairs")});
  REQUIRE(arrays.isOk());
  CHECK(bitIdentical(arrays->front().values<std::int32_t>().value(),
                     readDirect<std::int32_t>(sampleRoot().file("run.h5"), "/bonds/pairs")));
  // The limit from the file applies.
  CHECK(client.read("big.h5", {dataservice::Hyperslab::whole("/ramp")}).status().code() ==
        StatusCode::kResourceExhausted);
  CHECK(server.terminate() == 0);
  const auto logLines = lines(readText(dir.file("access.log")));
  REQUIRE(logLines.size() == 2);
  CHECK_THAT(logLines[0], Catch::Contains("method=Read") && Catch::Contains("file=\"run.h5\""));
}

TEST_CASE("crackvis-data --insecure warns and serves loopback", "[dataservice][integration]") {
  ServerProcess server({"--root", sampleRoot().root.path().string(), "--insecure", "--listen",
                        "127.0.0.1:0", "--access-log", ""});
  const std::string address = server.waitForAddress();
  CHECK_THAT(readText(server.out()), Catch::Contains("INSECURE"));
  CHECK_THAT(readText(server.err()), Catch::Contains("WARNING") && Catch::Contains("--insecure"));
  CHECK(healthyWithoutTls(address));
  CHECK(server.terminate() == 0);
}

TEST_CASE("crackvis-data re-executes itself once with glibc's huge pages where THP is on request",
          "[dataservice][integration][huge-pages]") {
  const bool onRequest =
      readText("/sys/kernel/mm/transparent_hugepage/enabled").find("[madvise]") !=
      std::string::npos;
  INFO("THP " << (onRequest ? "on request (madvise)" : "always or never"));
  // This process's environment without the variables the cases set.
  std::vector<std::string> base;
  for (char** v = environ; *v != nullptr; ++v) {
    const std::string_view variable = *v;
    if (!variable.starts_with("GLIBC_TUNABLES=") && !variable.starts_with("CRACKVIS_HUGE_PAGES")) {
      base.emplace_back(variable);
    }
  }
  struct Case {
    std::string extra;  // a variable added to the child's environment
    bool hugePages;     // whether the running server asked for them
  };
  for (const Case& c : std::vector<Case>{{"", onRequest},
                                         {"GLIBC_TUNABLES=glibc.malloc.arena_max=4", onRequest},
                                         {"GLIBC_TUNABLES=glibc.malloc.hugetlb=0", false},
                                         {"CRACKVIS_HUGE_PAGES=0", false},
                                         {"CRACKVIS_HUGE_PAGES_REEXECUTED=1", false}}) {
    std::vector<std::string> variables = base;
    if (!c.extra.empty()) {
      variables.push_back(c.extra);
    }
    std::vector<char*> environment;
    for (std::string& variable : variables) {
      environment.push_back(variable.data());
    }
    environment.push_back(nullptr);
    INFO("extra variable: " << (c.extra.empty() ? "none" : c.extra));
    ServerProcess server({"--root", sampleRoot().root.path().string(), "--insecure", "--listen",
                          "127.0.0.1:0", "--access-log", ""},
                         environment.data());
    const std::string address = server.waitForAddress();  // serves after the re-execution
    // The environment the running program started with. glibc ends each
    // tunable it reads with a NUL there, so the tunables are looked for
    // as text, not as whole variables.
    const std::string started = readText("/proc/" + std::to_string(server.pid()) + "/environ");
    CHECK((started.find("glibc.malloc.hugetlb=1") != std::string::npos) == c.hugePages);
    // With them, one malloc arena, unless the user chose a count.
    CHECK((started.find("glibc.malloc.arena_max=1") != std::string::npos) ==
          (c.hugePages && c.extra.find("arena_max") == std::string::npos));
    if (c.extra.starts_with("GLIBC_TUNABLES=")) {
      CHECK(started.find(c.extra) != std::string::npos);  // what the user set is kept
    }
    // Its HDF5 workers get huge pages and a heap that grows 16 MiB at a
    // time, unless the user turned huge pages off: nothing else of the
    // service's environment. A worker is not dumpable, so only root reads
    // its /proc/PID/environ; children are listed per thread of the service.
    const std::string tasks = "/proc/" + std::to_string(server.pid()) + "/task";
    const std::string firstTask = tasks + "/" + std::to_string(server.pid()) + "/children";
    if (::geteuid() != 0 || !std::filesystem::exists(firstTask)) {
      WARN("the workers' environment is not checked: needs root and /proc/PID/task/*/children");
    } else {
      const bool workersGetThem = onRequest && c.extra != "CRACKVIS_HUGE_PAGES=0";
      int workers = 0;
      for (const auto& task : std::filesystem::directory_iterator(tasks)) {
        std::istringstream children(readText((task.path() / "children").string()));
        for (std::string child; children >> child; ++workers) {
          std::string workerEnvironment = readText("/proc/" + child + "/environ");
          // glibc puts a NUL after each tunable's value it reads.
          std::replace(workerEnvironment.begin(), workerEnvironment.end(), '\0', ':');
          CHECK(workerEnvironment ==
                (workersGetThem ? "GLIBC_TUNABLES=glibc.malloc.hugetlb=1:glibc.malloc.top_pad="
                                  "16777216:glibc.malloc.mmap_threshold=33554432:"
                                : ""));
        }
      }
      CHECK(workers == 4);  // crackvis-data's default
    }
    // Re-executed from its own file, not /proc/self/exe: ps still names it.
    CHECK(readText("/proc/" + std::to_string(server.pid()) + "/comm") == "crackvis-data\n");
    CHECK(healthyWithoutTls(address));  // the same process and arguments: it still serves
    CHECK(server.terminate() == 0);
  }
}

}  // namespace
}  // namespace crackvis::testing
