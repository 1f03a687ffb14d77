// Bad numbers in a file never reach the extraction or the renderer: a step
// source (local, and remote through a real crackvis-data) refuses non-finite
// or huge positions, bad radii, bad bonds and bond states with
// FAILED_PRECONDITION naming the file, the step and the first bad index; a
// real crackvis-render answers OpenSession so and keeps serving; and the
// particle grid itself survives such positions.
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include "crackvis/v1/render.grpc.pb.h"
#include "dataservice/service_fixture.hpp"
#include "service/render_fixture.hpp"
#include "support/h5_tamper.hpp"
#include "support/process.hpp"
#include "support/sample_files.hpp"
#include <crackvis/cracks/particle_grid.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/source/step_source.hpp>
#include <crackvis/tls/tls_material.hpp>

using namespace crackvis;
using namespace crackvis::testing;
namespace v1 = crackvis::v1;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct BadFile {
  std::string name;  // file name in the data root
  std::function<void(const std::string& path, const SampleData& sample)> damage;
  int step;  // the step that fails; -1: opening fails
  std::vector<std::string> parts;
};

std::vector<BadFile> badFiles(const SampleData& sample) {
  const auto n = static_cast<std::int32_t>(sample.lattice.particleCount());
  return {
      {"inf.h5",
       [](const std::string& path, const SampleData&) {
         setElement(path, "/steps/000000/positions", 3 * 4 + 0, kInf);
       },
       0,
       {"step 0: position of particle 4 is not finite"}},
      {"huge.h5",
       [](const std::string& path, const SampleData&) {
         setElement(path, "/steps/000002/positions", 3 * 7 + 2, 1e300);
       },
       2,
       {"step 2: position of particle 7", "1e+300", "beyond 1e+15 m"}},
      {"state.h5",
       [](const std::string& path, const SampleData&) {
         setElement(path, "/steps/000001/bond_state", 5, 2);
       },
       1,
       {"step 1: state of bond 5 is 2, expected 0 (intact) or 1 (broken)"}},
      {"radius.h5",
       [](const std::string& path, const SampleData&) {
         setElement(path, "/particles/radius", 2, -1.0);
       },
       -1,
       {"radius of particle 2 is -1"}},
      {"selfbond.h5",
       [](const std::string& path, const SampleData&) {
         setInt32Elements(path, "/bonds/pairs", {7, 7}, 2 * 3);
       },
       -1,
       {"bond 3 is a self-bond of particle 7"}},
      {"duplicate.h5",
       [](const std::string& path, const SampleData& s) {
         const dem::Bond first = s.lattice.bonds[1];
         setInt32Elements(path, "/bonds/pairs", {first.second, first.first}, 2 * 4);
       },
       -1,
       {"bond 4 duplicates bond 1"}},
      {"index.h5",
       [n](const std::string& path, const SampleData&) {
         setInt32Elements(path, "/bonds/pairs", {0, n + 5}, 2 * 5);
       },
       -1,
       {fmt::format("bond 5 joins particles 0 and {}: index out of range", n + 5)}},
  };
}

// The bad files, made once per process beside cuboidA.h5 in the render
// fixture's data root.
const SampleData& writeBadFiles() {
  static SampleData sample = [] {
    const TempDir& root = crackRoot();
    std::lock_guard lock(dataservice::hdf5Mutex());
    SampleData made = writeSampleFile(root.file("good.h5"), 3, 3);
    for (const BadFile& bad : badFiles(made)) {
      writeSample(root.file(bad.name), made);
      bad.damage(root.file(bad.name), made);
    }
    return made;
  }();
  return sample;
}

void checkRefusal(const Status& status, const std::string& file, const BadFile& bad) {
  INFO(status.message());
  CHECK(status.code() == StatusCode::kFailedPrecondition);
  CHECK_THAT(status.message(), Catch::StartsWith(file + ": "));
  for (const std::string& part : bad.parts) {
    CHECK_THAT(status.message(), Catch::Contains(part));
  }
}

// Opens the source and reads every step; the bad one fails as the table says.
void checkSource(const std::function<Result<std::unique_ptr<source::StepSource>>()>& open,
                 const std::string& file, const BadFile& bad) {
  auto opened = open();
  if (bad.step < 0) {
    REQUIRE_FALSE(opened.isOk());
    checkRefusal(opened.status(), file, bad);
    return;
  }
  INFO(opened.status().message());
  REQUIRE(opened.isOk());
  source::StepCache cache(std::move(opened).value());
  for (int step = 0; step < 3; ++step) {
    auto read = cache.get(step);
    if (step == bad.step) {
      REQUIRE_FALSE(read.isOk());
      checkRefusal(read.status(), file, bad);
    } else {
      CHECK(read.isOk());
    }
  }
}

std::unique_ptr<v1::RenderService::Stub> connectRender(const service::RenderServer& server) {
  const auto tls = tls::loadTlsMaterial(clientTls()).value();
  auto credentials = grpc::SslCredentials({tls.caPem, tls.keyPem, tls.certPem});
  return v1::RenderService::NewStub(
      grpc::CreateChannel(fmt::format("localhost:{}", server.port()), credentials));
}

grpc::Status openSession(v1::RenderService::Stub& stub, const std::string& file, int step) {
  auto view = crackView();
  view.file = file;
  view.step = step;
  grpc::ClientContext context;
  v1::OpenSessionRequest request;
  request.set_pipeline_xml(pipeline::toXml(view));
  v1::OpenSessionResponse response;
  return stub.OpenSession(&context, request, &response);
}

}  // namespace

