// crackvis-data's HDF5 work in supervised worker processes (issue 13.7),
// through a real server on loopback: a worker that dies with SIGSEGV in the
// middle of a call fails only that call and is replaced; one stuck in
// libhdf5 is replaced at the call's time limit; a caller that gives up frees
// its worker; and a corpus of corrupt files costs the service nothing.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <random>
#include <thread>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <sys/types.h>

#include "service_fixture.hpp"
#include "support/process.hpp"
#include <crackvis/common/huge_pages.hpp>

namespace crackvis::testing {
namespace {

using dataservice::Hyperslab;

dataservice::ServerConfig oneWorker() {
  auto config = baseConfig();
  config.limits.hdf5Workers = 1;
  return config;
}

}  // namespace

TEST_CASE("A worker that dies with SIGSEGV fails only its call and is replaced",
          "[dataservice][integration]") {
  auto server = startServer(oneWorker());
  const int pid = server->hdf5WorkerPids().at(0);
  REQUIRE(pid > 0);
  auto client = connect(clientOptions(*server));
  // Stopped, the worker takes the request but cannot answer; the fault
  // arrives while the call waits for it, as a libhdf5 crash would.
  REQUIRE(::kill(pid, SIGSTOP) == 0);
  auto describe = std::async(std::launch::async, [&] { return client.describe("run.h5"); });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  REQUIRE(::kill(pid, SIGSEGV) == 0);
  REQUIRE(::kill(pid, SIGCONT) == 0);
  const auto result = describe.get();
  REQUIRE_FALSE(result.isOk());
  INFO(result.status().message());
  CHECK(result.status().code() == StatusCode::kFailedPrecondition);
  CHECK_THAT(result.status().message(), Catch::StartsWith("run.h5: libhdf5 faulted on this file") &&
                                            Catch::Contains("killed by SIGSEGV (signal 11)"));
  CHECK(server->hdf5WorkersReplaced() == 1);
  const int replacement = server->hdf5WorkerPids().at(0);
  CHECK(replacement > 0);
  CHECK(replacement != pid);
  // The next calls are served by the new worker, which outlives the thread
  // that replaced it (a worker dies with the thread that forked it: forked
  // on the call's thread, it died when that ended, and was replaced again).
  CHECK(client.describe("run.h5", /*uncached=*/true).isOk());
  CHECK(server->hdf5WorkersReplaced() == 1);
  CHECK(server->hdf5WorkerPids().at(0) == replacement);
  requireServerHealthy(*server);
}

namespace {

// Whether a child process has died (a zombie, not yet reaped by the server).
bool isZombie(int pid) {
  std::ifstream stat(fmt::format("/proc/{}/stat", pid));
  std::string line;
  std::getline(stat, line);
  const std::size_t close = line.rfind(')');
  return close != std::string::npos && close + 2 < line.size() && line[close + 2] == 'Z';
}

}  // namespace

TEST_CASE("A worker that died while idle is not blamed on the next caller's file",
          "[dataservice][integration]") {
  auto server = startServer(oneWorker());
  auto client = connect(clientOptions(*server));
  REQUIRE(client.describe("run.h5").isOk());
  // Killed between calls (by an operator, the OOM killer, a fault in the
  // previous call's clean-up): the next caller's good file must read.
  for (int round = 0; round < 2; ++round) {
    const int pid = server->hdf5WorkerPids().at(0);
    REQUIRE(::kill(pid, SIGKILL) == 0);
    REQUIRE(waitUntil([&] { return isZombie(pid); }, 2.0));
    const auto result = round == 0
                            ? client.describe("run.h5", /*uncached=*/true).status()
                            : client.read("run.h5", {Hyperslab::whole("/bonds/pairs")}).status();
    INFO(result.message());
    CHECK(result.isOk());
    CHECK(server->hdf5WorkersReplaced() == round + 1);
    CHECK(server->hdf5WorkerPids().at(0) != pid);
  }
  requireServerHealthy(*server);
}

TEST_CASE("A worker stuck in libhdf5 is replaced at the call's time limit",
          "[dataservice][integration]") {
  auto config = oneWorker();
  config.limits.hdf5CallSeconds = 0.5;
  auto server = startServer(config);
  const int pid = server->hdf5WorkerPids().at(0);
  auto client = connect(clientOptions(*server));
  REQUIRE(::kill(pid, SIGSTOP) == 0);  // as a worker in an endless loop
  const auto start = std::chrono::steady_clock::now();
  const Status stuck = client.read("run.h5", {Hyperslab::whole("/bonds/pairs")}).status();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  INFO(stuck.message());
  CHECK(stuck.code() == StatusCode::kDeadlineExceeded);
  CHECK_THAT(stuck.message(), Catch::Contains("did not finish in time") &&
                                  Catch::Contains("worker process was replaced"));
  CHECK(seconds < 5.0);
  CHECK(server->hdf5WorkersReplaced() == 1);
  CHECK(server->hdf5WorkerPids().at(0) != pid);
  requireServerHealthy(*server);
}

TEST_CASE("A caller that gives up on a slow Describe frees its worker",
          "[dataservice][integration]") {
  TempDir root;
  writeWideGroups(root.file("wide.h5"), 40'000);  // about 0.6 s of walking
  std::filesystem::copy_file(sampleRoot().file("run.h5"), root.file("run.h5"));
  auto config = oneWorker();
  config.dataRoot = root.path().string();
  auto server = startServer(config);
  auto options = clientOptions(*server);
  options.timeoutSeconds = 0.15;
  auto impatient = connect(options);
  // Connected first: the deadline is the walk's, not the TLS handshake's.
  impatient.startConnecting();
  REQUIRE(waitUntil([&] { return impatient.connected(); }, 10.0));
  CHECK(impatient.describe("wide.h5").status().code() == StatusCode::kDeadlineExceeded);
  // The walk is not left running for nobody: the one worker is free again.
  REQUIRE(waitUntil([&] { return server->hdf5WorkersReplaced() == 1; }, 2.0));
  auto client = connect(clientOptions(*server));
  CHECK(client.read("run.h5", {Hyperslab::whole("/bonds/pairs")}).isOk());
}

namespace {

// Copies of `source` with 1-8 bytes overwritten at random in the part of the
// file HDF5 reads first (superblock, object headers, B-trees, heaps), and
// the libhdf5 faults the fuzzer found (tests/fuzz/crashes).
std::vector<std::string> writeCorruptCorpus(const std::string& source, const TempDir& root,
                                            int count) {
  std::ifstream in(source, std::ios::binary);
  const std::string original((std::istreambuf_iterator<char>(in)), {});
  std::mt19937 random(20261124);
  std::vector<std::string> names;
  const std::size_t span = std::min<std::size_t>(original.size(), 64 * 1024);
  for (int i = 0; i < count; ++i) {
    std::string damaged = original;
    const int bytes = std::uniform_int_distribution<int>(1, 8)(random);
    for (int b = 0; b < bytes; ++b) {
      damaged[std::uniform_int_distribution<std::size_t>(0, span - 1)(random)] =
          static_cast<char>(std::uniform_int_distribution<int>(0, 255)(random));
    }
    names.push_back(fmt::format("corrupt-{:03d}.h5", i));
    std::ofstream(root.file(names.back()), std::ios::binary) << damaged;
  }
  const std::filesystem::path crashes =
      std::filesystem::path(CRACKVIS_SOURCE_DIR) / "tests" / "fuzz" / "crashes";
  for (const auto& entry : std::filesystem::directory_iterator(crashes)) {
    names.push_back(entry.path().filename().string());
    std::filesystem::copy_file(entry.path(), root.file(names.back()));
  }
  return names;
}

}  // namespace

TEST_CASE("A corpus of corrupt files costs the data service nothing",
          "[dataservice][integration]") {
  TempDir root;
  const auto names = writeCorruptCorpus(sampleRoot().file("run.h5"), root, 300);
  std::filesystem::copy_file(sampleRoot().file("run.h5"), root.file("run.h5"));
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  config.limits.hdf5Workers = 2;
  config.limits.hdf5CallSeconds = 2.0;
  config.limits.describe.maxTime = std::chrono::milliseconds(2000);
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));
  std::map<std::string, int> outcomes;
  for (const std::string& name : names) {
    const Status described = client.describe(name).status();
    const Status read = client.read(name, {Hyperslab::whole("/steps/000000/positions")}).status();
    for (const Status& status : {described, read}) {
      ++outcomes[std::string(toString(status.code()))];
      // Every call is answered by the service itself: never a lost
      // connection, never an internal error.
      INFO(name << ": " << status.message());
      CHECK(status.code() != StatusCode::kUnavailable);
      CHECK(status.code() != StatusCode::kInternal);
    }
  }
  std::string tally;
  for (const auto& [code, count] : outcomes) {
    tally += fmt::format(" {}={}", code, count);
  }
  std::printf("corrupt corpus: %zu files, calls:%s; HDF5 workers replaced: %d\n", names.size(),
              tally.c_str(), server->hdf5WorkersReplaced());
  CHECK(outcomes["OK"] > 0);  // some damage lands where nothing reads it
  CHECK(outcomes["FAILED_PRECONDITION"] > 0);
  // Zero service deaths: it still serves the intact file, bit for bit.
  auto intact = client.read("run.h5", {Hyperslab::whole("/steps/000001/positions")});
  INFO(intact.status().message());
  REQUIRE(intact.isOk());
  CHECK(intact->front().values<double>().value() ==
        readDirect<double>(root.file("run.h5"), "/steps/000001/positions"));
  CHECK(client.checkHealth().isOk());
}

