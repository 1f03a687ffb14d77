#include <cmath>
#include <cstring>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <tbb/global_control.h>

#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/sim/presets.hpp>
#include <crackvis/sim/run.hpp>
#include <crackvis/sim/simulator.hpp>
#include <crackvis/sim/strength.hpp>

using namespace crackvis;
using crackvis::testing::TempDir;

namespace {

// A small jittered FCC block with random velocities, unbreakable bonds.
sim::SimulationSetup vibratingBlock(double bondDamping) {
  dem::BlockSpec spec;
  spec.kind = dem::LatticeKind::kFcc;
  spec.sites = {7, 5, 5};
  spec.radius = 1e-3;
  spec.jitter = 0.05;
  spec.strength = 1e30;
  auto block = dem::generateBlock(spec);
  REQUIRE(block.isOk());
  sim::SimulationSetup setup;
  setup.lattice = block->lattice;
  setup.positions = block->positions;
  crackvis::SplitMix64 random(11);
  for (std::size_t p = 0; p < setup.positions.size(); ++p) {
    auto component = [&] { return 0.01 * (2.0 * random.uniformOpenClosed() - 1.0); };
    setup.velocities.push_back({component(), component(), component()});
  }
  setup.material.bondStiffness = 1e6;
  setup.material.bondDamping = bondDamping;
  setup.timeStep = 0.1 * sim::bondTimeScale(setup.lattice, setup.material);
  return setup;
}

// Two spheres joined by one bond of strength R, pulled apart at v each.
sim::SimulationSetup pulledPair(double strength, double v) {
  sim::SimulationSetup setup;
  setup.lattice.dimension = 3;
  setup.lattice.radius = {1e-3, 1e-3};
  setup.lattice.bonds = {{0, 1}};
  setup.lattice.strength = {strength};
  setup.positions = {{0.0, 0.0, 0.0}, {2e-3, 0.0, 0.0}};
  setup.clamped = {1, 1};
  setup.prescribedVelocity = {{-v, 0.0, 0.0}, {v, 0.0, 0.0}};
  setup.material.bondStiffness = 1e6;
  setup.timeStep = 1e-6;
  return setup;
}

}  // namespace

TEST_CASE("The energy of an undamped, unbroken lattice is conserved", "[sim][simulator]") {
  // Returns the largest relative energy error over ~60 periods of the
  // stiffest mode, and the smallest kinetic share seen.
  auto worstError = [](double stepFraction) {
    auto setup = vibratingBlock(0.0);
    setup.timeStep *= stepFraction / 0.1;
    auto simulator = sim::Simulator::create(setup);
    REQUIRE(simulator.isOk());
    const double initial = simulator->kineticEnergy() + simulator->potentialEnergy();
    REQUIRE(initial > 0.0);
    const int chunk = static_cast<int>(std::lround(5.0 / stepFraction));
    double worst = 0.0;
    double minKineticShare = 1.0;
    for (int k = 0; k < 40; ++k) {
      simulator->advance(chunk);
      const double kinetic = simulator->kineticEnergy();
      minKineticShare = std::min(minKineticShare, kinetic / initial);
      worst = std::max(worst, std::abs(kinetic + simulator->potentialEnergy() - initial) / initial);
    }
    CHECK(simulator->brokenBondCount() == 0);
    return std::pair{worst, minKineticShare};
  };
  // The presets' step, 0.15 sqrt(m/k), with every mode of the block excited:
  // the energy error stays below 2 % (measured 1.0 %; velocity Verlet's
  // error is bounded, it does not drift) ...
  const auto [coarse, coarseShare] = worstError(0.15);
  CHECK(coarse < 2e-2);
  // ... and falls as dt^2: half the step, about a quarter of the error.
  const auto [fine, fineShare] = worstError(0.075);
  CHECK(fine < 0.35 * coarse);
  CHECK(fine < 5e-3);
  // The energy really moved between kinetic and elastic.
  CHECK(coarseShare < 0.9);
  CHECK(fineShare < 0.9);

  // The bond dashpots, by contrast, dissipate.
  auto damped = sim::Simulator::create(vibratingBlock(0.1));
  REQUIRE(damped.isOk());
  const double initial = damped->kineticEnergy() + damped->potentialEnergy();
  damped->advance(2000);
  CHECK(damped->kineticEnergy() + damped->potentialEnergy() < 0.5 * initial);
}

