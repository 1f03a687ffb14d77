// Bond strengths R_n drawn from a seeded, shifted (three-parameter) Weibull
// distribution of the bond strain at break, so that fracture is scattered and
// the same seed gives the same lattice on every platform.
//
//   eps_break = minStrain + scaleStrain * (-ln U)^(1 / shape),  U uniform in (0, 1]
//   R_n       = k_n * L0 * eps_break
//
// A strain, not a force, is the random variable: a scaled preset (larger
// particles) then breaks at the same macroscopic strain as the full one.
#pragma once

#include <cstdint>
#include <vector>

#include <crackvis/common/random.hpp>
#include <crackvis/common/status.hpp>

namespace crackvis::sim {

struct StrengthDistribution {
  double minStrain = 0.0;    // threshold: no bond breaks below this strain
  double scaleStrain = 1.0;  // Weibull scale of the strain above the threshold
  double shape = 2.0;        // Weibull modulus m; smaller is more scattered

  double mean() const;  // expected strain at break
};

Status validate(const StrengthDistribution& distribution);

// One strain at break per bond, in bond order, from `seed`.
std::vector<double> drawBreakStrains(const StrengthDistribution& distribution, std::size_t count,
                                     std::uint64_t seed);

}  // namespace crackvis::sim
