#include <cstring>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using namespace crackvis;
using namespace crackvis::dem;
using crackvis::testing::makeSample;
using crackvis::testing::sameBytes;
using crackvis::testing::SampleData;
using crackvis::testing::TempDir;

TEST_CASE("write/read round trip is bit-exact in 2D and 3D", "[dem][h5]") {
  const int dimension = GENERATE(2, 3);
  TempDir dir;
  const std::string path = dir.file("roundtrip.h5");
  const SampleData sample = makeSample(dimension, 4);
  testing::writeSample(path, sample);

  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  const DemFileInfo& info = reader->info();
  CHECK(info.format == "crackvis-dem");
  CHECK(info.version == 1);
  CHECK(info.dimension == dimension);
  CHECK(info.units == "SI");
  CHECK(info.source == "crackvis tests");
  CHECK(info.particleCount == static_cast<std::int64_t>(sample.lattice.particleCount()));
  CHECK(info.bondCount == static_cast<std::int64_t>(sample.lattice.bondCount()));
  REQUIRE(reader->stepCount() == 4);
  CHECK(info.incompleteSteps == 0);

  auto lattice = reader->readLattice();
  REQUIRE(lattice.isOk());
  CHECK(lattice->dimension == dimension);
  CHECK(sameBytes(lattice->radius, sample.lattice.radius));
  CHECK(sameBytes(lattice->bonds, sample.lattice.bonds));
  CHECK(sameBytes(lattice->strength, sample.lattice.strength));

  for (int k = 0; k < 4; ++k) {
    auto step = reader->readStep(k);
    REQUIRE(step.isOk());
    const StepState& expected = sample.steps[static_cast<size_t>(k)];
    CHECK(std::memcmp(&step->time, &expected.time, sizeof(double)) == 0);
    CHECK(info.steps[static_cast<size_t>(k)].time == expected.time);
    CHECK(sameBytes(step->positions, expected.positions));
    CHECK(sameBytes(step->bondState, expected.bondState));
    CHECK(sameBytes(step->velocities, expected.velocities));
    CHECK(sameBytes(step->bondForce, expected.bondForce));
    auto bondState = reader->readBondState(k);
    REQUIRE(bondState.isOk());
    CHECK(sameBytes(*bondState, expected.bondState));
  }
}

TEST_CASE("optional per-step arrays may be absent", "[dem][h5]") {
  TempDir dir;
  const std::string path = dir.file("lean.h5");
  const SampleData sample = makeSample(3, 2, /*optionalArrays=*/false);
  testing::writeSample(path, sample);
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  auto step = reader->readStep(1);
  REQUIRE(step.isOk());
  CHECK(step->velocities.empty());
  CHECK(step->bondForce.empty());
  CHECK(step->positions == sample.steps[1].positions);
}

// A step read into a recycled one's memory (readStep's `recycled`) is the
// step, whatever the recycled one held: its own arrays of other sizes, the
// optional arrays this file lacks, scalars and extras.
TEST_CASE("a step read into a recycled step's memory equals the step read afresh", "[dem][h5]") {
  const bool optional = GENERATE(true, false);
  TempDir dir;
  const std::string path = dir.file("recycled.h5");
  const SampleData sample = makeSample(3, 4, optional);
  testing::writeSample(path, sample);
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  StepState stale;
  stale.positions.assign(7, Vec3{1.0, 2.0, 3.0});
  stale.bondState.assign(3, 1);
  stale.velocities.assign(5, {9.0f, 9.0f, 9.0f});
  stale.bondForce.assign(11, 4.0f);
  stale.scalars.push_back({"load", 12.0});
  stale.extras.push_back({"damage", ExtraOwner::kParticles, 1, {0.5}});
  const auto same = [](const StepState& a, const StepState& b) {
    return std::memcmp(&a.time, &b.time, sizeof(double)) == 0 &&
           sameBytes(a.positions, b.positions) && sameBytes(a.bondState, b.bondState) &&
           sameBytes(a.velocities, b.velocities) && sameBytes(a.bondForce, b.bondForce) &&
           a.scalars == b.scalars && a.extras.size() == b.extras.size();
  };
  for (int k = 0; k < 4; ++k) {
    auto fresh = reader->readStep(k);
    REQUIRE(fresh.isOk());
    auto intoStale = reader->readStep(k, stale);
    REQUIRE(intoStale.isOk());
    CHECK(same(*intoStale, *fresh));
    // Into the memory of another step of the same file.
    auto other = reader->readStep((k + 1) % 4);
    REQUIRE(other.isOk());
    const void* memory = other->positions.data();
    auto intoOther = reader->readStep(k, std::move(*other));
    REQUIRE(intoOther.isOk());
    CHECK(same(*intoOther, *fresh));
    CHECK(static_cast<const void*>(intoOther->positions.data()) == memory);  // no new array
    // A piece's rows into a whole step's memory.
    const std::vector<ParticleIndex> particles{0, 2, 3, 5};
    const std::vector<BondIndex> bonds{1, 4};
    auto rows = reader->readStepRows(k, particles, bonds, std::move(*intoOther));
    auto freshRows = reader->readStepRows(k, particles, bonds);
    REQUIRE(rows.isOk());
    REQUIRE(freshRows.isOk());
    CHECK(same(*rows, *freshRows));
  }
}

