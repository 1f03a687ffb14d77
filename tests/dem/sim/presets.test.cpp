#include <algorithm>
#include <chrono>
#include <cmath>

#include <catch2/catch.hpp>

#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/sim/presets.hpp>
#include <crackvis/sim/run.hpp>
#include <crackvis/sim/strength.hpp>

using namespace crackvis;
using crackvis::testing::TempDir;

namespace {

std::size_t clampedCount(const sim::Preset& preset) {
  return static_cast<std::size_t>(
      std::count(preset.setup.clamped.begin(), preset.setup.clamped.end(), sim::kClampX));
}

}  // namespace

TEST_CASE("Full-size presets have the dissertation's lattices and defects", "[sim][presets]") {
  SECTION("cuboid3d A, B, C") {
    const std::pair<char, std::size_t> sets[] = {{'A', 125}, {'B', 245}, {'C', 121}};
    for (auto [set, defect] : sets) {
      sim::PresetOptions options;
      options.defectSet = set;
      auto preset = sim::makePreset(options);
      REQUIRE(preset.isOk());
      INFO("set " << set);
      CHECK(preset->setup.lattice.dimension == 3);
      CHECK(preset->setup.lattice.particleCount() == 46875);
      CHECK(preset->setup.lattice.bondCount() == 267674);
      CHECK(preset->defectBonds == defect);
      CHECK(std::count(preset->setup.bondState.begin(), preset->setup.bondState.end(), 1) ==
            static_cast<long>(defect));
      CHECK(preset->savedSteps == 200);
      CHECK(preset->pullVelocity == 0.025);
      // Two layers of 25 x 25 at each end.
      CHECK(clampedCount(*preset) == 4 * 625);
      // The defect sits at the bottom (z small), centred in x and y.
      CHECK(preset->defectCentre.x == Approx(0.5 * preset->extent.x).margin(0.003));
      CHECK(preset->defectCentre.y == Approx(0.5 * preset->extent.y).margin(0.003));
      CHECK(preset->defectCentre.z < 0.25 * preset->extent.z);
      CHECK(preset->extent.x == Approx(0.211).epsilon(0.02));
      CHECK(preset->extent.y == Approx(0.1).epsilon(0.03));
    }
  }
  SECTION("plate2d") {
    sim::PresetOptions options;
    options.name = "plate2d";
    auto preset = sim::makePreset(options);
    REQUIRE(preset.isOk());
    CHECK(preset->setup.lattice.dimension == 2);
    CHECK(preset->setup.lattice.particleCount() == 4680);
    CHECK(preset->setup.lattice.bondCount() == 13723);
    CHECK(preset->defectBonds == 3);
    CHECK(preset->savedSteps == 1284);
    CHECK(preset->pullVelocity == 0.05);
    CHECK(clampedCount(*preset) == 4 * 39);
    CHECK(preset->defectCentre.y < 0.05 * preset->extent.y);
    CHECK(preset->extent.y == Approx(0.107).epsilon(0.01));
    for (const dem::Vec3& p : preset->setup.positions) {
      REQUIRE(p.z == 0.0);
    }
  }
}

TEST_CASE("Preset time steps are stable and land on the saved steps", "[sim][presets]") {
  for (const char* name : {"plate2d", "cuboid3d"}) {
    for (double scale : {1.0, 0.3}) {
      sim::PresetOptions options;
      options.name = name;
      options.scale = scale;
      auto preset = sim::makePreset(options);
      REQUIRE(preset.isOk());
      const sim::MaterialModel model = sim::defaultMaterial(preset->setup.lattice.dimension);
      const double limit = model.timeStepFraction *
                           sim::bondTimeScale(preset->setup.lattice, preset->setup.material);
      INFO(name << " scale " << scale);
      CHECK(preset->setup.timeStep <= limit * (1 + 1e-12));
      CHECK(preset->setup.timeStep > 0.5 * limit);
      const double lastTime = preset->setup.timeStep *
                              static_cast<double>(preset->stepsPerSave * (preset->savedSteps - 1));
      CHECK(lastTime == Approx(sim::presetDuration(name)).epsilon(1e-9));
    }
  }
}

TEST_CASE("Scaling shrinks a preset and keeps its geometry", "[sim][presets]") {
  sim::PresetOptions options;
  options.scale = 0.4;
  options.defectSet = 'C';
  auto preset = sim::makePreset(options);
  REQUIRE(preset.isOk());
  CHECK(preset->setup.lattice.particleCount() == 30 * 10 * 10);
  CHECK(preset->setup.lattice.radius.front() == Approx(0.005));
  CHECK(preset->extent.x == Approx(0.211).epsilon(0.03));
  CHECK(preset->extent.y == Approx(0.1).epsilon(0.06));
  CHECK(preset->defectBonds > 0);
  // Rescaled springs and masses keep the strain at break: strengths scale with
  // k_n d, i.e. with d^2.
  sim::PresetOptions full;
  full.defectSet = 'C';
  auto fullPreset = sim::makePreset(full);
  REQUIRE(fullPreset.isOk());
  const double ratio =
      preset->setup.material.bondStiffness / fullPreset->setup.material.bondStiffness;
  CHECK(ratio == Approx(2.5));
  CHECK(preset->setup.lattice.strength[7] / fullPreset->setup.lattice.strength[7] ==
        Approx(2.5 * 2.5).epsilon(1e-9));
}

