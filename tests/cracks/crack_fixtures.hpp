// Lattices with planted cracks whose crack surfaces geometry can predict.
#pragma once

#include <cmath>
#include <functional>
#include <span>
#include <vector>

#include <catch2/catch.hpp>

#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/dem/lattice_generator.hpp>

namespace crackvis::testing {

// The largest component's coverage of the specimen's section by its
// best-fit plane (sectionCoverage).
inline double largestCoverage(const cracks::CrackMesh& mesh, std::span<const dem::Vec3> positions,
                              std::span<const double> radius) {
  const cracks::CrackComponents set = cracks::findComponents(mesh);
  REQUIRE(!set.components.empty());
  return cracks::sectionCoverage(mesh, set, 0, positions, radius);
}

// The bond states of a crack through the plane x = cut: every bond whose
// ends lie on both sides is broken.
inline std::vector<std::uint8_t> bondsAcross(const std::vector<dem::Bond>& bonds,
                                             const std::vector<dem::Vec3>& positions, double cut) {
  std::vector<std::uint8_t> state(bonds.size(), 0);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const double xa = positions[static_cast<std::size_t>(bonds[b].first)].x;
    const double xb = positions[static_cast<std::size_t>(bonds[b].second)].x;
    state[b] = (xa - cut) * (xb - cut) < 0.0 ? 1 : 0;
  }
  return state;
}

struct PlantedCrack {
  dem::LatticeBlock block;
  std::vector<std::uint8_t> state;
  std::unique_ptr<cracks::BondGraph> graph;

  cracks::StepInput input() const {
    return {block.positions, state, block.lattice.radius, {}, {}, {}, {}, {}};
  }
  std::size_t brokenCount() const {
    return static_cast<std::size_t>(std::count(state.begin(), state.end(), 1));
  }
};

// A lattice block (radius 0.5, so d = 1) with every bond for which
// `crosses(x_first, x_second)` holds broken.
inline PlantedCrack plantCrack(dem::LatticeKind kind, std::array<int, 3> sites,
                               const std::function<bool(dem::Vec3, dem::Vec3)>& crosses,
                               double jitter = 0.0, std::uint64_t seed = 1) {
  dem::BlockSpec spec;
  spec.kind = kind;
  spec.sites = sites;
  spec.radius = 0.5;
  spec.jitter = jitter;
  spec.seed = seed;
  PlantedCrack crack{std::move(dem::generateBlock(spec)).value(), {}, nullptr};
  const auto& bonds = crack.block.lattice.bonds;
  crack.state.assign(bonds.size(), 0);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    crack.state[b] = crosses(crack.block.positions[static_cast<std::size_t>(bonds[b].first)],
                             crack.block.positions[static_cast<std::size_t>(bonds[b].second)])
                         ? 1
                         : 0;
  }
  crack.graph = std::make_unique<cracks::BondGraph>(crack.block.lattice.particleCount(), bonds);
  return crack;
}

// FCC (cubic orientation, sites 2n+1 per axis) cut by the plane
// dot(normal, x) = offset; normal (1,1,1) gives a (111) plane, (1,0,0) a (100) plane.
inline PlantedCrack fccPlaneCrack(int cells, dem::Vec3 normal, double offset, double jitter = 0.0) {
  return plantCrack(
      dem::LatticeKind::kFcc, dem::fccUnitCells(cells, cells, cells),
      [=](dem::Vec3 a, dem::Vec3 b) {
        return (dem::dot(normal, a) - offset) * (dem::dot(normal, b) - offset) < 0.0;
      },
      jitter);
}

}  // namespace crackvis::testing
