// Crack surfaces on packings that are no lattice (issue 15): a dense random
// packing, monodisperse and polydisperse 1:2, with a planted through crack
// (every bond crossing the mid-plane x = L/2 broken). Each method (cell
// attribute's cells in projection) must cover
// the specimen's cross-section there with one piece, not return fragments,
// and map the broken bonds to faces (sectionCoverage and mapBrokenBonds,
// whose geometry tests/cracks/crack_components.test.cpp checks).
#include <algorithm>
#include <cmath>

#include <catch2/catch.hpp>

#include "crack_fixtures.hpp"
#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/bond_mapping.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/metrics.hpp>
#include <crackvis/cracks/triangulation.hpp>
#include <crackvis/dem/planted_crack.hpp>
#include <crackvis/dem/random_packing.hpp>

using namespace crackvis;
using namespace crackvis::cracks;

namespace {

dem::RandomPacking makePacking(double rmin, double rmax, std::uint64_t seed = 7) {
  dem::RandomPackingSpec spec;
  spec.box = {0.02, 0.012, 0.012};
  spec.radiusMin = rmin;
  spec.radiusMax = rmax;
  spec.solidFraction = 0.58;
  spec.seed = seed;
  auto packing = dem::generateRandomPacking(spec);
  REQUIRE(packing.isOk());
  return std::move(packing).value();
}

// Every bond whose segment crosses x = cut.
std::vector<std::uint8_t> throughCrack(const dem::RandomPacking& packing, double cut) {
  return testing::bondsAcross(packing.lattice.bonds, packing.positions, cut);
}

// The largest component's coverage of the section by its best-fit plane.
double coverage(const CrackMesh& mesh, const dem::RandomPacking& packing) {
  return testing::largestCoverage(mesh, packing.positions, packing.lattice.radius);
}

}  // namespace

TEST_CASE("a random packing is dense, does not overlap, and comes from its seed",
          "[cracks][packing]") {
  for (const auto& [rmin, rmax] : {std::pair{3e-4, 3e-4}, std::pair{2.5e-4, 5e-4}}) {
    DYNAMIC_SECTION("radii " << rmin << " .. " << rmax) {
      const dem::RandomPacking packing = makePacking(rmin, rmax);
      CHECK(packing.solidFraction == Approx(0.58).margin(0.01));
      CHECK(packing.largestOverlap <= 0.01 * rmin);
      const auto [lo, hi] =
          std::minmax_element(packing.lattice.radius.begin(), packing.lattice.radius.end());
      CHECK(*lo >= rmin);
      CHECK(*hi <= rmax);
      if (rmax > rmin) {
        CHECK(*hi - *lo > 0.8 * (rmax - rmin));  // the range is used, not one size
      }
      const double coordination = 2.0 * static_cast<double>(packing.lattice.bondCount()) /
                                  static_cast<double>(packing.lattice.particleCount());
      CHECK(coordination > 6.0);
      CHECK(coordination < 11.0);
      for (std::size_t i = 0; i < packing.positions.size(); ++i) {
        const double r = packing.lattice.radius[i];
        const dem::Vec3 p = packing.positions[i];
        REQUIRE(p.x >= r - 1e-12);
        REQUIRE(p.x <= 0.02 - r + 1e-12);
      }
      const dem::RandomPacking again = makePacking(rmin, rmax);
      CHECK(again.positions == packing.positions);
      CHECK(again.lattice.bonds == packing.lattice.bonds);
      CHECK(makePacking(rmin, rmax, 8).positions != packing.positions);
    }
  }
  SECTION("a packing denser than random spheres can be is refused") {
    dem::RandomPackingSpec spec;
    spec.solidFraction = 0.7;
    const auto refused = dem::generateRandomPacking(spec);
    REQUIRE(!refused.isOk());
    CHECK(refused.status().message().find("solid fraction 0.7") != std::string::npos);
  }
}

