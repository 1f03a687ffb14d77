// The spatial index (/index, crackvis-dem v1.3) and the partial reads a
// reader of one slab uses: written with the first step in both layouts,
// describing the first step's configuration, and rows read through it equal
// the same rows of a whole read.
#include <algorithm>
#include <array>
#include <csignal>
#include <filesystem>
#include <numeric>
#include <optional>
#include <random>
#include <span>
#include <tuple>

#include <catch2/catch.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include "support/full_disk.hpp"
#include "support/h5_tamper.hpp"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/dem/spatial_index.hpp>

using namespace crackvis;
using namespace crackvis::dem;
using crackvis::testing::makeSample;
using crackvis::testing::SampleData;

namespace {

void writeWith(const std::string& path, const SampleData& sample, const DemMetadata& metadata) {
  auto writer = DemFileWriter::create(path, sample.lattice, metadata);
  REQUIRE(writer.isOk());
  for (const StepState& step : sample.steps) {
    REQUIRE(writer->appendStep(step).isOk());
  }
  REQUIRE(writer->close().isOk());
}

// About a third of 0..count-1, ascending: short runs and gaps.
std::vector<std::int32_t> someRows(std::size_t count, unsigned seed) {
  std::mt19937 random(seed);
  std::vector<std::int32_t> rows;
  std::size_t i = 0;
  while (i < count) {
    const std::size_t run = random() % 6;
    for (std::size_t k = 0; k < run && i < count; ++k, ++i) {
      rows.push_back(static_cast<std::int32_t>(i));
    }
    i += 1 + random() % 8;
  }
  return rows;
}

template <typename T>
std::vector<T> pick(const std::vector<T>& values, const std::vector<std::int32_t>& rows,
                    std::size_t width = 1) {
  std::vector<T> out;
  for (std::int32_t row : rows) {
    for (std::size_t k = 0; k < width; ++k) {
      out.push_back(values[static_cast<std::size_t>(row) * width + k]);
    }
  }
  return out;
}

}  // namespace

TEST_CASE("the writer stores the first step's spatial index: the order along the slice axis",
          "[dem][index]") {
  testing::TempDir dir;
  const int dimension = GENERATE(2, 3);
  const bool live = GENERATE(false, true);
  INFO(dimension << "D, " << (live ? "appendable" : "group") << " layout");
  const SampleData sample = makeSample(dimension, 3);
  DemMetadata metadata = metadataFrom("index test");
  metadata.decomposition = CellDecomposition::kLattice;
  metadata.stepLayout = live ? StepLayout::kAppendable : StepLayout::kGroups;
  const std::string path = dir.file("indexed.h5");
  writeWith(path, sample, metadata);

  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->info().minorVersion == 3);
  auto info = reader->readSpatialIndexInfo();
  REQUIRE(info.isOk());
  REQUIRE(info->has_value());
  const std::vector<Vec3>& reference = sample.steps[0].positions;
  const Bounds box = boundingBox(reference);
  CHECK((*info)->axis == sliceAxis(reference));
  CHECK((*info)->axis == 0);  // the sample is stretched along x
  CHECK((*info)->box.lo.x == box.lo.x);
  CHECK((*info)->box.hi.z == box.hi.z);
  CHECK((*info)->largestRadius ==
        *std::max_element(sample.lattice.radius.begin(), sample.lattice.radius.end()));
  CHECK((*info)->longestBond == longestBond(reference, sample.lattice.bonds));
  CHECK((*info)->longestBond > 0.0);
  CHECK((*info)->decomposition == CellDecomposition::kLattice);
  CHECK((*info)->hasBondStart);

  // The order is a permutation sorted by (coordinate, index), and the
  // coordinates are the first step's.
  const auto n = static_cast<std::int64_t>(reference.size());
  auto order = reader->readIndexOrder(0, n);
  REQUIRE(order.isOk());
  std::vector<std::int32_t> sorted = *order;
  std::sort(sorted.begin(), sorted.end());
  for (std::int64_t k = 0; k < n; ++k) {
    CHECK(sorted[static_cast<std::size_t>(k)] == k);
  }
  for (std::int64_t k = 0; k < n; k += 7) {
    const auto i = static_cast<std::size_t>((*order)[static_cast<std::size_t>(k)]);
    auto coordinate = reader->readIndexCoordinate(k);
    REQUIRE(coordinate.isOk());
    CHECK(*coordinate == reference[i].x);
    if (k > 0) {
      auto before = reader->readIndexCoordinate(k - 1);
      CHECK(*before <= *coordinate);
    }
  }
  // bond_start: the bonds of particle i are those whose first end is i.
  std::vector<std::int32_t> all(static_cast<std::size_t>(n + 1));
  std::iota(all.begin(), all.end(), 0);
  auto starts = reader->readBondStarts(all);
  REQUIRE(starts.isOk());
  CHECK(starts->front() == 0);
  CHECK(starts->back() == static_cast<std::int64_t>(sample.lattice.bondCount()));
  for (std::size_t i = 0; i + 1 < all.size(); ++i) {
    for (std::int64_t b = (*starts)[i]; b < (*starts)[i + 1]; ++b) {
      CHECK(sample.lattice.bonds[static_cast<std::size_t>(b)].first == static_cast<int>(i));
    }
  }
}

