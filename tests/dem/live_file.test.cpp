// Live files (crackvis-dem v1.2's appendable layout, docs/data-format.md
// "Live files"): a writer in HDF5's SWMR mode, readers in other processes.
// HDF5 shares one open file between all opens of a process, so every writer
// here runs in a forked child, as a simulation would run beside a viewer.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <thread>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/h5.hpp>

using namespace crackvis;
using namespace crackvis::dem;
using crackvis::testing::makeSample;
using crackvis::testing::sameBytes;
using crackvis::testing::SampleData;
using crackvis::testing::TempDir;

namespace {

// The sample with what v1.1 added: step scalars (one missing at step 1),
// per-step extras of both owners, a constant extra.
SampleData richSample(int dimension, int steps) {
  SampleData sample = makeSample(dimension, steps);
  const std::size_t n = sample.lattice.particleCount();
  const std::size_t m = sample.lattice.bondCount();
  sample.lattice.extras.push_back({"porosity", ExtraOwner::kParticles, 1, std::vector(n, 0.25)});
  for (int k = 0; k < steps; ++k) {
    StepState& step = sample.steps[static_cast<size_t>(k)];
    step.scalars.push_back({"load", 10.0 * k});
    if (k != 1) {
      step.scalars.push_back({"displacement", 1e-6 * k});
    }
    std::vector<double> damage(m);
    for (std::size_t b = 0; b < m; ++b) {
      damage[b] = 0.001 * static_cast<double>(b) + k;
    }
    std::vector<double> force(3 * n);
    for (std::size_t i = 0; i < force.size(); ++i) {
      force[i] = std::sin(static_cast<double>(i + k));
    }
    // In the order readers list them: particles' arrays, then bonds'.
    step.extras.push_back({"force", ExtraOwner::kParticles, 3, force});
    step.extras.push_back({"damage", ExtraOwner::kBonds, 1, damage});
  }
  return sample;
}

void writeWith(const std::string& path, const SampleData& sample, StepLayout layout,
               int deflate = 0) {
  DemMetadata metadata = metadataFrom("crackvis tests");
  metadata.stepLayout = layout;
  metadata.storage.deflateLevel = deflate;
  auto writer = DemFileWriter::create(path, sample.lattice, metadata);
  REQUIRE(writer.isOk());
  for (const StepState& step : sample.steps) {
    REQUIRE(writer->appendStep(step).isOk());
  }
  REQUIRE(writer->close().isOk());
}

void checkSameSteps(const std::vector<StepInfo>& a, const std::vector<StepInfo>& b) {
  REQUIRE(a.size() == b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    CHECK(a[k].index == b[k].index);
    CHECK(a[k].time == b[k].time);
    REQUIRE(a[k].scalars.size() == b[k].scalars.size());
    for (size_t s = 0; s < a[k].scalars.size(); ++s) {
      CHECK(a[k].scalars[s].name == b[k].scalars[s].name);
      CHECK(a[k].scalars[s].value == b[k].scalars[s].value);
    }
  }
}

void checkSameStep(const StepState& a, const StepState& b) {
  CHECK(std::memcmp(&a.time, &b.time, sizeof(double)) == 0);
  CHECK(sameBytes(a.positions, b.positions));
  CHECK(sameBytes(a.bondState, b.bondState));
  CHECK(sameBytes(a.velocities, b.velocities));
  CHECK(sameBytes(a.bondForce, b.bondForce));
  REQUIRE(a.extras.size() == b.extras.size());
  for (size_t e = 0; e < a.extras.size(); ++e) {
    CHECK(a.extras[e].name == b.extras[e].name);
    CHECK(a.extras[e].components == b.extras[e].components);
    CHECK(sameBytes(a.extras[e].values, b.extras[e].values));
  }
}

// Runs `body` in a forked child and returns its pid; the child exits 0
// when `body` returns true, 1 otherwise.
template <typename Body>
pid_t forkWriter(Body body) {
  const pid_t child = fork();
  if (child == 0) {
    _exit(body() ? 0 : 1);
  }
  return child;
}

}  // namespace