namespace {

// The largest resident size a process reached, from /proc/PID/status.
std::uint64_t peakResidentKiB(int pid) {
  std::ifstream status(fmt::format("/proc/{}/status", pid));
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      return std::stoull(line.substr(6));
    }
  }
  return 0;
}

}  // namespace

TEST_CASE("A corrupt size that asks libhdf5 for 20 GB fails its call, not the host",
          "[dataservice][integration]") {
  // Uncapped, the worker's libhdf5 allocated and zero-filled the 20 GB the
  // file's corrupt size asks for: within the call's 30 s it took a 24 GiB
  // node's memory and the OOM killer chose among all its processes.
  TempDir root;
  const std::string name = "dem_reader-hdf5-20gb-metadata-read.h5";
  std::filesystem::copy_file(
      std::filesystem::path(CRACKVIS_SOURCE_DIR) / "tests" / "fuzz" / "crashes" / name,
      root.file(name));
  std::filesystem::copy_file(sampleRoot().file("run.h5"), root.file("run.h5"));
  auto config = oneWorker();
  config.dataRoot = root.path().string();
  auto server = startServer(config);
  const int pid = server->hdf5WorkerPids().at(0);
  auto client = connect(clientOptions(*server));
  const Status described = client.describe(name).status();
  INFO(described.message());
  CHECK(described.code() == StatusCode::kFailedPrecondition);
  CHECK_THAT(described.message(), Catch::Contains("memory allocation failed"));
  // The worker answered: it was neither killed nor replaced, and it never
  // held more than a fraction of the 20 GB.
  CHECK(server->hdf5WorkersReplaced() == 0);
  CHECK(server->hdf5WorkerPids().at(0) == pid);
  CHECK(peakResidentKiB(pid) < std::uint64_t{1} << 20);
  requireServerHealthy(*server);
}

