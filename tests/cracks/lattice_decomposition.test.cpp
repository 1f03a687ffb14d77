#include <algorithm>
#include <set>

#include <catch2/catch.hpp>

#include "crack_fixtures.hpp"
#include <crackvis/cracks/lattice_decomposition.hpp>

using namespace crackvis;
using namespace crackvis::cracks;

namespace {

double cellVolume(const LatticeCell& cell, const std::vector<dem::Vec3>& x) {
  auto tet = [&](int a, int b, int c, int d) {
    const auto p = [&](int k) {
      return x[static_cast<std::size_t>(cell.nodes[static_cast<std::size_t>(k)])];
    };
    return std::abs(dem::dot(p(b) - p(a), cross(p(c) - p(a), p(d) - p(a)))) / 6.0;
  };
  return cell.type == CellType::kTetrahedron ? tet(0, 1, 2, 3) : tet(0, 1, 2, 4) + tet(0, 2, 3, 4);
}

std::set<std::vector<int>> cellSet(const LatticeDecomposition& decomposition) {
  std::set<std::vector<int>> result;
  for (const LatticeCell& cell : decomposition.cells()) {
    std::vector<int> key(cell.nodes.begin(), cell.nodes.begin() + cell.nodeCount());
    key.push_back(static_cast<int>(cell.type));
    result.insert(key);
  }
  return result;
}

}  // namespace

TEST_CASE("global FCC decomposition: 8 tetrahedra per cubic cell and the complete octahedra",
          "[cracks][decomposition]") {
  // Octahedral holes are the sites (i, j, k) with i + j + k odd (in units of
  // a/2); an octahedron is complete when all six neighbours are in the block,
  // i.e. for holes in [1, 2n-1]^3: n^3 with three odd coordinates plus
  // 3 n (n-1)^2 with one odd. Tetrahedral holes: 8 per cubic cell.
  const int n = GENERATE(1, 2, 3);
  auto crack = testing::fccPlaneCrack(n, {1, 0, 0}, -1.0);  // nothing broken
  LatticeDecomposition decomposition(*crack.graph, 3);
  decomposition.buildGlobal(crack.state);
  std::size_t tets = 0;
  std::size_t pyramids = 0;
  double volume = 0.0;
  for (const LatticeCell& cell : decomposition.cells()) {
    (cell.type == CellType::kTetrahedron ? tets : pyramids) += 1;
    volume += cellVolume(cell, crack.block.positions);
    for (int e = 0; e < cell.edgeCount(); ++e) {
      // Each edge's bond joins the edge's two particles.
      const dem::Bond bond = crack.graph->bond(decomposition.bondOf(cell, e));
      const auto& edge = shapeOf(cell.type).edges[static_cast<std::size_t>(e)];
      REQUIRE(std::minmax(bond.first, bond.second) ==
              std::minmax(cell.nodes[edge[0]], cell.nodes[edge[1]]));
    }
  }
  CHECK(tets == static_cast<std::size_t>(8 * n * n * n));
  CHECK(pyramids == static_cast<std::size_t>(2 * (n * n * n + 3 * n * (n - 1) * (n - 1))));
  // Tetrahedron (a/2)^3 / 3, octahedron (a/2)^3 * 4/3, with a = sqrt(2).
  const double h3 = std::pow(std::sqrt(2.0) / 2.0, 3);
  CHECK(volume == Approx(tets * h3 / 3.0 + pyramids / 2.0 * h3 * 4.0 / 3.0).epsilon(1e-12));
}

TEST_CASE("each cell knows its bonds and each interior bond its cells", "[cracks][decomposition]") {
  auto crack = testing::fccPlaneCrack(3, {1, 0, 0}, -1.0);
  LatticeDecomposition decomposition(*crack.graph, 3);
  decomposition.buildGlobal(crack.state);
  const dem::Vec3 centre = 0.5 * crack.block.extent;
  std::vector<CellIndex> cells;
  int interior = 0;
  for (std::size_t b = 0; b < crack.graph->bondCount(); ++b) {
    const dem::Bond& bond = crack.graph->bond(static_cast<dem::BondIndex>(b));
    const dem::Vec3 mid =
        0.5 * (crack.block.positions[bond.first] + crack.block.positions[bond.second]);
    decomposition.cellsOfBond(static_cast<dem::BondIndex>(b), cells);
    for (CellIndex c : cells) {
      const auto& cell = decomposition.cell(c);
      int holds = 0;
      for (int e = 0; e < cell.edgeCount(); ++e) {
        holds += decomposition.bondOf(cell, e) == static_cast<int>(b) ? 1 : 0;
      }
      REQUIRE(holds == 1);
    }
    if (dem::norm(mid - centre) < 1.0) {
      ++interior;
      // Around an FCC bond: 2 tetrahedra and 2 octahedra (as 2 to 4 pyramids).
      const auto tets = std::count_if(cells.begin(), cells.end(), [&](CellIndex c) {
        return decomposition.cell(c).type == CellType::kTetrahedron;
      });
      CHECK(tets == 2);
      CHECK(cells.size() - static_cast<std::size_t>(tets) >= 2);
      CHECK(cells.size() - static_cast<std::size_t>(tets) <= 4);
    }
  }
  CHECK(interior > 0);
}