TEST_CASE("a finished live file reads exactly like the same steps written at once",
          "[dem][h5][live]") {
  const int dimension = GENERATE(2, 3);
  const int deflate = GENERATE(0, 4);
  TempDir dir;
  const SampleData sample = richSample(dimension, 4);
  const std::string groups = dir.file("groups.h5");
  const std::string live = dir.file("live.h5");
  writeWith(groups, sample, StepLayout::kGroups, deflate);
  writeWith(live, sample, StepLayout::kAppendable, deflate);

  auto a = DemFileReader::open(groups);
  auto b = DemFileReader::open(live);
  REQUIRE(a.isOk());
  REQUIRE(b.isOk());
  CHECK(a->info().stepLayout == StepLayout::kGroups);
  CHECK(b->info().stepLayout == StepLayout::kAppendable);
  CHECK_FALSE(b->info().beingWritten);
  CHECK(b->info().incompleteSteps == 0);
  CHECK(b->info().minorVersion == kFormatMinorVersion);
  CHECK(a->info().scalarNames.size() == 2);
  CHECK(b->info().scalarNames.size() == a->info().scalarNames.size());
  checkSameSteps(a->info().steps, b->info().steps);
  CHECK(b->info().steps[1].scalars.size() == 1);  // "displacement" was not given at step 1
  REQUIRE(a->info().extras.size() == b->info().extras.size());
  for (size_t e = 0; e < a->info().extras.size(); ++e) {
    CHECK(a->info().extras[e].name == b->info().extras[e].name);
    CHECK(a->info().extras[e].perStep == b->info().extras[e].perStep);
    CHECK(a->info().extras[e].components == b->info().extras[e].components);
  }
  auto latticeA = a->readLattice();
  auto latticeB = b->readLattice();
  REQUIRE(latticeA.isOk());
  REQUIRE(latticeB.isOk());
  CHECK(sameBytes(latticeA->radius, latticeB->radius));
  CHECK(sameBytes(latticeA->bonds, latticeB->bonds));
  CHECK(latticeB->extras.size() == 1);
  auto breaksA = a->readBreakSteps();
  auto breaksB = b->readBreakSteps();
  REQUIRE(breaksA.isOk());
  REQUIRE(breaksB.isOk());
  CHECK(*breaksA == *breaksB);
  for (int k = 0; k < 4; ++k) {
    auto stepA = a->readStep(k);
    auto stepB = b->readStep(k);
    REQUIRE(stepA.isOk());
    REQUIRE(stepB.isOk());
    checkSameStep(*stepA, *stepB);
    checkSameStep(*stepB, sample.steps[static_cast<size_t>(k)]);
    auto states = b->readBondState(k);
    REQUIRE(states.isOk());
    CHECK(sameBytes(*states, sample.steps[static_cast<size_t>(k)].bondState));
    CHECK(b->checkStepHeaders(k).isOk());
  }
  CHECK(b->readStep(4).status().message() ==
        live + ": step 4 out of range (the file has steps 0..3)");
}

