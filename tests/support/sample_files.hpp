// Small, valid crackvis-dem data made in code for tests: a lattice block and a
// few steps in which bonds break progressively, as a fracture run would.
#pragma once

#include <array>
#include <cstring>
#include <string>
#include <vector>

#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/lattice_generator.hpp>

namespace crackvis::testing {

struct SampleData {
  dem::Lattice lattice;
  std::vector<dem::StepState> steps;
};

// A jittered block (fcc 3D or triangular 2D) stretched along x over `steps`
// steps; at step k the first k * M / (2 * steps) bonds are broken. With
// `optionalArrays`, steps also carry velocities and bond forces.
SampleData makeSample(int dimension, int steps, bool optionalArrays = true);

// Writes `sample` to `path`; throws on failure.
void writeSample(const std::string& path, const SampleData& sample);

// A monodisperse random packing (r = 0.3 mm in 8 x 5 x 5 mm, about 500
// particles) with a planted through crack over `steps` steps and `scatter` of
// the other bonds broken at random (dem::PlantedCrack), written to `path`;
// throws on failure.
void writePlantedRandomPacking(const std::string& path, int steps, double scatter = 0.002);

// An FCC block (radius 1 mm, `sites` per axis) with a planted through crack
// and no scattered damage: at the last step the right half has moved one
// bond length (2 mm) along x. Written to `path`; throws on failure.
SampleData writePlantedLattice(const std::string& path, int steps,
                               std::array<int, 3> sites = {13, 9, 9});

// Whether two arrays hold the same bytes (NaN payloads and -0.0 included):
// what a round trip through a file must keep.
template <typename T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  // memcmp may not be given the null data() of empty vectors, even for 0 bytes.
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Shorthand: makeSample + writeSample.
SampleData writeSampleFile(const std::string& path, int dimension = 3, int steps = 3);

}  // namespace crackvis::testing
