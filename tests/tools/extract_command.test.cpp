#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "support/process.hpp"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/random_packing.hpp>

using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {
const std::string kCli = CRACKVIS_CLI;

}  // namespace

TEST_CASE("crackvis extract writes a ParaView time series", "[cli][extract]") {
  TempDir dir;
  const std::string data = dir.file("run.h5");
  const auto sample = crackvis::testing::writeSampleFile(data, 3, 4);
  const std::string pvd = dir.file("out/lv.pvd");
  auto run =
      runProcess({kCli, "extract", data, "-m", "local-voronoi", "-s", "1:3", "-o", pvd, "-q"});
  REQUIRE(run.exitCode == 0);
  const std::string collection = crackvis::testing::fileText(pvd);
  for (int step = 1; step <= 3; ++step) {
    const std::string relative = fmt::format("lv/lv_{:06d}.vtp", step);
    CHECK_THAT(collection, Catch::Contains(fmt::format(R"(file="{}")", relative)));
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(dir.file("out/" + relative).c_str());
    reader->Update();
    // One face or inconsistency mark per broken bond.
    CHECK(reader->GetOutput()->GetNumberOfCells() ==
          static_cast<vtkIdType>(sample.steps[static_cast<std::size_t>(step)].brokenBondCount()));
  }
  CHECK_THAT(collection,
             Catch::Contains(fmt::format(R"(timestep="{:.17g}")", sample.steps[2].time)));
}

TEST_CASE("crackvis extract refuses volume cells in a .vtp name and keeps the old file",
          "[cli][extract]") {
  // ParaView picks its reader by the extension: an UnstructuredGrid in a
  // .vtp is a file it cannot open.
  TempDir dir;
  const std::string data = dir.file("run.h5");
  crackvis::testing::writeSampleFile(data, 3, 3);
  const std::string vtp = dir.file("a.vtp");
  std::ofstream(vtp) << "an earlier result";
  auto run =
      runProcess({kCli, "extract", data, "-m", "cell-attribute", "-s", "-1", "-o", vtp, "-q"});
  INFO(run.err);
  CHECK(run.exitCode == 1);
  CHECK(crackvis::testing::lines(run.err).size() == 1);
  CHECK_THAT(run.err, Catch::Contains("a.vtp: these cracks have volume cells") &&
                          Catch::Contains("name the output .vtu"));
  CHECK(crackvis::testing::fileText(vtp) == "an earlier result");
  CHECK_FALSE(std::filesystem::exists(vtp + ".partial"));
  auto vtu = runProcess(
      {kCli, "extract", data, "-m", "cell-attribute", "-s", "-1", "-o", dir.file("a.vtu"), "-q"});
  CHECK(vtu.exitCode == 0);
}

TEST_CASE("crackvis extract: cell attribute series are .vtu, single steps go where asked",
          "[cli][extract]") {
  TempDir dir;
  const std::string data = dir.file("run.h5");
  crackvis::testing::writeSampleFile(data, 3, 3);
  auto cells = runProcess(
      {kCli, "extract", data, "-m", "cell-attribute", "-o", dir.file("cells.pvd"), "-q"});
  REQUIRE(cells.exitCode == 0);
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(dir.file("cells/cells_000002.vtu").c_str());
  reader->Update();
  CHECK(reader->GetOutput()->GetNumberOfCells() > 0);
  auto stl = runProcess(
      {kCli, "extract", data, "-m", "cell-cut", "-s", "-1", "-o", dir.file("last.stl"), "-q"});
  REQUIRE(stl.exitCode == 0);
  CHECK(std::filesystem::file_size(dir.file("last.stl")) > 84);
  auto obj = runProcess(
      {kCli, "extract", data, "-m", "cell-centre", "-s", "0:2:2", "-o", dir.file("cc.obj"), "-q"});
  REQUIRE(obj.exitCode == 0);
  CHECK(std::filesystem::exists(dir.file("cc_000000.obj")));
  CHECK(std::filesystem::exists(dir.file("cc_000002.obj")));
  CHECK_FALSE(std::filesystem::exists(dir.file("cc_000001.obj")));
}