TEST_CASE("chunks along the step rows are balanced, so no edge chunk stands mostly empty",
          "[dem][h5][live]") {
  // At most 21,845 rows of 3 a chunk: cuboid A's 46,875 positions in three
  // chunks of 15,625 rows (the most-per-chunk split, 21,845 + 21,845 +
  // 3,185, stored its last chunk whole: 28 % of the dataset unused).
  CHECK(h5::balancedChunkRows(46875, 3, 1u << 16) == 15625);
  CHECK(h5::balancedChunkRows(21845, 3, 1u << 16) == 21845);  // one full chunk
  CHECK(h5::balancedChunkRows(21846, 3, 1u << 16) == 10923);  // two halves
  CHECK(h5::balancedChunkRows(10, 3, 1u << 16) == 10);
  CHECK(h5::balancedChunkRows(0, 3, 1u << 16) == 1);
  CHECK(h5::balancedChunkRows(5, 1u << 20, 1u << 16) == 1);  // a row beyond a chunk: one a chunk

  // A live file whose positions' rows split as 40 %, 40 % and 20 % by the
  // most per chunk: stored in three equal chunks, nothing beyond its rows.
  TempDir dir;
  const std::string path = dir.file("balanced.h5");
  const SampleData sample = makeSample(3, 2);
  const std::uint64_t n = sample.lattice.particleCount();
  const std::uint64_t most = n * 2 / 5;
  REQUIRE(most * 2 < n);
  DemMetadata metadata = metadataFrom("crackvis tests");
  metadata.stepLayout = StepLayout::kAppendable;
  metadata.storage.chunkValues = 3 * most;
  {
    auto writer = DemFileWriter::create(path, sample.lattice, metadata);
    REQUIRE(writer.isOk());
    for (const StepState& step : sample.steps) {
      REQUIRE(writer->appendStep(step).isOk());
    }
    REQUIRE(writer->close().isOk());
  }
  h5::Handle file = h5::fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  REQUIRE(file.valid());
  h5::Handle positions = h5::datasetHandle(H5Dopen2(file.get(), "/steps/positions", H5P_DEFAULT));
  REQUIRE(positions.valid());
  h5::Handle properties = h5::propertyListHandle(H5Dget_create_plist(positions.get()));
  std::array<hsize_t, 3> chunk{};
  REQUIRE(H5Pget_chunk(properties.get(), 3, chunk.data()) == 3);
  CHECK(chunk[0] == 1);
  CHECK(chunk[1] == (n + 2) / 3);
  CHECK(chunk[2] == 3);
  const hsize_t logical = sample.steps.size() * n * 3 * sizeof(double);
  const hsize_t stored = H5Dget_storage_size(positions.get());
  INFO(stored << " bytes stored for " << logical);
  CHECK(stored >= logical);
  CHECK(stored < logical + sample.steps.size() * 3 * 3 * sizeof(double));  // < a row per chunk
  properties = {};
  positions = {};
  file = {};
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  auto last = reader->readStep(1);
  INFO((last ? std::string() : last.status().message()));
  REQUIRE(last.isOk());
  checkSameStep(*last, sample.steps[1]);
}

TEST_CASE("a live file refuses a step whose arrays differ from the first step's",
          "[dem][h5][live]") {
  TempDir dir;
  const SampleData sample = richSample(3, 3);
  DemMetadata metadata = metadataFrom("crackvis tests");
  metadata.stepLayout = StepLayout::kAppendable;
  const std::string path = dir.file("strict.h5");
  auto writer = DemFileWriter::create(path, sample.lattice, metadata);
  REQUIRE(writer.isOk());
  REQUIRE(writer->appendStep(sample.steps[0]).isOk());

  StepState noVelocities = sample.steps[1];
  noVelocities.velocities.clear();
  Status refused = writer->appendStep(noVelocities);
  CHECK(refused.code() == StatusCode::kInvalidArgument);
  CHECK(refused.message() ==
        path +
            ": step 1: no velocities (every step of a live file carries the arrays and "
            "scalars of its first)");
  StepState newScalar = sample.steps[1];
  newScalar.scalars.push_back({"energy", 1.0});
  CHECK(writer->appendStep(newScalar).message().find("scalar 'energy' the first step lacked") !=
        std::string::npos);
  StepState noExtras = sample.steps[1];
  noExtras.extras.clear();
  CHECK(writer->appendStep(noExtras).code() == StatusCode::kInvalidArgument);
  // A refused step writes nothing: the next good one is step 1.
  REQUIRE(writer->appendStep(sample.steps[1]).isOk());
  REQUIRE(writer->close().isOk());
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->stepCount() == 2);
}