TEST_CASE("HDF5 workers run the worker program and keep nothing of the service but a socket",
          "[dataservice][integration]") {
  namespace fs = std::filesystem;
  auto server = startServer(oneWorker());
  const int pid = server->hdf5WorkerPids().at(0);
  REQUIRE(pid > 0);
  const std::string proc = fmt::format("/proc/{}", pid);
  // It serves (Describe, and a Read through the shared piece buffer); by
  // then it has mapped that buffer and closed its descriptor.
  auto client = connect(clientOptions(*server));
  REQUIRE(client.describe("run.h5").isOk());
  auto read = client.read("run.h5", {Hyperslab::whole("/steps/000001/positions")});
  REQUIRE(read.isOk());
  CHECK(read->front().values<double>().value() ==
        readDirect<double>(sampleRoot().file("run.h5"), "/steps/000001/positions"));

  // Started with exec, not forked: its own program, nothing of the
  // service's environment (at most malloc's tunables for huge pages,
  // common/huge_pages.hpp), and of the service's descriptors only its socket
  // (3) beside 0-2; any other is a file of the data root it has opened since.
  CHECK(fs::read_symlink(proc + "/exe").filename() == "crackvis-hdf5-worker");
  std::string environment = fileText(proc + "/environ");
  std::replace(environment.begin(), environment.end(), '\0', ':');  // glibc ends each tunable
  const std::string tunables = helperTunablesEntry();
  CHECK(environment == (tunables.empty() ? tunables : tunables + ":"));
  CHECK(fs::is_socket(proc + "/fd/3"));
  const std::string root = fs::canonical(sampleRoot().root.path()).string() + "/";
  for (const auto& entry : fs::directory_iterator(proc + "/fd")) {
    if (std::stoi(entry.path().filename().string()) > 3) {
      const std::string target = fs::read_symlink(entry.path()).string();
      INFO(target);
      CHECK(target.rfind(root, 0) == 0);
    }
  }

  // A server whose worker program is missing does not start, and says why.
  auto config = oneWorker();
  config.hdf5WorkerProgram = "/nonexistent/crackvis-hdf5-worker";
  auto refused = dataservice::DataServer::start(config);
  REQUIRE_FALSE(refused.isOk());
  CHECK(refused.status().code() == StatusCode::kFailedPrecondition);
  CHECK_THAT(refused.status().message(), Catch::Contains("/nonexistent/crackvis-hdf5-worker") &&
                                             Catch::Contains("--hdf5-worker-program"));
  // Nor does one whose worker program ends without getting ready.
  config.hdf5WorkerProgram = "/bin/true";
  auto notReady = dataservice::DataServer::start(config);
  REQUIRE_FALSE(notReady.isOk());
  CHECK(notReady.status().code() == StatusCode::kUnavailable);
  CHECK_THAT(notReady.status().message(),
             Catch::Contains("/bin/true did not get ready (exited with status 0)"));

  // Run by hand, the program says what it is for.
  const fs::path program = fs::path(CRACKVIS_DATA).parent_path() / "crackvis-hdf5-worker";
  const auto byHand = runProcess({program.string()});
  CHECK(byHand.exitCode == 2);
  CHECK_THAT(byHand.err, Catch::Contains("crackvis-data starts this program"));
}

}  // namespace crackvis::testing
