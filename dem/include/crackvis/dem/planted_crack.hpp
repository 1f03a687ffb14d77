// A planted through crack over a series of steps, for benchmarks and tests
// that need a known main crack in any specimen (a random packing has no
// lattice plane to break along): the bonds across the mid-plane x (moved half
// way to the next particle plane where particles lie on it) break from
// the bottom face (z in 3D, y in 2D) upwards as a front that reaches the top
// at 3/4 of the steps; meanwhile the right half moves away along x, up to
// `opening` mean bond lengths at the last step; and isolated bonds anywhere
// break at random (scattered damage, `scatter` of the bonds by the end).
// Deterministic from the seed.
#pragma once

#include <cstdint>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::dem {

struct PlantedCrackSpec {
  int steps = 200;       // saved steps after the intact step 0
  double opening = 1.0;  // mean bond lengths at the last step
  double scatter = 0.002;
  std::uint64_t seed = 1;
};

class PlantedCrack {
 public:
  static Result<PlantedCrack> create(const Lattice& lattice, std::vector<Vec3> initial,
                                     const PlantedCrackSpec& spec);
  int stepCount() const { return m_spec.steps + 1; }
  // Step k in 0 .. steps (0: intact, as given).
  StepState step(int k) const;
  // The plane x = cut the crack runs along.
  double cut() const { return m_cut; }

 private:
  PlantedCrack() = default;
  const Lattice* m_lattice = nullptr;
  std::vector<Vec3> m_initial;
  PlantedCrackSpec m_spec;
  double m_cut = 0.0;
  double m_bottom = 0.0;
  double m_height = 0.0;
  double m_bondLength = 0.0;
  int m_up = 2;
  std::vector<int> m_breakStep;  // per bond, 0: never
};

}  // namespace crackvis::dem