TEST_CASE("every method covers a through crack in a random packing", "[cracks][packing]") {
  for (const auto& [rmin, rmax] : {std::pair{3e-4, 3e-4}, std::pair{2.5e-4, 5e-4}}) {
    const dem::RandomPacking packing = makePacking(rmin, rmax);
    const BondGraph graph(packing.lattice.particleCount(), packing.lattice.bonds);
    REQUIRE_FALSE(isLatticeGraph(graph, 3));
    const auto state = throughCrack(packing, 0.01);
    for (Method method :
         {Method::kCellAttribute, Method::kCellCut, Method::kLocalVoronoi, Method::kCellCentre}) {
      DYNAMIC_SECTION(toString(method) << ", radii " << rmin << " .. " << rmax) {
        auto extractor = makeExtractor(method, graph, 3);
        CrackMesh mesh;
        const StepInput step{packing.positions, state, packing.lattice.radius, {}, {}, {}, {}, {}};
        REQUIRE(extractor->extract(step, mesh).isOk());
        CHECK(extractor->decompositionKind() == Decomposition::kTriangulation);
        const SurfaceMetrics metrics =
            computeMetrics(mesh, packing.positions, packing.lattice.radius);
        const double covered = coverage(mesh, packing);
        const BondMapping mapping = mapBrokenBonds(mesh, state, *extractor);
        CHECK(mapping.broken ==
              static_cast<std::size_t>(std::count(state.begin(), state.end(), 1)));
        CHECK(mapping.fraction() >= (method == Method::kLocalVoronoi ? 0.95 : 0.99));
        CHECK(findComponents(mesh).components.front().normal.x == Approx(1.0).margin(0.05));
        // The bonds between the halves are exactly the planted ones, and the
        // main crack they make lies in the largest component.
        const auto separating = separatingBonds(graph, state);
        CHECK(separating == state);
        const MainCrack main = measureMainCrack(mesh, separating, *extractor);
        CHECK(main.mapped.fraction() == Approx(mapping.fraction()));
        CHECK(main.largestShare >= 0.99);
        INFO("coverage " << covered << ", components " << metrics.components << ", inconsistent "
                         << metrics.inconsistentBonds);
        // Cell attribute's cells cover the section in projection; the
        // surfaces reach the hull of the centres the plane cuts, cell cut's
        // to the midpoints of the outermost cut bonds, a little inside it.
        CHECK(covered >= 0.95);
        // One surface. Cell attribute's cells are joined by shared faces,
        // and one at the specimen's side may stand alone where the hull's
        // slivers that joined it to the rest are peeled (one cell of 1,777,
        // 1.9 % of the area, with the unequal radii): a crumb, not a second
        // crack.
        if (method == Method::kCellAttribute) {
          const auto parts = findComponents(mesh).components;
          REQUIRE_FALSE(parts.empty());
          double crumbs = 0.0;
          for (std::size_t k = 1; k < parts.size(); ++k) {
            CHECK(parts[k].primitives <= 2);
            crumbs += parts[k].area;
          }
          CHECK(crumbs < 0.05 * parts.front().area);
        } else {
          CHECK(metrics.components == 1);
        }
        // A few faces of neighbour pairs at the specimen's surface lie
        // outside the domain even with its margin.
        const auto broken = static_cast<double>(std::count(state.begin(), state.end(), 1));
        CHECK(static_cast<double>(metrics.inconsistentBonds) <= 0.05 * broken);
        // The lattice cells the bonds span leave most of the section open:
        // what the methods gave before the triangulation.
        ExtractOptions lattice;
        lattice.decomposition = Decomposition::kLattice;
        auto latticeExtractor = makeExtractor(method, graph, 3, lattice);
        CrackMesh fragments;
        REQUIRE(latticeExtractor->extract(step, fragments).isOk());
        CHECK(coverage(fragments, packing) < 0.8);
        // ... and the run says so, naming the cause.
        const BondMapping few = mapBrokenBonds(fragments, state, *latticeExtractor);
        CHECK(few.fraction() < kMappedWarning);
        CHECK_THAT(
            diagnoseMapping(few, *latticeExtractor, graph, 3, packing.lattice.radius, lattice),
            Catch::Contains("span no lattice"));
      }
    }
  }
}

