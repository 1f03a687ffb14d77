// crackvis-dem v1.1: the optional parts round-trip (ids, groups, bond flags,
// no strengths, step scalars, extra arrays constant and per step,
// provenance), compressed storage reads like contiguous, and v1.0 rules
// still hold for files without version_minor.
#include <catch2/catch.hpp>

#include "support/h5_tamper.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using namespace crackvis;
using crackvis::testing::TempDir;

namespace {

dem::Lattice notchedTriple() {
  dem::Lattice lattice;
  lattice.dimension = 3;
  lattice.radius = {0.5, 0.5, 0.5};
  lattice.bonds = {{0, 1}, {1, 2}, {0, 2}};
  lattice.particleId = {7, 3, 100000000000};
  lattice.particleGroup = {2, 0, 3};
  lattice.bondFlags = {0, 0, dem::kBondCutAtStart};
  lattice.extras = {{"material", dem::ExtraOwner::kParticles, 1, {1, 2, 3}},
                    {"rest_length", dem::ExtraOwner::kBonds, 1, {1.0, 1.0, 2.0}}};
  return lattice;
}

dem::StepState stepOf(double x, std::vector<std::uint8_t> state) {
  dem::StepState step;
  step.time = x;
  step.positions = {{0, 0, 0}, {1 + x, 0, 0}, {2 + x, 0, 0}};
  step.bondState = std::move(state);
  step.scalars = {{"load", 10 * x}, {"displacement", x}};
  step.extras = {{"force", dem::ExtraOwner::kParticles, 3, {0, 0, 0, 1, 2, 3, 4, 5, x}},
                 {"damage", dem::ExtraOwner::kBonds, 1, {0, x, 1}}};
  return step;
}

void writeFile(const std::string& path, int deflate) {
  dem::DemMetadata metadata;
  metadata.source = "test";
  metadata.sourceCode = "LAMMPS";
  metadata.sourceVersion = "29 Sep 2021";
  metadata.sourceFiles = {"a.txt", "b.txt"};
  metadata.storage.deflateLevel = deflate;
  auto writer = dem::DemFileWriter::create(path, notchedTriple(), metadata);
  REQUIRE(writer);
  REQUIRE(writer->appendStep(stepOf(0.0, {0, 0, 1})));
  REQUIRE(writer->appendStep(stepOf(0.5, {0, 1, 1})));
  REQUIRE(writer->close());
}

}  // namespace

TEST_CASE("crackvis-dem v1.1 round-trips ids, groups, notch flags, scalars and extras",
          "[dem][v1.1]") {
  TempDir dir;
  const int deflate = GENERATE(0, 4);
  const std::string path = dir.file("v11.h5");
  writeFile(path, deflate);
  auto reader = dem::DemFileReader::open(path);
  REQUIRE(reader);
  const auto& info = reader->info();
  CHECK(info.version == 1);
  CHECK(info.minorVersion == dem::kFormatMinorVersion);
  CHECK_FALSE(info.hasStrength);
  CHECK(info.sourceCode == "LAMMPS");
  CHECK(info.sourceVersion == "29 Sep 2021");
  CHECK(info.sourceFiles == std::vector<std::string>{"a.txt", "b.txt"});
  CHECK(info.scalarNames == std::vector<std::string>{"displacement", "load"});
  REQUIRE(info.extras.size() == 4);
  CHECK(info.extras[0].name == "material");
  CHECK_FALSE(info.extras[0].perStep);
  CHECK(info.extras[2].name == "force");
  CHECK(info.extras[2].components == 3);
  CHECK(info.extras[2].perStep);

  auto lattice = reader->readLattice();
  REQUIRE(lattice);
  const dem::Lattice expected = notchedTriple();
  CHECK(lattice->strength.empty());
  CHECK(lattice->particleId == expected.particleId);
  CHECK(lattice->particleGroup == expected.particleGroup);
  CHECK(lattice->bondFlags == expected.bondFlags);
  REQUIRE(lattice->extras.size() == 2);
  CHECK(lattice->extras[1].values == expected.extras[1].values);

  auto step = reader->readStep(1);
  REQUIRE(step);
  const dem::StepState written = stepOf(0.5, {0, 1, 1});
  CHECK(step->positions == written.positions);
  CHECK(step->scalars == std::vector<dem::StepScalar>{{"displacement", 0.5}, {"load", 5.0}});
  REQUIRE(step->extras.size() == 2);
  CHECK(step->extras[0].name == "force");
  CHECK(step->extras[0].values == written.extras[0].values);
  CHECK(step->extras[1].values == written.extras[1].values);
  auto breaks = reader->readBreakSteps();
  REQUIRE(breaks);
  CHECK(*breaks == std::vector<std::int32_t>{-1, 1, 0});
}

