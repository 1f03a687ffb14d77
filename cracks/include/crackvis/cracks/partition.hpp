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
// ghost layer (a peeled one too: its edges are the triangulation's), and
// those nodes' bonded neighbours: at the specimen's surface
// flat cells reach particles far along it, and a cell's never-bonded edges
// are held by paths through its nodes' neighbours.
Piece partitionPiece(std::span<const Vec3> reference, std::span<const dem::Bond> bonds, int piece,
                     int pieces, double ghostWidth, const Triangulation* triangulation = nullptr);

// When the whole set's intact bonds stop joining a piece's particles, for a
// rank that holds only its piece: the union-find forest of every bond,
// joined in the reverse order of breaking (bonds never heal, so the bonds
// intact at step s are those whose break step is later, or none), kept
// only along the paths from the piece's particles to their roots. Going up,
// the steps before which the links hold only fall, so a particle's
// component at step s is the highest node it reaches by links that hold
// at s.
struct BreakForest {
  std::vector<std::int32_t> parent;        // per kept node: its parent's slot; -1 a root
  std::vector<std::int32_t> holdsBefore;   // per kept node: its link holds at steps < this
  std::vector<std::int32_t> particleSlot;  // per piece particle: its node's slot
};
// Each piece particle's component of the whole set by the bonds intact at
// `step` (a label: equal labels, one component); step -1: the intact
// packing's, every bond counted. As connectedComponents gives the whole
// set's, compared label for label within the piece.
std::vector<std::int32_t> componentsAt(const BreakForest& forest, int step);
// The forest for `particles` (ascending) from one pass over every bond's
// ends and break step, read in spans: transient memory of 16 bytes per
// particle and up to 36 per broken bond of the whole set. Again after a live
// file's writer added steps, since bonds broken since then were read as
// never breaking.
Result<BreakForest> readBreakForest(const dem::DemFileReader& reader,
                                    const std::vector<dem::ParticleIndex>& particles);

// The part of the whole set's triangulation a triangulated piece holds, in
// piece indices: every cell with a node in the slab and ghost layer (not
// peeled: its `peeled` stays empty), those cells' edges and those of the
// peeled cells there; and the forest that answers which particles the
// intact bonds still join.
struct PieceTriangulation {
  Triangulation triangulation;
  BreakForest forest;
};

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
  // A triangulated packing's (index.decomposition kTriangulation).
  std::optional<PieceTriangulation> triangulated;
};
// nullopt when the file cannot be read so: it has no index, no bond_start
// (bonds not sorted by first end), no recorded decomposition, or a
// triangulated packing without /index/wide_cells or /index/peeled_cells
// (files before 2026-11-30 lack the second), or whose slab and margin
// cannot be triangulated alone (too few particles, or all in one plane).
//
// A triangulated piece holds the particles and bonds partitionPiece holds
// with the whole set's triangulation, and of that triangulation the cells
// with a node in the slab and ghost layer, with their edges and those of
// the peeled cells there (not the other cells among its particles, which
// make no primitive it owns). The rank
// triangulates its slab, its ghost layer and a margin of 2.5 wide-cell
// reaches (dem::WideCells::reach) around them, and keeps the cells that
// touch the slab and ghost layer and whose reach (cellReach) is at most
// that: with every particle able to unmake them within two reaches of the
// zone, they are the whole set's. The cells of larger reach (the flat
// cells at the specimen's surface) come from /index/wide_cells, and the
// hull's slivers the whole set's triangulation peels (/index/peeled_cells)
// are taken out. The forest comes from readBreakForest's pass; its memory
// is freed before return.
Result<std::optional<IndexedPiece>> readIndexedPiece(const dem::DemFileReader& reader, int piece,
                                                     int pieces, double ghostBonds);

// A triangulated packing's wide cells (dem::WideCells) from its first
// step: the unpeeled triangulation's cells whose reach exceeds
// kWideCellReach longest bonds, and the hull's slivers it peels.
Result<dem::WideCells> wideCellsOf(std::span<const Vec3> first, const dem::Lattice& lattice);
inline constexpr double kWideCellReach = 1.5;

// What a writer's metadata says of the cells: the decomposition
// (decompositionOf), and for a triangulated packing the maker of its wide
// cells, so that its MPI ranks read only their pieces.
void describeCells(dem::DemMetadata& metadata, const dem::Lattice& lattice);

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