TEST_CASE("lattices keep their own cells", "[cracks][packing]") {
  // An FCC block is recognised from its bonds alone, and a random packing is not.
  std::vector<dem::Vec3> positions;
  for (int k = 0; k < 7; ++k) {
    for (int j = 0; j < 7; ++j) {
      for (int i = 0; i < 7; ++i) {
        if ((i + j + k) % 2 == 0) {
          positions.push_back(
              {0.5 + i * std::sqrt(0.5), 0.5 + j * std::sqrt(0.5), 0.5 + k * std::sqrt(0.5)});
        }
      }
    }
  }
  const std::vector<double> radius(positions.size(), 0.5);
  const auto bonds = dem::interactionRangeBonds(positions, radius, 1.01);
  const BondGraph fcc(positions.size(), bonds);
  CHECK(isLatticeGraph(fcc, 3));
}

TEST_CASE("auto takes the decomposition a file records, a chosen one and an unrecorded stay",
          "[cracks][packing]") {
  using dem::CellDecomposition;
  CHECK(settledByFile(Decomposition::kAuto, CellDecomposition::kLattice) ==
        Decomposition::kLattice);
  CHECK(settledByFile(Decomposition::kAuto, CellDecomposition::kTriangulation) ==
        Decomposition::kTriangulation);
  CHECK(settledByFile(Decomposition::kAuto, CellDecomposition::kUnknown) == Decomposition::kAuto);
  for (const Decomposition chosen : {Decomposition::kLattice, Decomposition::kTriangulation}) {
    for (const CellDecomposition recorded :
         {CellDecomposition::kLattice, CellDecomposition::kTriangulation,
          CellDecomposition::kUnknown}) {
      CHECK(settledByFile(chosen, recorded) == chosen);
    }
  }
}

TEST_CASE("a planted crack runs across the mid-plane, opens, and scatters isolated breaks",
          "[cracks][packing]") {
  const dem::RandomPacking packing = makePacking(3e-4, 3e-4);
  dem::PlantedCrackSpec spec;
  spec.steps = 20;
  auto crack = dem::PlantedCrack::create(packing.lattice, packing.positions, spec);
  REQUIRE(crack.isOk());
  CHECK(crack->stepCount() == 21);
  CHECK(crack->step(0).brokenBondCount() == 0);
  CHECK(crack->step(0).positions == packing.positions);
  const auto crossing = throughCrack(packing, crack->cut());
  const auto last = crack->step(20);
  std::size_t scattered = 0;
  std::size_t previous = 0;
  for (int k = 1; k <= 20; ++k) {
    const std::size_t broken = crack->step(k).brokenBondCount();
    CHECK(broken >= previous);  // never heals
    previous = broken;
  }
  for (std::size_t b = 0; b < crossing.size(); ++b) {
    if (crossing[b] != 0) {
      REQUIRE(last.bondState[b] == 1);
      REQUIRE(crack->step(15).bondState[b] == 1);  // the front is through at 3/4
    } else {
      scattered += last.bondState[b];
    }
  }
  const double fraction =
      static_cast<double>(scattered) / static_cast<double>(packing.lattice.bondCount());
  CHECK(fraction == Approx(0.002).margin(0.0015));
  // The right half moved away by about one bond length.
  for (std::size_t i = 0; i < packing.positions.size(); ++i) {
    const double moved = last.positions[i].x - packing.positions[i].x;
    REQUIRE(moved == Approx(packing.positions[i].x > crack->cut() ? 6.3e-4 : 0.0).margin(1.5e-4));
  }
}