TEST_CASE("A bond pulled past R_n breaks in that step and stays broken", "[sim][simulator]") {
  // Stretch after n steps: 2 v n dt; force k * stretch; it exceeds R first
  // at n = floor(R / (2 k v dt)) + 1.
  const double strength = 0.73;
  const double v = 0.01;
  auto simulator = sim::Simulator::create(pulledPair(strength, v));
  REQUIRE(simulator.isOk());
  const double perStep = 1e6 * 2.0 * v * 1e-6;  // force gained per step, N
  const auto breakStep = static_cast<std::int64_t>(std::floor(strength / perStep)) + 1;
  simulator->advance(breakStep - 1);
  CHECK(simulator->bondState()[0] == 0);
  CHECK(simulator->bondNormalForce()[0] == Approx(perStep * (breakStep - 1)).epsilon(1e-6));
  CHECK(simulator->bondNormalForce()[0] <= strength);
  simulator->advance(1);
  CHECK(simulator->bondState()[0] == 1);
  CHECK(simulator->bondNormalForce()[0] == 0.0);
  simulator->advance(100);
  CHECK(simulator->bondState()[0] == 1);
  CHECK(simulator->brokenBondCount() == 1);
}

TEST_CASE("A broken bond pushes back as a contact but never pulls", "[sim][simulator]") {
  // Free spheres on a pre-broken bond, approaching: they bounce (Hertz) and
  // fly apart past the rest length with nothing pulling them back.
  auto setup = pulledPair(1.0, 0.0);
  setup.clamped.clear();
  setup.prescribedVelocity.clear();
  setup.bondState = {1};
  setup.velocities = {{0.05, 0.0, 0.0}, {-0.05, 0.0, 0.0}};
  setup.material.contact.effectiveModulus = 1e9;
  setup.material.contact.restitution = 1.0;
  setup.timeStep = 1e-8;
  auto simulator = sim::Simulator::create(setup);
  REQUIRE(simulator.isOk());
  double maxCompression = 0.0;
  for (int step = 0; step < 20000; ++step) {
    simulator->advance(1);
    maxCompression = std::max(maxCompression, -simulator->bondNormalForce()[0]);
  }
  CHECK(maxCompression > 0.0);
  const auto& v = simulator->velocities();
  CHECK(v[0].x == Approx(-0.05).epsilon(1e-3));
  CHECK(v[1].x == Approx(0.05).epsilon(1e-3));
  CHECK(dem::norm(simulator->positions()[1] - simulator->positions()[0]) > 2.001e-3);
  CHECK(simulator->bondState()[0] == 1);
}

TEST_CASE("1 and 2 threads give bit-identical files", "[sim][simulator][determinism]") {
  TempDir dir;
  for (const char* name : {"cuboid3d", "plate2d"}) {
    sim::PresetOptions options;
    options.name = name;
    const bool plate = std::string(name) == "plate2d";
    options.scale = plate ? 0.3 : 0.4;
    options.savedSteps = plate ? 200 : 160;  // past the onset of fracture
    auto preset = sim::makePreset(options);
    REQUIRE(preset.isOk());
    std::vector<std::string> paths;
    for (std::size_t threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      sim::RunOptions run;
      run.path = dir.file(fmt::format("{}-{}.h5", name, threads));
      run.metadata.source = "determinism test";
      run.stepsPerSave = preset->stepsPerSave;
      run.savedSteps = preset->savedSteps;
      auto summary = sim::runToFile(preset->setup, run);
      REQUIRE(summary.isOk());
      // The run must fracture for the comparison to mean something.
      REQUIRE(summary->brokenPerSavedStep.back() > preset->defectBonds + 50);
      paths.push_back(run.path);
    }
    auto one = dem::DemFileReader::open(paths[0]);
    auto two = dem::DemFileReader::open(paths[1]);
    REQUIRE(one.isOk());
    REQUIRE(two.isOk());
    REQUIRE(one->stepCount() == two->stepCount());
    CHECK(*one->readBreakSteps() == *two->readBreakSteps());
    for (int step = 0; step < one->stepCount(); ++step) {
      auto a = one->readStep(step);
      auto b = two->readStep(step);
      REQUIRE(a.isOk());
      REQUIRE(b.isOk());
      INFO(name << " step " << step);
      CHECK(a->time == b->time);
      CHECK(std::memcmp(a->positions.data(), b->positions.data(),
                        a->positions.size() * sizeof(dem::Vec3)) == 0);
      CHECK(a->bondState == b->bondState);
      CHECK(std::memcmp(a->velocities.data(), b->velocities.data(),
                        a->velocities.size() * sizeof(a->velocities[0])) == 0);
      CHECK(std::memcmp(a->bondForce.data(), b->bondForce.data(),
                        a->bondForce.size() * sizeof(float)) == 0);
    }
  }
}

TEST_CASE("The simulator rejects inconsistent setups", "[sim][simulator]") {
  auto setup = pulledPair(1.0, 0.01);
  setup.positions.pop_back();
  CHECK(sim::Simulator::create(setup).status().code() == StatusCode::kInvalidArgument);
  setup = pulledPair(1.0, 0.01);
  setup.timeStep = 0.0;
  CHECK_THAT(sim::Simulator::create(setup).status().message(), Catch::Contains("time step"));
  setup = pulledPair(1.0, 0.01);
  setup.bondState = {2};
  CHECK_THAT(sim::Simulator::create(setup).status().message(), Catch::Contains("state 2"));
}
