// dem::PlantedCrack: the planted through crack exists whatever the site
// count. With an odd number of site planes along x a plane of particles lies
// on the block's middle; a cut there crossed no bond and planted nothing
// (the 1e7-particle block of tools/bench/scale.sh had no crack).
#include <algorithm>
#include <numeric>
#include <vector>

#include <catch2/catch.hpp>

#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/dem/planted_crack.hpp>

using namespace crackvis;
using namespace crackvis::dem;

namespace {

std::size_t findRoot(std::vector<std::size_t>& parent, std::size_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// The pieces the intact bonds hold together.
std::size_t pieceCount(const Lattice& lattice, const std::vector<std::uint8_t>& broken) {
  std::vector<std::size_t> parent(lattice.particleCount());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  for (std::size_t b = 0; b < lattice.bondCount(); ++b) {
    if (broken[b] == 0) {
      parent[findRoot(parent, static_cast<std::size_t>(lattice.bonds[b].first))] =
          findRoot(parent, static_cast<std::size_t>(lattice.bonds[b].second));
    }
  }
  std::size_t roots = 0;
  for (std::size_t i = 0; i < parent.size(); ++i) {
    roots += findRoot(parent, i) == i ? 1 : 0;
  }
  return roots;
}

}  // namespace

TEST_CASE("a planted crack cuts the block in two for odd and even site counts",
          "[dem][planted-crack]") {
  const int sites = GENERATE(9, 10, 11);
  BlockSpec block;
  block.kind = LatticeKind::kFcc;
  block.sites = {sites, 7, 7};
  block.radius = 0.5;
  auto generated = generateBlock(block);
  REQUIRE(generated.isOk());
  PlantedCrackSpec spec;
  spec.steps = 8;
  spec.scatter = 0.0;
  auto crack = PlantedCrack::create(generated->lattice, generated->positions, spec);
  REQUIRE(crack.isOk());
  INFO(sites << " site planes along x, cut at x = " << crack->cut());
  // No particle on the cut: every bond across it has an end on either side.
  for (const Vec3& p : generated->positions) {
    REQUIRE(std::abs(p.x - crack->cut()) > 1e-6);
  }
  // The crack starts intact, is through at 3/4 of the steps, and then the
  // intact bonds hold exactly two pieces, each about half the block.
  CHECK(pieceCount(generated->lattice, crack->step(0).bondState) == 1);
  const StepState last = crack->step(spec.steps);
  CHECK(std::count(last.bondState.begin(), last.bondState.end(), 1) > 0);
  CHECK(pieceCount(generated->lattice, last.bondState) == 2);
  const auto [lo, hi] = boundingBox(generated->positions);
  CHECK(crack->cut() > lo.x + 0.4 * (hi.x - lo.x));
  CHECK(crack->cut() < lo.x + 0.6 * (hi.x - lo.x));
}
