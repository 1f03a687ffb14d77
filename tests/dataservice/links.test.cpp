// HDF5 links may not lead a caller out of a file: not an external link, and
// not a soft link whose chain reaches one (soft -> external, soft -> soft ->
// external, or an external group in the middle of a path). Tried through a
// real crackvis-data with a user who may read only her own folder, against
// another user's file and a file outside the data root.
#include <catch2/catch.hpp>

#include "service_fixture.hpp"
#include "support/h5_tamper.hpp"
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::testing {
namespace {

using dataservice::Hyperslab;

struct LinkRoot {
  TempDir root;
  TempDir outside;
  SampleData alice;
  SampleData bob;
};

// alice/a.h5 carries every escape route; bob/b.h5 and <outside>/secret.h5
// are what the routes aim at.
std::unique_ptr<LinkRoot> makeLinkRoot() {
  auto made = std::make_unique<LinkRoot>();
  std::filesystem::create_directories(made->root.path() / "alice");
  std::filesystem::create_directories(made->root.path() / "bob");
  const std::string a = made->root.file("alice/a.h5");
  const std::string b = made->root.file("bob/b.h5");
  const std::string secret = made->outside.file("secret.h5");
  std::lock_guard lock(dataservice::hdf5Mutex());
  made->alice = writeSampleFile(a, 3, 2);
  made->bob = writeSampleFile(b, 3, 2);
  writeSampleFile(secret, 2, 1);
  addExternalLink(a, "/ext_bob", b, "/particles/radius");
  addSoftLink(a, "/soft_bob", "/ext_bob");
  addExternalLink(a, "/ext_out", secret, "/particles/radius");
  addSoftLink(a, "/soft_out", "/ext_out");
  addSoftLink(a, "/soft_soft_out", "/soft_out");
  addExternalLink(a, "/ext_group", secret, "/particles");
  addSoftLink(a, "/soft_group", "/ext_group");
  addExternalLink(a, "/particles/ext_here", secret, "/particles/radius");
  addSoftLink(a, "/particles/relative_out", "ext_here");
  addSoftLink(a, "/loop_a", "/loop_b");
  addSoftLink(a, "/loop_b", "/loop_a");
  addSoftLink(a, "/local_radius", "/particles/radius");  // a plain object in the same file
  return made;
}

TEST_CASE("Links out of a file are refused by Describe and Read, soft or external",
          "[dataservice][integration]") {
  auto links = makeLinkRoot();
  auto config = baseConfig();
  config.dataRoot = links->root.path().string();
  // The test client's certificate (CN crackvis-client) is alice, who may
  // read her folder only.
  config.users = {{"alice", "", "", "crackvis-client", {"alice"}}};
  auto server = startServer(config);
  auto client = connect(clientOptions(*server));

  SECTION("Describe lists objects, never what a link leads to") {
    auto description = client.describe("alice/a.h5");
    INFO(description.status().message());
    REQUIRE(description.isOk());
    CHECK(description->findDataset("/particles/radius") != nullptr);
    for (const char* link :
         {"/ext_bob", "/soft_bob", "/ext_out", "/soft_out", "/soft_soft_out", "/soft_group/radius",
          "/ext_group/radius", "/local_radius", "/particles/relative_out"}) {
      INFO(link);
      CHECK(description->findDataset(link) == nullptr);
    }
    CHECK(description->findGroup("/ext_group") == nullptr);
    CHECK(description->findGroup("/soft_group") == nullptr);
    CHECK(description->steps.size() == 2);
  }

  SECTION("Read refuses every route out, and names the link") {
    struct Route {
      std::string dataset;
      std::vector<std::string> parts;
    };
    const std::vector<Route> routes = {
        {"/ext_bob", {"/ext_bob is an external link"}},
        {"/ext_out", {"/ext_out is an external link"}},
        {"/soft_bob", {"/soft_bob is a soft link to /ext_bob", "/ext_bob is an external link"}},
        {"/soft_out", {"/soft_out is a soft link to /ext_out"}},
        {"/soft_soft_out", {"/soft_soft_out is a soft link to /soft_out", "external link"}},
        {"/soft_group/radius", {"/soft_group is a soft link to /ext_group", "external link"}},
        {"/ext_group/radius", {"/ext_group is an external link"}},
        {"/particles/relative_out",
         {"soft link to ext_here", "/particles/ext_here is an external link"}},
    };
    for (const Route& route : routes) {
      INFO(route.dataset);
      auto arrays = client.read("alice/a.h5", {Hyperslab::whole(route.dataset)});
      REQUIRE_FALSE(arrays.isOk());
      INFO(arrays.status().message());
      CHECK(arrays.status().code() == StatusCode::kPermissionDenied);
      CHECK_THAT(arrays.status().message(), Catch::Contains("alice/a.h5") &&
                                                Catch::Contains(route.dataset) &&
                                                Catch::Contains("never follows links out"));
      for (const std::string& part : route.parts) {
        CHECK_THAT(arrays.status().message(), Catch::Contains(part));
      }
    }
    auto loop = client.read("alice/a.h5", {Hyperslab::whole("/loop_a")});
    CHECK(loop.status().code() == StatusCode::kFailedPrecondition);
    CHECK_THAT(loop.status().message(), Catch::Contains("soft links in a row"));

    // Bob's file itself stays out of alice's reach, and a soft link to a
    // plain object in the same file still reads.
    CHECK(client.read("bob/b.h5", {Hyperslab::whole("/particles/radius")}).status().code() ==
          StatusCode::kPermissionDenied);
    auto local = client.read("alice/a.h5", {Hyperslab::whole("/local_radius")});
    REQUIRE(local.isOk());
    CHECK(local->front().values<double>().value() == links->alice.lattice.radius);
  }
  // Whatever was tried, the server keeps serving.
  auto after = client.read("alice/a.h5", {Hyperslab::whole("/particles/radius")});
  REQUIRE(after.isOk());
  CHECK(after->front().values<double>().value() == links->alice.lattice.radius);
}

TEST_CASE("The local reader refuses a crackvis-dem dataset that links out of the file",
          "[dem][h5]") {
  auto links = makeLinkRoot();
  const std::string a = links->root.file("alice/a.h5");
  {
    std::lock_guard lock(dataservice::hdf5Mutex());
    deleteLink(a, "/particles/radius");
    addSoftLink(a, "/particles/radius", "/ext_bob");
  }
  auto reader = dem::DemFileReader::open(a);
  REQUIRE_FALSE(reader.isOk());
  CHECK(reader.status().code() == StatusCode::kFailedPrecondition);
  CHECK_THAT(reader.status().message(),
             Catch::Contains(a) &&
                 Catch::Contains("/particles/radius is a soft link to /ext_bob") &&
                 Catch::Contains("/ext_bob is an external link") &&
                 Catch::Contains("only data inside the file"));
}

}  // namespace
}  // namespace crackvis::testing
