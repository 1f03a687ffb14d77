// A real simulated fracture series for tests: cuboid A of the dissertation's
// benchmark at a reduced scale, written by crackvis::sim (about a second at
// scale 0.3). Tests that link crackvis::sim compile simulated_cuboid.cpp.
#pragma once

#include <string>

namespace crackvis::testing {

// Writes cuboid3d set A at `scale` to `path`; fails the test on error.
void writeSimulatedCuboidA(const std::string& path, double scale = 0.3);

}  // namespace crackvis::testing