TEST_CASE("compressed storage chunks and shrinks the per-step arrays", "[dem][v1.1]") {
  TempDir dir;
  writeFile(dir.file("plain.h5"), 0);
  writeFile(dir.file("packed.h5"), 6);
  auto describe = [](const std::string& path) {
    dem::h5::Handle file = dem::h5::fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
    dem::h5::Handle dataset =
        dem::h5::datasetHandle(H5Dopen2(file.get(), "/steps/000001/positions", H5P_DEFAULT));
    return *dem::h5::describeDataset(dataset.get());
  };
  CHECK(describe(dir.file("plain.h5")).chunkDims.empty());
  CHECK(describe(dir.file("packed.h5")).chunkDims == std::vector<std::uint64_t>{3, 3});
}

TEST_CASE("a notch bond that is intact is refused by the writer", "[dem][v1.1]") {
  TempDir dir;
  auto writer = dem::DemFileWriter::create(dir.file("bad.h5"), notchedTriple(), {});
  REQUIRE(writer);
  auto written = writer->appendStep(stepOf(0.0, {0, 0, 0}));
  REQUIRE_FALSE(written);
  CHECK_THAT(written.message(), Catch::Contains("bond 2 is flagged cut at the start"));
}

TEST_CASE("v1.1 names and sizes are checked", "[dem][v1.1]") {
  dem::Lattice lattice = notchedTriple();
  SECTION("duplicate particle ids") {
    lattice.particleId = {7, 3, 7};
    CHECK_THAT(dem::validateLattice(lattice).message(),
               Catch::Contains("particles 0 and 2 have the same id 7"));
  }
  SECTION("an extra array with a path in its name") {
    lattice.extras[0].name = "../x";
    CHECK_THAT(dem::validateLattice(lattice).message(), Catch::Contains("extra array name '../x'"));
  }
  SECTION("an extra array of the wrong length") {
    lattice.extras[1].values.pop_back();
    CHECK_THAT(dem::validateLattice(lattice).message(),
               Catch::Contains("'rest_length' has 2 values, expected 3 x 1"));
  }
  SECTION("a step scalar named time") {
    dem::StepState step = stepOf(0.0, {0, 0, 1});
    step.scalars.push_back({"time", 1.0});
    CHECK_THAT(dem::validateStep(lattice, step).message(), Catch::Contains("'time' is reserved"));
  }
}

TEST_CASE("a v1.0 file (no version_minor) still needs its strengths", "[dem][v1.1]") {
  TempDir dir;
  const std::string path = dir.file("v10.h5");
  dem::Lattice lattice = notchedTriple();
  lattice.strength = {1, 1, 1};
  lattice.extras.clear();
  auto writer = dem::DemFileWriter::create(path, lattice, {});
  REQUIRE(writer);
  REQUIRE(writer->close());
  testing::deleteAttribute(path, "/", "version_minor");
  REQUIRE(dem::DemFileReader::open(path));
  testing::deleteLink(path, "/bonds/strength");
  auto reader = dem::DemFileReader::open(path);
  REQUIRE_FALSE(reader);
  CHECK_THAT(reader.status().message(), Catch::Contains("missing dataset /bonds/strength"));
}
