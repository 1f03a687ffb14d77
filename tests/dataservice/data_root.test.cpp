// Path rules of the data root, without a server: what is refused, with
// which status, and that symlinks may move inside the root but never out.
#include <catch2/catch.hpp>

#include "service_fixture.hpp"
#include <crackvis/dataservice_h5/data_root.hpp>

namespace crackvis::testing {
namespace {

using dataservice::DataRoot;

TEST_CASE("Client paths are normalized or refused", "[dataservice]") {
  CHECK(DataRoot::normalize("a/b.h5").value() == "a/b.h5");
  CHECK(DataRoot::normalize("a//./b.h5").value() == "a/b.h5");
  CHECK(DataRoot::normalize("./a/").value() == "a");
  CHECK(DataRoot::normalize("").value().empty());
  CHECK(DataRoot::normalize("a..b/c..").value() == "a..b/c..");  // ".." only as a whole part
  for (const std::string bad : {"..", "../a", "a/../b", "a/..", "/a", "/"}) {
    INFO(bad);
    auto result = DataRoot::normalize(bad);
    CHECK(result.status().code() == StatusCode::kInvalidArgument);
    CHECK_THAT(result.status().message(), Catch::Contains("'" + bad + "'"));
  }
  CHECK(DataRoot::normalize(std::string("a\0b", 3)).status().code() ==
        StatusCode::kInvalidArgument);
}

TEST_CASE("Files resolve inside the root, symlinks may not leave it", "[dataservice]") {
  const SampleRoot& sample = sampleRoot();
  auto root = DataRoot::open(sample.root.path().string());
  REQUIRE(root.isOk());
  auto run = root->resolveFile("run.h5");
  REQUIRE(run.isOk());
  CHECK(run->requested == "run.h5");
  CHECK(run->relative == "run.h5");
  CHECK(run->absolute == std::filesystem::canonical(sample.file("run.h5")));

  auto linked = root->resolveFile("inside-link.h5");
  REQUIRE(linked.isOk());
  CHECK(linked->requested == "inside-link.h5");
  CHECK(linked->relative == "run.h5");
  auto across = root->resolveFile("alice/bob-link.h5");
  REQUIRE(across.isOk());
  CHECK(across->relative == "bob/b.h5");

  CHECK(root->resolveFile("escape.h5").status().code() == StatusCode::kPermissionDenied);
  CHECK(root->resolveFile("nothing.h5").status().code() == StatusCode::kNotFound);
  CHECK(root->resolveFile("flat").status().code() == StatusCode::kInvalidArgument);
  CHECK(root->resolveFile("").status().code() == StatusCode::kInvalidArgument);
  CHECK(root->resolveFolder("").value().relative.empty());
  CHECK(root->resolveFolder("flat").value().relative == "flat");
  CHECK(root->resolveFolder("run.h5").status().code() == StatusCode::kInvalidArgument);

  CHECK(DataRoot::open(sample.file("run.h5")).status().code() == StatusCode::kInvalidArgument);
  CHECK(DataRoot::open(sample.file("absent")).status().code() == StatusCode::kNotFound);
}

TEST_CASE("HDF5 files are told apart by their signature", "[dataservice]") {
  const SampleRoot& sample = sampleRoot();
  CHECK(dataservice::hasHdf5Signature(sample.file("run.h5")));
  CHECK(dataservice::hasHdf5Signature(sample.file("truncated.h5")));
  CHECK_FALSE(dataservice::hasHdf5Signature(sample.file("notes.txt")));
  CHECK_FALSE(dataservice::hasHdf5Signature(sample.file("absent.h5")));
}

}  // namespace
}  // namespace crackvis::testing
