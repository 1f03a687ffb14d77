// Components of a crack mesh, their best-fit planes, the filter that keeps
// the main crack, and the section coverage, on meshes built by hand where
// geometry gives every answer.
#include <array>

#include <catch2/catch.hpp>

#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/metrics.hpp>

using namespace crackvis;
using namespace crackvis::cracks;

namespace {

// A square of side `side` in the plane x = x0, centred at (y, z), as two
// triangles sharing points; its cell data "bond_id" is `tag`.
void addSquare(CrackMesh& mesh, double x0, double y, double z, double side, double tag) {
  const auto first = static_cast<std::int32_t>(mesh.points.size());
  const double h = 0.5 * side;
  mesh.points.push_back({x0, y - h, z - h});
  mesh.points.push_back({x0, y + h, z - h});
  mesh.points.push_back({x0, y + h, z + h});
  mesh.points.push_back({x0, y - h, z + h});
  mesh.polygons.add({first, first + 1, first + 2});
  mesh.polygons.add({first, first + 2, first + 3});
  for (int k = 0; k < 2; ++k) {
    mesh.cellData[0].values.push_back(tag);
  }
}

CrackMesh twoSquares() {
  CrackMesh mesh;
  mesh.cellData.push_back({"bond_id", AttributeType::kInt32, 1, {}});
  addSquare(mesh, 1.0, 0.0, 0.0, 1.0, 7.0);  // area 1
  addSquare(mesh, 5.0, 3.0, 3.0, 2.0, 9.0);  // area 4, found second
  return mesh;
}

// Particle centres on a grid filling [0, 10] x [-5, 5] x [-5, 5], radius 0.25.
struct Block {
  std::vector<Vec3> positions;
  std::vector<double> radius;
};
Block block() {
  Block b;
  for (int i = 0; i <= 20; ++i) {
    for (int j = 0; j <= 20; ++j) {
      for (int k = 0; k <= 20; ++k) {
        b.positions.push_back({0.5 * i, -5.0 + 0.5 * j, -5.0 + 0.5 * k});
      }
    }
  }
  b.radius.assign(b.positions.size(), 0.25);
  return b;
}

}  // namespace

TEST_CASE("crack components: largest first, with area, box, centroid and plane",
          "[cracks][components]") {
  const CrackMesh mesh = twoSquares();
  const CrackComponents set = findComponents(mesh);
  REQUIRE(set.components.size() == 2);
  const CrackComponent& main = set.components[0];
  CHECK(main.area == Approx(4.0));
  CHECK(main.primitives == 2);
  CHECK(main.centroid.x == Approx(5.0));
  CHECK(main.centroid.y == Approx(3.0));
  CHECK(main.box.lo.y == Approx(2.0));
  CHECK(main.box.hi.z == Approx(4.0));
  CHECK(std::abs(main.normal.x) == Approx(1.0));
  CHECK(set.components[1].area == Approx(1.0));
  CHECK(set.ofPrimitive == std::vector<std::int32_t>{1, 1, 0, 0});

  SECTION("a tilted plane is found") {
    CrackMesh tilted;
    tilted.points = {{0, 0, 0}, {1, 0, 1}, {1, 1, 1}, {0, 1, 0}};
    tilted.polygons.add({0, 1, 2, 3});
    const CrackComponent c = findComponents(tilted).components.at(0);
    CHECK(std::abs(c.normal.x) == Approx(std::sqrt(0.5)));
    CHECK(std::abs(c.normal.z) == Approx(std::sqrt(0.5)));
    CHECK(c.normal.y == Approx(0.0).margin(1e-12));
    CHECK(c.area == Approx(std::sqrt(2.0)));
  }
}

TEST_CASE("the component filter keeps the main crack and its cell data", "[cracks][components]") {
  for (const ComponentFilter filter : {ComponentFilter{0.0, 1}, ComponentFilter{2.0, 0}}) {
    CrackMesh mesh = twoSquares();
    keepComponents(mesh, findComponents(mesh), filter);
    CHECK(mesh.polygons.size() == 2);
    CHECK(mesh.cellData[0].values == std::vector<double>{9.0, 9.0});
    CHECK(findComponents(mesh).components.size() == 1);
  }
  CrackMesh untouched = twoSquares();
  keepComponents(untouched, findComponents(untouched), ComponentFilter{});
  CHECK(untouched.polygons.size() == 4);
}

TEST_CASE("section coverage: the projected crack over the specimen's section",
          "[cracks][components]") {
  const Block b = block();
  SECTION("a crack across the whole section covers it") {
    CrackMesh mesh;
    mesh.points = {{5.1, -5, -5}, {5.1, 5, -5}, {5.1, 5, 5}, {5.1, -5, 5}};
    mesh.polygons.add({0, 1, 2, 3});
    CHECK(sectionCoverage(mesh, findComponents(mesh), 0, b.positions, b.radius) ==
          Approx(1.0).margin(0.01));
  }
  SECTION("half of it covers half, and a doubled sheet counts once") {
    CrackMesh mesh;
    mesh.points = {{5.1, -5, -5}, {5.1, 0, -5}, {5.1, 0, 5}, {5.1, -5, 5},
                   {5.2, -5, -5}, {5.2, 0, -5}, {5.2, 0, 5}};
    mesh.polygons.add({0, 1, 2, 3});
    mesh.polygons.add({0, 4, 5, 1});  // a fold joining a second sheet
    mesh.polygons.add({4, 5, 6});
    const CrackComponents set = findComponents(mesh);
    REQUIRE(set.components.size() == 1);
    CHECK(sectionCoverage(mesh, set, 0, b.positions, b.radius) == Approx(0.5).margin(0.02));
  }
  SECTION("2D: segments over the section's width") {
    CrackMesh mesh;
    mesh.dimension = 2;
    mesh.points = {{5.1, -5, 0}, {5.1, 0, 0}, {5.1, 2.5, 0}};
    mesh.lines.add({0, 1, 2});
    std::vector<Vec3> plate;
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; j <= 20; ++j) {
        plate.push_back({0.5 * i, -5.0 + 0.5 * j, 0.0});
      }
    }
    const std::vector<double> radius(plate.size(), 0.25);
    const CrackComponents set = findComponents(mesh);
    REQUIRE(set.components.size() == 1);
    CHECK(set.components[0].area == Approx(7.5));
    CHECK(std::abs(set.components[0].normal.x) == Approx(1.0));
    CHECK(sectionCoverage(mesh, set, 0, plate, radius) == Approx(0.75).margin(0.02));
  }
}

