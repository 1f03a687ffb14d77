// The Yade importer on a real Yade 2023.02a JCFpm run (tests/data/yade/
// notched_bar, made by tests/data/generators/yade/run.sh): VTKRecorder's
// compressed binary files read through VTK, bonds matched to particle ids
// by position, and the history checked two ways: against the pairs a
// PyRunner dumped from O.interactions (bonds.<iter>.txt, id1 id2 isCohesive)
// and against JCFpm's own crack record (cracks_notched_bar.txt).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <sstream>

#include <catch2/catch.hpp>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "import_helpers.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/importers/step_source.hpp>

using namespace crackvis;
using crackvis::testing::TempDir;

namespace {

const std::string kBar = testing::kTestData + "/yade/notched_bar";

using Pair = std::pair<std::int64_t, std::int64_t>;

// The cohesive pairs Yade itself listed at an iteration.
std::set<Pair> cohesivePairs(std::int64_t iteration) {
  std::ifstream in(kBar + "/bonds." + std::to_string(iteration) + ".txt");
  std::set<Pair> pairs;
  std::int64_t a = 0;
  std::int64_t b = 0;
  int cohesive = 0;
  while (in >> a >> b >> cohesive) {
    if (cohesive != 0) {
      pairs.emplace(std::min(a, b), std::max(a, b));
    }
  }
  return pairs;
}

}  // namespace

TEST_CASE("a Yade JCFpm notched bar imports with Yade's own record of its bonds and cracks",
          "[importers][yade]") {
  TempDir dir;
  const std::string out = dir.file("bar.h5");
  auto source = importers::openYade({kBar});
  REQUIRE(source);
  auto options = testing::quietImport(out);
  options.scalarsTable = kBar + "/history.txt";
  auto summary = importers::importSeries(**source, options);
  REQUIRE(summary);
  CHECK(summary->stepsWritten == 11);
  CHECK(summary->timesFromSource);  // the history's time column

  auto reader = dem::DemFileReader::open(out);
  REQUIRE(reader);
  CHECK(reader->info().sourceCode == "Yade");
  CHECK(reader->info().particleCount == 327);
  CHECK(reader->info().bondCount == 1589);
  auto lattice = reader->readLattice();
  REQUIRE(lattice);
  for (int step = 0; step < reader->stepCount(); ++step) {
    const auto& stepInfo = reader->info().steps[static_cast<std::size_t>(step)];
    const auto iteration = static_cast<std::int64_t>(testing::scalarOf(stepInfo, "source_step"));
    auto state = reader->readBondState(step);
    REQUIRE(state);
    std::set<Pair> intact;
    for (std::size_t b = 0; b < lattice->bondCount(); ++b) {
      if ((*state)[b] == 0) {
        const std::int64_t first =
            lattice->particleId[static_cast<std::size_t>(lattice->bonds[b].first)];
        const std::int64_t second =
            lattice->particleId[static_cast<std::size_t>(lattice->bonds[b].second)];
        intact.emplace(std::min(first, second), std::max(first, second));
      }
    }
    INFO("iteration " << iteration);
    CHECK(intact == cohesivePairs(iteration));
    const auto broken = std::count(state->begin(), state->end(), std::uint8_t{1});
    CHECK(broken == static_cast<std::ptrdiff_t>(testing::scalarOf(stepInfo, "jcfpm_cracks")));
    CHECK(broken == static_cast<std::ptrdiff_t>(testing::scalarOf(stepInfo, "tensCracks")));
    // Each bond seen broken has the mode JCFpm's crack file recorded for
    // the break nearest it (all tensile in this run); intact bonds none.
    auto full = reader->readStep(step);
    REQUIRE(full);
    const auto modes = std::find_if(full->extras.begin(), full->extras.end(),
                                    [](const auto& e) { return e.name == "break_mode"; });
    REQUIRE(modes != full->extras.end());
    for (std::size_t b = 0; b < lattice->bondCount(); ++b) {
      CHECK(modes->values[b] == ((*state)[b] == 1 ? 1.0 : 0.0));
    }
  }
  // The spheres' own arrays ride along as extras.
  auto last = reader->readStep(reader->stepCount() - 1);
  REQUIRE(last);
  std::vector<std::string> names;
  for (const auto& extra : last->extras) {
    names.push_back(extra.name);
  }
  // By name, as stored; break_mode is the import's (JCFpm's crack file).
  CHECK(names == std::vector<std::string>{"damage", "nbCracks", "break_mode", "forceN"});
  double cracksAtSpheres = 0.0;
  for (double v : last->extras[1].values) {
    cracksAtSpheres += v;
  }
  CHECK(cracksAtSpheres == 2 * 27);  // each broken bond counts at both its spheres

  // Every sphere array of the last record, read here with VTK: position,
  // radius and damage of each sphere by its id.
  vtkNew<vtkXMLUnstructuredGridReader> spheres;
  spheres->SetFileName((kBar + "/spheres.4000.vtu").c_str());
  spheres->Update();
  vtkUnstructuredGrid* grid = spheres->GetOutput();
  REQUIRE(grid->GetNumberOfPoints() == 327);
  vtkDataArray* ids = grid->GetPointData()->GetArray("id");
  vtkDataArray* radii = grid->GetPointData()->GetArray("radii");
  vtkDataArray* damage = grid->GetPointData()->GetArray("damage");
  REQUIRE((ids != nullptr && radii != nullptr && damage != nullptr));
  int matched = 0;
  for (vtkIdType k = 0; k < grid->GetNumberOfPoints(); ++k) {
    const auto id = static_cast<std::int64_t>(ids->GetComponent(k, 0));
    const auto i = static_cast<std::size_t>(
        std::find(lattice->particleId.begin(), lattice->particleId.end(), id) -
        lattice->particleId.begin());
    REQUIRE(i < lattice->particleId.size());
    double p[3];
    grid->GetPoint(k, p);
    matched += last->positions[i] == dem::Vec3{p[0], p[1], p[2]} &&
                       lattice->radius[i] == radii->GetComponent(k, 0) &&
                       last->extras[0].values[i] == damage->GetComponent(k, 0)
                   ? 1
                   : 0;
  }
  CHECK(matched == 327);
}

