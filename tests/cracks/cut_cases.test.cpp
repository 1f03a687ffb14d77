#include <set>

#include <catch2/catch.hpp>

#include <crackvis/cracks/cut_cases.hpp>

using namespace crackvis::cracks;

namespace {
bool broken(std::uint8_t mask, int e) {
  return (mask >> e) & 1u;
}
}  // namespace

TEST_CASE("every pattern of every cell type has a well-formed case", "[cracks][cell-cut]") {
  const auto type = GENERATE(CellType::kTriangle, CellType::kTetrahedron, CellType::kPyramid);
  const CellShape& shape = shapeOf(type);
  const int patterns = 1 << shape.edgeCount;
  int cleanPatterns = 0;
  for (int m = 0; m < patterns; ++m) {
    const auto mask = static_cast<std::uint8_t>(m);
    const CutCase& cut = cutCase(type, mask);
    std::set<int> used;
    for (const CutPolygon& polygon : cut.polygons) {
      // A polygon (segment in 2D) is a simple cycle of broken edges.
      REQUIRE(polygon.edges.size() >= (type == CellType::kTriangle ? 2u : 3u));
      REQUIRE(std::set<int>(polygon.edges.begin(), polygon.edges.end()).size() ==
              polygon.edges.size());
      for (auto e : polygon.edges) {
        REQUIRE(broken(mask, e));
        used.insert(e);
        // Each polygon edge has exactly one end inside the enclosed component.
        const auto& edge = shape.edges[e];
        REQUIRE(
            (((polygon.insideNodes >> edge[0]) & 1u) != ((polygon.insideNodes >> edge[1]) & 1u)));
      }
    }
    for (const auto& line : cut.lines) {
      REQUIRE(broken(mask, line[0]));
      REQUIRE(broken(mask, line[1]));
      used.insert(line[0]);
      used.insert(line[1]);
    }
    for (auto e : cut.points) {
      REQUIRE(broken(mask, e));
      used.insert(e);
    }
    // Every broken edge shows up: no crack is lost in a cell.
    for (int e = 0; e < shape.edgeCount; ++e) {
      REQUIRE(used.count(e) == (broken(mask, e) ? 1u : 0u));
    }
    // Clean cuts (broken edges exactly the edges between intact components)
    // give polygons only: the crack passes through the cell.
    int components = 0;
    const auto label = intactComponents(type, mask, components);
    bool clean = true;
    for (int e = 0; e < shape.edgeCount; ++e) {
      const auto& edge = shape.edges[e];
      clean = clean && broken(mask, e) == (label[edge[0]] != label[edge[1]]);
    }
    if (clean && mask != 0) {
      ++cleanPatterns;
      REQUIRE(cut.lines.empty());
      REQUIRE(cut.points.empty());
      REQUIRE(cut.polygons.size() == static_cast<std::size_t>(components - 1));
    }
  }
  CHECK(cleanPatterns > 0);
}

TEST_CASE("the cases the dissertation draws", "[cracks][cell-cut]") {
  // Tetrahedron edges 01 02 03 12 13 23.
  SECTION("one node cut off a tetrahedron: a triangle") {
    const CutCase& cut = cutCase(CellType::kTetrahedron, 0b000111);
    REQUIRE(cut.polygons.size() == 1);
    CHECK(cut.polygons[0].edges.size() == 3);
    CHECK(cut.polygons[0].insideNodes == 0b0001);
  }
  SECTION("a tetrahedron split two and two: a quad") {
    // nodes {0,1} | {2,3}: edges 02 03 12 13 broken
    const CutCase& cut = cutCase(CellType::kTetrahedron, 0b011110);
    REQUIRE(cut.polygons.size() == 1);
    CHECK(cut.polygons[0].edges.size() == 4);
  }
  SECTION("a pyramid's apex cut off: a quad through the four side edges") {
    const CutCase& cut = cutCase(CellType::kPyramid, 0b11110000);
    REQUIRE(cut.polygons.size() == 1);
    CHECK(std::set<int>(cut.polygons[0].edges.begin(), cut.polygons[0].edges.end()) ==
          std::set<int>{4, 5, 6, 7});
  }
  SECTION("a crack ending in a cell: a point, or a line") {
    const CutCase& one = cutCase(CellType::kTetrahedron, 0b000001);
    CHECK(one.polygons.empty());
    CHECK(one.points == std::vector<std::uint8_t>{0});
    const CutCase& two = cutCase(CellType::kTetrahedron, 0b001001);  // 01 and 12 share face 012
    CHECK(two.polygons.empty());
    REQUIRE(two.lines.size() == 1);
    const CutCase& apart = cutCase(CellType::kTetrahedron, 0b100001);  // 01 and 23: no common face
    CHECK(apart.points.size() == 2);
  }
  SECTION("2D: two broken sides give a segment, all three a junction") {
    CHECK(cutCase(CellType::kTriangle, 0b011).polygons.size() == 1);
    CHECK(cutCase(CellType::kTriangle, 0b111).polygons.size() == 2);
    CHECK(cutCase(CellType::kTriangle, 0b001).points.size() == 1);
  }
}
