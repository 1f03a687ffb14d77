// Every malformed-file case of the foundation issue, through the reader API:
// the error is a Status whose message names the file and the defect. The
// same cases run through `crackvis info` in tests/tools/info_command.test.cpp.
#include <filesystem>
#include <string_view>

#include <catch2/catch.hpp>

#include "support/dem_defects.hpp"
#include "support/h5_tamper.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>

using namespace crackvis;
using namespace crackvis::dem;

namespace {

// Everything a consumer of the file would read, stopping at the first error.
Status readEverything(const std::string& path) {
  auto reader = DemFileReader::open(path);
  if (!reader) {
    return reader.status();
  }
  if (auto lattice = reader->readLattice(); !lattice) {
    return lattice.status();
  }
  if (auto breaks = reader->readBreakSteps(); !breaks) {
    return breaks.status();
  }
  for (int k = 0; k < reader->stepCount(); ++k) {
    if (auto step = reader->readStep(k); !step) {
      return step.status();
    }
  }
  return Status::ok();
}

}  // namespace

TEST_CASE("the sample file is valid before it is damaged", "[dem][validation]") {
  testing::TempDir dir;
  testing::writeSampleFile(dir.file("good.h5"));
  CHECK(readEverything(dir.file("good.h5")).isOk());
}

TEST_CASE("malformed files are refused with a message naming the defect", "[dem][validation]") {
  testing::TempDir dir;
  const std::string reference = dir.file("reference.h5");
  const testing::SampleData sample = testing::writeSampleFile(reference);
  for (const testing::DemDefect& defect : testing::demDefects(sample)) {
    DYNAMIC_SECTION(defect.name) {
      const std::string path = dir.file("damaged.h5");
      std::filesystem::copy_file(reference, path,
                                 std::filesystem::copy_options::overwrite_existing);
      defect.damage(path, sample);
      const Status status = readEverything(path);
      REQUIRE_FALSE(status.isOk());
      CHECK(status.message().starts_with(path + ": "));
      for (const std::string& part : defect.messageParts) {
        CHECK_THAT(status.message(), Catch::Contains(part));
      }
      CHECK(status.message().find('\n') == std::string::npos);
    }
  }
}

TEST_CASE("a missing file is NOT_FOUND", "[dem][validation]") {
  auto reader = DemFileReader::open("/nonexistent/crackvis.h5");
  CHECK(reader.status().code() == StatusCode::kNotFound);
  CHECK(reader.status().message() == "/nonexistent/crackvis.h5: no such file");
}

TEST_CASE("a file declaring more rows than it stores is refused before allocating",
          "[dem][validation]") {
  // What the fuzzer found: chunks never written read as the fill value, so
  // a file of a few KB can declare 10^8 bonds and the reader used to
  // allocate every one of them.
  testing::TempDir dir;
  const std::string path = dir.file("declares.h5");
  testing::writeSampleFile(path);
  constexpr std::uint64_t kDeclaredBonds = 100'000'000;
  for (const char* dataset : {"/bonds/pairs", "/bonds/strength", "/bonds/break_step"}) {
    const bool pairs = std::string_view(dataset) == "/bonds/pairs";
    testing::replaceWithSparseDataset(path, dataset,
                                      pairs || std::string_view(dataset) == "/bonds/break_step"
                                          ? h5::ElementType::kInt32
                                          : h5::ElementType::kFloat64,
                                      pairs ? std::vector<std::uint64_t>{kDeclaredBonds, 2}
                                            : std::vector<std::uint64_t>{kDeclaredBonds});
  }
  REQUIRE(std::filesystem::file_size(path) < 256 * 1024);
  // It opens (a caller with size limits reports those first) ...
  auto reader = DemFileReader::open(path);
  REQUIRE(reader.isOk());
  CHECK(reader->info().bondCount == static_cast<std::int64_t>(kDeclaredBonds));
  // ... but nothing sized by M is read.
  const std::string expected =
      "dataset /bonds/pairs declares 100000000 rows (800000000 bytes) "
      "but the file stores only 0 bytes of it";
  const std::vector<Status> reads = {
      reader->readLattice().status(), reader->readBreakSteps().status(),
      reader->readStep(0).status(), reader->readBondState(0).status()};
  for (const Status& status : reads) {
    INFO(status.message());
    CHECK(status.code() == StatusCode::kFailedPrecondition);
    CHECK(status.message().starts_with(path + ": "));
    CHECK_THAT(status.message(), Catch::Contains(expected));
  }
}
