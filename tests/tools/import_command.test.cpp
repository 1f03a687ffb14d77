// crackvis import as a user runs it: one command per code, a dry run, the
// summary, and one line on stderr with exit status 1 for bad input.
#include <filesystem>
#include <fstream>
#include <iterator>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>

#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using crackvis::testing::runProcess;
using crackvis::testing::TempDir;

namespace {
const std::string kCli = CRACKVIS_CLI;
const std::string kData = CRACKVIS_TEST_DATA;
const std::string kRender = CRACKVIS_RENDER;
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
    CHECK_THAT(info.out, Catch::Contains("format        crackvis-dem v1.3"));
    CHECK_THAT(info.out, Catch::Contains("steps         11"));
  }
}

TEST_CASE("A run imported without any time shows iterations, not seconds", "[cli][import]") {
  // Yade's VTKRecorder writes no time: without --scalars (a time column) or
  // --timestep, `time` holds the iteration number, and info said
  // "time 0 .. 4000 s" (a Yade user read "t = 1.895e+04 s").
  TempDir dir;
  const std::string bare = dir.file("bare.h5");
  auto run = runProcess({kCli, "import", "yade", kData + "/yade/notched_bar", "-q", "-o", bare});
  REQUIRE(run.exitCode == 0);
  CHECK_THAT(run.out, Catch::Contains("labelled as iterations"));
  auto info = runProcess({kCli, "info", bare});
  REQUIRE(info.exitCode == 0);
  CHECK_THAT(info.out, Catch::Contains("(iterations 0 .. 4000; the code wrote no time)"));
  auto json = runProcess({kCli, "info", bare, "--json"});
  CHECK(nlohmann::json::parse(json.out)["time_unit"] == "iteration");
  // With --timestep the times are seconds again.
  const std::string timed = dir.file("timed.h5");
  REQUIRE(runProcess({kCli, "import", "yade", kData + "/yade/notched_bar", "--timestep", "1e-7",
                      "-q", "-o", timed})
              .exitCode == 0);
  auto seconds = runProcess({kCli, "info", timed});
  CHECK_THAT(seconds.out, Catch::Contains("(time 0 .. 0.0004 s)"));
  CHECK(nlohmann::json::parse(runProcess({kCli, "info", timed, "--json"}).out)["time_unit"] == "s");
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

TEST_CASE("crackvis export writes an imported run's particles and bonds for ParaView",
          "[cli][import][export]") {
  TempDir dir;
  const std::string h5 = dir.file("bar.h5");
  REQUIRE(runProcess({kCli, "import", "lammps", kData + "/lammps/notched_bar", "-o", h5, "-q"})
              .exitCode == 0);
  const std::string pvd = dir.file("bar.pvd");
  auto run =
      runProcess({kCli, "export", h5, "--particles", "--bonds", "-s", "0:-1:5", "-o", pvd, "-q"});
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  std::ifstream collection(pvd);
  const std::string text((std::istreambuf_iterator<char>(collection)),
                         std::istreambuf_iterator<char>());
  CHECK_THAT(text, Catch::Contains(R"(part="1" file="bar/bar_bonds_000010.vtp")"));

  vtkNew<vtkXMLPolyDataReader> particles;
  particles->SetFileName(dir.file("bar/bar_particles_000010.vtp").c_str());
  particles->Update();
  CHECK(particles->GetOutput()->GetNumberOfPoints() == 468);
  CHECK(particles->GetOutput()->GetNumberOfVerts() == 468);
  for (const char* name : {"radius", "id", "group", "velocity"}) {
    CHECK(particles->GetOutput()->GetPointData()->GetArray(name) != nullptr);
  }
  vtkNew<vtkXMLPolyDataReader> bonds;
  bonds->SetFileName(dir.file("bar/bar_bonds_000010.vtp").c_str());
  bonds->Update();
  REQUIRE(bonds->GetOutput()->GetNumberOfLines() == 2150);
  vtkDataArray* broken = bonds->GetOutput()->GetCellData()->GetArray("broken");
  vtkDataArray* notch = bonds->GetOutput()->GetCellData()->GetArray("cut_at_start");
  REQUIRE(broken != nullptr);
  REQUIRE(notch != nullptr);
  double brokenCount = 0.0;
  double notchCount = 0.0;
  for (vtkIdType b = 0; b < 2150; ++b) {
    brokenCount += broken->GetComponent(b, 0);
    notchCount += notch->GetComponent(b, 0);
  }
  CHECK(brokenCount == 60);
  CHECK(notchCount == 27);
}

TEST_CASE("an imported Yade packing gets a triangulation and its crack is covered",
          "[cli][import][packing]") {
  // Yade bonds spheres up to 1.5 x their radius sum: nearly every bond lies in
  // some bonded tetrahedron, but those overlap; taken for lattice cells they
  // covered 2-6 % of the crack. A triangulation covers it.
  TempDir dir;
  const std::string h5 = dir.file("yade.h5");
  REQUIRE(
      runProcess({kCli, "import", "yade", kData + "/yade/notched_bar", "-o", h5, "-q"}).exitCode ==
      0);
  auto info = runProcess({kCli, "info", h5});
  CHECK_THAT(info.out, Catch::Contains("crack cells   regular triangulation"));
  for (const char* method : {"cell-cut", "local-voronoi", "cell-centre", "cell-attribute"}) {
    auto run =
        runProcess({kCli, "extract", h5, "-m", method, "--metrics", "--json", "-s", "-1", "-q"});
    REQUIRE(run.exitCode == 0);
    const auto json = nlohmann::json::parse(run.out);
    INFO(method);
    CHECK(json["decomposition"] == "triangulation");
    CHECK(json["steps"][0]["largest_component_coverage"].get<double>() > 0.85);
    CHECK(json["steps"][0]["mapped_fraction"].get<double>() > 0.95);
  }
}

TEST_CASE("crackvis info refuses a file whose extents no index can reach", "[cli][info]") {
  // Found by the dem_reader fuzz target: /particles/radius declares 7.7e18
  // elements; reading it once threw out of a std::vector resize.
  auto info = runProcess({kCli, "info", kData + "/../fuzz/crashes/dem_reader-huge-extent.h5"});
  CHECK(info.exitCode == 1);
  CHECK_THAT(info.err, Catch::Contains("declares N = 7741240722073845778 particles") &&
                           Catch::Contains("file corrupt?"));
  CHECK_THAT(info.err, !Catch::Contains("internal error"));
}

TEST_CASE("Every local reader refuses every file the fuzzers kept, with one line", "[cli][info]") {
  // tests/fuzz/crashes: inputs that stopped a fuzz run (README "Findings"),
  // one of them a libhdf5 heap overflow that killed these readers with
  // SIGSEGV. Each reader opens a file with libhdf5's first look in a child
  // process (DemFileReader::openGuarded): exit 1 and one line naming the
  // file, never a signal, never "internal error".
  const std::filesystem::path crashes = kData + "/../fuzz/crashes";
  TempDir dir;
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(crashes)) {
    if (entry.path().extension() != ".h5") {
      continue;
    }
    ++files;
    const std::string path = entry.path().string();
    const std::string name = entry.path().filename().string();
    const std::string view = dir.file(name + ".xml");
    std::ofstream(view) << "<pipeline version=\"1\"><data file=\"" << name << "\"/></pipeline>\n";
    const std::vector<std::vector<std::string>> readers = {
        {kCli, "info", "--steps", path},
        {kCli, "extract", path, "-m", "cell-cut", "--metrics", "-q"},
        {kCli, "export", path, "--particles", "-o", dir.file("out.pvd")},
        {kCli, "snapshot", path, "-o", dir.file("out.png")},
        {kRender, "--snapshot", view, "--data-root", crashes.string(), "-o", dir.file("r.png")}};
    for (const auto& command : readers) {
      auto run = runProcess(command);
      INFO(command[1] << " " << command[2] << " on " << path << "\n" << run.err);
      CHECK(run.exitCode == 1);
      CHECK(crackvis::testing::programLines(run.err).size() == 1);
      CHECK_THAT(run.err, Catch::Contains(name));
      CHECK_THAT(run.err, !Catch::Contains("internal error"));
    }
    CHECK_FALSE(std::filesystem::exists(dir.file("out.png")));
    CHECK_FALSE(std::filesystem::exists(dir.file("r.png")));
  }
  CHECK(files >= 4);
}

