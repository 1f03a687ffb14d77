#include "support/simulated_cuboid.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <crackvis/sim/presets.hpp>
#include <crackvis/sim/run.hpp>

namespace crackvis::testing {

void writeSimulatedCuboidA(const std::string& path, double scale) {
  sim::PresetOptions options;
  options.name = "cuboid3d";
  options.defectSet = 'A';
  options.scale = scale;
  auto preset = sim::makePreset(options);
  REQUIRE(preset.isOk());
  sim::RunOptions run;
  run.path = path;
  run.metadata.source = fmt::format("crackvis tests: cuboid3d A, scale {}", scale);
  run.stepsPerSave = preset->stepsPerSave;
  run.savedSteps = preset->savedSteps;
  REQUIRE(sim::runToFile(std::move(preset->setup), run).isOk());
}

}  // namespace crackvis::testing
