// crackvis-data on a live file (issue 32): while `crackvis sim --live`
// writes into the data root, every Describe reports the steps committed so
// far, a new call sees new ones, and each step reads through the service
// exactly as the finished file holds it.
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <signal.h>
#include <sys/wait.h>

#include "service_fixture.hpp"
#include "support/process.hpp"
#include <crackvis/dataservice_client/remote_dem_file.hpp>
#include <crackvis/dem/dem_file.hpp>

using namespace crackvis;
using namespace crackvis::testing;

namespace {

bool exited(pid_t child, int& status) {
  return waitpid(child, &status, WNOHANG) == child;
}

}  // namespace

TEST_CASE("crackvis-data follows a live file: each Describe has the steps written so far",
          "[dataservice][integration][live]") {
  const std::string name = "live-follow.h5";
  const std::string path = sampleRoot().file(name);
  std::filesystem::remove(path);
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));

  constexpr int kSteps = 150;
  const pid_t writer =
      startProcess({CRACKVIS_CLI, "sim", "plate2d", "--scale", "0.4", "--steps",
                    std::to_string(kSteps), "--pace", "0.02", "--live", "-q", "-o", path});
  REQUIRE(writer > 0);
  std::set<std::size_t> counts;                  // step counts Describe reported
  std::map<int, std::vector<dem::Vec3>> served;  // the last step of each look, as served
  int status = 0;
  bool done = false;
  while (!done) {
    done = exited(writer, status);  // one more look after the writer ended
    if (!std::filesystem::exists(path)) {
      REQUIRE_FALSE(done);
      continue;  // the live file takes its name after its first step
    }
    auto description = client.describe(name);
    INFO((description ? std::string() : description.status().message()));
    REQUIRE(description.isOk());
    const std::size_t count = description->steps.size();
    REQUIRE(count >= 1);
    REQUIRE(count <= static_cast<std::size_t>(kSteps));
    // Steps are committed for good: a later look never sees fewer.
    CHECK((counts.empty() || count >= *counts.rbegin()));
    counts.insert(count);
    auto file = dataservice::RemoteDemFile::open(client, name);
    INFO((file ? std::string() : file.status().message()));
    REQUIRE(file.isOk());
    CHECK(file->appendable());
    REQUIRE(file->stepCount() >= static_cast<int>(count));
    const int last = static_cast<int>(count) - 1;
    auto step = file->readStep(last);
    INFO((step ? std::string() : step.status().message()));
    REQUIRE(step.isOk());
    served[last] = step->positions;
  }
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  INFO(counts.size() << " different step counts seen");
  CHECK(*counts.rbegin() == static_cast<std::size_t>(kSteps));
  CHECK(counts.size() >= 3);  // Describe followed the run, not only its end

  auto local = dem::DemFileReader::open(path);
  REQUIRE(local.isOk());
  REQUIRE(local->stepCount() == kSteps);
  CHECK_FALSE(local->info().beingWritten);
  for (const auto& [index, positions] : served) {
    auto step = local->readStep(index);
    REQUIRE(step.isOk());
    CHECK(step->positions == positions);
  }
  std::filesystem::remove(path);
}

TEST_CASE("a finished live file reads through crackvis-data as the local reader reads it",
          "[dataservice][integration][live]") {
  const std::string name = "live-rich.h5";
  const std::string path = sampleRoot().file(name);
  // Every optional part a step can have: velocities, bond forces, scalars
  // (one missing at step 1), per-step extras of both owners.
  SampleData sample = makeSample(3, 3);
  const std::size_t n = sample.lattice.particleCount();
  const std::size_t m = sample.lattice.bondCount();
  for (int k = 0; k < 3; ++k) {
    dem::StepState& step = sample.steps[static_cast<std::size_t>(k)];
    step.scalars.push_back({"load", 5.0 * k});
    if (k != 1) {
      step.scalars.push_back({"displacement", 1e-6 * k});
    }
    step.extras.push_back(
        {"force", dem::ExtraOwner::kParticles, 3, std::vector<double>(3 * n, 0.5 + k)});
    step.extras.push_back({"damage", dem::ExtraOwner::kBonds, 1, std::vector<double>(m, 0.1 * k)});
  }
  dem::DemMetadata metadata = dem::metadataFrom("crackvis tests");
  metadata.stepLayout = dem::StepLayout::kAppendable;
  {
    auto writer = dem::DemFileWriter::create(path, sample.lattice, metadata);
    REQUIRE(writer.isOk());
    for (const dem::StepState& step : sample.steps) {
      REQUIRE(writer->appendStep(step).isOk());
    }
    REQUIRE(writer->close().isOk());
  }
  auto server = startServer(baseConfig());
  auto client = connect(clientOptions(*server));
  auto remote = dataservice::RemoteDemFile::open(client, name);
  INFO((remote ? std::string() : remote.status().message()));
  REQUIRE(remote.isOk());
  CHECK(remote->appendable());
  CHECK_FALSE(remote->beingWritten());
  REQUIRE(remote->stepCount() == 3);
  for (int k = 0; k < 3; ++k) {
    auto step = remote->readStep(k, {true, true, "force", "damage"});
    INFO((step ? std::string() : step.status().message()));
    REQUIRE(step.isOk());
    const dem::StepState& expected = sample.steps[static_cast<std::size_t>(k)];
    CHECK(step->time == expected.time);
    CHECK(step->positions == expected.positions);
    CHECK(step->bondState == expected.bondState);
    CHECK(step->velocities == expected.velocities);
    CHECK(step->bondForce == expected.bondForce);
    CHECK(step->particleExtraComponents == 3);
    CHECK(step->particleExtra == expected.extras[0].values);
    CHECK(step->bondExtra == expected.extras[1].values);
    auto part = remote->positions(k, 5, 7);
    REQUIRE(part.isOk());
    CHECK(*part ==
          std::vector<dem::Vec3>(expected.positions.begin() + 5, expected.positions.begin() + 12));
  }
  auto scalars = remote->stepScalars();
  REQUIRE(scalars.isOk());
  REQUIRE(scalars->size() == 2);
  CHECK((*scalars)[0].name == "displacement");
  CHECK(std::isnan((*scalars)[0].values[1]));  // step 1 has none
  CHECK((*scalars)[0].values[2] == 2e-6);
  CHECK((*scalars)[1].name == "load");
  CHECK((*scalars)[1].values == std::vector<double>{0.0, 5.0, 10.0});
  auto breaks = remote->breakSteps();
  auto local = dem::DemFileReader::open(path);
  REQUIRE(local.isOk());
  REQUIRE(breaks.isOk());
  CHECK(*breaks == *local->readBreakSteps());
  std::filesystem::remove(path);
}
