#include <fstream>
#include <iterator>
#include <string>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "support/full_disk.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using namespace crackvis;
using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {
const std::string kCli = CRACKVIS_CLI;
}

TEST_CASE("crackvis sim writes a crackvis-dem file with its command line as source", "[sim][cli]") {
  TempDir dir;
  const std::string path = dir.file("plate.h5");
  const std::vector<std::string> argv{kCli,      "sim", "plate2d", "--scale", "0.2",
                                      "--steps", "25",  "--seed",  "9",       "--threads",
                                      "2",       "-o",  path};
  auto run = runProcess(argv);
  REQUIRE(run.exitCode == 0);
  CHECK_THAT(run.out, Catch::Contains("wrote " + path + ": 25 saved steps"));
  CHECK_THAT(run.err, Catch::Contains("plate2d, scale 0.2"));
  auto reader = dem::DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->info().dimension == 2);
  CHECK(reader->stepCount() == 25);
  CHECK(reader->info().source ==
        "crackvis sim plate2d --scale 0.2 --steps 25 --seed 9 --threads 2 -o " + path);
  auto first = reader->readStep(0);
  REQUIRE(first.isOk());
  CHECK(first->brokenBondCount() == 1);  // 3 bonds at full size, round(3 * 0.2) = 1
  CHECK(first->velocities.size() == first->positions.size());
  CHECK(first->bondForce.size() == first->bondState.size());
  auto last = reader->readStep(24);
  REQUIRE(last.isOk());
  CHECK(last->time > 0.0);
  // The ends moved apart.
  CHECK(last->positions.back().x > first->positions.back().x);
  CHECK(last->positions.front().x < first->positions.front().x);
}

TEST_CASE("crackvis sim --quiet and the optional arrays", "[sim][cli]") {
  TempDir dir;
  const std::string path = dir.file("cube.h5");
  auto run = runProcess({kCli, "sim", "cuboid3d", "--set", "C", "--scale", "0.2", "--steps", "3",
                         "--no-velocities", "--no-bond-force", "-q", "-o", path});
  REQUIRE(run.exitCode == 0);
  CHECK(run.out.empty());
  CHECK(run.err.empty());
  auto reader = dem::DemFileReader::open(path);
  REQUIRE(reader.isOk());
  auto step = reader->readStep(2);
  REQUIRE(step.isOk());
  CHECK(step->velocities.empty());
  CHECK(step->bondForce.empty());
}

TEST_CASE("crackvis sim rejects bad input with one clear line", "[sim][cli]") {
  TempDir dir;
  auto setOnPlate = runProcess({kCli, "sim", "plate2d", "--set", "B", "-o", dir.file("x.h5")});
  CHECK(setOnPlate.exitCode == 1);
  CHECK(setOnPlate.err ==
        "crackvis sim: --set applies to cuboid3d only (plate2d has one defect)\n");
  auto unwritable =
      runProcess({kCli, "sim", "plate2d", "--scale", "0.2", "-o", "/nonexistent/dir/x.h5"});
  CHECK(unwritable.exitCode == 1);
  CHECK(testing::lines(unwritable.err).size() == 1);
  CHECK_THAT(unwritable.err, Catch::StartsWith("crackvis sim: /nonexistent/dir/x.h5"));
  auto badMaterial = runProcess({kCli, "sim", "plate2d", "--scale", "0.2", "--strain-threshold",
                                 "-1", "-o", dir.file("x.h5")});
  CHECK(badMaterial.exitCode == 2);
  auto unknown = runProcess({kCli, "sim", "sphere", "-o", dir.file("x.h5")});
  CHECK(unknown.exitCode == 2);
  CHECK_THAT(unknown.err, Catch::Contains("sphere"));
  auto badScale = runProcess({kCli, "sim", "plate2d", "--scale", "2", "-o", dir.file("x.h5")});
  CHECK(badScale.exitCode == 2);
  auto noOutput = runProcess({kCli, "sim", "plate2d"});
  CHECK(noOutput.exitCode == 2);
  CHECK_THAT(noOutput.err, Catch::Contains("--output"));
}

TEST_CASE("crackvis sim --help explains presets and options", "[sim][cli]") {
  auto help = runProcess({kCli, "sim", "--help"});
  CHECK(help.exitCode == 0);
  for (const char* text : {"plate2d", "cuboid3d", "--set", "--scale", "--threads", "--seed",
                           "--steps", "docs/simulator.md"}) {
    CHECK_THAT(help.out, Catch::Contains(text));
  }
}

namespace {

// A tmpfs of `size` mounted on a fresh directory for the test's lifetime.
// Mounting needs root, which the test environment has; a failure to mount
// fails the test rather than skipping it.

}  // namespace

