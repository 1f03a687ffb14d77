// Every writer replaces its output only when complete (issue 29 point 7):
// on a full disk each CLI writer fails with one line, and an existing file
// of the same name is left byte for byte as it was, with no partial file
// beside it. The disk is a real tmpfs of a few hundred KiB, filled up;
// where this process may not mount one, the writers run under a file size
// limit (RLIMIT_FSIZE with SIGXFSZ ignored), which fails their writes the
// same way (EFBIG instead of ENOSPC).
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mount.h>
#include <unistd.h>

#include "support/process.hpp"
#include "support/temp_dir.hpp"

using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {

const std::string kCli = CRACKVIS_CLI;
const std::string kData = CRACKVIS_TEST_DATA;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A tmpfs of `size` bytes mounted on a fresh folder and filled until
// `slack` bytes are left, or (when mounting is not allowed) a plain folder
// whose writers run under a file size limit of `slack` bytes.
class FullDisk {
 public:
  FullDisk(std::size_t size, std::size_t slack) : m_slack(slack) {
    std::filesystem::create_directories(m_dir.path() / "disk");
    m_mounted = ::mount("tmpfs", path().c_str(), "tmpfs", MS_NOSUID | MS_NODEV,
                        fmt::format("size={}", size).c_str()) == 0;
  }
  ~FullDisk() {
    if (m_mounted) {
      ::umount2(path().c_str(), MNT_DETACH);
    }
  }
  std::string path() const { return (m_dir.path() / "disk").string(); }
  std::string file(const std::string& name) const { return path() + "/" + name; }
  bool mounted() const { return m_mounted; }

  // Fills the disk, keeping `slack` bytes free; call after placing the
  // files that must survive.
  void fill() const {
    if (!m_mounted) {
      return;
    }
    const std::string slack = file("slack");
    std::ofstream(slack, std::ios::binary) << std::string(m_slack, 's');
    const int fd = ::open(file("filler").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    REQUIRE(fd >= 0);
    const std::string block(4096, 'f');
    while (::write(fd, block.data(), block.size()) > 0) {
    }
    CHECK(errno == ENOSPC);
    ::close(fd);
    std::filesystem::remove(slack);
  }

  // `argv` run as a writer on this disk.
  std::vector<std::string> command(const std::vector<std::string>& argv) const {
    if (m_mounted) {
      return argv;
    }
    std::vector<std::string> limited{"/bin/bash", "-c",
                                     fmt::format("trap '' XFSZ; ulimit -f {}; exec \"$@\"",
                                                 std::max<std::size_t>(1, m_slack / 1024)),
                                     "writer"};
    limited.insert(limited.end(), argv.begin(), argv.end());
    return limited;
  }

 private:
  TempDir m_dir;
  std::size_t m_slack;
  bool m_mounted = false;
};

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
      const std::string before = slurp(disk.file(writer.output));
      auto run = runProcess(disk.command(writer.argv));
      INFO(run.err);
      CHECK(run.exitCode == 1);
      CHECK(crackvis::testing::lines(run.err).size() == 1);
      CHECK_THAT(run.err, !Catch::Contains("internal error"));
      CHECK(slurp(disk.file(writer.output)) == before);
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
  CHECK(slurp(out).substr(1, 3) == "HDF");
  CHECK_FALSE(std::filesystem::exists(out + ".partial"));
}
