// `crackvis import CODE DIR --follow` beside a run that is still writing
// (issue 32). The test plays the DEM code: it copies the committed output of
// a real LAMMPS, ESyS-Particle or Yade run into a folder step by step, with
// pauses, while the import follows; `crackvis info` sees the live file grow,
// and the finished file holds exactly what a one-shot import of the whole
// folder holds.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <signal.h>

#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using crackvis::testing::runProcess;
using crackvis::testing::startProcess;
using crackvis::testing::TempDir;
using crackvis::testing::waitProcess;
namespace fs = std::filesystem;

namespace {

const std::string kCli = CRACKVIS_CLI;
const std::string kData = CRACKVIS_TEST_DATA;

// A run's files by the step number in their names (the first run of digits:
// atoms.1500.txt, snap_t=1400_0.txt, spheres.400.vtu); -1 for the files of
// the whole run (tables, Yade's crack file), which the code writes first.
std::map<long, std::vector<fs::path>> filesByStep(const fs::path& folder) {
  std::map<long, std::vector<fs::path>> steps;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    const auto digit = std::find_if(name.begin(), name.end(),
                                    [](unsigned char c) { return std::isdigit(c) != 0; });
    long step = -1;
    if (digit != name.end()) {
      step = std::stol(std::string(digit, name.end()));
    }
    steps[step].push_back(entry.path());
  }
  return steps;
}

int infoSteps(const std::string& path) {
  const auto info = runProcess({kCli, "info", "--json", path});
  return info.exitCode == 0 ? nlohmann::json::parse(info.out).at("steps").get<int>() : -1;
}

}  // namespace

