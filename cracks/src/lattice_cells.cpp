#include <algorithm>

#include <crackvis/cracks/lattice_cells.hpp>

namespace crackvis::cracks {
namespace {

constexpr CellShape kTriangle{
    3,
    3,
    3,
    {{{0, 1}, {1, 2}, {2, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 0}}},
    {{{0, 1, -1, -1}, {1, 2, -1, -1}, {2, 0, -1, -1}, {-1, -1, -1, -1}, {-1, -1, -1, -1}}},
    {2, 2, 2, 0, 0}};
constexpr CellShape kTetrahedron{
    4,
    6,
    4,
    {{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}, {0, 0}, {0, 0}}},
    {{{0, 1, 2, -1}, {0, 1, 3, -1}, {0, 2, 3, -1}, {1, 2, 3, -1}, {-1, -1, -1, -1}}},
    {3, 3, 3, 3, 0}};
constexpr CellShape kPyramid{
    5,
    8,
    5,
    {{{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}}},
    {{{0, 1, 2, 3}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}}},
    {4, 3, 3, 3, 3}};

}  // namespace

const CellShape& shapeOf(CellType type) {
  switch (type) {
    case CellType::kTriangle:
      return kTriangle;
    case CellType::kTetrahedron:
      return kTetrahedron;
    case CellType::kPyramid:
      return kPyramid;
  }
  return kTetrahedron;
}

int localEdge(CellType type, int a, int b) {
  const CellShape& shape = shapeOf(type);
  for (int e = 0; e < shape.edgeCount; ++e) {
    const auto& edge = shape.edges[static_cast<std::size_t>(e)];
    if ((edge[0] == a && edge[1] == b) || (edge[0] == b && edge[1] == a)) {
      return e;
    }
  }
  return -1;
}

int vtkCellTypeOf(CellType type) {
  switch (type) {
    case CellType::kTriangle:
      return 5;  // VTK_TRIANGLE
    case CellType::kTetrahedron:
      return 10;  // VTK_TETRA
    case CellType::kPyramid:
      return 14;  // VTK_PYRAMID
  }
  return 0;
}

bool LatticeCell::contains(dem::ParticleIndex p) const {
  return localNode(p) >= 0;
}

int LatticeCell::localNode(dem::ParticleIndex p) const {
  const int count = nodeCount();
  for (int k = 0; k < count; ++k) {
    if (nodes[static_cast<std::size_t>(k)] == p) {
      return k;
    }
  }
  return -1;
}

dem::ParticleIndex LatticeCell::lowestNode() const {
  dem::ParticleIndex lowest = nodes[0];
  for (int k = 1; k < nodeCount(); ++k) {
    lowest = std::min(lowest, nodes[static_cast<std::size_t>(k)]);
  }
  return lowest;
}

}  // namespace crackvis::cracks