TEST_CASE("readers see each step a live writer commits, while it writes", "[dem][h5][live]") {
  TempDir dir;
  const std::string path = dir.file("growing.h5");
  const SampleData sample = richSample(3, 5);
  int toWriter[2];
  int fromWriter[2];
  REQUIRE(pipe(toWriter) == 0);
  REQUIRE(pipe(fromWriter) == 0);
  const pid_t child = forkWriter([&] {
    DemMetadata metadata = metadataFrom("crackvis tests");
    metadata.stepLayout = StepLayout::kAppendable;
    auto writer = DemFileWriter::create(path, sample.lattice, metadata);
    char go = 0;
    for (const StepState& step : sample.steps) {
      if (!writer || read(toWriter[0], &go, 1) != 1 || !writer->appendStep(step)) {
        return false;
      }
      const char done = 'k';
      if (write(fromWriter[1], &done, 1) != 1) {
        return false;
      }
    }
    return read(toWriter[0], &go, 1) == 1 && writer->close().isOk();
  });
  REQUIRE(child > 0);
  auto step = [&] {
    const char go = 'g';
    REQUIRE(write(toWriter[1], &go, 1) == 1);
    char done = 0;
    REQUIRE(read(fromWriter[0], &done, 1) == 1);
  };

  step();  // step 0 committed: the file exists with one step
  auto following = DemFileReader::open(path);
  REQUIRE(following.isOk());
  CHECK(following->info().beingWritten);
  REQUIRE(following->stepCount() == 1);
  CHECK(following->info().extras.size() == 3);
  for (int k = 1; k < 5; ++k) {
    step();
    // A reader opened now sees the new step ...
    auto fresh = DemFileReader::open(path);
    REQUIRE(fresh.isOk());
    REQUIRE(fresh->stepCount() == k + 1);
    auto read = fresh->readStep(k);
    REQUIRE(read.isOk());
    checkSameStep(*read, sample.steps[static_cast<size_t>(k)]);
    // ... and one opened before sees it after refreshSteps(), not before.
    CHECK(following->stepCount() == k);
    REQUIRE(following->refreshSteps().isOk());
    REQUIRE(following->stepCount() == k + 1);
    auto followed = following->readStep(k);
    REQUIRE(followed.isOk());
    checkSameStep(*followed, sample.steps[static_cast<size_t>(k)]);
    CHECK(following->info().steps[static_cast<size_t>(k)].scalars.size() ==
          sample.steps[static_cast<size_t>(k)].scalars.size());
  }
  const char go = 'g';
  REQUIRE(write(toWriter[1], &go, 1) == 1);
  int status = 0;
  REQUIRE(waitpid(child, &status, 0) == child);
  CHECK((WIFEXITED(status) && WEXITSTATUS(status) == 0));
  REQUIRE(following->refreshSteps().isOk());
  CHECK_FALSE(following->info().beingWritten);
  CHECK(following->stepCount() == 5);
  for (int fd : {toWriter[0], toWriter[1], fromWriter[0], fromWriter[1]}) {
    close(fd);
  }
}

TEST_CASE("a file a writer holds without SWMR is refused at once, with both opens' reasons",
          "[dem][h5][live]") {
  // A reader tries the plain open, then the SWMR open a live file needs,
  // retried a few times while a writer holds the file (a live writer's
  // metadata can be mid-write). A writer that never starts SWMR writing
  // (here: a file of the fixed layout still being written) keeps both
  // refusing: the error gives each reason, and the retries stay short.
  TempDir dir;
  const std::string path = dir.file("held.h5");
  const SampleData sample = makeSample(3, 2);
  int toWriter[2];
  int fromWriter[2];
  REQUIRE(pipe(toWriter) == 0);
  REQUIRE(pipe(fromWriter) == 0);
  const pid_t child = forkWriter([&] {
    auto writer = DemFileWriter::create(path, sample.lattice, metadataFrom("crackvis tests"));
    const char opened = 'o';
    char go = 0;
    return writer && writer->appendStep(sample.steps[0]) && write(fromWriter[1], &opened, 1) == 1 &&
           read(toWriter[0], &go, 1) == 1 && writer->appendStep(sample.steps[1]) &&
           writer->close().isOk();
  });
  REQUIRE(child > 0);
  char opened = 0;
  REQUIRE(read(fromWriter[0], &opened, 1) == 1);

  const auto start = std::chrono::steady_clock::now();
  auto held = DemFileReader::open(path);
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  REQUIRE_FALSE(held.isOk());
  const std::string message = held.status().message();
  INFO(message);
  CHECK(message.find("held.h5") != std::string::npos);
  CHECK(message.find("cannot open: another process is writing it, not as a live file") !=
        std::string::npos);
  CHECK(message.find("; as a live file: ") != std::string::npos);
  CHECK(took.count() < 1.0);  // three retries, 60 ms of pauses in all

  const char go = 'g';
  REQUIRE(write(toWriter[1], &go, 1) == 1);
  int status = 0;
  REQUIRE(waitpid(child, &status, 0) == child);
  CHECK((WIFEXITED(status) && WEXITSTATUS(status) == 0));
  auto finished = DemFileReader::open(path);
  REQUIRE(finished.isOk());
  CHECK(finished->stepCount() == 2);
  for (int fd : {toWriter[0], toWriter[1], fromWriter[0], fromWriter[1]}) {
    close(fd);
  }
}

