// Accuracy and quality of an extracted crack surface (dissertation 3.3.3 and
// Fig. 3.32 onwards).
//
//  - area: total area of the surface polygons (3D) or length of the surface
//    segments (2D); inconsistency marks are not surface. For the cell
//    attribute method's cells, the sum of its components' areas: the crack
//    the cells enclose, projected (crack_components.hpp).
//  - cut depth: a surface primitive cuts particle k by depth r_k - dist(x_k,
//    primitive) when positive. Each particle counts once, with its deepest
//    cut: totalDepth sums those, maxDepth is the largest (also relative to r).
//  - components: connected pieces (primitives sharing a point, after welding
//    points that coincide within 1e-9 of the mesh size; cells sharing a face).
//  - non-manifold edges: in 3D, welded edges shared by more than two
//    polygons; in 2D, points shared by more than two segments.
//  - inconsistent bonds: primitives flagged "inconsistent" (local Voronoi).
#pragma once

#include <span>

#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::cracks {

struct SurfaceMetrics {
  std::size_t points = 0;
  std::size_t polygons = 0;
  std::size_t lines = 0;
  std::size_t vertices = 0;
  double area = 0.0;
  double totalDepth = 0.0;
  double maxDepth = 0.0;
  double maxRelativeDepth = 0.0;  // maxDepth over the radius of the particle cut deepest
  std::size_t cutParticles = 0;
  std::size_t components = 0;
  std::size_t nonManifoldEdges = 0;
  std::size_t inconsistentBonds = 0;
};

SurfaceMetrics computeMetrics(const CrackMesh& mesh, std::span<const Vec3> positions,
                              std::span<const double> radius);

// Distance from p to the triangle (a, b, c).
double pointTriangleDistance(Vec3 p, Vec3 a, Vec3 b, Vec3 c);
double pointSegmentDistance(Vec3 p, Vec3 a, Vec3 b);

}  // namespace crackvis::cracks
