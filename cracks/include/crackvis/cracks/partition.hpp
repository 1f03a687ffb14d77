// A particle set cut into pieces for distributed extraction (one piece per
// MPI rank under ParaView's pvbatch or pvserver), and the rule that makes the
// pieces' crack meshes add up to the whole set's, face for face.
//
// The pieces are slabs across the slice axis of the reference configuration
// (dem::sliceAxis: the longest, or among near ties the one the file's order
// runs slowest along) with equal particle counts. A piece holds the particles it
// owns plus a ghost layer: every particle within `ghostWidth` of its slab,
// so that each primitive it owns is made from the same neighbourhood as in
// the whole set. Every primitive has an owner particle, the smallest particle
// index it is made from (ownerParticles); a piece keeps the primitives whose
// owner particle it owns (keepOwned). A piece's particles and bonds keep the
// whole set's relative order, so index-based choices (the smaller end, an
// octahedron's diagonal) fall the same way in every piece.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <crackvis/cracks/crack_mesh.hpp>
#include <crackvis/cracks/triangulation.hpp>
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/model.hpp>
#include <crackvis/dem/spatial_index.hpp>

namespace crackvis::cracks {

struct Piece {
  std::vector<dem::ParticleIndex> particles;  // whole-set indices, ascending
  std::vector<std::uint8_t> owned;            // per piece particle; 0: a ghost
  std::vector<dem::BondIndex> bonds;          // whole-set indices, ascending: both ends held
  std::vector<dem::Bond> localBonds;          // the same bonds in piece particle indices
  std::vector<std::uint8_t> bondOwned;        // per piece bond: its smaller end is owned
};

// The longest reference bond (the unit of the default ghost width).
using dem::longestBond;

// Piece `piece` of `pieces` (0 <= piece < pieces): a slab across
// dem::sliceAxis(reference) with equal particle counts; ghostWidth in metres.
// With the whole set's triangulation (a packing that is no lattice), the
// ghost layer also holds every node of a cell that touches the slab and
// ghost layer, and those nodes' bonded neighbours: at the specimen's surface
// flat cells reach particles far along it, and a cell's never-bonded edges
// are held by paths through its nodes' neighbours.
Piece partitionPiece(std::span<const Vec3> reference, std::span<const dem::Bond> bonds, int piece,
                     int pieces, double ghostWidth, const Triangulation* triangulation = nullptr);

// A piece read from a file through its spatial index (/index, v1.3;
// dem::SpatialIndex): the piece partitionPiece cuts, found by binary searches
// of the stored coordinates and read row by row, so that a rank holds its
// slab and ghost layer and never the whole set. With the piece's part of the
// time-independent arrays; a step's part is
// reader.readStepRows(step, part.particles, part.bonds).
struct IndexedPiece {
  Piece part;
  dem::Lattice lattice;                  // the piece's rows; bonds in piece indices
  std::vector<std::int32_t> breakSteps;  // of the piece's bonds
  std::vector<Vec3> reference;           // the piece's particles at the first step
  dem::SpatialIndexInfo index;           // the whole set's box, largest radius, decomposition
};
// nullopt when the file cannot be read so: it has no index, no bond_start
// (bonds not sorted by first end), or a decomposition other than a lattice
// (a triangulated packing's pieces need the whole set's triangulation).
Result<std::optional<IndexedPiece>> readIndexedPiece(const dem::DemFileReader& reader, int piece,
                                                     int pieces, double ghostBonds);

// Each particle's connected component by the bonds that are intact in
// `bondState` (all of them when it is empty), labelled by a member's index.
std::vector<std::int32_t> connectedComponents(std::size_t particleCount,
                                              std::span<const dem::Bond> bonds,
                                              std::span<const std::uint8_t> bondState);

// Cell data "owner_particle" for each primitive of `mesh`: the smallest
// particle index among the particles it is made from, read from its
// "bond_id" (cell data: the bond's ends; point data: the ends of its points'
// bonds) or its points' "particle_id", with `bonds` the pairs bond ids refer
// to; -1 where the mesh names none.
void appendOwnerParticles(CrackMesh& mesh, std::span<const dem::Bond> bonds);

// Keeps the primitives whose "owner_particle" is owned (or -1), drops that
// array and the points no primitive uses, and keeps every attribute array in
// step.
void keepOwned(CrackMesh& mesh, std::span<const std::uint8_t> owned);

}  // namespace crackvis::cracks
