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
  // The finite cells not peeled, with their nodes ascending: tetrahedra, or
  // triangles in 2D (the fourth node -1). Sorted, so the order does not
  // depend on CGAL's.
  std::vector<std::array<dem::ParticleIndex, 4>> cells;
  // The hull's slivers peeled from `cells` (TriangulateOptions::peelHull),
  // nodes ascending, sorted; empty in a piece's (cracks::PieceTriangulation).
  std::vector<std::array<dem::ParticleIndex, 4>> peeled;
  // Unique edges (first < second), sorted: every edge of the triangulation,
  // the peeled cells' too, since local Voronoi takes them for the pairs of
  // particles whose cells meet (the Delaunay graph).
  std::vector<dem::Bond> edges;
  // Particles that are no vertex of the triangulation (a regular
  // triangulation hides a sphere lying inside others' power cells).
  std::size_t hiddenParticles = 0;
};

struct TriangulateOptions {
  // Radii that differ by more than a relative 1e-9 make the triangulation
  // regular, unless this says (a piece of a set triangulates as the whole
  // set does).
  std::optional<bool> weighted;
  // Whether to peel the hull's slivers (their edges stay). The triangulation fills the convex
  // hull of the centres, and on a specimen's sides its outermost cells are
  // slivers spanning the outer layer of centres: crack faces built from
  // them lean into the side (docs/methods.md, "The triangulation's hull
  // cells"). Peeled: every cell of quality under kSliverQuality reached from
  // outside the hull through such cells, unless they are more than half the
  // cells (a layer one particle thick is all slivers, and all it has). A
  // piece of a set, whose hull is not the set's, is not peeled: it takes the
  // set's peeled cells from the file (dem::WideCells::peeled).
  bool peelHull = true;
};

// Fails on fewer than dimension + 1 particles or all of them coplanar
// (collinear in 2D).
Result<Triangulation> triangulate(std::span<const dem::Vec3> positions,
                                  std::span<const double> radius, int dimension,
                                  const TriangulateOptions& options = {});

// A cell's shape quality: 6 sqrt(2) V / l_rms^3 for a tetrahedron (l_rms the
// root mean square of its six edges), 4 sqrt(3) A / (sum of squared edges)
// for a triangle; 1 for a regular one, 0 for a flat one.
double tetrahedronQuality(const std::array<double, 4>& x, const std::array<double, 4>& y,
                          const std::array<double, 4>& z);
double triangleQuality(const std::array<double, 3>& x, const std::array<double, 3>& y);
// Below it a cell on the hull is a sliver. On a Yade bar's cracked cells
// (docs/methods.md) it holds 32.5 % of those near the sides (median 0.18)
// and 0.3 % of those inside (median 0.76).
inline constexpr double kSliverQuality = 0.1;

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
