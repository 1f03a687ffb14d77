// The cell cut method's case table: for each cell type and each pattern of
// broken edges (2^3 triangle, 2^6 tetrahedron, 2^8 pyramid patterns), the
// primitives through the midpoints of the broken edges.
//
// The table is derived once from one rule, so every pattern is covered and
// the rule is documented in one place (docs/methods.md):
//  1. Split the cell's nodes into components joined by intact edges.
//  2. With two or more components, every component except the largest (ties:
//     the one holding local node 0 is kept) is enclosed by one polygon
//     through the midpoints of its cut edges (edges with one end inside),
//     ordered around the component through the cell faces they share. In 2D
//     the enclosure is a line segment. A 1|3 tetrahedron gives a triangle, a
//     2|2 tetrahedron a quad, an isolated pyramid apex a quad.
//  3. A broken edge whose ends are still joined through intact edges marks a
//     crack that ends inside the cell: it is joined by a line to every other
//     broken edge on a common face, or is a lone point if there is none.
#pragma once

#include <cstdint>
#include <vector>

#include <crackvis/cracks/lattice_cells.hpp>

namespace crackvis::cracks {

struct CutPolygon {
  std::vector<std::uint8_t> edges;  // local edge indices, in cycle order
  std::uint8_t insideNodes = 0;     // local nodes of the enclosed component (bitmask)
};

struct CutCase {
  std::vector<CutPolygon> polygons;  // 3D polygons; in 2D two-edge "polygons" are segments
  std::vector<std::array<std::uint8_t, 2>> lines;
  std::vector<std::uint8_t> points;
};

const CutCase& cutCase(CellType type, std::uint8_t brokenMask);

// Components of a cell's nodes joined by intact edges: label per local node.
std::array<int, kMaxCellNodes> intactComponents(CellType type, std::uint8_t brokenMask, int& count);

}  // namespace crackvis::cracks
