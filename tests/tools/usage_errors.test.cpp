// A misspelt subcommand or option is one line with the nearest right one
// (issue 18: errors that say what to do); every case exits 2 and prints
// nothing else.
#include <filesystem>

#include <catch2/catch.hpp>

#include "support/process.hpp"
#include "support/temp_dir.hpp"

using crackvis::testing::lines;
using crackvis::testing::runProcess;

namespace {
const std::string kCli = CRACKVIS_CLI;
}

TEST_CASE("crackvis names the subcommand or option it did not know, and the nearest one", "[cli]") {
  struct Case {
    std::vector<std::string> args;
    std::string line;
  };
  for (const Case& c : std::vector<Case>{
           {{"extrat", "a.h5"}, "crackvis: unknown subcommand 'extrat' (did you mean extract?)"},
           {{"extrat", "a.h5", "--method", "cell-cut"},
            "crackvis: unknown subcommand 'extrat' (did you mean extract?)"},
           {{"bench", "tranfer"},
            "crackvis bench: unknown subcommand 'tranfer' (did you mean transfer?)"},
           {{"frobnicate"},
            "crackvis: unknown subcommand 'frobnicate' (one of: bench, generate, import, info, "
            "extract"},
           {{"extract", "a.h5", "--stpes", "0:3"},
            "crackvis extract: unknown option '--stpes' (did you mean --steps?)"},
           {{"extract", "a.h5", "--metods=cell-cut"},
            "crackvis extract: unknown option '--metods' (did you mean --method?)"},
           {{"info", "--jsno", "a.h5"},
            "crackvis info: unknown option '--jsno' (did you mean --json?)"},
           {{"info", "--frobnicate", "a.h5"}, "crackvis info: unknown option '--frobnicate'"},
           {{"--verison"}, "crackvis: unknown option '--verison' (did you mean --version?)"}}) {
    std::vector<std::string> argv{kCli};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    DYNAMIC_SECTION(c.args.front() << " " << c.args.back()) {
      const auto result = runProcess(argv);
      CHECK(result.exitCode == 2);
      CHECK(result.out.empty());
      const auto errorLines = lines(result.err);
      REQUIRE(errorLines.size() == 1);
      CHECK_THAT(errorLines[0], Catch::StartsWith(c.line));
    }
  }
}

TEST_CASE("Other usage errors keep CLI11's message", "[cli]") {
  const auto missing = runProcess({kCli, "info"});
  CHECK(missing.exitCode == 2);
  CHECK_THAT(missing.err, Catch::Contains("file is required"));
  const auto none = runProcess({kCli, "bench"});
  CHECK(none.exitCode == 2);
  CHECK_THAT(none.err, Catch::Contains("subcommand is required"));
}

TEST_CASE("Numbers no run can use are one line and exit 1, before any work", "[cli]") {
  crackvis::testing::TempDir dir;
  const std::string out = dir.file("out");
  struct Case {
    std::vector<std::string> args;
    std::string part;
  };
  for (const Case& c : std::vector<Case>{
           {{"movie", "a.h5", "--orbit", "nan", "-o", out + ".mp4"}, "--orbit nan: degrees from"},
           {{"movie", "a.h5", "--orbit", "inf", "-o", out + ".mp4"}, "--orbit inf: degrees from"},
           {{"movie", "a.h5", "--orbit", "1e308", "-o", out + ".mp4"},
            "degrees from -3600 to 3600"},
           {{"movie", "a.h5", "--size", "2147483648x2", "-o", out + ".mp4"},
            "--size '2147483648x2': a number beyond any frame size"},
           {{"movie", "a.h5", "--size", "-64x64", "-o", out + ".mp4"},
            "--size -64x64: H.264 (4:2:0) needs even sizes from 16 to 7680 pixels"},
           {{"movie", "a.h5", "--size", "64x64x2", "-o", out + ".mp4"}, "expected WIDTHxHEIGHT"},
           {{"sim", "cuboid3d", "--duration", "1e308", "-o", out + ".h5"},
            "a duration of 1e+308 s needs"}}) {
    std::vector<std::string> argv{kCli};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    DYNAMIC_SECTION(c.args[0] << " " << c.args[2] << " " << c.args[3]) {
      const auto result = runProcess(argv);
      INFO(result.err);
      CHECK(result.exitCode == 1);
      const auto errorLines = lines(result.err);
      REQUIRE(errorLines.size() == 1);
      CHECK_THAT(errorLines[0], Catch::Contains(c.part));
      CHECK_THAT(result.err, !Catch::Contains("internal error"));
      CHECK_FALSE(std::filesystem::exists(out + ".mp4"));
      CHECK_FALSE(std::filesystem::exists(out + ".h5"));
    }
  }
}
