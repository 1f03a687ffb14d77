#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "support/dem_defects.hpp"
#include "support/h5_tamper.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using crackvis::testing::lines;
using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {
const std::string kCli = CRACKVIS_CLI;
}

TEST_CASE("crackvis info prints the counts of a generated FCC block", "[cli][info]") {
  TempDir dir;
  const std::string path = dir.file("block.h5");
  // 3 x 3 x 3 cubic cells: N = 4^3 + 3*9*4 = 172, M = 12*9*7 = 756.
  auto generated = runProcess({kCli, "generate", "--lattice", "fcc", "--sites", "7", "7", "7",
                               "--radius", "0.002", "-o", path});
  REQUIRE(generated.exitCode == 0);
  CHECK_THAT(generated.out, Catch::Contains("172 particles, 756 bonds"));

  auto info = runProcess({kCli, "info", path});
  REQUIRE(info.exitCode == 0);
  CHECK(info.err.empty());
  CHECK_THAT(info.out, Catch::Contains("format        crackvis-dem v1"));
  CHECK_THAT(info.out, Catch::Contains("dimension     3D"));
  CHECK_THAT(info.out, Catch::Contains("particles     N = 172"));
  CHECK_THAT(info.out, Catch::Contains("bonds         M = 756 (mean coordination 8.791)"));
  CHECK_THAT(info.out, Catch::Contains("crack cells   lattice"));
  // generate writes the spatial index (v1.3), with the lattice decided;
  // the block is a cube written x fastest, so its slabs run across z.
  CHECK_THAT(info.out, Catch::Contains("format        crackvis-dem v1.3"));
  CHECK_THAT(info.out,
             Catch::Contains("index         order along z: MPI ranks read only their slab"));
  CHECK_THAT(info.out, Catch::Contains("steps         1 (time 0 .. 0 s)"));
  CHECK_THAT(info.out,
             Catch::Contains("broken bonds  first step: 0 (0.00 %), last step: 0 (0.00 %)"));
  CHECK_THAT(info.out,
             Catch::Contains("source        crackvis generate --lattice fcc --sites 7 7 7"));
}

TEST_CASE("crackvis info --json parses and agrees with the file", "[cli][info]") {
  TempDir dir;
  const std::string path = dir.file("sample.h5");
  const auto sample = crackvis::testing::writeSampleFile(path, 3, 4);
  auto info = runProcess({kCli, "info", path, "--json", "--steps"});
  REQUIRE(info.exitCode == 0);
  const auto json = nlohmann::json::parse(info.out);
  const auto m = static_cast<std::int64_t>(sample.lattice.bondCount());
  CHECK(json["format"] == "crackvis-dem");
  CHECK(json["version"] == 1);
  CHECK(json["dimension"] == 3);
  CHECK(json["particles"] == sample.lattice.particleCount());
  CHECK(json["bonds"] == m);
  CHECK(json["steps"] == 4);
  CHECK(json["time"]["first"] == 0.0);
  CHECK(json["time"]["last"] == sample.steps[3].time);
  CHECK(json["broken_bonds"]["first"] == 0);
  CHECK(json["broken_bonds"]["last"] == sample.steps[3].brokenBondCount());
  REQUIRE(json["per_step"].size() == 4);
  std::int64_t previous = 0;
  for (int k = 0; k < 4; ++k) {
    const auto& row = json["per_step"][static_cast<size_t>(k)];
    const auto broken =
        static_cast<std::int64_t>(sample.steps[static_cast<size_t>(k)].brokenBondCount());
    CHECK(row["step"] == k);
    CHECK(row["broken"] == broken);
    CHECK(row["new"] == broken - previous);
    previous = broken;
  }
}

TEST_CASE("crackvis info says which cells the crack methods use on a random packing",
          "[cli][info]") {
  TempDir dir;
  for (const auto& [radius, cells] :
       {std::pair<std::vector<std::string>, std::string>{{"--radius", "1e-3"}, "Delaunay"},
        {{"--radius-range", "1e-3:2e-3"}, "regular"}}) {
    const std::string path = dir.file(cells + ".h5");
    std::vector<std::string> args{kCli,   "generate", "--packing", "random", "--box", "0.02",
                                  "0.02", "0.02",     "-q",        "-o",     path};
    args.insert(args.end(), radius.begin(), radius.end());
    REQUIRE(runProcess(args).exitCode == 0);
    auto info = runProcess({kCli, "info", path});
    REQUIRE(info.exitCode == 0);
    CHECK_THAT(info.out, Catch::Contains("crack cells   " + cells +
                                         " triangulation (the bonds "
                                         "span no lattice"));
    const auto json = nlohmann::json::parse(runProcess({kCli, "info", path, "--json"}).out);
    CHECK_THAT(json["cells"].get<std::string>(), Catch::StartsWith(cells + " triangulation"));
    // Its ranks triangulate their slabs, with the wide cells it stores.
    CHECK(json["spatial_index"]["decomposition"] == "triangulation");
    CHECK(json["spatial_index"]["per_rank_reads"] == true);
    CHECK_THAT(info.out, Catch::Contains("MPI ranks read only their slab"));
  }
}