TEST_CASE("damaged Yade records are refused naming the file", "[importers][yade]") {
  TempDir dir;
  for (const auto& entry : std::filesystem::directory_iterator(kBar)) {
    std::filesystem::copy_file(entry.path(), dir.path() / entry.path().filename());
  }
  SECTION("an interaction file missing") {
    std::filesystem::remove(dir.file("intrs.1200.vtp"));
    auto source = importers::openYade({dir.path().string()});
    REQUIRE_FALSE(source);
    CHECK_THAT(source.status().message(),
               Catch::Contains("iteration 1200") && Catch::Contains("no intrs.1200.vtp"));
  }
  SECTION("a truncated sphere file") {
    std::filesystem::resize_file(dir.file("spheres.2000.vtu"), 3000);
    auto source = importers::openYade({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("out.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(), Catch::Contains("spheres.2000.vtu"));
  }
  SECTION("a header declaring more points than the file holds") {
    // VTK's reader allocates by the header's counts before reading data.
    const std::string path = dir.file("spheres.2000.vtu");
    std::string text = testing::fileText(path);
    const std::string was = "NumberOfPoints=\"327\"      ";
    const std::size_t at = text.find(was);
    REQUIRE(at != std::string::npos);
    text.replace(at, was.size(), "NumberOfPoints=\"400000000\"");
    std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
    auto source = importers::openYade({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("out.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(
        result.status().message(),
        Catch::Contains("spheres.2000.vtu: the header declares NumberOfPoints=\"400000000\"") &&
            Catch::Contains("more than a file of"));
  }
  SECTION("a file that is not VTK") {
    std::ofstream(dir.file("intrs.800.vtp"), std::ios::trunc) << "not xml";
    auto source = importers::openYade({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("out.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(), Catch::Contains("intrs.800.vtp"));
  }
}

namespace {

// history.txt with only the rows whose iteration `keep` accepts, and an
// extra text column (Yade's phase label) when asked.
std::string historyWith(const TempDir& dir, const std::function<bool(std::int64_t)>& keep,
                        bool phase = false) {
  std::ifstream in(kBar + "/history.txt");
  const std::string path = dir.file(phase ? "phased.txt" : "partial.txt");
  std::ofstream out(path);
  std::string line;
  std::getline(in, line);
  out << line << (phase ? "\tphase" : "") << "\n";
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string cracks;
    std::string force;
    std::int64_t iter = 0;
    fields >> cracks >> force >> iter;
    if (keep(iter)) {
      out << line << (phase ? "\tloading" : "") << "\n";
    }
  }
  return path;
}

}  // namespace

TEST_CASE("a scalar table that matches no step, or only some, is refused unless asked",
          "[importers][yade]") {
  TempDir dir;
  auto import = [&](const std::string& table, bool partial) {
    auto source = importers::openYade({kBar});
    REQUIRE(source);
    auto options = testing::quietImport(dir.file("out.h5"));
    options.scalarsTable = table;
    options.partialScalars = partial;
    return importers::importSeries(**source, options);
  };
  SECTION("no row matches") {
    const std::string table = historyWith(dir, [](std::int64_t iter) { return iter % 400 == 7; });
    std::ofstream(table, std::ios::app) << "0\t0\t7\t0\t0\t0\t0\t0\t0\t0\n";
    auto result = import(table, true);
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("partial.txt: no row matches an imported step") &&
                   Catch::Contains("code steps 7 .. 7"));
  }
  SECTION("some rows match") {
    // Iteration 0 has no row: it used to keep the iteration number as its
    // time, beside seconds for the other steps.
    const std::string table = historyWith(dir, [](std::int64_t iter) { return iter != 0; });
    auto refused = import(table, false);
    REQUIRE_FALSE(refused);
    CHECK_THAT(refused.status().message(),
               Catch::Contains("rows for 10 of the 11 imported steps (none for code steps 0)") &&
                   Catch::Contains("--partial-scalars"));
    auto summary = import(table, true);
    REQUIRE(summary);
    CHECK(summary->scalarRowsMatched == 10);
    const std::string text = importers::formatSummary(*summary, testing::quietImport("out.h5"));
    CHECK_THAT(text, Catch::Contains("note          ") &&
                         Catch::Contains("has no row for 1 imported steps (code steps 0)"));
    auto reader = dem::DemFileReader::open(dir.file("out.h5"));
    REQUIRE(reader);
    // Step 0's time lies on the table's line through (400, 1.72e-4 s), ...:
    // about 0 s, not 0 iterations read as seconds or 1.
    const auto& steps = reader->info().steps;
    CHECK(std::abs(steps[0].time) < 1e-5);
    CHECK(steps[1].time == Approx(0.00017225728815021166));
  }
  SECTION("a text column is skipped with a note") {
    const std::string table = historyWith(
        dir, [](std::int64_t) { return true; }, true);
    auto summary = import(table, false);
    REQUIRE(summary);
    const std::string text = importers::formatSummary(*summary, testing::quietImport("out.h5"));
    CHECK_THAT(text, Catch::Contains("skipped the columns that hold text: phase"));
    CHECK(std::find(summary->scalarNames.begin(), summary->scalarNames.end(), "phase") ==
          summary->scalarNames.end());
  }
}

TEST_CASE("files of VTKRecorder's other recorders are skipped with a note, named or found",
          "[importers][yade]") {
  TempDir dir;
  std::vector<std::string> named;
  for (const auto& entry : std::filesystem::directory_iterator(kBar)) {
    std::filesystem::copy_file(entry.path(), dir.path() / entry.path().filename());
    const std::string name = entry.path().filename().string();
    if (name.ends_with(".vtu") || name.ends_with(".vtp")) {
      named.push_back(dir.file(name));
    }
  }
  // What the 'cracks' recorder writes beside the others (its content is not read).
  for (const char* name : {"cracks.400.vtu", "cracks.800.vtu"}) {
    std::ofstream(dir.file(name)) << "<VTKFile/>";
    named.push_back(dir.file(name));
  }
  for (const auto& inputs : {std::vector<std::string>{dir.path().string()}, named}) {
    auto source = importers::openYade(inputs);
    INFO((source ? std::string() : source.status().message()));
    REQUIRE(source);
    const auto& notes = (*source)->description().notes;
    REQUIRE(notes.size() == 1);
    CHECK_THAT(notes[0], Catch::StartsWith("skipped 2 files of VTKRecorder's 'cracks' recorder"));
    CHECK((*source)->stepCount() == 11);
  }
}