TEST_CASE("A corrupt size that asks libhdf5 for 20 GB is refused at once, not by the OOM killer",
          "[cli][info]") {
  // Uncapped, the guarded child allocated and zero-filled the 20 GB: on a
  // 24 GiB node the OOM killer ended it after 45 s ("killed by SIGKILL"),
  // five readers of this file outlasted ctest's 300 s, and any process on
  // the node could have been chosen instead.
  const std::string name = "dem_reader-hdf5-20gb-metadata-read.h5";
  const std::string path = kData + "/../fuzz/crashes/" + name;
  TempDir dir;
  const std::string view = dir.file("view.xml");
  std::ofstream(view) << "<pipeline version=\"1\"><data file=\"" << name << "\"/></pipeline>\n";
  for (const auto& command : std::vector<std::vector<std::string>>{
           {kCli, "info", path},
           {kRender, "--snapshot", view, "--data-root", kData + "/../fuzz/crashes", "-o",
            dir.file("r.png")}}) {
    auto run = runProcess(command);
    INFO(command[0] << "\n" << run.err);
    CHECK(run.exitCode == 1);
    CHECK(crackvis::testing::lines(run.err).size() == 1);
    CHECK_THAT(run.err, Catch::Contains(name) && Catch::Contains("memory allocation failed"));
  }
}

TEST_CASE("A libhdf5 fault while opening is one line naming the file and the signal",
          "[cli][info]") {
  // libhdf5 overflows its heap in H5Aexists on this file. Whether that
  // faults depends on the heap's layout, which any change of the program
  // moves: it faulted in every build until the live-file reader's (issue 32),
  // whose libhdf5 reads a wrong attribute list instead. Either way the
  // answer is one line naming the file and exit 1; a fault names its signal.
  const std::string path = kData + "/../fuzz/crashes/dem_reader-hdf5-H5Aexists-heap-overflow.h5";
  auto info = runProcess({kCli, "info", path});
  INFO(info.err);
  CHECK(info.exitCode == 1);
  CHECK(crackvis::testing::lines(info.err).size() == 1);
  const bool faulted = info.err.find("libhdf5 faulted") != std::string::npos;
  if (faulted) {
    CHECK_THAT(info.err, Catch::StartsWith("crackvis info: " + path +
                                           ": libhdf5 faulted reading the "
                                           "file's structure (killed by SIG") &&
                             Catch::Contains("the file is probably corrupt"));
  } else {
    CHECK_THAT(info.err, Catch::StartsWith("crackvis info: " + path + ": ") &&
                             Catch::Contains("crackvis-dem file without a version"));
  }
}