TEST_CASE("incremental and from-scratch local decompositions have identical cells",
          "[cracks][decomposition]") {
  // A crack front advancing through a jittered block, step by step.
  auto crack = testing::fccPlaneCrack(4, {1, 1, 1}, 0.0, 0.1);
  const auto& x = crack.block.positions;
  const double plane = dem::dot(dem::Vec3{1, 1, 1}, 0.5 * crack.block.extent) + 0.2;
  LatticeDecomposition incremental(*crack.graph, 3);
  std::vector<std::uint8_t> state(crack.graph->bondCount(), 0);
  for (int step = 0; step < 6; ++step) {
    const double front = -1.0 + 1.2 * step;  // grows along x
    for (std::size_t b = 0; b < state.size(); ++b) {
      const dem::Bond& bond = crack.graph->bond(static_cast<dem::BondIndex>(b));
      const dem::Vec3 a = x[bond.first];
      const dem::Vec3 c = x[bond.second];
      const bool crosses = (dem::dot({1, 1, 1}, a) - plane) * (dem::dot({1, 1, 1}, c) - plane) < 0;
      if (crosses && std::min(a.x, c.x) < front) {
        state[b] = 1;
      }
    }
    incremental.update(state);
    LatticeDecomposition scratch(*crack.graph, 3);
    scratch.update(state);
    REQUIRE(cellSet(incremental) == cellSet(scratch));
    // Broken masks agree with the state, and every broken bond is covered.
    std::set<int> covered;
    for (const LatticeCell& cell : incremental.cells()) {
      for (int e = 0; e < cell.edgeCount(); ++e) {
        const auto b = static_cast<std::size_t>(incremental.bondOf(cell, e));
        REQUIRE(((cell.brokenMask >> e) & 1u) == state[b]);
        if (state[b]) {
          covered.insert(static_cast<int>(b));
        }
      }
    }
    CHECK(covered.size() == static_cast<std::size_t>(std::count(state.begin(), state.end(), 1)));
  }
  CHECK(incremental.cellCount() > 0);
}

TEST_CASE("stepping back in time clears the masks of healed bonds", "[cracks][decomposition]") {
  auto crack = testing::fccPlaneCrack(2, {1, 0, 0}, 1.5);
  LatticeDecomposition decomposition(*crack.graph, 3);
  decomposition.update(crack.state);
  const std::size_t cells = decomposition.cellCount();
  std::vector<std::uint8_t> intact(crack.state.size(), 0);
  const auto& changed = decomposition.update(intact);
  CHECK(changed.size() == crack.brokenCount());
  CHECK(decomposition.cellCount() == cells);  // cells stay
  for (const LatticeCell& cell : decomposition.cells()) {
    REQUIRE(cell.brokenMask == 0);
  }
}

TEST_CASE("2D decomposition: the triangles of the triangular lattice", "[cracks][decomposition]") {
  auto crack = testing::plantCrack(dem::LatticeKind::kTriangular, {6, 5, 1},
                                   [](dem::Vec3, dem::Vec3) { return false; });
  LatticeDecomposition decomposition(*crack.graph, 2);
  decomposition.buildGlobal(crack.state);
  // nx by ny sites: the 2 nx - 1 bonds between two staggered rows zigzag
  // through 2 nx - 2 triangles, so (ny - 1)(2 nx - 2) in all. Euler's formula
  // agrees: V - E + F = 30 - (5*5 + 4*11) + 40 = 1 for a triangulated disc.
  CHECK(decomposition.cellCount() == static_cast<std::size_t>(4 * (2 * 6 - 2)));
  for (const LatticeCell& cell : decomposition.cells()) {
    REQUIRE(cell.type == CellType::kTriangle);
  }
}
