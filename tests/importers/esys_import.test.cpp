// The ESyS-Particle importer on a real ESyS-Particle run (tests/data/esys/
// notched_bar, made by tests/data/generators/esys/run.sh): a random
// polydisperse packing, particles keyed by id although their order changes
// between snapshots, and the broken-bond history against ESyS's own
// count of intact bonds (bond_count.dat, an InteractionScalarFieldSaver).
#include <filesystem>
#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>

#include "import_helpers.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/importers/step_source.hpp>

using namespace crackvis;
using crackvis::testing::TempDir;

namespace {
const std::string kBar = testing::kTestData + "/esys/notched_bar";
}

TEST_CASE("an ESyS-Particle notched bar imports with ESyS's own bond count", "[importers][esys]") {
  TempDir dir;
  const std::string out = dir.file("bar.h5");
  auto source = importers::openEsys({kBar});
  REQUIRE(source);
  CHECK((*source)->description().code == "ESyS-Particle");
  REQUIRE(importers::importSeries(**source, testing::quietImport(out)));

  auto reader = dem::DemFileReader::open(out);
  REQUIRE(reader);
  CHECK(reader->info().particleCount == 398);
  CHECK(reader->info().bondCount == 1001);
  auto lattice = reader->readLattice();
  REQUIRE(lattice);
  // Ids 0..399 without the two the notch removed; tags as groups.
  CHECK(lattice->particleId.front() == 0);
  CHECK(lattice->particleId.back() == 399);
  CHECK(std::count(lattice->particleGroup.begin(), lattice->particleGroup.end(), 2) == 53);
  CHECK(std::count(lattice->particleGroup.begin(), lattice->particleGroup.end(), 3) == 60);
  const auto [small, large] = std::minmax_element(lattice->radius.begin(), lattice->radius.end());
  CHECK(*small >= 0.2);
  CHECK(*large <= 0.5);
  CHECK(*large > 2 * *small);  // polydisperse

  std::ifstream counts(kBar + "/bond_count.dat");
  for (int step = 0; step < reader->stepCount(); ++step) {
    double intact = 0.0;
    REQUIRE(counts >> intact);
    auto state = reader->readBondState(step);
    REQUIRE(state);
    CHECK(std::count(state->begin(), state->end(), std::uint8_t{0}) ==
          static_cast<std::ptrdiff_t>(intact));
    CHECK(reader->info().steps[static_cast<std::size_t>(step)].time == Approx(0.14 * step));
  }
  // Positions and forces follow the id, not the row: particle 207 is row 2
  // of the first snapshot.
  auto first = reader->readStep(0);
  REQUIRE(first);
  const auto at = std::find(lattice->particleId.begin(), lattice->particleId.end(), 207) -
                  lattice->particleId.begin();
  CHECK(first->positions[static_cast<std::size_t>(at)] ==
        dem::Vec3{0.974252112, 0.211817382, 0.353436629});
  CHECK(lattice->radius[static_cast<std::size_t>(at)] == 0.211817382);

  // Every array of particle 207 at step 4200 (snapshot index 6), as the
  // worker file lists it: pos, rad, id, tag, ..., vel (13-15), force (16-18).
  std::ifstream worker(kBar + "/snap_t=4200_1.txt");
  std::string line;
  std::vector<double> row;
  while (std::getline(worker, line)) {
    std::istringstream words(line);
    std::vector<double> values;
    double v = 0.0;
    while (words >> v) {
      values.push_back(v);
    }
    if (values.size() == 29 && values[4] == 207) {
      row = values;
    }
  }
  REQUIRE(row.size() == 29);
  auto later = reader->readStep(6);
  REQUIRE(later);
  const auto i = static_cast<std::size_t>(at);
  CHECK(later->positions[i] == dem::Vec3{row[0], row[1], row[2]});
  CHECK(lattice->particleGroup[i] == static_cast<std::int32_t>(row[5]));
  CHECK(later->velocities[i][0] == static_cast<float>(row[13]));
  CHECK(later->velocities[i][2] == static_cast<float>(row[15]));
  REQUIRE(later->extras.size() == 1);
  CHECK(later->extras[0].name == "force");
  CHECK(later->extras[0].values[3 * i] == row[16]);
  CHECK(later->extras[0].values[3 * i + 2] == row[18]);
}

TEST_CASE("damaged ESyS-Particle snapshots are refused naming the file", "[importers][esys]") {
  TempDir dir;
  for (const auto& entry : std::filesystem::directory_iterator(kBar)) {
    std::filesystem::copy_file(entry.path(), dir.path() / entry.path().filename());
  }
  SECTION("a worker file missing") {
    std::filesystem::remove(dir.file("snap_t=2100_1.txt"));
    auto source = importers::openEsys({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("o.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(), Catch::Contains("snap_t=2100_1.txt: no such file"));
  }
  SECTION("a truncated worker file") {
    std::filesystem::resize_file(dir.file("snap_t=4200_1.txt"), 5000);
    auto source = importers::openEsys({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("o.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("snap_t=4200_1.txt") && Catch::Contains("truncated"));
  }
  SECTION("a master file that is not one") {
    std::ofstream(dir.file("snap_t=700_0.txt"), std::ios::trunc) << "hello\n";
    auto source = importers::openEsys({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("o.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("snap_t=700_0.txt:1") && Catch::Contains("not an ESyS-Particle"));
  }
}
