// The LAMMPS importer on a real LAMMPS run (tests/data/lammps/notched_bar,
// made by tests/data/generators/lammps/run.sh): counts, the broken-bond
// history against LAMMPS's own count of breaks, every array round-tripped,
// and malformed inputs refused with the file and line.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "import_helpers.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/importers/step_source.hpp>

using namespace crackvis;
using crackvis::testing::TempDir;

namespace {

const std::string kBar = testing::kTestData + "/lammps/notched_bar";

// A copy of the run to damage.
void copyRun(const TempDir& dir) {
  for (const auto& entry : std::filesystem::directory_iterator(kBar)) {
    std::filesystem::copy_file(entry.path(), dir.path() / entry.path().filename());
  }
}

std::vector<std::string> readLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    lines.push_back(line);
  }
  return lines;
}

void writeLines(const std::string& path, const std::vector<std::string>& lines) {
  std::ofstream out(path, std::ios::trunc);
  for (const std::string& line : lines) {
    out << line << '\n';
  }
}

Result<importers::ImportSummary> importFolder(const std::string& folder, const std::string& out) {
  auto source = importers::openLammps({folder});
  if (!source) {
    return source.status();
  }
  return importers::importSeries(**source, testing::quietImport(out));
}

}  // namespace

TEST_CASE("a LAMMPS notched bar imports with LAMMPS's own count of breaks", "[importers][lammps]") {
  TempDir dir;
  const std::string out = dir.file("bar.h5");
  auto source = importers::openLammps({kBar});
  REQUIRE(source);
  CHECK((*source)->description().code == "LAMMPS");
  CHECK((*source)->description().version == "29 Sep 2021 - Update 2");
  auto options = testing::quietImport(out);
  options.scalarsTable = kBar + "/breaks.txt";
  auto summary = importers::importSeries(**source, options);
  REQUIRE(summary);
  CHECK(summary->stepsWritten == 11);

  auto reader = dem::DemFileReader::open(out);
  REQUIRE(reader);
  const auto& info = reader->info();
  CHECK(info.minorVersion == dem::kFormatMinorVersion);
  CHECK(info.sourceCode == "LAMMPS");
  CHECK(info.particleCount == 468);
  CHECK(info.bondCount == 2150);
  auto lattice = reader->readLattice();
  REQUIRE(lattice);
  CHECK(lattice->strength.empty());  // LAMMPS stores none; nothing is invented
  // The 27 bonds delete_bonds turned off (type -1) are the notch.
  std::size_t notch = 0;
  for (std::size_t b = 0; b < lattice->bondCount(); ++b) {
    notch += lattice->cutAtStart(b) ? 1 : 0;
  }
  CHECK(notch == 27);
  // Particles in id order, ids and types as the dump has them.
  CHECK(std::is_sorted(lattice->particleId.begin(), lattice->particleId.end()));
  CHECK(lattice->particleId.front() == 1);
  CHECK(lattice->particleId.back() == 468);
  CHECK(std::count(lattice->particleGroup.begin(), lattice->particleGroup.end(), 2) == 54);
  CHECK(std::count(lattice->particleGroup.begin(), lattice->particleGroup.end(), 3) == 54);

  // The broken-bond history: broken by load = LAMMPS's cumulative count of
  // fix bond/break, at every step; times from the log's timestep (2e-6 s).
  const auto breaks = testing::readTable(kBar + "/breaks.txt");
  for (int step = 0; step < reader->stepCount(); ++step) {
    const auto& stepInfo = info.steps[static_cast<std::size_t>(step)];
    const double sourceStep = testing::scalarOf(stepInfo, "source_step");
    const auto row = std::find(breaks.at("step").begin(), breaks.at("step").end(), sourceStep) -
                     breaks.at("step").begin();
    REQUIRE(row < static_cast<std::ptrdiff_t>(breaks.at("step").size()));
    auto state = reader->readBondState(step);
    REQUIRE(state);
    const auto broken = std::count(state->begin(), state->end(), std::uint8_t{1});
    CHECK(broken - 27 ==
          static_cast<std::ptrdiff_t>(breaks.at("broken_total")[static_cast<std::size_t>(row)]));
    CHECK(testing::scalarOf(stepInfo, "load") == breaks.at("load")[static_cast<std::size_t>(row)]);
    CHECK(stepInfo.time == Approx(sourceStep * 2e-6));
  }

  // Every array of one row round-trips: atom 130 at step 6260.
  const int step = 7;
  REQUIRE(testing::scalarOf(info.steps[step], "source_step") == 6260);
  auto state = reader->readStep(step);
  REQUIRE(state);
  for (const std::string& line : readLines(kBar + "/atoms.6260.txt")) {
    std::istringstream words(line);
    std::int64_t id = 0;
    int type = 0;
    double x, y, z, r, vx, vy, vz;
    if (!(words >> id >> type >> x >> y >> z >> r >> vx >> vy >> vz)) {
      continue;
    }
    const auto i = static_cast<std::size_t>(id - 1);  // ids 1..468, sorted
    REQUIRE(lattice->particleId[i] == id);
    CHECK(lattice->particleGroup[i] == type);
    CHECK(lattice->radius[i] == r);
    CHECK(state->positions[i] == dem::Vec3{x, y, z});
    CHECK(state->velocities[i][0] == static_cast<float>(vx));
    CHECK(state->velocities[i][2] == static_cast<float>(vz));
  }
}