TEST_CASE("crackvis sim on a full disk exits 1 with one line, keeps the old file and its steps",
          "[sim][cli]") {
  testing::FullDisk disk(300 * 1024, 0);  // small, not filled: the run fills it
  REQUIRE(disk.mounted());
  const std::string output = disk.file("plate.h5");
  std::ofstream(output) << "an earlier run";
  auto run = runProcess({kCli, "sim", "plate2d", "--scale", "0.2", "--steps", "400", "--quiet",
                         "--threads", "1", "-o", output});
  INFO("stderr: " << run.err);
  CHECK(run.exitCode == 1);
  const auto errors = testing::lines(run.err);
  REQUIRE(errors.size() == 1);
  const std::string path = output + ".partial";
  CHECK_THAT(errors[0], Catch::StartsWith("crackvis sim: " + output + ": step ") &&
                            Catch::Contains("not written") &&
                            Catch::EndsWith("complete steps are in " + path + ")"));
  CHECK_THAT(run.err, !Catch::Contains("HDF5-DIAG"));
  // The output's name still holds the earlier run (issue 29: it held the
  // partial one).
  CHECK(testing::fileText(output) == "an earlier run");

  // Every step the count promises is there and valid.
  auto reader = dem::DemFileReader::open(path);
  INFO(reader.status().message());
  REQUIRE(reader.isOk());
  const int steps = reader->stepCount();
  CHECK(steps > 0);
  CHECK(steps < 400);
  CHECK(reader->info().plannedSteps == 400);
  CHECK(reader->info().stoppedEarly());
  for (int step = 0; step < steps; ++step) {
    INFO("step " << step);
    CHECK(reader->readStep(step).isOk());
  }

  auto info = runProcess({kCli, "info", path});
  CHECK(info.exitCode == 0);
  CHECK_THAT(info.out, Catch::Contains(fmt::format(
                           "stopped early the run wrote {} of 400 planned steps", steps)));
  auto json = runProcess({kCli, "info", "--json", path});
  CHECK(json.exitCode == 0);
  CHECK_THAT(json.out, Catch::Contains("\"stopped_early\": true") &&
                           Catch::Contains("\"planned_steps\": 400"));
}

TEST_CASE("crackvis info says nothing of an early stop when a run finished", "[sim][cli]") {
  TempDir dir;
  const std::string path = dir.file("plate.h5");
  auto run =
      runProcess({kCli, "sim", "plate2d", "--scale", "0.2", "--steps", "3", "--quiet", "-o", path});
  REQUIRE(run.exitCode == 0);
  auto reader = dem::DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->info().plannedSteps == 3);
  CHECK_FALSE(reader->info().stoppedEarly());
  auto info = runProcess({kCli, "info", "--json", path});
  CHECK_THAT(info.out, Catch::Contains("\"stopped_early\": false"));
}

TEST_CASE("crackvis sim tension pulls a generated random packing apart from its notch",
          "[sim][cli]") {
  TempDir dir;
  const std::string specimen = dir.file("random.h5");
  const std::string run = dir.file("run.h5");
  REQUIRE(runProcess({kCli, "generate", "--packing", "random", "--radius-range", "1e-3:2e-3",
                      "--box", "0.08", "0.03", "0.03", "-q", "-o", specimen})
              .exitCode == 0);
  auto sim = runProcess({kCli, "sim", "tension", specimen, "--notch-depth", "0.2", "--steps", "60",
                         "--duration", "2e-3", "-o", run});
  REQUIRE(sim.exitCode == 0);
  CHECK_THAT(sim.err, Catch::Contains("tension of a 3D specimen"));
  auto reader = dem::DemFileReader::open(run);
  REQUIRE(reader.isOk());
  auto before = dem::DemFileReader::open(specimen);
  REQUIRE(before.isOk());
  CHECK(reader->info().particleCount == before->info().particleCount);
  CHECK(reader->info().bondCount == before->info().bondCount);
  auto first = reader->readStep(0);
  auto last = reader->readStep(reader->stepCount() - 1);
  REQUIRE(first.isOk());
  REQUIRE(last.isOk());
  // The notch: bonds across the mid-plane near the bottom, broken from the start.
  auto lattice = reader->readLattice();
  REQUIRE(lattice.isOk());
  double lowest = 1.0;
  double highest = 0.0;
  for (std::size_t b = 0; b < first->bondState.size(); ++b) {
    if (first->bondState[b] != 0) {
      const auto& bond = lattice->bonds[b];
      const dem::Vec3 a = first->positions[static_cast<std::size_t>(bond.first)];
      const dem::Vec3 c = first->positions[static_cast<std::size_t>(bond.second)];
      CHECK((a.x - 0.04) * (c.x - 0.04) < 0.0);
      lowest = std::min(lowest, 0.5 * (a.z + c.z));
      highest = std::max(highest, 0.5 * (a.z + c.z));
    }
  }
  CHECK(first->brokenBondCount() > 0);
  CHECK(highest <= 0.2 * 0.03 + 0.002);
  // Pulled: the ends moved apart and more bonds broke.
  CHECK(last->brokenBondCount() > 2 * first->brokenBondCount());
  const auto spanOf = [](const std::vector<dem::Vec3>& positions) {
    const auto [lo, hi] = dem::boundingBox(positions);
    return hi.x - lo.x;
  };
  CHECK(spanOf(last->positions) > spanOf(first->positions));

  auto missing = runProcess({kCli, "sim", "tension", "-o", dir.file("x.h5")});
  CHECK(missing.exitCode == 1);
  CHECK(missing.err ==
        "crackvis sim: tension needs the specimen file: crackvis sim tension FILE -o OUT\n");
}
