#include <cmath>

#include <fmt/format.h>

#include <crackvis/sim/strength.hpp>

namespace crackvis::sim {

double StrengthDistribution::mean() const {
  return minStrain + scaleStrain * std::tgamma(1.0 + 1.0 / shape);
}

Status validate(const StrengthDistribution& distribution) {
  if (!(distribution.minStrain >= 0.0) || !std::isfinite(distribution.minStrain)) {
    return invalidArgument(
        fmt::format("strength threshold strain must be >= 0, got {}", distribution.minStrain));
  }
  if (!(distribution.scaleStrain > 0.0) || !std::isfinite(distribution.scaleStrain)) {
    return invalidArgument(
        fmt::format("strength scale strain must be > 0, got {}", distribution.scaleStrain));
  }
  if (!(distribution.shape > 0.0) || !std::isfinite(distribution.shape)) {
    return invalidArgument(fmt::format("Weibull shape must be > 0, got {}", distribution.shape));
  }
  return Status::ok();
}

std::vector<double> drawBreakStrains(const StrengthDistribution& distribution, std::size_t count,
                                     std::uint64_t seed) {
  SplitMix64 random(seed);
  std::vector<double> strains(count);
  const double exponent = 1.0 / distribution.shape;
  for (double& strain : strains) {
    const double u = random.uniformOpenClosed();
    strain = distribution.minStrain + distribution.scaleStrain * std::pow(-std::log(u), exponent);
  }
  return strains;
}

}  // namespace crackvis::sim