TEST_CASE("crackvis extract --metrics prints a row per step, or JSON", "[cli][extract]") {
  TempDir dir;
  const std::string data = dir.file("run.h5");
  const auto sample = crackvis::testing::writeSampleFile(data, 3, 3);
  auto json = runProcess({kCli, "extract", data, "-m", "cell-cut", "--metrics", "--json", "-q"});
  REQUIRE(json.exitCode == 0);
  const auto parsed = nlohmann::json::parse(json.out);
  REQUIRE(parsed["steps"].size() == 3);
  CHECK(parsed["steps"][0]["broken_bonds"] == 0);
  CHECK(parsed["steps"][2]["broken_bonds"] == sample.steps[2].brokenBondCount());
  CHECK(parsed["steps"][2]["points"] == sample.steps[2].brokenBondCount());  // one per broken bond
  auto table = runProcess({kCli, "extract", data, "-m", "local-voronoi", "--metrics", "-q"});
  REQUIRE(table.exitCode == 0);
  CHECK(crackvis::testing::lines(table.out).size() == 4);  // header + 3 steps
}

TEST_CASE("crackvis extract refuses bad requests with one line", "[cli][extract]") {
  TempDir dir;
  const std::string data = dir.file("run.h5");
  crackvis::testing::writeSampleFile(data, 3, 3);
  auto range = runProcess({kCli, "extract", data, "-s", "2:9", "--metrics"});
  CHECK(range.exitCode == 1);
  CHECK(range.err == "crackvis extract: step range '2:9' is outside the file's steps 0..2\n");
  auto format = runProcess({kCli, "extract", data, "-o", dir.file("x.ply")});
  CHECK(format.exitCode == 1);
  CHECK_THAT(format.err, Catch::Contains("unknown output format '.ply'"));
  auto nothing = runProcess({kCli, "extract", data});
  CHECK(nothing.exitCode == 2);
  CHECK_THAT(nothing.err, Catch::Contains("nothing to do"));
  auto method = runProcess({kCli, "extract", data, "-m", "marching-cubes", "--metrics"});
  CHECK(method.exitCode == 2);
  auto missing = runProcess({kCli, "extract", dir.file("none.h5"), "--metrics"});
  CHECK(missing.exitCode == 1);
  CHECK(missing.err == "crackvis extract: " + dir.file("none.h5") + ": no such file\n");
}

TEST_CASE("crackvis bench methods prints per-step times and ratios as JSON", "[cli][bench]") {
  TempDir dir;
  const std::string data = dir.file("run.h5");
  crackvis::testing::writeSampleFile(data, 3, 3);
  auto run = runProcess({kCli, "bench", "methods", data, "--json", "-q", "--runs", "3", "--threads",
                         "2", "--voro-every", "2"});
  REQUIRE(run.exitCode == 0);
  const auto json = nlohmann::json::parse(run.out);
  CHECK(json["runs"] == 3);
  CHECK(json["load_before"].size() == 3);
  CHECK_THAT(json["machine"].get<std::string>(), Catch::Contains("hardware threads"));
  // Equal terms: 1 thread against one container, 2 threads against 2 slabs.
  REQUIRE(json["configs"].size() == 2);
  for (int c = 0; c < 2; ++c) {
    const auto& config = json["configs"][c];
    INFO("configuration " << c);
    CHECK(config["threads"] == c + 1);
    CHECK(config["voro++"]["containers"] == c + 1);
    CHECK(config["voro++"]["exact"] == true);
    CHECK(config["voro++"]["steps_measured"] == 2);  // steps 0 and 2 (the last)
    CHECK(config["per_step"].size() == 3);
    CHECK(config["per_step"][1]["voro++_ms"].is_null());
    for (const char* method : {"cell-attribute", "cell-cut", "local-voronoi", "cell-centre"}) {
      const auto& m = config["methods"][method];
      CHECK(m["total_s"].get<double>() > 0.0);
      CHECK(m["median_ms"].get<double>() > 0.0);
      CHECK(m["over_voro++_last_step"].get<double>() > 0.0);
      CHECK(m["over_voro++_median_over_steps"].get<double>() > 0.0);
    }
  }
  // Both configurations computed the same diagram.
  CHECK(json["configs"][0]["voro++"]["faces"] == json["configs"][1]["voro++"]["faces"]);
  CHECK(json["methods"]["local-voronoi"]["state_bytes_per_particle"].get<double>() > 0.0);
  const auto& goals = json["goals"];
  CHECK(goals["local_voronoi_over_voro++_1_thread_last_step"] ==
        json["configs"][0]["methods"]["local-voronoi"]["over_voro++_last_step"]);
  CHECK(goals["met"].is_boolean());

  auto table = runProcess({kCli, "bench", "methods", data, "-q", "--runs", "1", "--threads", "1"});
  REQUIRE(table.exitCode == 0);
  CHECK_THAT(table.out, Catch::Contains("1 thread: the four methods against Voro++") &&
                            Catch::Contains("load before") && Catch::Contains("goals, 1 thread"));
  CHECK_THAT(table.out, !Catch::Contains("2 threads:"));
}

