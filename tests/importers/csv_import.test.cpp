// The plain folder format for in-house codes: bonds.csv with break steps, a
// notch column and strengths; per-step particles as CSV or NumPy .npy; and
// steps.csv with times and scalars. Everything round-trips into v1.1.
#include <cstring>
#include <fstream>

#include <catch2/catch.hpp>

#include "import_helpers.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/importers/step_source.hpp>

using namespace crackvis;
using crackvis::testing::TempDir;

namespace {

void write(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::trunc) << text;
}

// A float64 (n, 5) .npy: id, x, y, z, radius; its header may declare
// another row count than it holds.
void writeNpy(const std::string& path, const std::vector<std::array<double, 5>>& rows,
              std::uint64_t declaredRows = ~std::uint64_t{0}) {
  const std::uint64_t declared = declaredRows == ~std::uint64_t{0} ? rows.size() : declaredRows;
  std::string header =
      "{'descr': '<f8', 'fortran_order': False, 'shape': (" + std::to_string(declared) + ", 5), }";
  while ((10 + header.size() + 1) % 64 != 0) {
    header += ' ';
  }
  header += '\n';
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write("\x93NUMPY\x01\x00", 8);
  const auto size = static_cast<std::uint16_t>(header.size());
  out.put(static_cast<char>(size & 0xff)).put(static_cast<char>(size >> 8));
  out << header;
  for (const auto& row : rows) {
    out.write(reinterpret_cast<const char*>(row.data()), sizeof(row));
  }
}

// Four particles in a row, bonds 10-11, 11-12, 12-13 and a notch 10-12.
void writeFolder(const TempDir& dir) {
  write(dir.file("bonds.csv"),
        "id1,id2,break_step,notch,strength\n"
        "10,11,-1,0,5.0\n"
        "11,12,20,0,4.0\n"
        "12,13,-1,0,3.0\n"
        "10,12,-1,1,0.0\n");
  write(dir.file("particles_0.csv"),
        "id,x,y,z,radius,group,damage\n"
        "13,3,0,0,0.5,2,0\n"
        "10,0,0,0,0.5,1,0\n"
        "11,1,0,0,0.5,0,0\n"
        "12,2,0,0,0.5,0,0.25\n");
  write(dir.file("particles_20.csv"),
        "id,x,y,z,radius,group,damage\n"
        "10,0,0,0,0.5,1,0\n"
        "11,1,0,0,0.5,0,0.5\n"
        "12,2.5,0,0,0.5,0,1\n"
        "13,3.5,0,0,0.5,2,0\n");
  write(dir.file("steps.csv"), "step,time,load\n0,0.0,0.0\n20,0.002,15.5\n");
}

}  // namespace

TEST_CASE("a CSV folder imports bonds, notch, strengths, groups, extras and scalars",
          "[importers][csv]") {
  TempDir dir;
  writeFolder(dir);
  auto source = importers::openCsv({dir.path().string()});
  REQUIRE(source);
  REQUIRE((*source)->stepCount() == 2);
  const std::string out = dir.file("out.h5");
  REQUIRE(importers::importSeries(**source, testing::quietImport(out)));

  auto reader = dem::DemFileReader::open(out);
  REQUIRE(reader);
  auto lattice = reader->readLattice();
  REQUIRE(lattice);
  CHECK(lattice->particleId == std::vector<std::int64_t>{10, 11, 12, 13});
  CHECK(lattice->particleGroup == std::vector<std::int32_t>{1, 0, 0, 2});
  // Bonds in pair order: 10-11, 10-12 (notch), 11-12, 12-13.
  REQUIRE(lattice->bondCount() == 4);
  CHECK(lattice->bonds[1] == dem::Bond{0, 2});
  CHECK(lattice->cutAtStart(1));
  CHECK_FALSE(lattice->cutAtStart(2));
  CHECK(lattice->strength == std::vector<double>{5.0, 0.0, 4.0, 3.0});

  auto first = reader->readStep(0);
  auto last = reader->readStep(1);
  REQUIRE(first);
  REQUIRE(last);
  CHECK(first->bondState == std::vector<std::uint8_t>{0, 1, 0, 0});
  CHECK(last->bondState == std::vector<std::uint8_t>{0, 1, 1, 0});
  CHECK(last->positions[2] == dem::Vec3{2.5, 0, 0});
  CHECK(last->time == 0.002);
  CHECK(testing::scalarOf(reader->info().steps[1], "load") == 15.5);
  REQUIRE(last->extras.size() == 1);
  CHECK(last->extras[0].name == "damage");
  CHECK(last->extras[0].values == std::vector<double>{0, 0.5, 1, 0});
  CHECK(first->extras[0].values == std::vector<double>{0, 0, 0.25, 0});
  auto breaks = reader->readBreakSteps();
  REQUIRE(breaks);
  CHECK(*breaks == std::vector<std::int32_t>{-1, 0, 1, -1});
}

