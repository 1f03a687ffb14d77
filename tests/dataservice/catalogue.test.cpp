// The catalogue without gRPC: how a Read is split into pieces, and that
// pieces put back together are the slab.
#include <catch2/catch.hpp>

#include "service_fixture.hpp"
#include <crackvis/dataservice/catalogue.hpp>

namespace crackvis::testing {
namespace {

using namespace crackvis::dataservice;

TEST_CASE("A Read is split into pieces of whole rows of at most 1 MiB", "[dataservice]") {
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
    if (slabs[piece->slab].rowBytes <= kMaxChunkBytes) {
      CHECK(piece->bytes <= kMaxChunkBytes);
    } else {
      CHECK(piece->rows == 1);  // a row larger than a chunk is a piece of its own
    }
    std::vector<char> buffer(piece->bytes);
    REQUIRE((*reader)->read(*piece, buffer.data()).isOk());
    data[piece->slab].insert(data[piece->slab].end(), buffer.begin(), buffer.end());
    ++pieces[piece->slab];
  }
  CHECK(pieces[0] == 16);
  CHECK(pieces[1] == 2);
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

}  // namespace
}  // namespace crackvis::testing
