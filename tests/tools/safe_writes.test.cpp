// Every writer replaces its output only when complete (issue 29 point 7):
// on a full disk each CLI writer fails with one line, and an existing file
// of the same name is left byte for byte as it was, with no partial file
// beside it. The disk is a real tmpfs of a few hundred KiB, filled up;
// where this process may not mount one, the writers run under a file size
// limit (RLIMIT_FSIZE with SIGXFSZ ignored), which fails their writes the
// same way (EFBIG instead of ENOSPC).
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "support/full_disk.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"

using crackvis::testing::FullDisk;
using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {

const std::string kCli = CRACKVIS_CLI;
const std::string kData = CRACKVIS_TEST_DATA;

}  // namespace

TEST_CASE("On a full disk every writer fails with one line and keeps the existing file",
          "[cli][write]") {
  TempDir inputs;
  // A planted through crack: its surfaces and pictures are larger than the
  // disk's slack.
  const std::string sample = inputs.file("run.h5");
  REQUIRE(runProcess({kCli, "generate", "--lattice", "fcc", "--sites", "9", "9", "9", "-r", "0.001",
                      "--planted-crack", "3", "-q", "-o", sample})
              .exitCode == 0);
  const std::string view = inputs.file("view.xml");
  std::ofstream(view) << "<pipeline version=\"1\"><data file=\"run.h5\"/></pipeline>\n";
  FullDisk disk(512 * 1024, 4 * 1024);
  INFO((disk.mounted() ? "a full tmpfs" : "a file size limit (mount not allowed here)"));
  struct Writer {
    std::string output;  // on the disk; it exists, and must survive
    std::vector<std::string> argv;
  };
  const std::vector<Writer> writers = {
      {"generated.h5",
       {kCli, "generate", "--lattice", "fcc", "--sites", "13", "13", "13", "-r", "0.001", "-q",
        "-o", disk.file("generated.h5")}},
      {"simulated.h5",
       {kCli, "sim", "plate2d", "--scale", "0.2", "--steps", "3", "-q", "-o",
        disk.file("simulated.h5")}},
      {"imported.h5",
       {kCli, "import", "lammps", kData + "/lammps/notched_bar", "-q", "-o",
        disk.file("imported.h5")}},
      {"cracks.vtp",
       {kCli, "extract", sample, "-m", "local-voronoi", "-s", "-1", "-q", "-o",
        disk.file("cracks.vtp")}},
      {"series.pvd",
       {kCli, "extract", sample, "-m", "cell-cut", "-q", "-o", disk.file("series.pvd")}},
      {"specimen.pvd",
       {kCli, "export", sample, "--particles", "--bonds", "-q", "-o", disk.file("specimen.pvd")}},
      {"picture.png", {kCli, "snapshot", sample, "-q", "-o", disk.file("picture.png")}},
      {"movie.mp4",
       {kCli, "movie", sample, "-p", view, "--size", "640x480", "--frames", "30", "-q", "-o",
        disk.file("movie.mp4")}},
  };
  for (const Writer& writer : writers) {
    std::ofstream(disk.file(writer.output), std::ios::binary)
        << "a good earlier " << writer.output << " that must survive\n";
  }
  disk.fill();
  for (const Writer& writer : writers) {
    DYNAMIC_SECTION(writer.argv[1] << " -o " << writer.output) {
      const std::string before = crackvis::testing::fileText(disk.file(writer.output));
      auto run = runProcess(disk.limitedCommand(writer.argv));
      INFO(run.err);
      CHECK(run.exitCode == 1);
      CHECK(crackvis::testing::lines(run.err).size() == 1);
      CHECK_THAT(run.err, !Catch::Contains("internal error"));
      CHECK(crackvis::testing::fileText(disk.file(writer.output)) == before);
      for (const char* suffix : {".partial", ".importing"}) {
        CHECK_FALSE(std::filesystem::exists(disk.file(writer.output) + suffix));
      }
    }
  }
}

TEST_CASE("With room on the disk, each writer replaces the existing file", "[cli][write]") {
  // The other half of the contract: the rename really happens.
  TempDir dir;
  const std::string out = dir.file("out.h5");
  std::ofstream(out) << "old";
  auto run = runProcess({kCli, "generate", "--lattice", "fcc", "--sites", "3", "3", "3", "-r",
                         "0.001", "-q", "-o", out});
  REQUIRE(run.exitCode == 0);
  CHECK(crackvis::testing::fileText(out).substr(1, 3) == "HDF");
  CHECK_FALSE(std::filesystem::exists(out + ".partial"));
}
