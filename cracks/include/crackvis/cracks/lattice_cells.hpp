// Cells of the space decomposition that the lattice's bonds span, and the
// fixed local numbering of their nodes, edges and faces that the case tables
// and the crack methods share.
//
//  - triangle (2D): nodes 0 1 2; edges 01 12 20.
//  - tetrahedron: nodes 0 1 2 3 (sorted by particle index); edges 01 02 03 12 13 23.
//  - pyramid: one half of a lattice octahedron (6 nodes, 12 bonds, 3 absent
//    diagonals), split along the diagonal through the octahedron's lowest
//    particle index. Base nodes 0 1 2 3 form the base cycle (the base's two
//    diagonals are not bonds), node 4 is the apex; edges 01 12 23 30 (base)
//    then 04 14 24 34 (lateral). The two pyramids of an octahedron are stored
//    next to each other and share the base.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include <crackvis/dem/model.hpp>

namespace crackvis::cracks {

enum class CellType : std::uint8_t { kTriangle, kTetrahedron, kPyramid };

inline constexpr int kMaxCellNodes = 5;
inline constexpr int kMaxCellEdges = 8;
inline constexpr int kMaxCellFaces = 5;

struct CellShape {
  int nodeCount;
  int edgeCount;
  int faceCount;
  std::array<std::array<std::uint8_t, 2>, kMaxCellEdges> edges;
  // Faces as node cycles; triangles have 3 nodes, the pyramid's base has 4.
  // In 2D the "faces" are the triangle's edges (2 nodes).
  std::array<std::array<std::int8_t, 4>, kMaxCellFaces> faces;
  std::array<std::uint8_t, kMaxCellFaces> faceSizes;
};

const CellShape& shapeOf(CellType type);

// Local index of the edge joining local nodes a and b, or -1.
int localEdge(CellType type, int a, int b);

// VTK cell type codes (vtkCellType.h) for writers and VTK adapters.
int vtkCellTypeOf(CellType type);

// 32 bytes: a decomposition of a fractured cuboid holds over two cells per
// particle, and the memory budget is 200 bytes per particle for everything.
struct LatticeCell {
  std::array<dem::ParticleIndex, kMaxCellNodes> nodes{-1, -1, -1, -1, -1};
  // Edge e's bond is BondGraph::bondsOf(nodes[edges[e][0]])[edgeSlots[e]]
  // (see LatticeDecomposition::bondOf): a byte instead of a bond index.
  std::array<std::uint8_t, kMaxCellEdges> edgeSlots{};
  CellType type = CellType::kTetrahedron;
  std::int8_t partnerOffset = 0;  // pyramids: +1 or -1 to the other half of the octahedron
  std::uint8_t brokenMask = 0;    // bit e set when local edge e's bond is broken
  std::uint8_t spare = 0;

  int nodeCount() const { return shapeOf(type).nodeCount; }
  int edgeCount() const { return shapeOf(type).edgeCount; }
  // Number of broken bonds (eq. 2.2 of the dissertation).
  int brokenCount() const { return __builtin_popcount(brokenMask); }
  bool contains(dem::ParticleIndex p) const;
  // Local index of particle p in this cell, or -1.
  int localNode(dem::ParticleIndex p) const;
  dem::ParticleIndex lowestNode() const;
};
static_assert(sizeof(LatticeCell) == 32);

}  // namespace crackvis::cracks
