#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <crackvis/common/random.hpp>
#include <crackvis/dem/planted_crack.hpp>

namespace crackvis::dem {

namespace {

// The plane x = cut half way between the particles nearest the middle of
// [lo, hi] on either side. A lattice with an odd number of site planes has a
// plane of particles at the middle itself: a cut there would cross no bond
// (every bond would end on it) and plant no crack.
double cutBetweenPlanes(const std::vector<Vec3>& positions, double lo, double hi) {
  const double middle = 0.5 * (lo + hi);
  const double tolerance = 1e-9 * std::max(hi - lo, 1e-300);
  double below = lo;
  for (const Vec3& p : positions) {
    below = p.x <= middle + tolerance ? std::max(below, p.x) : below;
  }
  double above = hi;
  for (const Vec3& p : positions) {
    above = p.x > below + tolerance ? std::min(above, p.x) : above;
  }
  return above > below ? 0.5 * (below + above) : middle;
}

}  // namespace

Result<PlantedCrack> PlantedCrack::create(const Lattice& lattice, std::vector<Vec3> initial,
                                          const PlantedCrackSpec& spec) {
  CRACKVIS_RETURN_IF_ERROR(validateTopology(lattice));
  if (initial.size() != lattice.particleCount() || initial.empty()) {
    return invalidArgument(
        fmt::format("{} positions for N = {} particles", initial.size(), lattice.particleCount()));
  }
  if (spec.steps < 1 || !(spec.opening >= 0.0) || !(spec.scatter >= 0.0 && spec.scatter < 0.5)) {
    return invalidArgument(
        "a planted crack needs steps >= 1, opening >= 0 and scatter in [0, 0.5)");
  }
  PlantedCrack crack;
  crack.m_lattice = &lattice;
  crack.m_initial = std::move(initial);
  crack.m_spec = spec;
  const auto [lo, hi] = boundingBox(crack.m_initial);
  crack.m_cut = cutBetweenPlanes(crack.m_initial, lo.x, hi.x);
  crack.m_up = lattice.dimension == 2 ? 1 : 2;
  crack.m_bottom = component(lo, crack.m_up);
  crack.m_height = std::max(component(hi, crack.m_up) - crack.m_bottom, 1e-300);
  SplitMix64 random(spec.seed);
  crack.m_breakStep.assign(lattice.bondCount(), 0);
  double length = 0.0;
  const int frontSteps = std::max(1, (3 * spec.steps) / 4);
  for (std::size_t b = 0; b < lattice.bondCount(); ++b) {
    const Vec3 a = crack.m_initial[static_cast<std::size_t>(lattice.bonds[b].first)];
    const Vec3 c = crack.m_initial[static_cast<std::size_t>(lattice.bonds[b].second)];
    length += norm(c - a) / static_cast<double>(lattice.bondCount());
    const double u = 0.5 * (random.symmetric() + 1.0);
    if ((a.x - crack.m_cut) * (c.x - crack.m_cut) < 0.0) {
      const double height =
          (component(0.5 * (a + c), crack.m_up) - crack.m_bottom) / crack.m_height;
      crack.m_breakStep[b] =
          1 + std::clamp(static_cast<int>(height * (frontSteps - 1)), 0, frontSteps - 1);
    } else if (u < spec.scatter) {
      crack.m_breakStep[b] = 1 + static_cast<int>(u / spec.scatter * (spec.steps - 1));
    }
  }
  crack.m_bondLength = length;
  return crack;
}

StepState PlantedCrack::step(int k) const {
  StepState state;
  state.time = static_cast<double>(k);
  state.positions = m_initial;
  const double shift = m_spec.opening * m_bondLength * static_cast<double>(k) / m_spec.steps;
  for (Vec3& p : state.positions) {
    p.x += p.x > m_cut ? shift : 0.0;
  }
  state.bondState.resize(m_breakStep.size());
  for (std::size_t b = 0; b < m_breakStep.size(); ++b) {
    state.bondState[b] = m_breakStep[b] > 0 && m_breakStep[b] <= k ? 1 : 0;
  }
  return state;
}

}  // namespace crackvis::dem