TEST_CASE("a particle with more than 256 neighbours: its cells are left out, none is garbled",
          "[cracks][packing]") {
  // A centre bonded to 300 particles on a sphere around it: the fan a
  // triangulation's hull can make. A cell stores its edges' bonds as byte
  // slots in its nodes' bond lists, so the centre's cells beyond slot 255
  // are left out and counted; before, they read other bonds' states.
  std::vector<dem::Vec3> positions{{0.0, 0.0, 0.0}};
  const int count = 300;
  for (int k = 0; k < count; ++k) {  // a Fibonacci sphere
    const double z = 1.0 - 2.0 * (k + 0.5) / count;
    const double phi = 2.399963229728653 * k;
    const double rho = std::sqrt(1.0 - z * z);
    positions.push_back({rho * std::cos(phi), rho * std::sin(phi), z});
  }
  std::vector<dem::Bond> bonds;
  std::vector<std::uint8_t> state;
  for (int k = 1; k <= count; ++k) {
    bonds.push_back({0, k});
    state.push_back(k % 3 == 0 ? 1 : 0);  // a period that 256 is no multiple of
  }
  const std::vector<double> radius(positions.size(), 0.05);
  const BondGraph graph(positions.size(), bonds);
  for (Method method :
       {Method::kCellAttribute, Method::kCellCut, Method::kLocalVoronoi, Method::kCellCentre}) {
    DYNAMIC_SECTION(toString(method)) {
      auto extractor = makeExtractor(method, graph, 3);
      CrackMesh mesh;
      REQUIRE(extractor->extract({positions, state, radius, {}, {}, {}, {}, {}}, mesh).isOk());
      if (method != Method::kLocalVoronoi) {
        REQUIRE(extractor->decomposition() != nullptr);
        CHECK(extractor->decomposition()->skippedCells() > 0);
      }
      const auto points = static_cast<std::int32_t>(mesh.points.size());
      for (const PrimitiveList* list : {&mesh.lines, &mesh.polygons, &mesh.volumeCells}) {
        for (std::int32_t id : list->connectivity) {
          REQUIRE(id >= 0);
          REQUIRE(id < points);
        }
      }
      // Cell cut's points are midpoints of broken bonds only.
      if (const AttributeArray* ids = mesh.findPointData("bond_id")) {
        for (double id : ids->values) {
          if (id >= 0.0) {
            REQUIRE(state[static_cast<std::size_t>(id)] == 1);
          }
        }
      }
    }
  }
}

namespace {

// The volume VTK gives a cell (vtkTetra::ComputeVolume's sign convention; a
// pyramid as the tetrahedra 0 1 2 4 and 0 2 3 4), times 6.
double vtkSignedVolume(const CrackMesh& mesh, std::size_t cell) {
  const auto begin = static_cast<std::size_t>(mesh.volumeCells.offsets[cell]);
  auto at = [&](std::size_t k) {
    return mesh.points[static_cast<std::size_t>(mesh.volumeCells.connectivity[begin + k])];
  };
  auto tet = [](dem::Vec3 a, dem::Vec3 b, dem::Vec3 c, dem::Vec3 d) {
    return dem::dot(b - a, cross(c - a, d - a));
  };
  if (mesh.volumeCellTypes[cell] == 10) {
    return tet(at(0), at(1), at(2), at(3));
  }
  return tet(at(0), at(1), at(2), at(4)) + tet(at(0), at(2), at(3), at(4));
}

void requireRightSideOut(const CrackMesh& mesh) {
  REQUIRE(mesh.volumeCellTypes.size() > 0);
  std::size_t insideOut = 0;
  for (std::size_t c = 0; c < mesh.volumeCellTypes.size(); ++c) {
    insideOut += vtkSignedVolume(mesh, c) > 0.0 ? 0 : 1;
  }
  INFO(insideOut << " of " << mesh.volumeCellTypes.size() << " cells inside out");
  CHECK(insideOut == 0);
}

}  // namespace

