// One user's load must not stall another user's calls (issue 29 point 2),
// through a real server on loopback. A separate executable whose tests run
// alone (RUN_SERIAL): they assert latencies, which a test running beside
// them on the two cores would distort.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "service_fixture.hpp"
#include <crackvis/rpc_server/credentials.hpp>

namespace crackvis::testing {
namespace {

using dataservice::Hyperslab;

double secondsOf(const std::function<void()>& work) {
  const auto start = std::chrono::steady_clock::now();
  work();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

TEST_CASE("One user's parallel Describes do not stall another user's Reads",
          "[dataservice][integration]") {
  // The attack as it was found: user A runs 12 parallel uncached Describes
  // of a file with 40,000 groups; user B's small Reads went from 1.9 ms to
  // 11.5 s median while A's walks held every HDF5 worker.
  TempDir root;
  writeWideGroups(root.file("wide.h5"), 40'000);
  std::filesystem::copy_file(sampleRoot().file("run.h5"), root.file("run.h5"));
  auto config = baseConfig();
  config.dataRoot = root.path().string();
  config.users = {{"alice", rpc::hashToken("alice's token").value(), "", "", {"*"}},
                  {"bob", rpc::hashToken("bob's token").value(), "", "", {"*"}}};
  auto server = startServer(config);
  auto as = [&](const std::string& token) {
    auto options = clientOptions(*server);
    options.token = token;
    options.timeoutSeconds = 120.0;
    return connect(options);
  };
  auto alice = as("alice's token");
  auto bob = as("bob's token");
  REQUIRE(bob.read("run.h5", {Hyperslab::whole("/steps/000001/positions")}).isOk());
  std::atomic<bool> done{false};
  std::atomic<int> walks{0};
  std::vector<double> walkSeconds(12, 0.0);
  std::vector<std::thread> attackers;
  for (std::size_t k = 0; k < walkSeconds.size(); ++k) {
    attackers.emplace_back([&, k] {
      while (!done) {
        walkSeconds[k] = std::max(
            walkSeconds[k], secondsOf([&] { (void)alice.describe("wide.h5", /*uncached=*/true); }));
        ++walks;
      }
    });
  }
  std::this_thread::sleep_for(
      std::chrono::milliseconds(300));  // every worker A may take is walking
  std::vector<double> readMs;
  while (readMs.size() < 40) {
    readMs.push_back(
        1000.0 * secondsOf([&] {
          REQUIRE(bob.read("run.h5", {Hyperslab::whole("/steps/000001/positions")}).isOk());
        }));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  done = true;
  for (auto& attacker : attackers) {
    attacker.join();
  }
  std::sort(readMs.begin(), readMs.end());
  const double p95 = readMs[readMs.size() * 95 / 100];
  const double slowestWalk = *std::max_element(walkSeconds.begin(), walkSeconds.end());
  std::printf(
      "user B's Read while user A runs 12 parallel Describes of 40,000 groups: p50 %.1f ms, p95 "
      "%.1f ms, max %.1f ms (%zu reads); A's slowest Describe %.2f s, %d walks\n",
      readMs[readMs.size() / 2], p95, readMs.back(), readMs.size(), slowestWalk, walks.load());
  CHECK(slowestWalk > 0.3);  // the load was real
  CHECK(p95 <= 50.0);
  CHECK(alice.describe("wide.h5").isOk());  // A is served too
}

}  // namespace crackvis::testing
