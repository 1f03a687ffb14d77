#include <map>
#include <numeric>
#include <set>

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include "crack_fixtures.hpp"
#include <crackvis/cracks/local_voronoi.hpp>
#include <crackvis/cracks_voro/voro_reference.hpp>

using namespace crackvis;
using namespace crackvis::cracks;
using namespace crackvis::testing;

namespace {

// The domain both sides use: the centres' box, a hair larger so Voro++
// accepts particles on its walls.
Box sharedBox(const PlantedCrack& crack) {
  Box box = defaultDomain(crack.block.positions, crack.block.lattice.radius, 3);
  box.lo = box.lo - dem::Vec3{1e-12, 1e-12, 1e-12};
  box.hi = box.hi + dem::Vec3{1e-12, 1e-12, 1e-12};
  return box;
}

std::map<int, ReferenceCell> referenceCells(const PlantedCrack& crack, const Box& box) {
  std::map<int, ReferenceCell> cells;
  globalVoronoi(crack.block.positions, box,
                [&](const ReferenceCell& cell) { cells[cell.particle] = cell; });
  return cells;
}

std::vector<dem::ParticleIndex> endParticles(const PlantedCrack& crack) {
  std::set<dem::ParticleIndex> ends;
  for (std::size_t b = 0; b < crack.state.size(); ++b) {
    if (crack.state[b]) {
      ends.insert(crack.graph->bond(static_cast<dem::BondIndex>(b)).first);
      ends.insert(crack.graph->bond(static_cast<dem::BondIndex>(b)).second);
    }
  }
  return {ends.begin(), ends.end()};
}

// A small deterministic generator of uniform numbers in [0, 1).
struct UniformRandom {
  std::uint64_t seed;
  double operator()() {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(seed >> 11) * 0x1.0p-53;
  }
};

double bondFaceArea() {
  return 1.0 / (2.0 * std::sqrt(2.0));
}

}  // namespace

TEST_CASE("local Voronoi cells equal Voro++'s face by face on an undeformed lattice",
          "[cracks][local-voronoi][voro++]") {
  const double h = 1.0 / std::sqrt(2.0);
  const PlantedCrack crack = fccPlaneCrack(4, {1, 1, 1}, 13 * h + 1.5);
  const Box box = sharedBox(crack);
  const auto reference = referenceCells(crack, box);
  const auto ends = endParticles(crack);
  REQUIRE(ends.size() > 50);
  ConvexCell cell;
  int facesCompared = 0;
  for (dem::ParticleIndex i : ends) {
    computeLocalVoronoiCell(*crack.graph, crack.block.positions, i, box, cell);
    const ReferenceCell& expected = reference.at(i);
    CHECK(cell.volume() == Approx(expected.volume).epsilon(1e-9));
    std::size_t nonZero = 0;
    for (const ReferenceFace& face : expected.faces) {
      if (face.area < 1e-9) {
        continue;  // the FCC degeneracy: second neighbours touch at a point
      }
      ++nonZero;
      const std::int32_t label =
          face.neighbour >= 0 ? crack.graph->bondBetween(i, face.neighbour) : face.neighbour;
      INFO("particle " << i << " at " << crack.block.positions[i].x << " "
                       << crack.block.positions[i].y << " " << crack.block.positions[i].z
                       << ", neighbour " << face.neighbour << " area " << face.area);
      if (face.neighbour >= 0) {
        REQUIRE(label >= 0);  // else a Voronoi neighbour that is not a lattice neighbour
      }
      const std::int32_t f = cell.findFace(label);
      REQUIRE(f >= 0);
      CHECK(cell.faceArea(static_cast<std::size_t>(f)) == Approx(face.area).epsilon(1e-9));
      const auto ours = cell.face(static_cast<std::size_t>(f));
      for (const dem::Vec3& v : face.vertices) {
        const bool found = std::any_of(ours.begin(), ours.end(), [&](std::int32_t k) {
          return dem::norm(cell.vertices()[static_cast<std::size_t>(k)] - v) < 1e-9;
        });
        REQUIRE(found);
      }
      ++facesCompared;
    }
    CHECK(cell.faceCount() == nonZero);
  }
  CHECK(facesCompared > 500);
}

