// Planted plane cracks in undeformed lattices, where geometry gives every
// answer. Radius r = 0.5 and bond length d = 1 throughout.
//
// FCC, (111) plane: the crack separates two close-packed layers h = d sqrt(2/3)
// apart. Every bond crossing it makes angle theta with the normal, cos theta =
// h / d = sqrt(2/3), and its Voronoi face is tilted by the same angle, so the
// local Voronoi surface has sqrt(3/2) times the area of the plane it spans.
// Cell cut polygons lie in the mid-plane: area = cut area. Their cut depth:
//  - triangle (a tetrahedron with one particle across): the particle sits
//    above the triangle's centre at h/2 = r sqrt(2/3), depth r (1 - sqrt(2/3)) = 0.1835 r;
//  - quad (half of an octahedron's hexagonal mid-section): no particle projects
//    into it; the closest is at horizontal distance d/(4 sqrt 3) from its
//    edge and height h/2, distance r sqrt(3)/2, depth r (1 - sqrt(3)/2) = 0.1340 r.
// FCC, (100) planes: layers d/sqrt(2) apart, the cut plane r/sqrt(2) from
// the particles on both sides; crossing bonds at 45 degrees, so local Voronoi
// area = sqrt(2) x cut area. Which polygons appear depends on the plane and
// on the octahedra's split axis (the diagonal through their lowest particle
// index, z in a generated block):
//  - a particle whose projection falls inside its cut polygon (a pyramid's
//    cut-off apex: quad; a base particle cut off: triangle) is cut by
//    r (1 - 1/sqrt 2) = 0.2929 r;
//  - a tetrahedron split two and two gives a quad whose nearest particles lie
//    outside it, d/(4 sqrt 2) sideways: distance r sqrt(3)/2, depth 0.1340 r.
// So a plane normal to x (not the split axis) gives triangles at 0.2929 r and
// quads at 0.1340 r; a plane normal to z (the split axis) gives quads only,
// the deepest (apex) quads at 0.2929 r.
// Triangular lattice (2D), crack between two rows: rows d sqrt(3)/2 apart,
// cut depth r (1 - sqrt(3)/2); crossing bonds at 30 degrees to the normal,
// Voronoi edges total 2/sqrt(3) x the cut length.
#include <map>
#include <set>

#include <catch2/catch.hpp>

#include "crack_fixtures.hpp"
#include "window.hpp"
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/metrics.hpp>

using namespace crackvis;
using namespace crackvis::cracks;
using namespace crackvis::testing;

namespace {

constexpr double kR = 0.5;
constexpr double kTight = 1e-9;

CrackMesh run(Method method, const PlantedCrack& crack, ExtractOptions options = {}) {
  auto extractor = makeExtractor(method, *crack.graph, crack.block.lattice.dimension, options);
  CrackMesh mesh;
  REQUIRE(extractor->extract(crack.input(), mesh).isOk());
  return mesh;
}

SurfaceMetrics metricsOf(const CrackMesh& mesh, const PlantedCrack& crack) {
  return computeMetrics(mesh, crack.block.positions, crack.block.lattice.radius);
}

// The (111) plane halfway between layers i + j + k = 14 and 16 of an FCC
// block of 5 cells (site planes h = 1/sqrt(2) apart, first at r).
PlantedCrack fcc111() {
  const double h = 1.0 / std::sqrt(2.0);
  return fccPlaneCrack(5, {1, 1, 1}, 15 * h + 3 * kR);
}

PlantedCrack fcc100(dem::Vec3 normal) {
  const double h = 1.0 / std::sqrt(2.0);
  return fccPlaneCrack(5, normal, kR + 4.5 * h);
}

}  // namespace

TEST_CASE("(111) crack: cell cut area equals the cut area, depths 0.1835 r and 0.1340 r",
          "[cracks][cell-cut][geometry]") {
  const PlantedCrack crack = fcc111();
  const CrackMesh mesh = run(Method::kCellCut, crack);
  const dem::Vec3 centre = 0.5 * crack.block.extent;
  const auto window = prismWindow(centre, {1, 1, 1}, 1.5);
  CHECK(measureInWindow(mesh, window, false) == Approx(9.0).epsilon(kTight));
  CHECK(mesh.lines.size() == 0);
  CHECK(mesh.vertices.size() == 0);

  const auto triangles = metricsOf(polygonsOfSize(mesh, 3), crack);
  const auto quads = metricsOf(polygonsOfSize(mesh, 4), crack);
  CHECK(triangles.maxDepth / kR == Approx(1.0 - std::sqrt(2.0 / 3.0)).epsilon(kTight));
  CHECK(quads.maxDepth / kR == Approx(1.0 - std::sqrt(3.0) / 2.0).epsilon(kTight));
  CHECK(polygonsOfSize(mesh, 3).polygons.size() + polygonsOfSize(mesh, 4).polygons.size() ==
        mesh.polygons.size());
}

