// The surface primitives of a crack mesh and the welding of its points:
// what the metrics, the components and the analyses of a crack share.
#pragma once

#include <cstdint>
#include <vector>

#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::cracks {

// A surface primitive: polygon (3D) or segment (2D), as point ids; `index`
// is its position among the mesh's polygons (3D) or lines (2D).
struct Primitive {
  const std::int32_t* ids;
  std::size_t count;
  std::size_t index;
};

// Polygons (3D), or the segments of lines not flagged "inconsistent" (2D).
std::vector<Primitive> surfacePrimitives(const CrackMesh& mesh);

// Area of a polygon, length of a segment.
double measure(const CrackMesh& mesh, const Primitive& primitive);

// Welded point ids: points closer than `tolerance` (in a grid of that size)
// share an id.
std::vector<std::int32_t> weld(const std::vector<Vec3>& points, double tolerance);

// Union-find root with path halving.
std::int32_t findRoot(std::vector<std::int32_t>& parent, std::int32_t x);

}  // namespace crackvis::cracks