TEST_CASE("cell attribute's cells are right side out, as VTK counts volume", "[cracks][packing]") {
  // Before, a tetrahedron's nodes came in particle order and about half had
  // a negative volume in ParaView.
  SECTION("FCC lattice: tetrahedra and the pyramids of octahedra") {
    const testing::PlantedCrack crack =
        testing::fccPlaneCrack(4, {1, 0, 0}, 0.5 + 3.5 / std::sqrt(2.0));
    auto extractor = makeExtractor(Method::kCellAttribute, *crack.graph, 3);
    CrackMesh mesh;
    REQUIRE(extractor->extract(crack.input(), mesh).isOk());
    CHECK(std::count(mesh.volumeCellTypes.begin(), mesh.volumeCellTypes.end(), 14) > 0);
    requireRightSideOut(mesh);
  }
  SECTION("random packing: the triangulation's tetrahedra") {
    const dem::RandomPacking packing = makePacking(2.5e-4, 5e-4);
    const BondGraph graph(packing.lattice.particleCount(), packing.lattice.bonds);
    const auto state = throughCrack(packing, 0.01);
    auto extractor = makeExtractor(Method::kCellAttribute, graph, 3);
    CrackMesh mesh;
    const StepInput step{packing.positions, state, packing.lattice.radius, {}, {}, {}, {}, {}};
    REQUIRE(extractor->extract(step, mesh).isOk());
    requireRightSideOut(mesh);
  }
}

TEST_CASE("a cell's reach is its circumradius, or its power radius widened by the largest weight",
          "[cracks][packing][triangulation]") {
  const std::vector<dem::Vec3> tetrahedron{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  SECTION("equal radii: the circumsphere") {
    const std::vector<double> radius(4, 0.1);
    auto triangulation = cracks::triangulate(tetrahedron, radius, 3);
    REQUIRE(triangulation.isOk());
    REQUIRE(triangulation->cells.size() == 1);
    CHECK_FALSE(triangulation->weighted);
    const auto reach = cracks::cellReach(*triangulation, tetrahedron, radius, 0.1);
    CHECK(reach.at(0) == Approx(std::sqrt(0.75)).epsilon(1e-12));
  }
  SECTION("unequal radii: the power centre (0.485, 0.5, 0.5), power 0.725225, plus 0.2^2") {
    const std::vector<double> radius{0.1, 0.2, 0.1, 0.1};
    auto triangulation = cracks::triangulate(tetrahedron, radius, 3);
    REQUIRE(triangulation.isOk());
    REQUIRE(triangulation->cells.size() == 1);
    CHECK(triangulation->weighted);
    const auto reach = cracks::cellReach(*triangulation, tetrahedron, radius, 0.2);
    CHECK(reach.at(0) == Approx(std::sqrt(0.725225 + 0.04)).epsilon(1e-12));
    // A piece triangulates as the whole set does, whatever its own radii.
    auto forced =
        cracks::triangulate(tetrahedron, std::vector<double>(4, 0.1), 3, {.weighted = true});
    REQUIRE(forced.isOk());
    CHECK(forced->weighted);
  }
  SECTION("a triangle in 2D: its circumcircle") {
    const std::vector<dem::Vec3> triangle{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
    const std::vector<double> radius(3, 0.1);
    auto triangulation = cracks::triangulate(triangle, radius, 2);
    REQUIRE(triangulation.isOk());
    REQUIRE(triangulation->cells.size() == 1);
    const auto reach = cracks::cellReach(*triangulation, triangle, radius, 0.1);
    CHECK(reach.at(0) == Approx(std::sqrt(2.0)).epsilon(1e-12));
    // Unequal radii: the power centre (0.9925, 1), power 1.97505625, plus 0.2^2.
    const std::vector<double> unequal{0.1, 0.2, 0.1};
    auto regular = cracks::triangulate(triangle, unequal, 2);
    REQUIRE(regular.isOk());
    REQUIRE(regular->cells.size() == 1);
    CHECK(regular->weighted);
    const auto power = cracks::cellReach(*regular, triangle, unequal, 0.2);
    CHECK(power.at(0) == Approx(std::sqrt(1.97505625 + 0.04)).epsilon(1e-12));
  }
}