TEST_CASE("on jittered lattices per-bond face areas approach Voro++'s as the jitter shrinks",
          "[cracks][local-voronoi][voro++]") {
  // Jitter breaks FCC's degeneracy: Voro++ then adds small faces between
  // second neighbours across octahedral holes, taking area from the bond faces.
  auto largestError = [](double jitter) {
    const double h = 1.0 / std::sqrt(2.0);
    const PlantedCrack crack = fccPlaneCrack(4, {1, 1, 1}, 13 * h + 1.5, jitter);
    const Box box = sharedBox(crack);
    const auto reference = referenceCells(crack, box);
    ConvexCell cell;
    double worst = 0.0;
    for (dem::ParticleIndex i : endParticles(crack)) {
      const dem::Vec3 p = crack.block.positions[static_cast<std::size_t>(i)];
      const double margin = std::min({p.x - box.lo.x, p.y - box.lo.y, p.z - box.lo.z,
                                      box.hi.x - p.x, box.hi.y - p.y, box.hi.z - p.z});
      if (margin < 1.5) {
        continue;  // jittered surfaces are not planes: compare the interior
      }
      computeLocalVoronoiCell(*crack.graph, crack.block.positions, i, box, cell);
      for (const ReferenceFace& face : reference.at(i).faces) {
        if (face.neighbour < 0) {
          continue;
        }
        const std::int32_t bond = crack.graph->bondBetween(i, face.neighbour);
        const double ours = bond >= 0 && cell.findFace(bond) >= 0
                                ? cell.faceArea(static_cast<std::size_t>(cell.findFace(bond)))
                                : 0.0;
        worst = std::max(worst, std::abs(ours - face.area) / bondFaceArea());
      }
    }
    return worst;
  };
  const double small = largestError(0.01);
  const double large = largestError(0.05);
  INFO("largest per-bond area error: jitter 0.01 r -> " << small << ", 0.05 r -> " << large);
  CHECK(small < large);
  CHECK(small < 0.002);
  CHECK(large < 0.03);
}

TEST_CASE("validation flags a bond whose ends are no longer Voronoi neighbours (Fig. 2.10)",
          "[cracks][local-voronoi][validation]") {
  // In a triangular lattice, bond (a, b) is the short diagonal of the rhombus
  // a-c-b-e. Squeezing c and e towards each other makes c-e the shorter
  // diagonal: the Voronoi diagram now joins c and e, not a and b.
  PlantedCrack crack = plantCrack(dem::LatticeKind::kTriangular, {9, 7, 1},
                                  [](dem::Vec3, dem::Vec3) { return false; });
  const dem::Vec3 centre = 0.5 * crack.block.extent;
  dem::BondIndex target = -1;
  double best = 1e9;
  for (std::size_t b = 0; b < crack.graph->bondCount(); ++b) {
    const dem::Bond& bond = crack.graph->bond(static_cast<dem::BondIndex>(b));
    const auto& x = crack.block.positions;
    const dem::Vec3 mid = 0.5 * (x[bond.first] + x[bond.second]);
    if (std::abs(x[bond.first].y - x[bond.second].y) < 1e-9 && dem::norm(mid - centre) < best) {
      best = dem::norm(mid - centre);
      target = static_cast<dem::BondIndex>(b);
    }
  }
  REQUIRE(target >= 0);
  const dem::Bond bond = crack.graph->bond(target);
  auto& x = crack.block.positions;
  const dem::Vec3 mid = 0.5 * (x[bond.first] + x[bond.second]);
  int moved = 0;
  for (dem::BondIndex b : crack.graph->bondsOf(bond.first)) {
    const dem::ParticleIndex c = crack.graph->otherEnd(b, bond.first);
    if (crack.graph->bonded(c, bond.second)) {
      x[static_cast<std::size_t>(c)] =
          x[static_cast<std::size_t>(c)] + 0.6 * (mid - x[static_cast<std::size_t>(c)]);
      ++moved;
    }
  }
  REQUIRE(moved == 2);
  crack.state[static_cast<std::size_t>(target)] = 1;

  auto extractor = makeExtractor(Method::kLocalVoronoi, *crack.graph, 2);
  CrackMesh mesh;
  REQUIRE(extractor->extract(crack.input(), mesh).isOk());
  REQUIRE(extractor->inconsistentBondCount() == 1);
  const AttributeArray* flag = mesh.findCellData("inconsistent");
  const AttributeArray* bondId = mesh.findCellData("bond_id");
  REQUIRE(mesh.lines.size() == 1);  // the mark, and no face
  CHECK(flag->values[0] == 1.0);
  CHECK(bondId->values[0] == target);
  // The mark is the bond itself, between the particle centres.
  CHECK(mesh.points[0] == x[bond.first]);
  CHECK(mesh.points[1] == x[bond.second]);
}