TEST_CASE("crackvis bench methods without the baseline shows every step and no ratio",
          "[cli][bench]") {
  TempDir dir;
  const std::string data = dir.file("run.h5");
  crackvis::testing::writeSampleFile(data, 3, 3);
  auto run = runProcess(
      {kCli, "bench", "methods", data, "--json", "-q", "--threads", "1", "--voro-every", "0"});
  REQUIRE(run.exitCode == 0);
  const auto json = nlohmann::json::parse(run.out);
  const auto& lv = json["configs"][0]["methods"]["local-voronoi"];
  CHECK(lv["over_voro++_last_step"].is_null());
  CHECK(lv["over_voro++_median_over_steps"].is_null());
  // A goal the run did not measure is neither met nor failed.
  CHECK(json["goals"]["met"].is_null());

  auto table = runProcess(
      {kCli, "bench", "methods", data, "-q", "--runs", "1", "--threads", "1", "--voro-every", "0"});
  REQUIRE(table.exitCode == 0);
  // One row per step, the baseline's columns empty.
  bool lastStepRow = false;
  std::istringstream lines(table.out);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::vector<std::string> row{std::istream_iterator<std::string>(words), {}};
    lastStepRow =
        lastStepRow || (row.size() == 8 && row[0] == "2" && row[6] == "-" && row[7] == "-");
  }
  CHECK(lastStepRow);
  CHECK_THAT(table.out, Catch::Contains("not measured") && !Catch::Contains(": met"));
}

TEST_CASE("addresses without a port are refused before anything connects", "[cli][bench]") {
  // gRPC would otherwise try port 443 of the host and fail after a timeout.
  auto health = runProcess({kCli, "health", "localhost"});
  CHECK(health.exitCode == 2);
  CHECK_THAT(health.err, Catch::StartsWith("crackvis health: server 'localhost': expected "
                                           "HOST:PORT with the port"));
  auto render = runProcess({kCli, "bench", "render", "--server", "[::1]", "--file", "x.h5"});
  CHECK(render.exitCode == 1);
  CHECK_THAT(render.err, Catch::Contains("--server '[::1]': expected HOST:PORT"));
  // The raw TLS baseline has no default: the port after crackvis-data's is
  // crackvis-render's in the documented layout.
  auto noRaw =
      runProcess({kCli, "bench", "transfer", "--server", "localhost:50051", "--file", "x.h5"});
  CHECK(noRaw.exitCode == 2);
  CHECK_THAT(noRaw.err, Catch::Contains("--raw is required"));
  auto badRaw = runProcess({kCli, "bench", "transfer", "--server", "localhost:50051", "--raw",
                            "localhost:99999", "--file", "x.h5"});
  CHECK(badRaw.exitCode == 1);
  CHECK_THAT(badRaw.err, Catch::Contains("--raw 'localhost:99999': expected HOST:PORT"));
}

TEST_CASE("crackvis snapshot renders a step to PNG off screen", "[cli][snapshot]") {
  TempDir dir;
  const std::string data = dir.file("run.h5");
  crackvis::testing::writeSampleFile(data, 3, 3);
  auto run = runProcess({kCli, "snapshot", data, "-s", "-1", "--width", "96", "--height", "64",
                         "-o", dir.file("last.png")});
  REQUIRE(run.exitCode == 0);
  CHECK_THAT(run.out, Catch::Contains("llvmpipe"));
  const std::string png = crackvis::testing::fileText(dir.file("last.png"));
  REQUIRE(png.size() > 8);
  CHECK(png.substr(1, 3) == "PNG");

  std::ofstream(dir.file("bad.xml"))
      << "<pipeline version=\"1\">\n  <data file=\"x\"/>\n  <cracks method=\"x\"/>\n</pipeline>\n";
  auto bad =
      runProcess({kCli, "snapshot", data, "-p", dir.file("bad.xml"), "-o", dir.file("x.png")});
  CHECK(bad.exitCode == 1);
  CHECK_THAT(bad.err, Catch::Contains("pipeline line 3, element <cracks>"));
  auto range = runProcess({kCli, "snapshot", data, "-s", "7", "-o", dir.file("x.png")});
  CHECK(range.exitCode == 1);
  CHECK_THAT(range.err, Catch::Contains("step 7 out of range (the file has steps 0..2)"));
}

