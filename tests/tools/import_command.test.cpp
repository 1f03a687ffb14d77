// crackvis import as a user runs it: one command per code, a dry run, the
// summary, and one line on stderr with exit status 1 for bad input.
#include <filesystem>

#include <catch2/catch.hpp>

#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {
const std::string kCli = CRACKVIS_CLI;
const std::string kData = CRACKVIS_TEST_DATA;
}  // namespace

TEST_CASE("crackvis import reads each code's run in one command", "[cli][import]") {
  TempDir dir;
  struct Case {
    std::string code;
    std::string folder;
    std::int64_t particles;
  };
  for (const Case& c : {Case{"lammps", kData + "/lammps/notched_bar", 468},
                        Case{"esys", kData + "/esys/notched_bar", 398},
                        Case{"yade", kData + "/yade/notched_bar", 327}}) {
    const std::string out = dir.file(c.code + ".h5");
    auto run = runProcess({kCli, "import", c.code, c.folder, "-o", out, "-q"});
    INFO(run.err);
    REQUIRE(run.exitCode == 0);
    CHECK_THAT(run.out, Catch::Contains("particles     N = " + std::to_string(c.particles)));
    CHECK_THAT(run.out, Catch::Contains("wrote         " + out));
    auto info = runProcess({kCli, "info", out});
    REQUIRE(info.exitCode == 0);
    CHECK_THAT(info.out, Catch::Contains("format        crackvis-dem v1.1"));
    CHECK_THAT(info.out, Catch::Contains("steps         11"));
  }
}

TEST_CASE("crackvis import --dry-run writes nothing", "[cli][import]") {
  TempDir dir;
  auto run = runProcess(
      {kCli, "import", "lammps", kData + "/lammps/notched_bar", "--dry-run", "--steps", "0:-1:5"});
  REQUIRE(run.exitCode == 0);
  CHECK_THAT(run.out, Catch::Contains("3 of 11 steps (dry run: would import)"));
  CHECK_THAT(run.out, Catch::Contains("27 of them cut at the start (notch)"));
}

TEST_CASE("crackvis import fails with one line naming the input", "[cli][import]") {
  TempDir dir;
  auto missing = runProcess({kCli, "import", "esys", dir.path().string(), "-o", dir.file("o.h5")});
  CHECK(missing.exitCode == 1);
  CHECK_THAT(missing.err, Catch::StartsWith("crackvis import: no ESyS-Particle snapshot"));
  auto noOutput = runProcess({kCli, "import", "yade", kData + "/yade/notched_bar"});
  CHECK(noOutput.exitCode == 2);
  CHECK_THAT(noOutput.err, Catch::Contains("-o FILE.h5"));
  auto badRange = runProcess({kCli, "import", "yade", kData + "/yade/notched_bar", "--steps", "20",
                              "-o", dir.file("o.h5")});
  CHECK(badRange.exitCode == 1);
  CHECK_THAT(badRange.err, Catch::Contains("outside the file's steps 0..10"));
  CHECK_FALSE(std::filesystem::exists(dir.file("o.h5")));
}