TEST_CASE("import --follow appends each step a running code completes", "[cli][import][live]") {
  const std::string code =
      GENERATE(std::string("lammps"), std::string("esys"), std::string("yade"));
  INFO(code);
  const fs::path run = fs::path(kData) / code / "notched_bar";
  TempDir dir;
  const fs::path writing = dir.path() / "run";
  fs::create_directory(writing);
  const std::string followed = dir.file("followed.h5");
  const std::string errors = dir.file("follow.err");
  const auto steps = filesByStep(run);
  // The code starts: its run files, then step by step.
  auto step = steps.begin();
  if (step->first == -1) {
    for (const fs::path& file : step->second) {
      fs::copy_file(file, writing / file.filename());
    }
    ++step;
  }
  const pid_t follow = startProcess({kCli, "import", code, writing.string(), "--follow",
                                     "--until-idle", "4", "--settle", "0.5", "-q", "-o", followed},
                                    errors);
  int growing = 0;  // looks at the live file that saw it between the first and the last step
  int copied = 0;
  for (; step != steps.end(); ++step, ++copied) {
    for (const fs::path& file : step->second) {
      // Written under another name and renamed, as a code's file appears
      // whole to a lister; a half-written one is what --settle waits out.
      fs::copy_file(file, writing / (file.filename().string() + ".tmp"));
      fs::rename(writing / (file.filename().string() + ".tmp"), writing / file.filename());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    const int seen = fs::exists(followed) ? infoSteps(followed) : 0;
    if (seen > 0 && seen <= copied + 1 && copied + 1 < static_cast<int>(steps.size())) {
      ++growing;
    }
  }
  const int exit = waitProcess(follow);
  INFO(crackvis::testing::fileText(errors));
  REQUIRE(exit == 0);
  CHECK(growing >= 2);  // readers saw the file while the code was still writing

  const std::string whole = dir.file("whole.h5");
  const auto once = runProcess({kCli, "import", code, run.string(), "-q", "-o", whole});
  INFO(once.err);
  REQUIRE(once.exitCode == 0);
  auto a = crackvis::dem::DemFileReader::open(whole);
  auto b = crackvis::dem::DemFileReader::open(followed);
  REQUIRE(a.isOk());
  REQUIRE(b.isOk());
  CHECK(b->info().stepLayout == crackvis::dem::StepLayout::kAppendable);
  CHECK_FALSE(b->info().beingWritten);
  REQUIRE(b->stepCount() == a->stepCount());
  CHECK(*b->readBreakSteps() == *a->readBreakSteps());
  for (int k = 0; k < a->stepCount(); ++k) {
    auto stepA = a->readStep(k);
    auto stepB = b->readStep(k);
    REQUIRE(stepA.isOk());
    REQUIRE(stepB.isOk());
    CHECK(stepA->time == stepB->time);
    CHECK(stepA->positions == stepB->positions);
    CHECK(stepA->bondState == stepB->bondState);
  }
}

TEST_CASE("import --follow ends on SIGTERM with every complete step written",
          "[cli][import][live]") {
  TempDir dir;
  const fs::path run = fs::path(kData) / "lammps" / "notched_bar";
  const fs::path writing = dir.path() / "run";
  fs::create_directory(writing);
  const auto steps = filesByStep(run);
  int stepsCopied = 0;
  for (const auto& [number, files] : steps) {
    if (number >= 0 && stepsCopied == 3) {
      break;
    }
    for (const fs::path& file : files) {
      fs::copy_file(file, writing / file.filename());
    }
    stepsCopied += number >= 0 ? 1 : 0;
  }
  const std::string followed = dir.file("followed.h5");
  const pid_t follow =
      startProcess({kCli, "import", "lammps", writing.string(), "--follow", "-q", "-o", followed});
  REQUIRE(crackvis::testing::waitUntil([&] { return infoSteps(followed) >= 2; }, 30.0));
  kill(follow, SIGTERM);
  REQUIRE(waitProcess(follow) == 0);
  auto reader = crackvis::dem::DemFileReader::open(followed);
  REQUIRE(reader.isOk());
  CHECK(reader->stepCount() == 3);  // the newest step too: the code is done
  CHECK_FALSE(reader->info().beingWritten);

  SECTION("and refuses what cannot follow") {
    const auto withSteps = runProcess({kCli, "import", "lammps", writing.string(), "--follow", "-s",
                                       "0:1", "-o", dir.file("x.h5")});
    CHECK(withSteps.exitCode == 1);
    CHECK(withSteps.err.find("--steps cannot be combined with --follow") != std::string::npos);
    const auto idleAlone = runProcess(
        {kCli, "import", "lammps", writing.string(), "--until-idle", "2", "-o", dir.file("y.h5")});
    CHECK(idleAlone.exitCode == 2);
    CHECK(idleAlone.err.find("go with --follow") != std::string::npos);
  }
}

TEST_CASE("import --follow --pid ends when the code's process has ended", "[cli][import][live]") {
  TempDir dir;
  const fs::path run = fs::path(kData) / "lammps" / "notched_bar";
  const fs::path writing = dir.path() / "run";
  fs::create_directory(writing);
  int stepsCopied = 0;
  for (const auto& [number, files] : filesByStep(run)) {
    if (number >= 0 && stepsCopied == 2) {
      break;
    }
    for (const fs::path& file : files) {
      fs::copy_file(file, writing / file.filename());
    }
    stepsCopied += number >= 0 ? 1 : 0;
  }
  // The "code": a process that ends by itself after two seconds.
  const pid_t code = startProcess({"sleep", "2"});
  const std::string followed = dir.file("followed.h5");
  const auto started = std::chrono::steady_clock::now();
  const pid_t follow = startProcess({kCli, "import", "lammps", writing.string(), "--follow",
                                     "--pid", std::to_string(code), "-q", "-o", followed});
  CHECK(waitProcess(code) == 0);
  REQUIRE(waitProcess(follow) == 0);
  CHECK(std::chrono::steady_clock::now() - started >= std::chrono::milliseconds(1500));
  auto reader = crackvis::dem::DemFileReader::open(followed);
  REQUIRE(reader.isOk());
  CHECK(reader->stepCount() == 2);
  CHECK_FALSE(reader->info().beingWritten);
}