namespace {

// A random packing (crackvis-dem, two steps): intact, then a through crack at
// x = 0.01 plus `scattered` isolated broken bonds far from it.
void writeCrackedRandomPacking(const std::string& path, int scattered) {
  crackvis::dem::RandomPackingSpec spec;
  spec.box = {0.02, 0.01, 0.01};
  spec.radiusMin = 3e-4;
  spec.radiusMax = 6e-4;
  spec.solidFraction = 0.55;
  auto packing = crackvis::dem::generateRandomPacking(spec);
  REQUIRE(packing.isOk());
  auto writer = crackvis::dem::DemFileWriter::create(path, packing->lattice,
                                                     crackvis::dem::metadataFrom("test"));
  REQUIRE(writer.isOk());
  crackvis::dem::StepState step;
  step.positions = packing->positions;
  step.bondState.assign(packing->lattice.bondCount(), 0);
  REQUIRE(writer->appendStep(step).isOk());
  int isolated = 0;
  for (std::size_t b = 0; b < step.bondState.size(); ++b) {
    const auto& bond = packing->lattice.bonds[b];
    const double xa = packing->positions[static_cast<std::size_t>(bond.first)].x;
    const double xb = packing->positions[static_cast<std::size_t>(bond.second)].x;
    if ((xa - 0.01) * (xb - 0.01) < 0.0) {
      step.bondState[b] = 1;
    } else if (xa < 0.004 && b % 97 == 0 && isolated < scattered) {
      step.bondState[b] = 1;
      ++isolated;
    }
  }
  step.time = 1e-3;
  REQUIRE(writer->appendStep(step).isOk());
  REQUIRE(writer->close().isOk());
}

}  // namespace

TEST_CASE("crackvis extract on a random packing: the main crack, its coverage, scattered damage",
          "[cli][extract][packing]") {
  TempDir dir;
  const std::string data = dir.file("random.h5");
  writeCrackedRandomPacking(data, 6);
  auto json = runProcess(
      {kCli, "extract", data, "-m", "cell-centre", "-s", "1", "--metrics", "--json", "-q"});
  REQUIRE(json.exitCode == 0);
  CHECK(json.err.empty());
  const auto report = nlohmann::json::parse(json.out);
  CHECK(report["decomposition"] == "triangulation");
  const auto& row = report["steps"][0];
  CHECK(row["mapped_fraction"].get<double>() >= 0.99);
  CHECK(row["largest_component_coverage"].get<double>() >= 0.9);
  const auto& components = row["component_list"];
  REQUIRE(components.size() >= 2);  // the main crack and scattered pieces
  CHECK(std::abs(components[0]["normal"][0].get<double>()) > 0.95);
  CHECK(components[0]["area"].get<double>() > 8.0 * components[1]["area"].get<double>());

  SECTION("--largest 1 keeps the main crack only") {
    const std::string out = dir.file("main.vtp");
    auto run = runProcess({kCli, "extract", data, "-m", "cell-centre", "-s", "1", "--largest", "1",
                           "-o", out, "--metrics", "--json", "-q"});
    REQUIRE(run.exitCode == 0);
    const auto kept = nlohmann::json::parse(run.out)["steps"][0];
    CHECK(kept["components"] == 1);
    CHECK(kept["polygons"].get<int>() < row["polygons"].get<int>());
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(out.c_str());
    reader->Update();
    CHECK(reader->GetOutput()->GetNumberOfPolys() == kept["polygons"].get<int>());
  }
  SECTION("the lattice's cells on a random packing: a warning that names the cause") {
    auto run = runProcess({kCli, "extract", data, "-m", "cell-cut", "-s", "1", "--decomposition",
                           "lattice", "--metrics", "--json", "-q"});
    REQUIRE(run.exitCode == 0);
    CHECK_THAT(run.err, Catch::StartsWith("crackvis extract: warning: only "));
    CHECK_THAT(run.err, Catch::Contains("span no lattice"));
    CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
    CHECK_THAT(nlohmann::json::parse(run.out)["warning"].get<std::string>(),
               Catch::Contains("span no lattice"));
  }
}