TEST_CASE("break_step records the first step at which each bond is broken", "[dem][h5]") {
  TempDir dir;
  const std::string path = dir.file("breaks.h5");
  const SampleData sample = testing::writeSampleFile(path, 3, 5);
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  auto breakSteps = reader->readBreakSteps();
  REQUIRE(breakSteps.isOk());
  const size_t m = sample.lattice.bondCount();
  REQUIRE(breakSteps->size() == m);
  for (size_t b = 0; b < m; ++b) {
    int expected = -1;
    for (int k = 0; k < 5; ++k) {
      if (sample.steps[static_cast<size_t>(k)].bondState[b] == 1) {
        expected = k;
        break;
      }
    }
    REQUIRE((*breakSteps)[b] == expected);
  }
  CHECK(std::count((*breakSteps).begin(), (*breakSteps).end(), -1) > 0);
  CHECK(std::count((*breakSteps).begin(), (*breakSteps).end(), 4) > 0);
}

TEST_CASE("the writer refuses steps that do not fit the lattice or heal a bond", "[dem][h5]") {
  TempDir dir;
  const std::string path = dir.file("refuse.h5");
  SampleData sample = makeSample(3, 3);
  auto writer = DemFileWriter::create(path, sample.lattice, metadataFrom("test"));
  REQUIRE(writer.isOk());
  REQUIRE(writer->appendStep(sample.steps[0]).isOk());
  REQUIRE(writer->appendStep(sample.steps[2]).isOk());

  StepState healed = sample.steps[2];
  healed.bondState[0] = 0;
  const Status heal = writer->appendStep(healed);
  CHECK(heal.code() == StatusCode::kInvalidArgument);
  CHECK(heal.message() ==
        path + ": step 2: bond 0 is intact again after breaking at step 1 (bonds break for good)");

  StepState shortStep = sample.steps[2];
  shortStep.positions.pop_back();
  CHECK(writer->appendStep(shortStep).message() ==
        fmt::format("{}: step 2: {} positions for N = {} particles", path,
                    sample.lattice.particleCount() - 1, sample.lattice.particleCount()));
  // Refused steps leave no trace; a good one still goes in.
  REQUIRE(writer->appendStep(sample.steps[2]).isOk());
  REQUIRE(writer->close().isOk());
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->stepCount() == 3);

  Lattice bad = sample.lattice;
  bad.bonds[2] = bad.bonds[2 + 1];
  CHECK(DemFileWriter::create(dir.file("bad.h5"), bad, {})
            .status()
            .message()
            .find("refusing to write: bond 3 duplicates bond 2") != std::string::npos);
}

TEST_CASE("a writer killed without closing leaves its completed steps readable", "[dem][h5]") {
  TempDir dir;
  const std::string path = dir.file("killed.h5");
  const SampleData sample = makeSample(3, 4);
  const bool midStep = GENERATE(false, true);

  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    auto writer = DemFileWriter::create(path, sample.lattice, metadataFrom("killed"));
    for (int k = 0; k < 3 && writer.isOk(); ++k) {
      (void)writer->appendStep(sample.steps[static_cast<size_t>(k)]);
    }
    if (midStep) {
      // Start step 3 behind the writer's back, as a crash inside appendStep
      // would leave it: a group with some arrays and no commit of the count.
      hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
      hid_t group = H5Gcreate2(file, "/steps/000003", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
      (void)h5::writeDataset(group, "positions", h5::ElementType::kFloat64,
                             {sample.lattice.particleCount(), 3}, sample.steps[3].positions.data());
      H5Fflush(file, H5F_SCOPE_GLOBAL);
    }
    raise(SIGKILL);
    _exit(3);
  }
  int status = 0;
  REQUIRE(waitpid(child, &status, 0) == child);
  REQUIRE(WIFSIGNALED(status));

  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->stepCount() == 3);
  CHECK(reader->info().incompleteSteps == (midStep ? 1 : 0));
  auto last = reader->readStep(2);
  REQUIRE(last.isOk());
  CHECK(last->positions == sample.steps[2].positions);
  auto breakSteps = reader->readBreakSteps();
  REQUIRE(breakSteps.isOk());
  CHECK(std::count(breakSteps->begin(), breakSteps->end(), 2) > 0);
  CHECK(reader->readStep(3).status().message() ==
        path + ": step 3 out of range (the file has steps 0..2)");
}

TEST_CASE("reading a step out of range is OUT_OF_RANGE with the one step message", "[dem][h5]") {
  TempDir dir;
  const std::string path = dir.file("range.h5");
  testing::writeSampleFile(path, 2, 2);
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->readStep(-1).status().code() == StatusCode::kOutOfRange);
  CHECK(reader->readStep(-1).status().message() ==
        path + ": step -1 out of range (the file has steps 0..1)");
  CHECK(reader->readBondState(2).status().code() == StatusCode::kOutOfRange);
  CHECK(reader->readBondState(2).status().message() ==
        path + ": step 2 out of range (the file has steps 0..1)");
}