namespace {

// The cell attribute method's output for a slab of cells across the plane
// x = 5 ([4.9, 5.1] x [-5, 5]^2: the box split into six tetrahedra along its
// diagonal), and one tetrahedron touching the slab only at its corner
// (5.1, 5, 5): cells, not a surface.
CrackMesh cellSlab() {
  CrackMesh mesh;
  for (int corner = 0; corner < 8; ++corner) {
    mesh.points.push_back({(corner & 1) != 0 ? 5.1 : 4.9, (corner & 2) != 0 ? 5.0 : -5.0,
                           (corner & 4) != 0 ? 5.0 : -5.0});
  }
  AttributeArray broken{"broken_bonds", AttributeType::kInt32, 1, {}};
  for (const auto& tetrahedron : std::vector<std::array<std::int32_t, 4>>{
           {0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}}) {
    mesh.volumeCells.addRange(tetrahedron.begin(), tetrahedron.end());
    mesh.volumeCellTypes.push_back(10);
    broken.values.push_back(2.0);
  }
  mesh.points.push_back({5.5, 5.5, 5.0});
  mesh.points.push_back({5.5, 5.0, 5.5});
  mesh.points.push_back({6.0, 6.0, 6.0});
  mesh.volumeCells.add({7, 8, 9, 10});
  mesh.volumeCellTypes.push_back(10);
  broken.values.push_back(1.0);
  mesh.cellData.push_back(std::move(broken));
  return mesh;
}

}  // namespace

TEST_CASE("cell attribute's cells: components through shared faces, the crack they enclose",
          "[cracks][components]") {
  const CrackMesh mesh = cellSlab();
  REQUIRE(mesh.holdsCells());
  const CrackComponents set = findComponents(mesh);
  REQUIRE(set.components.size() == 2);  // the corner alone joins nothing
  const CrackComponent& slab = set.components[0];
  CHECK(slab.primitives == 6);
  // Its area: the 10 x 10 square the slab encloses, not its faces' area.
  CHECK(slab.area == Approx(100.0).epsilon(0.01));
  CHECK(std::abs(slab.normal.x) == Approx(1.0));
  CHECK(slab.centroid.x == Approx(5.0));
  CHECK(slab.centroid.y == Approx(0.0).margin(1e-12));
  CHECK(slab.box.lo.x == 4.9);
  CHECK(slab.box.hi.z == 5.0);
  CHECK(set.ofPrimitive == std::vector<std::int32_t>{0, 0, 0, 0, 0, 0, 1});
  CHECK(componentPrimitiveBase(mesh) == 0);

  const Block b = block();
  CHECK(sectionCoverage(mesh, set, 0, b.positions, b.radius) == Approx(1.0).margin(0.01));
  const SurfaceMetrics metrics = computeMetrics(mesh, b.positions, b.radius);
  CHECK(metrics.components == 2);
  CHECK(metrics.area == Approx(slab.area + set.components[1].area));

  CrackMesh kept = cellSlab();
  keepComponents(kept, set, ComponentFilter{0.0, 1});
  CHECK(kept.volumeCells.size() == 6);
  CHECK(kept.volumeCellTypes.size() == 6);
  CHECK(kept.cellData[0].values == std::vector<double>(6, 2.0));
}

TEST_CASE("2D cells: triangles joined through edges, the length they enclose",
          "[cracks][components]") {
  CrackMesh mesh;
  mesh.dimension = 2;
  mesh.points = {{4.9, -5, 0}, {5.1, -5, 0}, {5.1, 5, 0}, {4.9, 5, 0}, {8, 8, 0}, {9, 8, 0}};
  mesh.polygons.add({0, 1, 2});
  mesh.polygons.add({0, 2, 3});
  mesh.polygons.add({2, 4, 5});  // touches the strip at a corner only
  REQUIRE(mesh.holdsCells());
  const CrackComponents set = findComponents(mesh);
  REQUIRE(set.components.size() == 2);
  CHECK(set.components[0].area == Approx(10.0).epsilon(0.01));
  CHECK(std::abs(set.components[0].normal.x) == Approx(1.0));
  CHECK(componentPrimitiveBase(mesh) == 0);
  std::vector<Vec3> plate;
  for (int i = 0; i <= 20; ++i) {
    for (int j = 0; j <= 20; ++j) {
      plate.push_back({0.5 * i, -5.0 + 0.5 * j, 0.0});
    }
  }
  const std::vector<double> radius(plate.size(), 0.25);
  CHECK(sectionCoverage(mesh, set, 0, plate, radius) == Approx(1.0).margin(0.01));
}