TEST_CASE("crackvis info --steps prints a per-step table", "[cli][info]") {
  TempDir dir;
  const std::string path = dir.file("table.h5");
  const auto sample = crackvis::testing::writeSampleFile(path, 2, 3);
  auto info = runProcess({kCli, "info", "--steps", path});
  REQUIRE(info.exitCode == 0);
  const auto out = lines(info.out);
  const auto header = std::find_if(out.begin(), out.end(), [](const std::string& l) {
    return l.find("broken %") != std::string::npos;
  });
  REQUIRE(header != out.end());
  REQUIRE(out.end() - header == 4);  // header and three rows
  const auto lastBroken = sample.steps[2].brokenBondCount();
  CHECK_THAT(*(header + 3), Catch::Contains(fmt::format(" {} ", lastBroken)));
  CHECK_THAT(info.out, Catch::Contains("dimension     2D"));
}

TEST_CASE("crackvis info reports each malformed file in one line and exits 1",
          "[cli][info][validation]") {
  TempDir dir;
  const std::string reference = dir.file("reference.h5");
  const auto sample = crackvis::testing::writeSampleFile(reference);
  for (const auto& defect : crackvis::testing::demDefects(sample)) {
    DYNAMIC_SECTION(defect.name) {
      const std::string path = dir.file("damaged.h5");
      std::filesystem::copy_file(reference, path,
                                 std::filesystem::copy_options::overwrite_existing);
      defect.damage(path, sample);
      // --steps makes info read every step, as a consumer of the file would.
      auto info = runProcess({kCli, "info", "--steps", path});
      CHECK(info.exitCode == 1);
      CHECK(info.out.empty());
      const auto errorLines = lines(info.err);
      REQUIRE(errorLines.size() == 1);
      CHECK(errorLines[0].starts_with("crackvis info: " + path + ": "));
      for (const auto& part : defect.messageParts) {
        CHECK_THAT(errorLines[0], Catch::Contains(part));
      }
      CHECK_THAT(info.err, !Catch::Contains("HDF5-DIAG"));
    }
  }
}

TEST_CASE("crackvis info refuses a middle step's short arrays, as a render session does",
          "[cli][info][validation]") {
  // Without --steps, info reads the first and last steps whole; a middle
  // step that a session would refuse must be refused here too.
  TempDir dir;
  const std::string path = dir.file("short.h5");
  const auto sample = crackvis::testing::writeSampleFile(path);
  const auto n = static_cast<std::uint64_t>(sample.lattice.particleCount());
  crackvis::testing::replaceDataset(path, "/steps/000001/positions",
                                    crackvis::dem::h5::ElementType::kFloat64, {n - 3, 3});
  for (const bool perStep : {false, true}) {
    auto info =
        perStep ? runProcess({kCli, "info", "--steps", path}) : runProcess({kCli, "info", path});
    INFO(info.err);
    CHECK(info.exitCode == 1);
    REQUIRE(lines(info.err).size() == 1);
    CHECK_THAT(info.err,
               Catch::Contains(fmt::format(
                   "dataset /steps/000001/positions has shape [{},3], expected [{},3]", n - 3, n)));
  }
  auto reader = crackvis::dem::DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->readStep(1).status().code() == crackvis::StatusCode::kFailedPrecondition);
}

TEST_CASE("crackvis info on a missing file or without arguments", "[cli][info]") {
  auto missing = runProcess({kCli, "info", "/nonexistent/x.h5"});
  CHECK(missing.exitCode == 1);
  CHECK(missing.err == "crackvis info: /nonexistent/x.h5: no such file\n");
  auto usage = runProcess({kCli, "info"});
  CHECK(usage.exitCode == 2);
  CHECK_THAT(usage.err, Catch::Contains("file is required"));
}