TEST_CASE("the validation tolerance decides how much lattice noise counts as inconsistency",
          "[cracks][local-voronoi][validation]") {
  // Jitter splits FCC's degenerate vertices (six particles on one sphere), so
  // a strict empty-sphere test flags bonds all over the crack; the default
  // tolerance (10 % of the sphere's radius) accepts 5 % jitter in the bulk.
  // On the block's faces jittered particles leave dents in the centres' box
  // that their local cells fill: those few are real inconsistencies.
  const double h = 1.0 / std::sqrt(2.0);
  const PlantedCrack crack = fccPlaneCrack(4, {1, 1, 1}, 13 * h + 1.5, 0.05);
  const Box box = defaultDomain(crack.block.positions, crack.block.lattice.radius, 3);
  auto inconsistent = [&](double tolerance, bool validate) {
    ExtractOptions options;
    options.validate = validate;
    options.validationTolerance = tolerance;
    auto extractor = makeExtractor(Method::kLocalVoronoi, *crack.graph, 3, options);
    CrackMesh mesh;
    REQUIRE(extractor->extract(crack.input(), mesh).isOk());
    REQUIRE(mesh.polygons.size() + mesh.lines.size() == crack.brokenCount());
    std::pair<std::size_t, std::size_t> counts{extractor->inconsistentBondCount(), 0};
    for (std::size_t k = 0; k < mesh.lines.size(); ++k) {
      const dem::Vec3 mid =
          0.5 * (mesh.points[static_cast<std::size_t>(mesh.lines.connectivity[2 * k])] +
                 mesh.points[static_cast<std::size_t>(mesh.lines.connectivity[2 * k + 1])]);
      const double margin = std::min({mid.x - box.lo.x, mid.y - box.lo.y, mid.z - box.lo.z,
                                      box.hi.x - mid.x, box.hi.y - mid.y, box.hi.z - mid.z});
      counts.second += margin > 1.0 ? 1 : 0;
    }
    return counts;
  };
  const auto strict = inconsistent(1e-6, true);
  const auto normal = inconsistent(ExtractOptions{}.validationTolerance, true);
  INFO("inconsistent (all, interior) at 5 % jitter: tolerance 1e-6 -> "
       << strict.first << ", " << strict.second << "; default -> " << normal.first << ", "
       << normal.second);
  CHECK(strict.second > 20);
  CHECK(normal.second == 0);
  CHECK(normal.first < strict.first / 10);
  CHECK(inconsistent(1e-6, false).first == 0);
}

TEST_CASE("every method gives identical output for 1 and 2 threads", "[cracks][determinism]") {
  // A jittered block with a tenth of its bonds broken at random: many blocks
  // of work for every method.
  UniformRandom random{12345};
  const PlantedCrack crack = plantCrack(
      dem::LatticeKind::kFcc, dem::fccUnitCells(7, 7, 7),
      [&](dem::Vec3, dem::Vec3) { return random() < 0.1; }, 0.02);
  for (Method method :
       {Method::kCellAttribute, Method::kCellCut, Method::kLocalVoronoi, Method::kCellCentre}) {
    auto runWith = [&](int threads) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                static_cast<std::size_t>(threads));
      auto extractor = makeExtractor(method, *crack.graph, 3);
      CrackMesh mesh;
      REQUIRE(extractor->extract(crack.input(), mesh).isOk());
      return mesh;
    };
    const CrackMesh one = runWith(1);
    const CrackMesh two = runWith(2);
    INFO(toString(method));
    CHECK(one.primitiveCount() > 600);  // several blocks of 512
    CHECK(one.points == two.points);
    CHECK(one.polygons.connectivity == two.polygons.connectivity);
    CHECK(one.polygons.offsets == two.polygons.offsets);
    CHECK(one.lines.connectivity == two.lines.connectivity);
    CHECK(one.vertices == two.vertices);
    CHECK(one.volumeCells.connectivity == two.volumeCells.connectivity);
    REQUIRE(one.cellData.size() == two.cellData.size());
    for (std::size_t a = 0; a < one.cellData.size(); ++a) {
      CHECK(one.cellData[a].values == two.cellData[a].values);
    }
  }
}