TEST_CASE("(111) crack: local Voronoi area is sqrt(3/2) x the cut area and cuts no particle",
          "[cracks][local-voronoi][geometry]") {
  const PlantedCrack crack = fcc111();
  const CrackMesh mesh = run(Method::kLocalVoronoi, crack);
  const auto window = prismWindow(0.5 * crack.block.extent, {1, 1, 1}, 1.5);
  CHECK(measureInWindow(mesh, window, false) == Approx(std::sqrt(1.5) * 9.0).epsilon(kTight));
  const auto metrics = metricsOf(mesh, crack);
  CHECK(metrics.maxDepth <= kTight * kR);
  CHECK(metrics.inconsistentBonds == 0);
  // Every face belongs to exactly one broken bond, and none is missing.
  const AttributeArray* bondId = mesh.findCellData("bond_id");
  REQUIRE(bondId != nullptr);
  std::set<double> bonds(bondId->values.begin(), bondId->values.end());
  CHECK(bonds.size() == bondId->values.size());
  CHECK(mesh.polygons.size() == crack.brokenCount());
  // The interior faces are rhombic-dodecahedron faces: area d^2 / (2 sqrt 2).
  for (std::size_t k = 0; k < mesh.polygons.size(); ++k) {
    const auto begin = static_cast<std::size_t>(mesh.polygons.offsets[k]);
    const std::size_t count = static_cast<std::size_t>(mesh.polygons.offsets[k + 1]) - begin;
    dem::Vec3 c{};
    for (std::size_t v = 0; v < count; ++v) {
      c = c + mesh.points[static_cast<std::size_t>(mesh.polygons.connectivity[begin + v])];
    }
    c = (1.0 / count) * c;
    if (dem::norm(c - 0.5 * crack.block.extent) < 2.5) {
      REQUIRE(polygonArea(mesh.points, mesh.polygons.connectivity.data() + begin, count) ==
              Approx(1.0 / (2.0 * std::sqrt(2.0))).epsilon(kTight));
    }
  }
}

TEST_CASE("(111) crack: cell centre with merged octahedra gives exactly the Voronoi faces",
          "[cracks][cell-centre][geometry]") {
  const PlantedCrack crack = fcc111();
  ExtractOptions merged;
  merged.mergeOctahedra = true;
  const CrackMesh centre = run(Method::kCellCentre, crack, merged);
  const CrackMesh voronoi = run(Method::kLocalVoronoi, crack);
  // One primitive per broken bond: polygons, and lines for bonds on the
  // block's surface whose fan holds a single cell.
  REQUIRE(centre.primitiveCount() == crack.brokenCount());
  CHECK(centre.polygons.size() > crack.brokenCount() / 2);
  // Per bond, compare the vertex sets of the faces whose fan of cells is
  // complete (bonds away from the block's faces).
  auto facesByBond = [](const CrackMesh& mesh) {
    std::map<int, std::vector<dem::Vec3>> faces;
    const AttributeArray* bondId = mesh.findCellData("bond_id");
    const std::size_t base = mesh.vertices.size() + mesh.lines.size();
    for (std::size_t k = 0; k < mesh.polygons.size(); ++k) {
      auto& face = faces[static_cast<int>(bondId->values[base + k])];
      for (auto i = mesh.polygons.offsets[k]; i < mesh.polygons.offsets[k + 1]; ++i) {
        face.push_back(mesh.points[static_cast<std::size_t>(
            mesh.polygons.connectivity[static_cast<std::size_t>(i)])]);
      }
    }
    return faces;
  };
  const auto expected = facesByBond(voronoi);
  int compared = 0;
  for (const auto& [bond, face] : facesByBond(centre)) {
    const dem::Bond& pair = crack.graph->bond(bond);
    const dem::Vec3 mid =
        0.5 * (crack.block.positions[pair.first] + crack.block.positions[pair.second]);
    const dem::Vec3 e = crack.block.extent;
    const double margin = std::min({mid.x, mid.y, mid.z, e.x - mid.x, e.y - mid.y, e.z - mid.z});
    if (margin < 1.2) {
      continue;
    }
    ++compared;
    const auto& other = expected.at(bond);
    REQUIRE(face.size() == other.size());
    for (const dem::Vec3& p : face) {
      const bool matched = std::any_of(other.begin(), other.end(), [&](const dem::Vec3& q) {
        return dem::norm(p - q) < kTight;
      });
      REQUIRE(matched);
    }
  }
  CHECK(compared > 20);
  // Without merging, octahedra count as two pyramids and faces differ.
  const CrackMesh split = run(Method::kCellCentre, crack);
  CHECK(metricsOf(split, crack).area != Approx(metricsOf(centre, crack).area).epsilon(1e-6));
}

