// `crackvis sim --live` (issue 32): the output takes its name once the
// first step is complete, readers (`crackvis info`) see steps while the run
// goes on, and a run killed with SIGKILL leaves every complete step
// readable by info and extract.
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <signal.h>

#include "support/process.hpp"
#include "support/temp_dir.hpp"

using crackvis::testing::runProcess;
using crackvis::testing::startProcess;
using crackvis::testing::TempDir;
using crackvis::testing::waitProcess;
using crackvis::testing::waitUntil;

namespace {

const std::string kCli = CRACKVIS_CLI;

// The number of complete steps `crackvis info --json` reports; -1 when it
// cannot read the file.
int infoSteps(const std::string& path) {
  const auto info = runProcess({kCli, "info", "--json", path});
  if (info.exitCode != 0) {
    return -1;
  }
  return nlohmann::json::parse(info.out).at("steps").get<int>();
}

}  // namespace

TEST_CASE("crackvis sim --live: info follows the run, and a killed run keeps its steps",
          "[cli][live]") {
  TempDir dir;
  const std::string output = dir.file("live.h5");
  // An earlier file of the name stays until the live run's first step is in.
  REQUIRE(runProcess({kCli, "sim", "plate2d", "--scale", "0.2", "--steps", "2", "-q", "-o", output})
              .exitCode == 0);
  REQUIRE(infoSteps(output) == 2);
  const pid_t run = startProcess({kCli, "sim", "plate2d", "--scale", "0.5", "--steps", "100000",
                                  "--pace", "0.05", "--live", "-q", "-o", output});
  REQUIRE(run > 0);
  int seen = 0;
  // info opens the file while the writer holds it: the steps it reports
  // grow from one look to the next.
  REQUIRE(waitUntil(
      [&] {
        const auto info = runProcess({kCli, "info", "--json", output});
        if (info.exitCode == 0) {
          const auto json = nlohmann::json::parse(info.out);
          if (json.value("step_layout", "") == "appendable") {
            seen = json.at("steps").get<int>();
          }
        }
        return seen >= 3;
      },
      60.0));
  int later = seen;
  REQUIRE(waitUntil([&] { return (later = infoSteps(output)) > seen; }, 30.0));
  kill(run, SIGKILL);
  REQUIRE(waitProcess(run) == 128 + SIGKILL);

  const auto info = runProcess({kCli, "info", "--json", output});
  INFO(info.err);
  REQUIRE(info.exitCode == 0);
  const auto json = nlohmann::json::parse(info.out);
  CHECK(json.at("steps").get<int>() >= later);
  CHECK(json.at("being_written").get<bool>());  // the writer never closed it
  CHECK(json.at("stopped_early").get<bool>());
  CHECK(json.at("incomplete_steps").get<int>() <= 1);
  // The last complete step reads: its cracks extract.
  const std::string cracks = dir.file("last.vtp");
  const auto extracted =
      runProcess({kCli, "extract", output, "-m", "cell-centre", "-s", "-1", "-q", "-o", cracks});
  INFO(extracted.err);
  CHECK(extracted.exitCode == 0);
  CHECK(std::filesystem::file_size(cracks) > 0);
  // A movie and a snapshot of the live file, as of its complete steps.
  const std::string movie = dir.file("live.mp4");
  const auto movieRun = runProcess(
      {kCli, "movie", output, "-s", "0:-1", "--size", "96x64", "--frames", "4", "-q", "-o", movie});
  INFO(movieRun.err);
  CHECK(movieRun.exitCode == 0);
  CHECK(std::filesystem::file_size(movie) > 0);
  const std::string png = dir.file("live.png");
  const auto snapshot = runProcess(
      {kCli, "snapshot", output, "-s", "-1", "--width", "96", "--height", "64", "-q", "-o", png});
  INFO(snapshot.err);
  CHECK(snapshot.exitCode == 0);
  CHECK(std::filesystem::file_size(png) > 0);
  // No partial file is left beside it: the live file took the name.
  CHECK_FALSE(std::filesystem::exists(output + ".partial"));
}
