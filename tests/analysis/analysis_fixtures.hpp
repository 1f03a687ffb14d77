// Specimens whose cracks have known openings, slips and fragments: a lattice
// block with a planted through crack (dem::PlantedCrack) whose right half is
// moved by a known vector, extracted by a crack method.
#pragma once

#include <memory>
#include <vector>

#include <catch2/catch.hpp>

#include <crackvis/analysis/growth.hpp>
#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/dem/planted_crack.hpp>

namespace crackvis::testing {

struct MovedHalf {
  dem::LatticeBlock block;
  std::vector<dem::Vec3> positions;
  std::vector<std::uint8_t> state;
  std::unique_ptr<cracks::BondGraph> graph;
  cracks::CrackMesh mesh;
  double cut = 0.0;

  cracks::StepInput input() const {
    return {positions, state, block.lattice.radius, {}, {}, block.positions, {}, {}};
  }
};

// The planted crack's last step (every bond across the cut broken, no
// scattered damage) with the particles beyond the cut moved by `shift`,
// extracted by `method`.
inline MovedHalf movedHalf(dem::LatticeKind kind, std::array<int, 3> sites, dem::Vec3 shift,
                           cracks::Method method) {
  dem::BlockSpec spec;
  spec.kind = kind;
  spec.sites = sites;
  spec.radius = 0.5;
  MovedHalf out{dem::generateBlock(spec).value(), {}, {}, nullptr, {}, 0.0};
  dem::PlantedCrackSpec planted;
  planted.steps = 4;
  planted.scatter = 0.0;
  auto crack = dem::PlantedCrack::create(out.block.lattice, out.block.positions, planted);
  REQUIRE(crack);
  out.cut = crack->cut();
  out.state = crack->step(planted.steps).bondState;
  out.positions = out.block.positions;
  for (dem::Vec3& p : out.positions) {
    if (p.x > out.cut) {
      p = p + shift;
    }
  }
  const auto& bonds = out.block.lattice.bonds;
  out.graph = std::make_unique<cracks::BondGraph>(out.block.lattice.particleCount(), bonds);
  auto extractor = cracks::makeExtractor(method, *out.graph, dem::dimensionOf(kind));
  REQUIRE(extractor->extract(out.input(), out.mesh));
  return out;
}

}  // namespace crackvis::testing
