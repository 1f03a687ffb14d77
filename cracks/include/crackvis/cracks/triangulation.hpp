// The Delaunay triangulation of particle centres (equal radii) or the
// regular (weighted Delaunay, power) triangulation with weights r^2 (unequal
// radii): the space decomposition of packings whose bonds do not span a
// lattice. Computed once, on the reference configuration, by CGAL; the cells
// are then fixed like a lattice's, so crack faces made from them are carried
// by their particles however far a crack opens.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::cracks {

struct Triangulation {
  int dimension = 3;
  bool weighted = false;  // regular (power) triangulation
  // Finite cells with their nodes ascending: tetrahedra, or triangles in 2D
  // (the fourth node -1). Sorted, so the order does not depend on CGAL's.
  std::vector<std::array<dem::ParticleIndex, 4>> cells;
  // Unique edges (first < second), sorted.
  std::vector<dem::Bond> edges;
  // Particles that are no vertex of the triangulation (a regular
  // triangulation hides a sphere lying inside others' power cells).
  std::size_t hiddenParticles = 0;
};

// Radii that differ by more than a relative 1e-9 make the triangulation
// regular, unless `weighted` says (a piece of a set triangulates as the
// whole set does). Fails on fewer than dimension + 1 particles or all of
// them coplanar (collinear in 2D).
Result<Triangulation> triangulate(std::span<const dem::Vec3> positions,
                                  std::span<const double> radius, int dimension,
                                  std::optional<bool> weighted = std::nullopt);

// Whether radii differ enough to make the triangulation regular.
bool needsRegularTriangulation(std::span<const double> radius);

// Each cell's reach: the radius of the ball around its circumcentre (a
// regular triangulation's power centre) that holds every particle able to
// unmake the cell, one inside its circumsphere or whose weight (up to
// largestRadius^2) makes its power distance negative. So a cell of the
// triangulation of a subset whose ball holds no particle outside the subset
// is a cell of the whole set's (Delaunay and regular triangulations are
// local). +infinity for a degenerate cell. The nodes are taken in ascending
// order, so equal input gives equal reach, bit for bit.
std::vector<double> cellReach(const Triangulation& triangulation,
                              std::span<const dem::Vec3> positions, std::span<const double> radius,
                              double largestRadius);

}  // namespace crackvis::cracks
