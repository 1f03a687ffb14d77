// The catalogue without gRPC: how a Read is split into pieces, and that
// pieces put back together are the slab.
#include <chrono>

#include <catch2/catch.hpp>

#include "service_fixture.hpp"
#include <crackvis/dataservice_h5/catalogue.hpp>

namespace crackvis::testing {
namespace {

using namespace crackvis::dataservice;

TEST_CASE("A Read is split into pieces of at most 1 MiB, whole rows where a row fits",
          "[dataservice]") {
  Catalogue catalogue(DataRoot::open(sampleRoot().root.path().string()).value());
  auto file = catalogue.root().resolveFile("big.h5");
  REQUIRE(file.isOk());
  auto reader = catalogue.openRead(
      *file, {Hyperslab::whole("/ramp"), {"/wide", {1, 10}, {2, 149990}}}, std::uint64_t{1} << 30);
  INFO(reader.status().message());
  REQUIRE(reader.isOk());
  const auto& slabs = (*reader)->slabs();
  REQUIRE(slabs.size() == 2);
  CHECK(slabs[0].bytes == (std::uint64_t{16} << 20));
  CHECK(slabs[0].rowBytes == 8);
  CHECK(slabs[1].count == std::vector<std::uint64_t>{2, 149990});
  CHECK(slabs[1].rowBytes == 149990 * 8);
  CHECK((*reader)->totalBytes() == slabs[0].bytes + slabs[1].bytes);

  std::vector<std::vector<char>> data(2);
  std::vector<int> pieces(2, 0);
  while (auto piece = (*reader)->nextPiece()) {
    CHECK(piece->offset == data[piece->slab].size());
    CHECK(piece->bytes <= kMaxChunkBytes);  // also where one row is larger
    std::vector<char> buffer(piece->bytes);
    REQUIRE((*reader)->read(*piece, buffer.data()).isOk());
    data[piece->slab].insert(data[piece->slab].end(), buffer.begin(), buffer.end());
    ++pieces[piece->slab];
  }
  CHECK(pieces[0] == 16);
  CHECK(pieces[1] == 4);  // each 1.2 MB row in two pieces
  const auto ramp = readDirect<double>(sampleRoot().file("big.h5"), "/ramp");
  REQUIRE(data[0].size() == ramp.size() * 8);
  CHECK(std::memcmp(data[0].data(), ramp.data(), data[0].size()) == 0);
  const auto wide = readDirect<double>(sampleRoot().file("big.h5"), "/wide");
  std::vector<double> expected;
  for (int row = 1; row < 3; ++row) {
    expected.insert(expected.end(), wide.begin() + row * 150000 + 10,
                    wide.begin() + (row + 1) * 150000);
  }
  REQUIRE(data[1].size() == expected.size() * 8);
  CHECK(std::memcmp(data[1].data(), expected.data(), data[1].size()) == 0);
}

TEST_CASE("The catalogue describes a 2D file and refuses what it must", "[dataservice]") {
  Catalogue catalogue(DataRoot::open(sampleRoot().root.path().string()).value());
  auto description = catalogue.describe(catalogue.root().resolveFile("flat/run2d.h5").value());
  REQUIRE(description.isOk());
  CHECK(description->steps.size() == 2);
  CHECK(description->findDataset("/steps/000001/positions") != nullptr);
  // Describe reports the external link's file but never opens what it names.
  auto external = catalogue.describe(catalogue.root().resolveFile("extlink.h5").value());
  REQUIRE(external.isOk());
  CHECK(external->findDataset("/inside") != nullptr);
  CHECK(external->findDataset("/outside") == nullptr);
  CHECK(external->steps.empty());

  auto text = catalogue.openFetch(catalogue.root().resolveFile("notes.txt").value(), 1 << 20);
  CHECK(text.status().code() == StatusCode::kFailedPrecondition);
  auto fetch = catalogue.openFetch(catalogue.root().resolveFile("run.h5").value(), 1 << 30);
  REQUIRE(fetch.isOk());
  CHECK((*fetch)->size() == std::filesystem::file_size(sampleRoot().file("run.h5")));
}

TEST_CASE("A worker's rehearsal describes and reads a crackvis-dem file held in memory",
          "[dataservice]") {
  auto description = rehearseDescribeAndRead();
  INFO(description.status().message());
  REQUIRE(description.isOk());
  // Found as a crackvis-dem file with its steps: the walk and the summary ran.
  CHECK(description->format == "crackvis-dem");
  REQUIRE(description->steps.size() == 2);
  CHECK(description->steps[1].time == Approx(0.1));
  const DatasetInfo* states = description->findDataset("/steps/000001/bond_state");
  REQUIRE(states != nullptr);
  CHECK(states->chunkShape == std::vector<std::uint64_t>{256});  // chunked, as compressed ones are
  const DatasetInfo* pairs = description->findDataset("/bonds/pairs");
  REQUIRE(pairs != nullptr);
  CHECK(pairs->shape == std::vector<std::uint64_t>{1024, 2});
  // A second one in the same process: nothing of the first is left open.
  CHECK(rehearseDescribeAndRead().isOk());
}

// A (3, 5, 70000) float64 ramp (value = flat index) in a file of its own.
void writeRamp3d(const std::string& path) {
  std::lock_guard lock(hdf5Mutex());
  namespace h5 = dem::h5;
  h5::Handle file =
      h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  REQUIRE(file.valid());
  std::vector<double> ramp(3 * 5 * 70000);
  for (size_t i = 0; i < ramp.size(); ++i) {
    ramp[i] = static_cast<double>(i);
  }
  REQUIRE(
      h5::writeDataset(file.get(), "ramp3", h5::ElementType::kFloat64, {3, 5, 70000}, ramp.data())
          .isOk());
}

TEST_CASE("A slab whose rows exceed a chunk is read in pieces along an inner dimension",
          "[dataservice]") {
  TempDir root;
  writeRamp3d(root.file("ramp3.h5"));
  Catalogue catalogue(DataRoot::open(root.path().string()).value());
  const auto file = catalogue.root().resolveFile("ramp3.h5").value();
  // A row of the slab is 4 x 69990 values (2.2 MB), one index of the second
  // dimension 69990 values (0.56 MB): pieces run along the second dimension.
  auto reader = catalogue.openRead(file, {{"/ramp3", {1, 1, 7}, {2, 4, 69990}}}, 1 << 30);
  INFO(reader.status().message());
  REQUIRE(reader.isOk());
  std::vector<double> data;
  int pieces = 0;
  while (auto piece = (*reader)->nextPiece()) {
    CHECK(piece->bytes <= kMaxChunkBytes);
    CHECK(piece->offset == data.size() * 8);
    std::vector<double> buffer(piece->bytes / 8);
    REQUIRE((*reader)->read(*piece, buffer.data()).isOk());
    data.insert(data.end(), buffer.begin(), buffer.end());
    ++pieces;
  }
  CHECK(pieces == 8);
  std::vector<double> expected;
  for (int i = 1; i < 3; ++i) {
    for (int j = 1; j < 5; ++j) {
      for (int k = 7; k < 7 + 69990; ++k) {
        expected.push_back(static_cast<double>((i * 5 + j) * 70000 + k));
      }
    }
  }
  REQUIRE(data.size() == expected.size());
  CHECK(data == expected);
}

TEST_CASE("Describe is bounded in depth, objects and time, and stops when cancelled",
          "[dataservice]") {
  TempDir root;
  writeNestedGroups(root.file("deep.h5"), 1000);
  writeNestedGroups(root.file("shallow.h5"), 60);
  writeWideGroups(root.file("wide.h5"), 10'000);  // about 0.15 s of walking: far past 1 ms
  Catalogue catalogue(DataRoot::open(root.path().string()).value());
  const auto deep = catalogue.root().resolveFile("deep.h5").value();

  SECTION("a 1,000-level chain stops at the depth limit, at once") {
    const auto start = std::chrono::steady_clock::now();
    auto description = catalogue.describe(deep);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    REQUIRE_FALSE(description.isOk());
    INFO(description.status().message());
    CHECK(description.status().code() == StatusCode::kResourceExhausted);
    CHECK_THAT(description.status().message(),
               Catch::StartsWith("deep.h5: /g/g/g") &&
                   Catch::Contains("deeper than 64 levels, Describe's limit"));
    CHECK(description.status().message().size() < 200);  // the path is not echoed whole
    CHECK(seconds < 1.0);
  }
  SECTION("a chain within the limit is described whole") {
    auto description = catalogue.describe(catalogue.root().resolveFile("shallow.h5").value());
    REQUIRE(description.isOk());
    CHECK(description->groups.size() == 61);  // the root and 60 levels
    CHECK(description->datasets.size() == 1);
  }
  SECTION("the object and time limits") {
    DescribeOptions options;
    options.limits.maxObjects = 10;
    auto objects = catalogue.describe(deep, options);
    CHECK(objects.status().code() == StatusCode::kResourceExhausted);
    CHECK_THAT(objects.status().message(), Catch::Contains("more than 10 objects"));
    options = {};
    options.limits.maxTime = std::chrono::milliseconds(1);
    auto timed = catalogue.describe(catalogue.root().resolveFile("wide.h5").value(), options);
    CHECK(timed.status().code() == StatusCode::kResourceExhausted);
    CHECK_THAT(timed.status().message(), Catch::Contains("longer than 0.001 s"));
  }
  SECTION("the chain unbounded is walked in linear time") {
    // Objects are opened by the address their link holds: a lookup by path
    // walked every level above, and this walk took seconds.
    DescribeOptions options;
    options.limits.maxDepth = 2000;
    const auto start = std::chrono::steady_clock::now();
    auto description = catalogue.describe(deep, options);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    INFO(description.status().message());
    REQUIRE(description.isOk());
    CHECK(description->groups.size() == 1001);  // the root and 1,000 levels
    REQUIRE(description->datasets.size() == 1);
    CHECK(description->datasets[0].path.size() == 1000 * 2 + std::string("/bottom").size());
    CHECK(seconds < 2.0);
  }
  SECTION("a cancelled caller stops the walk") {
    DescribeOptions options;
    int asked = 0;
    options.cancelled = [&] { return ++asked > 3; };
    auto cancelled = catalogue.describe(deep, options);
    CHECK(cancelled.status().code() == StatusCode::kUnavailable);
    CHECK_THAT(cancelled.status().message(), Catch::Contains("cancelled"));
    CHECK(asked == 4);
  }
}

}  // namespace
}  // namespace crackvis::testing

namespace crackvis::testing {
namespace {

using namespace crackvis::dataservice;

TEST_CASE("A description finds every group and dataset by path, with and without its index",
          "[dataservice]") {
  // Depth-first by name is not byte order ("/a/b" comes before "/a-x"), so
  // the index sorts on its own.
  FileDescription description;
  for (const char* path : {"/", "/a", "/a/b", "/a-x", "/steps", "/steps/000000"}) {
    description.groups.push_back({path, {}});
  }
  for (const char* path : {"/a/b/d", "/a/c", "/a-x/e", "/steps/000000/positions", "/z"}) {
    description.datasets.push_back({path, DataType::kFloat64, "float64", {3}, {}, {}});
  }
  const FileDescription unindexed = description;
  description.buildIndex();
  CHECK(description == unindexed);
  for (const FileDescription* d : {&unindexed, static_cast<const FileDescription*>(&description)}) {
    for (const GroupInfo& group : d->groups) {
      CHECK(d->findGroup(group.path) == &group);
    }
    for (const DatasetInfo& dataset : d->datasets) {
      CHECK(d->findDataset(dataset.path) == &dataset);
    }
    CHECK(d->findDataset("/a") == nullptr);
    CHECK(d->findDataset("/a/b/d/") == nullptr);
    CHECK(d->findDataset("") == nullptr);
    CHECK(d->findGroup("/a/b/d") == nullptr);
  }
  // A list changed after the index: the stale index is ignored.
  description.datasets.push_back({"/b", DataType::kInt32, "int32", {1}, {}, {}});
  CHECK(description.findDataset("/b") == &description.datasets.back());
  CHECK(description.findDataset("/a/c") == &description.datasets[1]);
}

}  // namespace
}  // namespace crackvis::testing