TEST_CASE("a LAMMPS dry run reads two steps and writes nothing", "[importers][lammps]") {
  TempDir dir;
  auto source = importers::openLammps({kBar});
  REQUIRE(source);
  auto options = testing::quietImport(dir.file("none.h5"));
  options.dryRun = true;
  options.steps = "2:-1";
  auto summary = importers::importSeries(**source, options);
  REQUIRE(summary);
  CHECK(summary->selected.size() == 9);
  CHECK(summary->firstSourceStep == 3000);
  CHECK(summary->lastSourceStep == 8000);
  CHECK(summary->bonds == 2150);
  CHECK(summary->brokenLast == 60);
  CHECK_FALSE(std::filesystem::exists(dir.file("none.h5")));
  const std::string text = importers::formatSummary(*summary, options);
  CHECK_THAT(text, Catch::Contains("M = 2150 at the first step, 27 of them cut at the start"));
  CHECK_THAT(text, Catch::Contains("dry run"));
}

TEST_CASE("malformed LAMMPS dumps are refused naming the file and line", "[importers][lammps]") {
  TempDir dir;
  copyRun(dir);
  const std::string folder = dir.path().string();
  const std::string out = dir.file("out.h5");
  SECTION("a truncated particle dump") {
    auto lines = readLines(dir.file("atoms.6220.txt"));
    lines.resize(100);
    writeLines(dir.file("atoms.6220.txt"), lines);
    auto result = importFolder(folder, out);
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(), Catch::Contains("atoms.6220.txt:100: truncated"));
  }
  SECTION("a particle that vanishes") {
    auto lines = readLines(dir.file("atoms.6400.txt"));
    lines[3] = "467";
    lines.erase(lines.begin() + 20);  // the row of atom 12 (rows start at line 10)
    writeLines(dir.file("atoms.6400.txt"), lines);
    auto result = importFolder(folder, out);
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(), Catch::Contains("step 6400: particle id 12 vanished"));
  }
  SECTION("a step without its bond dump") {
    std::filesystem::remove(dir.file("bonds.4500.txt"));
    auto result = importFolder(folder, out);
    REQUIRE_FALSE(result);
    CHECK_THAT(
        result.status().message(),
        Catch::Contains("step 4500") && Catch::Contains("has a particle dump but no bond dump"));
  }
  SECTION("a bond that appears after the first step") {
    auto lines = readLines(dir.file("bonds.1500.txt"));
    lines[3] = std::to_string(std::stoi(lines[3]) + 1);
    lines.push_back("1 468 1 ");
    writeLines(dir.file("bonds.1500.txt"), lines);
    auto result = importFolder(folder, out);
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("step 1500: bond 1-468 appears") && Catch::Contains("--steps"));
  }
  SECTION("a row count beyond what the file holds") {
    // Readers size their arrays by the count: it must not be believed.
    auto lines = readLines(dir.file("atoms.3000.txt"));
    REQUIRE(lines[2] == "ITEM: NUMBER OF ATOMS");
    lines[3] = "400000000";
    writeLines(dir.file("atoms.3000.txt"), lines);
    auto result = importFolder(folder, out);
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("atoms.3000.txt:4: the header declares 400000000 rows, but only") &&
                   Catch::Contains("bytes follow"));
  }
  SECTION("a garbled number") {
    auto lines = readLines(dir.file("atoms.3000.txt"));
    lines[12] = "3 2 0.0007 x 0.0007 0.0005 0 0 0";
    writeLines(dir.file("atoms.3000.txt"), lines);
    auto result = importFolder(folder, out);
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("atoms.3000.txt:13: column 4: 'x' is not a number"));
  }
  SECTION("a file that is no dump at all") {
    writeLines(dir.file("atoms.0.txt"), {"hello"});
    auto result = importers::openLammps({dir.file("atoms.0.txt")});
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(), Catch::Contains("atoms.0.txt:1: not a LAMMPS dump"));
  }
}

TEST_CASE("a failed import leaves an existing output file as it was", "[importers][lammps]") {
  TempDir dir;
  copyRun(dir);
  const std::string out = dir.file("out.h5");
  writeLines(out, {"the user's earlier file"});
  auto lines = readLines(dir.file("atoms.8000.txt"));
  lines.resize(50);
  writeLines(dir.file("atoms.8000.txt"), lines);
  REQUIRE_FALSE(importFolder(dir.path().string(), out));
  CHECK(readLines(out) == std::vector<std::string>{"the user's earlier file"});
  CHECK_FALSE(std::filesystem::exists(out + ".importing"));
}
