// The spatial index of a crackvis-dem file (/index, v1.3): the particles in
// order along the reference configuration's slice axis (sliceAxis), with what a reader
// of one slab of the specimen (an MPI rank of the ParaView plugin) needs to
// find its particles and bonds without reading every particle
// (docs/data-format.md, "The spatial index").
//
// The order is the one cracks::partitionPiece cuts: by the coordinate along
// the slice axis, ties by index. So slab k of R holds
// order[k N / R, (k + 1) N / R), and its ghost layer, every particle within a
// width of the slab, is the range of order around it that a binary search of
// `coordinate` finds.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::dem {

// How the crack methods divide a specimen into cells, decided once on the
// whole bond graph (cracks::isLatticeGraph) and stored, since a piece's
// graph, cut at its ghost layer, might not look like a lattice.
enum class CellDecomposition : std::int32_t {
  kUnknown = -1,       // not recorded: a reader decides on the whole bond graph
  kLattice = 0,        // the bonds span lattice cells
  kTriangulation = 1,  // a packing that is no lattice: a Delaunay triangulation
};

// Where the index lives (docs/data-format.md).
inline constexpr const char* kSpatialIndexGroup = "/index";
inline constexpr const char* kIndexOrderPath = "/index/order";
inline constexpr const char* kIndexCoordinatePath = "/index/coordinate";
inline constexpr const char* kIndexBondStartPath = "/index/bond_start";
inline constexpr const char* kIndexBoxPath = "/index/box";
inline constexpr const char* kIndexWideCellsPath = "/index/wide_cells";
inline constexpr const char* kIndexPeeledCellsPath = "/index/peeled_cells";

// "lattice", "triangulation" (the attribute /index@decomposition); "" unknown.
const char* decompositionName(CellDecomposition decomposition);
// The decomposition decompositionName calls `name`; kUnknown for any other.
CellDecomposition decompositionNamed(std::string_view name);

// The index's scalar part (attributes of /index).
struct SpatialIndexInfo {
  int axis = 0;  // 0 x, 1 y, 2 z: the slice axis of the reference configuration
  Bounds box;    // of the reference configuration (step 0)
  double largestRadius = 0.0;
  double longestBond = 0.0;  // the longest bond's length in the reference configuration
  CellDecomposition decomposition = CellDecomposition::kUnknown;
  // Whether /index/bond_start is stored: only when the bonds are sorted by
  // their first end, as crackvis writes them.
  bool hasBondStart = false;
  // Whether /index/wide_cells is stored (a triangulated packing's part of
  // the index, WideCells), with its attributes.
  bool hasWideCells = false;
  double wideCellReach = 0.0;
  bool weightedTriangulation = false;
  // Whether /index/peeled_cells is stored with them (files since
  // 2026-11-30): without it a rank cannot peel the hull as the whole set's
  // triangulation does, and reads the whole set.
  bool hasPeeledCells = false;
};

// A triangulated packing's part of the index (/index/wide_cells): what a
// rank cannot learn from its slab. A rank triangulates its slab and a margin
// around it; a cell of that triangulation whose reach (the radius of the
// ball around its circumcentre, or power centre, that holds every particle
// able to unmake it: cracks::cellReach) lies inside the margin is a cell of
// the whole set's triangulation. Cells whose reach exceeds `reach` (the flat
// cells at the specimen's surface, which reach far along it) are stored
// here, found once on the whole set by its writer.
struct WideCells {
  double reach = 0.0;     // metres: every cell of larger reach is listed
  bool weighted = false;  // a regular (power) triangulation: the radii differ
  // Nodes ascending; in 2D the fourth is -1. Sorted.
  std::vector<std::array<ParticleIndex, 4>> cells;
  // The hull's slivers that the whole set's triangulation peels
  // (cracks::TriangulateOptions::peelHull), which a rank's triangulation of
  // its slab, with a hull of its own, cannot tell: it takes them out of its
  // cells. The same form; those of reach over `reach` are in `cells` too
  // (the unpeeled triangulation's wide cells).
  std::vector<std::array<ParticleIndex, 4>> peeled;
};

// Makes a triangulated packing's WideCells from its first step (the writer
// calls it with the step it writes, so the cells match the stored
// positions exactly); set by cracks::describeCells, since dem knows no
// triangulation.
using WideCellsMaker =
    std::function<Result<WideCells>(std::span<const Vec3> first, const Lattice& lattice)>;

struct SpatialIndex {
  SpatialIndexInfo info;
  std::vector<ParticleIndex> order;  // [N]: particles by (coordinate, index)
  std::vector<double> coordinate;    // [N]: order[k]'s reference coordinate along info.axis
  // [N + 1]: bonds [bondStart[i], bondStart[i + 1]) are those whose first
  // end is particle i; empty when the bonds are not sorted by first end.
  std::vector<std::int64_t> bondStart;
};

// The longest axis of a box: x, then y, then z on ties.
int longestAxis(const Bounds& box);
// The axis a specimen is cut across into slabs (the spatial index's, and
// cracks::partitionPiece's): the longest of the reference box, since slabs
// across it carry the thinnest ghost layers. Among the axes within
// kSliceAxisTolerance of the longest, the one along which the particles'
// order runs slowest (the coordinate falls least in all from one particle to
// the next; x, then y, then z on ties): a cube written x fastest
// is cut across z, and a slab is then one run of rows of every per-particle
// array, not part of every row (issue 34 point 4).
int sliceAxis(std::span<const Vec3> reference);
// Axes this close to the longest (relative) count as equally long: a slab's
// ghost layer grows by as much, a read by less than a row per row.
inline constexpr double kSliceAxisTolerance = 0.05;
// A point's coordinate along an axis (0 x, 1 y, 2 z).
inline double axisCoordinate(const Vec3& p, int axis) {
  return axis == 0 ? p.x : (axis == 1 ? p.y : p.z);
}
// The longest bond of a configuration (0 without bonds).
double longestBond(std::span<const Vec3> positions, std::span<const Bond> bonds);

// The index of a lattice with the reference configuration `reference`.
SpatialIndex buildSpatialIndex(std::span<const Vec3> reference, const Lattice& lattice,
                               CellDecomposition decomposition);

}  // namespace crackvis::dem
