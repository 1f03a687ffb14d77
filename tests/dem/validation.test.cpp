// Every malformed-file case of the foundation issue, through the reader API:
// the error is a Status whose message names the file and the defect. The
// same cases run through `crackvis info` in tests/tools/info_command.test.cpp.
#include <catch2/catch.hpp>

#include "support/dem_defects.hpp"
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