TEST_CASE("NumPy particle files import like CSV ones", "[importers][csv]") {
  TempDir dir;
  writeFolder(dir);
  std::filesystem::remove(dir.file("particles_0.csv"));
  std::filesystem::remove(dir.file("particles_20.csv"));
  writeNpy(
      dir.file("particles_0.npy"),
      {{{13, 3, 0, 0, 0.5}}, {{12, 2, 0, 0, 0.5}}, {{11, 1, 0, 0, 0.5}}, {{10, 0, 0, 0, 0.5}}});
  writeNpy(
      dir.file("particles_20.npy"),
      {{{13, 3.5, 0, 0, 0.5}}, {{12, 2.5, 0, 0, 0.5}}, {{11, 1, 0, 0, 0.5}}, {{10, 0, 0, 0, 0.5}}});
  auto source = importers::openCsv({dir.path().string()});
  REQUIRE(source);
  const std::string out = dir.file("out.h5");
  REQUIRE(importers::importSeries(**source, testing::quietImport(out)));
  auto reader = dem::DemFileReader::open(out);
  REQUIRE(reader);
  auto lattice = reader->readLattice();
  REQUIRE(lattice);
  CHECK(lattice->particleId == std::vector<std::int64_t>{10, 11, 12, 13});
  CHECK(lattice->particleGroup.empty());
  auto last = reader->readStep(1);
  REQUIRE(last);
  CHECK(last->positions[3] == dem::Vec3{3.5, 0, 0});
  CHECK(last->bondState == std::vector<std::uint8_t>{0, 1, 1, 0});
}

TEST_CASE("a malformed CSV folder is refused naming the file and line", "[importers][csv]") {
  TempDir dir;
  writeFolder(dir);
  SECTION("a row with a missing value") {
    write(dir.file("particles_20.csv"), "id,x,y,z,radius,group,damage\n10,0,0,0,0.5,1\n");
    auto source = importers::openCsv({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("o.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("particles_20.csv:2: 6 values for 7 columns"));
  }
  SECTION("a step without an array the first step had") {
    write(
        dir.file("particles_20.csv"),
        "id,x,y,z,radius,group\n10,0,0,0,0.5,1\n11,1,0,0,0.5,0\n12,2,0,0,0.5,0\n13,3,0,0,0.5,2\n");
    auto source = importers::openCsv({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("o.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("particles_20.csv: step 20: no array 'damage'"));
  }
  SECTION("no bond list") {
    std::filesystem::remove(dir.file("bonds.csv"));
    auto source = importers::openCsv({dir.path().string()});
    REQUIRE_FALSE(source);
    CHECK_THAT(source.status().message(), Catch::Contains("bonds.csv: no such file"));
  }
  SECTION("a bond to a particle that does not exist") {
    write(dir.file("bonds.csv"), "id1,id2\n10,99\n");
    auto source = importers::openCsv({dir.path().string()});
    REQUIRE(source);
    auto result = importers::importSeries(**source, testing::quietImport(dir.file("o.h5")));
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(),
               Catch::Contains("bond 10-99 joins particle id 99, which the step does not list"));
  }
  // The folder's third step (particles_30.npy, written by the section).
  auto importStepTwo = [&] {
    auto source = importers::openCsv({dir.path().string()});
    REQUIRE(source);
    auto options = testing::quietImport(dir.file("o.h5"));
    options.steps = "2";
    return importers::importSeries(**source, options);
  };
  for (const std::uint64_t declared :
       {std::uint64_t{400'000'000}, std::uint64_t{100'000'000'000}}) {
    SECTION("a .npy header declaring " + std::to_string(declared) + " rows in a small file") {
      // Believed, it allocated 15.7 GB (4e8 rows) or ended in std::bad_alloc.
      writeNpy(dir.file("particles_30.npy"), {{{10, 0, 0, 0, 0.5}}}, declared);
      auto result = importStepTwo();
      REQUIRE_FALSE(result);
      CHECK_THAT(result.status().message(),
                 Catch::Contains("particles_30.npy: truncated: the header declares " +
                                 std::to_string(declared) + " x 5 values") &&
                     Catch::Contains("the file holds 40 bytes of data"));
    }
  }
  SECTION("a truncated .npy") {
    writeNpy(dir.file("particles_30.npy"), {{{10, 0, 0, 0, 0.5}}});
    std::filesystem::resize_file(dir.file("particles_30.npy"), 140);  // 128-byte header
    auto result = importStepTwo();
    REQUIRE_FALSE(result);
    CHECK_THAT(result.status().message(), Catch::Contains("particles_30.npy: truncated"));
  }
}