TEST_CASE(
    "the slice axis is the longest, and among near ties the one the file's order runs slowest "
    "along",
    "[dem][index]") {
  BlockSpec spec;
  spec.sites = {9, 9, 9};  // a cube, written x fastest and z slowest
  auto cube = generateBlock(spec);
  REQUIRE(cube.isOk());
  const std::vector<Vec3>& written = cube->positions;
  CHECK(longestAxis(boundingBox(written)) == 0);
  CHECK(sliceAxis(written) == 2);

  // The same cube written z fastest, x slowest: cut across x.
  std::vector<Vec3> zFastest = written;
  std::sort(zFastest.begin(), zFastest.end(), [](const Vec3& a, const Vec3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  CHECK(sliceAxis(zFastest) == 0);
  // y slowest, then z, then x.
  std::vector<Vec3> ySlowest = written;
  std::sort(ySlowest.begin(), ySlowest.end(), [](const Vec3& a, const Vec3& b) {
    return std::tie(a.y, a.z, a.x) < std::tie(b.y, b.z, b.x);
  });
  CHECK(sliceAxis(ySlowest) == 1);

  // Jitter makes the slowest axis fall a little at almost every particle,
  // the fastest a lot at each row's end: still cut across z.
  BlockSpec jittered = spec;
  jittered.sites = {13, 13, 13};
  jittered.jitter = 0.3;
  auto shaken = generateBlock(jittered);
  REQUIRE(shaken.isOk());
  CHECK(sliceAxis(shaken->positions) == 2);

  // An axis clearly the longest wins whatever the order: a slab's ghost
  // layer is then the thinnest.
  spec.sites = {12, 9, 9};
  auto stretched = generateBlock(spec);
  REQUIRE(stretched.isOk());
  CHECK(sliceAxis(stretched->positions) == 0);
  // Within the tolerance, the order decides.
  std::vector<Vec3> squeezed = written;
  for (Vec3& p : squeezed) {
    p.z *= 1.0 - 0.5 * kSliceAxisTolerance;
  }
  CHECK(sliceAxis(squeezed) == 2);
  for (Vec3& p : squeezed) {
    p.z *= 1.0 - 2.0 * kSliceAxisTolerance;
  }
  CHECK(sliceAxis(squeezed) == 1);  // of x and y, the order runs slower along y

  // A plane (2D) is never cut across its empty axis; nothing to cut is x.
  spec.kind = LatticeKind::kTriangular;
  spec.sites = {9, 9, 1};
  auto plane = generateBlock(spec);
  REQUIRE(plane.isOk());
  CHECK(sliceAxis(plane->positions) != 2);
  CHECK(sliceAxis(std::vector<Vec3>{}) == 0);
  CHECK(sliceAxis(std::vector<Vec3>{{1.0, 2.0, 3.0}}) == 0);
}

TEST_CASE("files without an index, or with unsorted bonds, say so and still read whole",
          "[dem][index]") {
  testing::TempDir dir;
  SampleData sample = makeSample(3, 2);
  const std::string path = dir.file("plain.h5");
  SECTION("a writer told not to write one") {
    DemMetadata metadata = metadataFrom("no index");
    metadata.spatialIndex = false;
    writeWith(path, sample, metadata);
    auto reader = DemFileReader::open(path);
    REQUIRE(reader.isOk());
    auto info = reader->readSpatialIndexInfo();
    REQUIRE(info.isOk());
    CHECK_FALSE(info->has_value());
    CHECK(reader->readStep(1).isOk());
  }
  SECTION("bonds another writer left unsorted: no bond_start, decomposition not recorded") {
    std::reverse(sample.lattice.bonds.begin(), sample.lattice.bonds.end());
    std::reverse(sample.lattice.strength.begin(), sample.lattice.strength.end());
    for (StepState& step : sample.steps) {
      std::reverse(step.bondState.begin(), step.bondState.end());
      std::reverse(step.bondForce.begin(), step.bondForce.end());
    }
    writeWith(path, sample, metadataFrom("unsorted"));
    auto reader = DemFileReader::open(path);
    REQUIRE(reader.isOk());
    auto info = reader->readSpatialIndexInfo();
    REQUIRE(info.isOk());
    REQUIRE(info->has_value());
    CHECK_FALSE((*info)->hasBondStart);
    CHECK((*info)->decomposition == CellDecomposition::kUnknown);
  }
}

TEST_CASE("rows read in spans equal the same rows of a whole read, in both layouts",
          "[dem][index]") {
  testing::TempDir dir;
  const bool live = GENERATE(false, true);
  const int compress = GENERATE(0, 4);
  INFO((live ? "appendable" : "group") << " layout, deflate " << compress);
  SampleData sample = makeSample(3, 3);
  DemMetadata metadata = metadataFrom("rows test");
  metadata.stepLayout = live ? StepLayout::kAppendable : StepLayout::kGroups;
  metadata.storage.deflateLevel = compress;
  const std::string path = dir.file("rows.h5");
  writeWith(path, sample, metadata);
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  const auto particles = someRows(sample.lattice.particleCount(), 1);
  const auto bonds = someRows(sample.lattice.bondCount(), 2);
  REQUIRE(particles.size() >= 5);
  REQUIRE(bonds.size() > 10);

  auto whole = reader->readLattice();
  auto part = reader->readLatticeRows(particles, bonds);
  REQUIRE(whole.isOk());
  REQUIRE(part.isOk());
  CHECK(part->radius == pick(whole->radius, particles));
  CHECK(part->bonds == pick(whole->bonds, bonds));
  CHECK(part->strength == pick(whole->strength, bonds));
  auto breaks = reader->readBreakSteps();
  auto partBreaks = reader->readBreakStepRows(bonds);
  REQUIRE(partBreaks.isOk());
  CHECK(*partBreaks == pick(*breaks, bonds));
  for (int step = 0; step < reader->stepCount(); ++step) {
    auto full = reader->readStep(step);
    auto rows = reader->readStepRows(step, particles, bonds);
    REQUIRE(rows.isOk());
    CHECK(rows->time == full->time);
    CHECK(rows->positions == pick(full->positions, particles));
    CHECK(rows->bondState == pick(full->bondState, bonds));
    CHECK(rows->velocities == pick(full->velocities, particles));
    CHECK(rows->bondForce == pick(full->bondForce, bonds));
  }
}

TEST_CASE("partial reads refuse rows out of range, out of order, and a corrupt index",
          "[dem][index]") {
  testing::TempDir dir;
  const SampleData sample = makeSample(3, 2);
  DemMetadata metadata = metadataFrom("bad rows");
  metadata.decomposition = CellDecomposition::kLattice;
  const std::string path = dir.file("bad.h5");
  writeWith(path, sample, metadata);
  const auto n = static_cast<std::int32_t>(sample.lattice.particleCount());
  {
    auto reader = DemFileReader::open(path);
    REQUIRE(reader.isOk());
    const std::vector<std::int32_t> beyond{0, n};
    CHECK(reader->readStepRows(1, beyond, {}).status().code() == StatusCode::kOutOfRange);
    const std::vector<std::int32_t> unordered{5, 3};
    CHECK(reader->readStepRows(1, unordered, {}).status().code() == StatusCode::kOutOfRange);
    const std::vector<std::int32_t> twice{3, 3};
    CHECK(reader->readLatticeRows(twice, {}).status().code() == StatusCode::kOutOfRange);
    CHECK(reader->readIndexOrder(0, n + 1).status().code() == StatusCode::kOutOfRange);
    CHECK(reader->readIndexCoordinate(n).status().code() == StatusCode::kOutOfRange);
  }
  SECTION("an order naming a particle that does not exist") {
    testing::setInt32Elements(path, kIndexOrderPath, {n + 5}, 3);
    auto reader = DemFileReader::open(path);
    REQUIRE(reader.isOk());
    auto order = reader->readIndexOrder(0, 10);
    CHECK(order.status().code() == StatusCode::kFailedPrecondition);
    CHECK_THAT(order.status().message(), Catch::Contains("/index/order names particle"));
  }
  SECTION("a bond_start past the bonds") {
    testing::setElement(path, kIndexBondStartPath, 2, 1e9);
    auto reader = DemFileReader::open(path);
    REQUIRE(reader.isOk());
    const std::vector<std::int32_t> rows{1, 2, 3};
    CHECK(reader->readBondStarts(rows).status().code() == StatusCode::kFailedPrecondition);
  }
  SECTION("an index of the wrong shape") {
    testing::replaceDataset(path, kIndexCoordinatePath, h5::ElementType::kFloat64,
                            {static_cast<std::uint64_t>(n - 1)});
    auto reader = DemFileReader::open(path);
    REQUIRE(reader.isOk());
    auto info = reader->readSpatialIndexInfo();
    CHECK(info.status().code() == StatusCode::kFailedPrecondition);
    CHECK_THAT(info.status().message(), Catch::Contains("/index/coordinate"));
    CHECK(reader->readStep(1).isOk());  // the rest of the file reads as before
  }
  SECTION("a decomposition nobody knows") {
    testing::setStringAttribute(path, kSpatialIndexGroup, "decomposition", "voronoi");
    auto reader = DemFileReader::open(path);
    REQUIRE(reader.isOk());
    CHECK_THAT(reader->readSpatialIndexInfo().status().message(),
               Catch::Contains("expected 'lattice' or 'triangulation'"));
  }
}

TEST_CASE("a decomposition's name in /index@decomposition reads back as itself, others unknown",
          "[dem][index]") {
  for (const CellDecomposition kind :
       {CellDecomposition::kLattice, CellDecomposition::kTriangulation}) {
    CHECK(decompositionNamed(decompositionName(kind)) == kind);
  }
  CHECK(decompositionNamed("") == CellDecomposition::kUnknown);
  CHECK(decompositionNamed("voronoi") == CellDecomposition::kUnknown);
  CHECK(decompositionNamed("Lattice") == CellDecomposition::kUnknown);
}

TEST_CASE("h5::readRowsAt reads far-apart rows, gapped rows and long runs in spans, exactly",
          "[dem][index]") {
  testing::TempDir dir;
  const std::string path = dir.file("values.h5");
  // 3 M int32 (12 MB): runs longer than a span's 4 MiB, and gaps wider than
  // the 64 KiB that one span may swallow.
  constexpr std::int32_t kCount = 3'000'000;
  std::vector<std::int32_t> values(kCount);
  for (std::int32_t i = 0; i < kCount; ++i) {
    values[static_cast<std::size_t>(i)] = 3 * i + 1;
  }
  {
    h5::Handle file =
        h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
    REQUIRE(h5::writeDataset(file.get(), "/values", h5::ElementType::kInt32,
                             {static_cast<std::uint64_t>(kCount)}, values.data())
                .isOk());
  }
  std::vector<std::int32_t> rows;
  for (std::int32_t i = 0; i < 1'500'000; ++i) {
    rows.push_back(i);  // one run of 6 MB: two spans, read into place
  }
  for (std::int32_t i = 1'520'000; i < 1'530'000; i += 7) {
    rows.push_back(i);  // close gaps: one span, its rows copied out
  }
  for (std::int32_t i = 1'600'000; i < kCount; i += 40'000) {
    rows.push_back(i);  // 160 KB apart: a span each
    rows.push_back(i + 1);
  }
  rows.push_back(kCount - 1);
  h5::Handle file = h5::fileHandle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  h5::Handle dataset = h5::datasetHandle(H5Dopen2(file.get(), "/values", H5P_DEFAULT));
  std::vector<std::int32_t> read(rows.size(), -1);
  REQUIRE(h5::readRowsAt(dataset.get(), h5::ElementType::kInt32, -1, rows, read.data()).isOk());
  CHECK(read == pick(values, rows));
  const std::vector<std::int32_t> past{kCount};
  CHECK(h5::readRowsAt(dataset.get(), h5::ElementType::kInt32, -1, past, read.data()).code() ==
        StatusCode::kOutOfRange);
  CHECK(h5::readRowsAt(dataset.get(), h5::ElementType::kInt32, 0, rows, read.data()).code() ==
        StatusCode::kFailedPrecondition);  // no step axis
}

// What a reader makes of a file whose writer failed or died at the wide
// cells: an error that says so, or the file without steps; never a crash,
// and never cells it takes for good that are not.
void checkFaultedFile(const std::string& path) {
  auto reader = DemFileReader::open(path);
  if (!reader) {
    CHECK_FALSE(reader.status().message().empty());
    return;
  }
  CHECK(reader->stepCount() == 0);  // the first step was never committed
  auto wide = reader->readWideCells();
  if (!wide) {
    // Rows the failed write left unwritten (zeros) are refused, by name.
    CHECK_THAT(wide.status().message(), Catch::Contains(kIndexWideCellsPath));
  } else if (wide->has_value()) {
    // Or every row is one the writer gave.
    const std::array<ParticleIndex, 4> given{0, 1, 2, 3};
    for (const auto& cell : (*wide)->cells) {
      CHECK(cell == given);
    }
  }
}

TEST_CASE("a writer that fails or dies writing the wide cells leaves a file no reader misreads",
          "[dem][index][write]") {
  testing::TempDir dir;
  const bool live = GENERATE(false, true);
  INFO((live ? "appendable" : "group") << " layout");
  const SampleData sample = makeSample(3, 3);
  DemMetadata metadata = metadataFrom("wide cells fault test");
  metadata.decomposition = CellDecomposition::kTriangulation;
  metadata.stepLayout = live ? StepLayout::kAppendable : StepLayout::kGroups;
  const std::string path = dir.file("faulted.h5");
  // Cells far larger than the room left: 16 MiB.
  auto manyCells = [] {
    WideCells wide;
    wide.reach = 1.0;
    wide.cells.assign(std::size_t{1} << 20, {0, 1, 2, 3});
    return wide;
  };

  SECTION("the disk fills while the cells are written") {
    // The limit starts once the cells are made, just before they are
    // written: 64 KiB beyond the file as it is then.
    std::optional<testing::FileSizeLimit> full;
    metadata.wideCells = [&](std::span<const Vec3>, const Lattice&) -> Result<WideCells> {
      full.emplace(std::filesystem::file_size(path) + 64 * 1024);
      return manyCells();
    };
    {
      auto writer = DemFileWriter::create(path, sample.lattice, metadata);
      REQUIRE(writer.isOk());
      const Status appended = writer->appendStep(sample.steps[0]);
      full.reset();  // before any CHECK: Catch writes nothing under the limit
      REQUIRE_FALSE(appended.isOk());
      CHECK_THAT(appended.message(), Catch::Contains(kIndexWideCellsPath));
      // A second try fails too: no step is written over a half-made index.
      CHECK_FALSE(writer->appendStep(sample.steps[0]).isOk());
    }  // the writer closes the file
    checkFaultedFile(path);
  }

  SECTION("the writer is killed while it makes the cells") {
    metadata.wideCells = [&](std::span<const Vec3>, const Lattice&) -> Result<WideCells> {
      raise(SIGKILL);
      return manyCells();
    };
    const pid_t child = fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      try {
        auto writer = DemFileWriter::create(path, sample.lattice, metadata);
        if (writer) {
          (void)writer->appendStep(sample.steps[0]);
        }
      } catch (...) {
      }
      _exit(3);
    }
    int status = 0;
    REQUIRE(waitpid(child, &status, 0) == child);
    REQUIRE(WIFSIGNALED(status));
    REQUIRE(WTERMSIG(status) == SIGKILL);  // killed where meant, not crashed
    checkFaultedFile(path);
  }
}