TEST_CASE("step sources refuse bad numbers once, naming file, step and index",
          "[source][integration]") {
  const SampleData& sample = writeBadFiles();
  auto config = baseConfig();
  config.dataRoot = crackRoot().path().string();
  auto server = startServer(config);
  auto client = testing::connect(clientOptions(*server));
  for (const BadFile& bad : badFiles(sample)) {
    DYNAMIC_SECTION("local " << bad.name) {
      const std::string path = crackRoot().file(bad.name);
      checkSource([&] { return source::openLocalSource(path); }, path, bad);
    }
    DYNAMIC_SECTION("remote " << bad.name) {
      checkSource([&] { return source::openRemoteSource(client, bad.name); }, bad.name, bad);
    }
  }
  auto good = source::openRemoteSource(client, "good.h5");
  REQUIRE(good.isOk());
  CHECK((*good)->read(2).isOk());
}

TEST_CASE("crackvis-render refuses a session on bad numbers and keeps serving",
          "[render][service][integration]") {
  const SampleData& sample = writeBadFiles();
  auto services = startServices();
  auto stub = connectRender(*services.render);
  for (const BadFile& bad : badFiles(sample)) {
    DYNAMIC_SECTION(bad.name) {
      const grpc::Status status = openSession(*stub, bad.name, bad.step < 0 ? 0 : bad.step);
      INFO(status.error_message());
      CHECK(status.error_code() == grpc::StatusCode::FAILED_PRECONDITION);
      CHECK_THAT(status.error_message(), Catch::Contains(bad.name));
      for (const std::string& part : bad.parts) {
        CHECK_THAT(status.error_message(), Catch::Contains(part));
      }
      if (bad.step > 0) {
        // The steps before the bad one open fine.
        CHECK(openSession(*stub, bad.name, 0).ok());
      }
    }
  }
  const grpc::Status good = openSession(*stub, "cuboidA.h5", -1);
  INFO(good.error_message());
  CHECK(good.ok());
}

namespace {

constexpr std::uint64_t kDeclaredBonds = 100'000'000;

// good.h5 whose bond datasets declare 10^8 bonds, a file of a few KB.
std::string writeDeclaringFile() {
  const SampleData& sample = writeBadFiles();
  const std::string path = crackRoot().file("declares.h5");
  std::lock_guard lock(dataservice::hdf5Mutex());
  writeSample(path, sample);
  using dem::h5::ElementType;
  replaceWithSparseDataset(path, "/bonds/pairs", ElementType::kInt32, {kDeclaredBonds, 2});
  replaceWithSparseDataset(path, "/bonds/strength", ElementType::kFloat64, {kDeclaredBonds});
  replaceWithSparseDataset(path, "/bonds/break_step", ElementType::kInt32, {kDeclaredBonds});
  for (int step = 0; step < 3; ++step) {
    replaceWithSparseDataset(path, fmt::format("/steps/{:06d}/bond_state", step),
                             ElementType::kUInt8, {kDeclaredBonds});
  }
  return path;
}

}  // namespace

TEST_CASE("a file declaring more bonds than the limit is refused before allocating",
          "[source][render][service][integration]") {
  const std::string path = writeDeclaringFile();
  REQUIRE(std::filesystem::file_size(path) < 256 * 1024);
  const dem::SizeLimits limits{1'000'000, 50'000'000};
  SECTION("local and remote step sources") {
    auto config = baseConfig();
    config.dataRoot = crackRoot().path().string();
    auto server = startServer(config);
    auto client = testing::connect(clientOptions(*server));
    for (const auto& opened : {source::openLocalSource(path, limits),
                               source::openRemoteSource(client, "declares.h5", limits)}) {
      REQUIRE_FALSE(opened.isOk());
      INFO(opened.status().message());
      CHECK(opened.status().code() == StatusCode::kResourceExhausted);
      CHECK_THAT(opened.status().message(),
                 Catch::Contains("declares M = 100000000 bonds, more than the limit of "
                                 "50000000 (max_bonds)"));
    }
  }
  SECTION("crackvis-render with its default limits") {
    auto services = startServices();
    auto stub = connectRender(*services.render);
    const std::uint64_t before = residentBytes();
    const grpc::Status status = openSession(*stub, "declares.h5", 0);
    INFO(status.error_message());
    CHECK(status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED);
    CHECK_THAT(status.error_message(),
               Catch::Contains("declares.h5") && Catch::Contains("(max_bonds)"));
    // Before, the session allocated the declared arrays (2.65 GB for this).
    CHECK(residentBytes() < before + (std::uint64_t{256} << 20));
    CHECK(openSession(*stub, "good.h5", 0).ok());
  }
}

TEST_CASE("the particle grid survives infinite and huge positions", "[cracks]") {
  std::vector<dem::Vec3> positions = {
      {0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {1e300, 0.0, 0.0}, {-1e300, 5.0, 0.0}};
  SECTION("huge") {}
  SECTION("infinite") {
    positions.push_back({kInf, 0.0, -kInf});
  }
  SECTION("not a number") {
    positions.push_back({std::nan(""), 0.0, 0.0});
  }
  cracks::ParticleGrid grid(positions, 0.5);
  // A few cells for a few particles, not 10^600 of them.
  CHECK(grid.memoryBytes() < 4096);
  std::vector<int> near;
  grid.forEachNear({0.0, 0.0, 0.0}, 1.5, [&](std::int32_t i) { near.push_back(i); });
  // Candidates may include far particles; the near ones must all be there.
  for (int expected : {0, 1, 2}) {
    CHECK(std::count(near.begin(), near.end(), expected) == 1);
  }
}