TEST_CASE("(100) cracks: cut area, and depths 0.2929 r and 0.1340 r by polygon origin",
          "[cracks][cell-cut][geometry]") {
  const double deep = 1.0 - 1.0 / std::sqrt(2.0);
  const double shallow = 1.0 - std::sqrt(3.0) / 2.0;
  SECTION("normal to x: triangles and quads") {
    const PlantedCrack crack = fcc100({1, 0, 0});
    const CrackMesh mesh = run(Method::kCellCut, crack);
    const auto window = prismWindow(0.5 * crack.block.extent, {1, 0, 0}, 1.5);
    CHECK(measureInWindow(mesh, window, false) == Approx(9.0).epsilon(kTight));
    CHECK(metricsOf(polygonsOfSize(mesh, 3), crack).maxDepth / kR == Approx(deep).epsilon(kTight));
    CHECK(metricsOf(polygonsOfSize(mesh, 4), crack).maxDepth / kR ==
          Approx(shallow).epsilon(kTight));
    const CrackMesh voronoi = run(Method::kLocalVoronoi, crack);
    CHECK(measureInWindow(voronoi, window, false) == Approx(std::sqrt(2.0) * 9.0).epsilon(kTight));
    CHECK(metricsOf(voronoi, crack).maxDepth <= kTight * kR);
  }
  SECTION("normal to z, the octahedra's split axis: quads only") {
    const PlantedCrack crack = fcc100({0, 0, 1});
    const CrackMesh mesh = run(Method::kCellCut, crack);
    const auto window = prismWindow(0.5 * crack.block.extent, {0, 0, 1}, 1.5);
    CHECK(measureInWindow(mesh, window, false) == Approx(9.0).epsilon(kTight));
    CHECK(polygonsOfSize(mesh, 3).polygons.size() == 0);
    CHECK(metricsOf(polygonsOfSize(mesh, 4), crack).maxDepth / kR == Approx(deep).epsilon(kTight));
  }
}

TEST_CASE("2D crack between two rows: the same relations on the triangular lattice",
          "[cracks][geometry]") {
  const double rowSpacing = std::sqrt(3.0) / 2.0;
  const double line = kR + 3.5 * rowSpacing;
  const PlantedCrack crack =
      plantCrack(dem::LatticeKind::kTriangular, {16, 8, 1},
                 [&](dem::Vec3 a, dem::Vec3 b) { return (a.y - line) * (b.y - line) < 0; });
  const dem::Vec3 centre{0.5 * crack.block.extent.x, line, 0.0};
  const std::vector<HalfSpace> window{{{1, 0, 0}, centre.x + 3.0}, {{-1, 0, 0}, -centre.x + 3.0}};

  const CrackMesh cut = run(Method::kCellCut, crack);
  CHECK(measureInWindow(cut, window, true) == Approx(6.0).epsilon(kTight));
  const auto cutMetrics = metricsOf(cut, crack);
  CHECK(cutMetrics.maxDepth / kR == Approx(1.0 - std::sqrt(3.0) / 2.0).epsilon(kTight));
  CHECK(cutMetrics.components == 1);
  CHECK(cutMetrics.nonManifoldEdges == 0);

  const CrackMesh voronoi = run(Method::kLocalVoronoi, crack);
  CHECK(measureInWindow(voronoi, window, true) ==
        Approx(6.0 * 2.0 / std::sqrt(3.0)).epsilon(kTight));
  CHECK(metricsOf(voronoi, crack).maxDepth <= kTight * kR);
  CHECK(voronoi.lines.size() == crack.brokenCount());

  const CrackMesh centreMesh = run(Method::kCellCentre, crack);
  CHECK(measureInWindow(centreMesh, window, true) ==
        Approx(measureInWindow(voronoi, window, true)).epsilon(kTight));
}

TEST_CASE("cell attribute: cells with their number of broken bonds", "[cracks][cell-attribute]") {
  const PlantedCrack crack = fcc111();
  const CrackMesh local = run(Method::kCellAttribute, crack);
  ExtractOptions all;
  all.globalDecomposition = true;
  all.minBrokenBonds = 0;
  const CrackMesh global = run(Method::kCellAttribute, crack, all);
  // 5 cubic cells: 8 * 125 tetrahedra and 2 * (125 + 3*5*16) pyramids.
  CHECK(global.volumeCells.size() == 1000u + 2u * 365u);
  const AttributeArray* broken = local.findCellData("broken_bonds");
  REQUIRE(broken != nullptr);
  REQUIRE(broken->values.size() == local.volumeCells.size());
  // A (111) cut breaks 3 bonds of a tetrahedron with one particle across, and
  // 4 of every pyramid it crosses (2 sides, 2 base edges).
  for (std::size_t k = 0; k < local.volumeCells.size(); ++k) {
    const int expected = local.volumeCellTypes[k] == 10 ? 3 : 4;
    REQUIRE(broken->values[k] == expected);
  }
}
