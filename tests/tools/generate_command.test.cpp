#include <algorithm>

#include <catch2/catch.hpp>

#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/lattice_generator.hpp>

using namespace crackvis;
using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {
const std::string kCli = CRACKVIS_CLI;
}

TEST_CASE("crackvis generate writes a valid one-step lattice file", "[cli][generate]") {
  TempDir dir;
  const std::string path = dir.file("tri.h5");
  auto run = runProcess({kCli, "generate", "--lattice", "triangular", "--sites", "12", "6",
                         "--radius", "0.00158", "--jitter", "0.1", "--seed", "3", "-o", path});
  REQUIRE(run.exitCode == 0);
  auto reader = dem::DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->info().dimension == 2);
  CHECK(reader->info().particleCount == 72);
  CHECK(reader->info().bondCount == 6 * 11 + 5 * 23);
  REQUIRE(reader->stepCount() == 1);
  auto step = reader->readStep(0);
  REQUIRE(step.isOk());
  CHECK(step->brokenBondCount() == 0);
  auto lattice = reader->readLattice();
  REQUIRE(lattice.isOk());
  CHECK(lattice->radius.front() == 0.00158);
}

TEST_CASE("crackvis generate --box fills the box", "[cli][generate]") {
  TempDir dir;
  const std::string path = dir.file("box.h5");
  auto run = runProcess({kCli, "generate", "--lattice", "hcp", "--box", "0.05", "0.03", "0.02",
                         "--radius", "0.002", "-q", "-o", path});
  REQUIRE(run.exitCode == 0);
  CHECK(run.out.empty());
  auto reader = dem::DemFileReader::open(path);
  REQUIRE(reader.isOk());
  const auto sites = dem::sitesForBox(dem::LatticeKind::kHcp, {0.05, 0.03, 0.02}, 0.002);
  CHECK(reader->info().particleCount == sites[0] * sites[1] * sites[2]);
}

TEST_CASE("crackvis generate rejects bad options with one clear line", "[cli][generate]") {
  TempDir dir;
  auto wrongCount = runProcess({kCli, "generate", "--lattice", "triangular", "--sites", "3", "3",
                                "3", "-o", dir.file("x.h5")});
  CHECK(wrongCount.exitCode == 1);
  CHECK(wrongCount.err ==
        "crackvis generate: --sites needs 2 values for a 2D triangular lattice, got 3\n");
  auto badLattice = runProcess({kCli, "generate", "--lattice", "bcc", "-o", dir.file("x.h5")});
  CHECK(badLattice.exitCode == 2);
  CHECK_THAT(badLattice.err, Catch::Contains("bcc"));
  auto unwritable = runProcess({kCli, "generate", "-o", "/nonexistent/dir/x.h5"});
  CHECK(unwritable.exitCode == 1);
  CHECK_THAT(unwritable.err,
             Catch::StartsWith("crackvis generate: /nonexistent/dir/x.h5: cannot create file"));
  CHECK(testing::lines(unwritable.err).size() == 1);
}

TEST_CASE("crackvis generate --packing random writes a polydisperse random packing",
          "[cli][generate]") {
  TempDir dir;
  const std::string path = dir.file("random.h5");
  auto run = runProcess({kCli, "generate", "--packing", "random", "--radius-range", "5e-4:1e-3",
                         "--solid-fraction", "0.55", "--box", "0.012", "0.012", "0.012", "--seed",
                         "4", "-o", path});
  REQUIRE(run.exitCode == 0);
  CHECK_THAT(run.out, Catch::Contains("random 3D packing"));
  CHECK_THAT(run.out, Catch::Contains("solid fraction 0.55"));
  auto reader = dem::DemFileReader::open(path);
  REQUIRE(reader.isOk());
  auto lattice = reader->readLattice();
  REQUIRE(lattice.isOk());
  const auto [lo, hi] = std::minmax_element(lattice->radius.begin(), lattice->radius.end());
  CHECK(*lo >= 5e-4);
  CHECK(*hi <= 1e-3);
  CHECK(*hi > 1.5 * *lo);
  CHECK(lattice->bondCount() > 2 * lattice->particleCount());
  CHECK(dem::validateLattice(*lattice).isOk());

  auto reversed = runProcess({kCli, "generate", "--packing", "random", "--radius-range",
                              "1e-3:5e-4", "-o", dir.file("x.h5")});
  CHECK(reversed.exitCode == 1);
  CHECK(reversed.err ==
        "crackvis generate: --radius-range '1e-3:5e-4' is not RMIN:RMAX with 0 < RMIN <= RMAX "
        "(metres, e.g. 5e-4:1e-3)\n");
  auto tooDense = runProcess(
      {kCli, "generate", "--packing", "random", "--solid-fraction", "0.7", "-o", dir.file("x.h5")});
  CHECK(tooDense.exitCode == 1);
  CHECK_THAT(tooDense.err, Catch::Contains("solid fraction 0.7 is outside (0, 0.64]"));
}