TEST_CASE("a live writer killed at any moment leaves its complete steps readable",
          "[dem][h5][live]") {
  // Big enough that a step takes a while to write, so kills land inside
  // steps as well as between them.
  TempDir dir;
  const SampleData sample = makeSample(3, 3);
  int midStep = 0;
  for (int attempt = 0; attempt < 6; ++attempt) {
    const std::string path = dir.file(fmt::format("killed{}.h5", attempt));
    const pid_t child = forkWriter([&] {
      DemMetadata metadata = metadataFrom("crackvis tests");
      metadata.stepLayout = StepLayout::kAppendable;
      // Created under another name and renamed after its first step, as
      // `crackvis import --follow` does (PendingFile): a reader that opens
      // the file between H5Fcreate's open(2) and its lock takes a shared
      // lock that makes the create fail (seen once in CI).
      const std::string pending = path + ".partial";
      auto writer = DemFileWriter::create(pending, sample.lattice, metadata);
      // After the sample's steps, the last one again and again (bonds stay
      // broken) until killed.
      for (size_t k = 0; writer; ++k) {
        const StepState& step = sample.steps[std::min(k, sample.steps.size() - 1)];
        if (!writer->appendStep(step) ||
            (k == 0 && std::rename(pending.c_str(), path.c_str()) != 0)) {
          return false;
        }
      }
      return false;
    });
    REQUIRE(child > 0);
    // Wait for a few steps, then kill at a moment that varies.
    for (int tries = 0; tries < 2000; ++tries) {
      auto reader = DemFileReader::open(path);
      if (reader && reader->stepCount() >= 3) {
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    std::this_thread::sleep_for(std::chrono::microseconds(137 * attempt));
    kill(child, SIGKILL);
    int status = 0;
    REQUIRE(waitpid(child, &status, 0) == child);
    INFO("the writer exited with " << (WIFEXITED(status) ? WEXITSTATUS(status) : -1)
                                   << " before it was killed");
    REQUIRE(WIFSIGNALED(status));

    auto reader = DemFileReader::open(path);
    REQUIRE(reader.isOk());
    INFO(path << ": " << reader->stepCount() << " steps, " << reader->info().incompleteSteps
              << " incomplete");
    CHECK(reader->stepCount() >= 3);
    CHECK(reader->info().beingWritten);  // the writer never closed it
    CHECK(reader->info().incompleteSteps <= 1);
    midStep += reader->info().incompleteSteps;
    for (int k = 0; k < reader->stepCount(); ++k) {
      auto step = reader->readStep(k);
      REQUIRE(step.isOk());
      checkSameStep(*step, sample.steps[std::min<size_t>(static_cast<size_t>(k), 2)]);
    }
    auto breaks = reader->readBreakSteps();
    REQUIRE(breaks.isOk());
  }
  // Not asserted (it depends on timing); printed for the record.
  WARN(midStep << " of 6 kills landed inside a step");
}
