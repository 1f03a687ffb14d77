// Local Voronoi cells (dissertation 2.2): the cell of a particle cut from the
// domain box by the bisector planes of its lattice neighbours only (bonded
// particles, broken or not), as Voro++ would cut it if those were the only
// particles. Where the lattice is consistent with the Voronoi diagram this is
// the Voronoi cell; where it is not, the empty-sphere validation finds out.
// With radii, the planes are radical (power) planes, as Voro++'s
// container_poly cuts them; for equal radii they are the bisectors. On a
// packing that is no lattice the graph holds every triangulation neighbour
// (triangulated_extractor.cpp), so the local cell is the power cell.
#pragma once

#include <span>

#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/convex_cell.hpp>
#include <crackvis/cracks/extractor.hpp>

namespace crackvis::cracks {

// The default domain: the bounding box of the particle centres (in 2D with
// z in [-r, r]).
Box defaultDomain(std::span<const Vec3> positions, std::span<const double> radius, int dimension);

// Computes the local cell of particle i into `cell`; face labels are bond
// indices (>= 0) or walls (< 0). In 2D the box's z range is [-r, r] and the
// cell is a prism over the 2D cell.
void computeLocalVoronoiCell(const BondGraph& graph, std::span<const Vec3> positions,
                             dem::ParticleIndex i, const Box& box, ConvexCell& cell,
                             std::span<const double> radius = {});

// Only the face of bond b in particle i's local cell: the bisector plane of
// b clipped by i's other bisectors and the box, counter-clockwise seen from
// the other end. Empty when the face does not exist. The same polygon as the
// cell's face, for a fraction of the work when only broken bonds are drawn.
void computeLocalVoronoiFace(const BondGraph& graph, std::span<const Vec3> positions,
                             dem::ParticleIndex i, dem::BondIndex b, const Box& box,
                             std::vector<Vec3>& polygon, std::vector<Vec3>& scratch,
                             std::span<const double> radius = {});

}  // namespace crackvis::cracks