TEST_CASE("Presets reject bad options with clear messages", "[sim][presets]") {
  sim::PresetOptions options;
  options.scale = 0.0;
  CHECK_THAT(sim::makePreset(options).status().message(), Catch::Contains("scale"));
  options.scale = 1.5;
  CHECK_THAT(sim::makePreset(options).status().message(), Catch::Contains("scale"));
  options = {};
  options.defectSet = 'D';
  CHECK_THAT(sim::makePreset(options).status().message(), Catch::Contains("defect set 'D'"));
  options = {};
  options.name = "sphere";
  CHECK_THAT(sim::makePreset(options).status().message(), Catch::Contains("unknown preset"));
  options = {};
  options.customMaterial = true;
  options.material.strength.shape = -1.0;
  CHECK_THAT(sim::makePreset(options).status().message(), Catch::Contains("Weibull"));
}

TEST_CASE("Bond strain at break follows the seeded shifted Weibull law", "[sim][presets]") {
  const sim::StrengthDistribution law{2e-5, 6e-5, 2.0};
  const auto a = sim::drawBreakStrains(law, 100000, 1);
  const auto again = sim::drawBreakStrains(law, 100000, 1);
  const auto other = sim::drawBreakStrains(law, 100000, 2);
  CHECK(a == again);
  CHECK(a != other);
  CHECK(*std::min_element(a.begin(), a.end()) >= law.minStrain);
  double sum = 0.0;
  std::size_t belowScale = 0;
  for (double e : a) {
    sum += e;
    belowScale += e < law.minStrain + law.scaleStrain ? 1 : 0;
  }
  CHECK(sum / static_cast<double>(a.size()) == Approx(law.mean()).epsilon(0.01));
  // Weibull CDF at the scale: 1 - 1/e = 0.632.
  CHECK(static_cast<double>(belowScale) / static_cast<double>(a.size()) ==
        Approx(0.632).margin(0.01));
  // The generator is splitmix64 (portable): its first output for seed 1 is fixed.
  crackvis::SplitMix64 random(1);
  CHECK(random.next() == 0x910a2dec89025cc1ULL);
}

TEST_CASE("Scaled runs of every preset fracture from the defect within seconds",
          "[sim][presets][fracture]") {
  TempDir dir;
  struct Case {
    const char* name;
    char set;
    double scale;
    int savedSteps;  // 0: all
  };
  // The plate at full size (4,680 particles) up to saved step 250 of 1,284,
  // past its fast growth; at half size its defect is 2 bonds, too weak a
  // stress concentration to be sure to break first. The cuboids at half size.
  for (const Case& c : {Case{"plate2d", 'A', 1.0, 250}, Case{"cuboid3d", 'A', 0.5, 0},
                        Case{"cuboid3d", 'B', 0.5, 0}, Case{"cuboid3d", 'C', 0.5, 0}}) {
    sim::PresetOptions options;
    options.name = c.name;
    options.defectSet = c.set;
    options.scale = c.scale;
    options.savedSteps = c.savedSteps;
    auto preset = sim::makePreset(options);
    REQUIRE(preset.isOk());
    const dem::Vec3 defect = preset->defectCentre;
    const auto positions = preset->setup.positions;
    sim::RunOptions run;
    run.path = dir.file("run.h5");
    run.stepsPerSave = preset->stepsPerSave;
    run.savedSteps = preset->savedSteps;
    run.writeVelocities = false;
    run.writeBondForce = false;
    const auto start = std::chrono::steady_clock::now();
    auto summary = sim::runToFile(preset->setup, run);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    REQUIRE(summary.isOk());
    INFO(c.name << " set " << c.set << ": " << seconds << " s, broken at the end "
                << summary->brokenPerSavedStep.back() << " of " << summary->bonds);
#ifndef __SANITIZE_ADDRESS__
    // A budget for the test suite's sake (the scaled runs are what the other
    // tests use), not a speed claim; sanitizers make the run 4-5x slower.
    CHECK(seconds < 20.0);
#endif
    const auto& broken = summary->brokenPerSavedStep;
    CHECK(broken.front() == preset->defectBonds);
    CHECK(std::is_sorted(broken.begin(), broken.end()));
    const double finalFraction =
        static_cast<double>(broken.back()) / static_cast<double>(summary->bonds);
    CHECK(finalFraction > 0.02);
    CHECK(finalFraction < 0.15);

    // The first bonds to break after the defect lie next to it: closer than a
    // sixth of the specimen's length, while bonds on average are a quarter away.
    auto reader = dem::DemFileReader::open(run.path);
    REQUIRE(reader.isOk());
    const auto breakSteps = reader->readBreakSteps();
    REQUIRE(breakSteps.isOk());
    const auto& bonds = preset->setup.lattice.bonds;
    int firstStep = 1 << 30;
    for (std::int32_t s : *breakSteps) {
      if (s > 0) {
        firstStep = std::min(firstStep, s);
      }
    }
    REQUIRE(firstStep < preset->savedSteps);
    double firstDistance = 0.0;
    int firstCount = 0;
    double allDistance = 0.0;
    for (std::size_t b = 0; b < bonds.size(); ++b) {
      const dem::Vec3 mid = 0.5 * (positions[static_cast<std::size_t>(bonds[b].first)] +
                                   positions[static_cast<std::size_t>(bonds[b].second)]);
      const double distance = dem::norm(mid - defect);
      allDistance += distance;
      if ((*breakSteps)[b] == firstStep) {
        firstDistance += distance;
        ++firstCount;
      }
    }
    firstDistance /= firstCount;
    allDistance /= static_cast<double>(bonds.size());
    INFO("first new breaks at saved step " << firstStep << ", mean distance " << firstDistance
                                           << " m; all bonds " << allDistance << " m");
    CHECK(firstDistance < preset->extent.x / 6.0);
    CHECK(allDistance > preset->extent.x / 4.0);
  }
}