TEST_CASE("a face computed alone equals the same face of the whole cell",
          "[cracks][local-voronoi]") {
  // The extractor computes only broken bonds' faces; the cell is the
  // reference (the test above ties it to Voro++).
  const double h = 1.0 / std::sqrt(2.0);
  const PlantedCrack crack = fccPlaneCrack(4, {1, 1, 1}, 13 * h + 1.5, 0.05);
  const Box box = defaultDomain(crack.block.positions, crack.block.lattice.radius, 3);
  ConvexCell cell;
  std::vector<dem::Vec3> face;
  std::vector<dem::Vec3> scratch;
  int compared = 0;
  for (dem::ParticleIndex i : endParticles(crack)) {
    computeLocalVoronoiCell(*crack.graph, crack.block.positions, i, box, cell);
    for (dem::BondIndex b : crack.graph->bondsOf(i)) {
      computeLocalVoronoiFace(*crack.graph, crack.block.positions, i, b, box, face, scratch);
      const std::int32_t f = cell.findFace(b);
      if (f < 0) {
        REQUIRE(face.size() < 3);
        continue;
      }
      const auto cycle = cell.face(static_cast<std::size_t>(f));
      REQUIRE(face.size() == cycle.size());
      std::vector<std::int32_t> ids(face.size());
      std::iota(ids.begin(), ids.end(), 0);
      CHECK(polygonArea(face, ids.data(), ids.size()) ==
            Approx(cell.faceArea(static_cast<std::size_t>(f))).epsilon(1e-12));
      for (const dem::Vec3& p : face) {
        REQUIRE(std::any_of(cycle.begin(), cycle.end(), [&](std::int32_t k) {
          return dem::norm(cell.vertices()[static_cast<std::size_t>(k)] - p) < 1e-12;
        }));
      }
      ++compared;
    }
  }
  CHECK(compared > 1000);
}

TEST_CASE("the lean Voro++ baseline over slabs is the single container's diagram",
          "[cracks][voro++][bench]") {
  // A jittered FCC block with unequal radii: the power diagram, as local
  // Voronoi uses for unequal radii.
  UniformRandom random{777};
  const PlantedCrack crack = plantCrack(
      dem::LatticeKind::kFcc, dem::fccUnitCells(8, 5, 4),
      [](dem::Vec3, dem::Vec3) { return false; }, 0.05);
  std::vector<double> radius(crack.block.positions.size());
  for (double& r : radius) {
    r = 0.3 + 0.1 * random();
  }
  const Box box = sharedBox(crack);
  const GlobalVoronoiSummary full = globalVoronoi(crack.block.positions, box, {}, radius);
  const LeanVoronoiSummary one = leanVoronoi(crack.block.positions, box, radius, 1);
  CHECK(one.containers == 1);
  CHECK(one.cells == full.cells);
  CHECK(one.faces == full.faces);
  CHECK(one.haloWallFaces == 0);
  for (int slabs : {2, 3}) {
    INFO(slabs << " slabs");
    const LeanVoronoiSummary split = leanVoronoi(crack.block.positions, box, radius, slabs);
    CHECK(split.containers == slabs);
    CHECK(split.haloWallFaces == 0);
    CHECK(split.cells == one.cells);
    CHECK(split.faces == one.faces);
    CHECK(split.faceArea == Approx(one.faceArea).epsilon(1e-9));
  }
}

TEST_CASE("the slab baseline reports cells its halo was too thin for", "[cracks][voro++][bench]") {
  // Two clusters far apart along x: the cells between them reach across the
  // middle of the box, beyond any halo of a few mean spacings.
  std::vector<dem::Vec3> positions;
  for (int k = 0; k < 8; ++k) {
    const double y = (k % 2) * 1.0;
    const double z = ((k / 2) % 2) * 1.0;
    positions.push_back({k < 4 ? 0.0 : 0.5, y, z});
    positions.push_back({k < 4 ? 100.0 : 99.5, y, z});
  }
  const Box box{{-1e-9, -1e-9, -1e-9}, {100.0 + 1e-9, 1.0 + 1e-9, 1.0 + 1e-9}};
  const LeanVoronoiSummary one = leanVoronoi(positions, box, {}, 1);
  const LeanVoronoiSummary split = leanVoronoi(positions, box, {}, 2);
  CHECK(one.haloWallFaces == 0);
  CHECK(one.cells == positions.size());
  CHECK(split.haloWallFaces > 0);
}
