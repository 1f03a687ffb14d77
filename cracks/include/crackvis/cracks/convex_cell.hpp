// A convex polyhedron clipped by half-spaces: the local Voronoi cell of a
// particle, cut from the domain box by the bisector planes of its lattice
// neighbours (the Voro++ construction, restricted to bonded neighbours).
//
// Faces carry a label: the neighbour particle whose bisector made them, or a
// wall (-1..-6: x-, x+, y-, y+, z-, z+). Face vertex cycles are counter-
// clockwise seen from outside. Buffers are reused between cells, so one
// ConvexCell per thread computes many cells without allocating.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::cracks {

class ConvexCell {
 public:
  // The box [lo, hi] with its six wall faces.
  void reset(Vec3 lo, Vec3 hi);
  // Keeps {x : dot(normal, x) <= offset}; the new face gets `label`.
  // The new face is assembled from the edges the clipped faces leave on the
  // plane; only if rounding breaks that chain are its vertices sorted by angle.
  // Vertices within `tolerance` of the plane count as on it. Returns false
  // when nothing is left.
  bool clip(Vec3 normal, double offset, std::int32_t label, double tolerance);

  const std::vector<Vec3>& vertices() const { return m_vertices; }
  std::size_t faceCount() const { return m_labels.size(); }
  std::span<const std::int32_t> face(std::size_t f) const {
    return {m_faceVertices.data() + m_faceStart[f], m_faceVertices.data() + m_faceStart[f + 1]};
  }
  std::int32_t faceLabel(std::size_t f) const { return m_labels[f]; }
  // Index of the face with this label, or -1.
  std::int32_t findFace(std::int32_t label) const;
  double faceArea(std::size_t f) const;
  double volume() const;

 private:
  void orderByAngle(Vec3 normal);

  std::vector<Vec3> m_vertices;
  std::vector<std::int32_t> m_faceStart{0};
  std::vector<std::int32_t> m_faceVertices;
  std::vector<std::int32_t> m_labels;
  // scratch
  std::vector<double> m_distance;
  std::vector<std::int8_t> m_side;
  std::vector<std::int32_t> m_remap;
  std::vector<Vec3> m_newVertices;
  std::vector<std::int32_t> m_newStart, m_newFaceVertices, m_newLabels, m_cap;
  std::vector<std::array<std::int32_t, 3>> m_edgePoints;          // (a, b, new vertex)
  std::vector<std::pair<std::int32_t, std::int32_t>> m_capEdges;  // (from, to) around the cap
  std::vector<std::pair<double, std::int32_t>> m_byAngle;
};

}  // namespace crackvis::cracks
