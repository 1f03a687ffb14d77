// The four crack extraction methods behind one interface. An extractor is
// made once per data set (it keeps the bond graph view and, for the
// cell-based methods, the local decomposition across steps) and called once
// per step; calling it on steps in order is what makes it incremental.
//
// All methods run on all cores (TBB) and give the same output, in the same
// order, for any thread count.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <crackvis/common/status.hpp>
#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/crack_mesh.hpp>
#include <crackvis/cracks/lattice_decomposition.hpp>
#include <crackvis/cracks/triangulation.hpp>
#include <crackvis/dem/spatial_index.hpp>
#include <crackvis/vocabulary/crack_method.hpp>

// dem::Bounds has no comparison of its own; ExtractOptions compares its domain.
namespace crackvis::dem {
inline bool operator==(const Bounds& a, const Bounds& b) {
  return a.lo == b.lo && a.hi == b.hi;
}
}  // namespace crackvis::dem

namespace crackvis::cracks {

// An axis-aligned box (the domain that clips local Voronoi cells).
using Box = dem::Bounds;

// Everything one step provides; optional arrays may be empty.
struct StepInput {
  std::span<const Vec3> positions;          // [N]
  std::span<const std::uint8_t> bondState;  // [M], 1 broken
  std::span<const double> radius;           // [N]
  std::span<const float> bondForce;         // [M] optional
  std::span<const std::int32_t> breakStep;  // [M] optional
  // [N] optional: the configuration the cells of a triangulation are made
  // in (the file's first step); the positions of the first step extracted
  // when empty.
  std::span<const Vec3> referencePositions;
  // [N] optional, for a piece of a larger set (partition.hpp): each
  // particle's connected component by intact bonds in the whole set, at this
  // step and in the intact packing. A triangulation opens a never-bonded pair
  // when a crack separates its ends; the piece's own graph, cut at its ghost
  // layer, may split what the whole set joins. Labels are only compared.
  std::span<const std::int32_t> components;
  std::span<const std::int32_t> intactComponents;
};

struct ExtractOptions {
  Decomposition decomposition = Decomposition::kAuto;
  // cell attribute: decompose the whole lattice instead of the fractured
  // region, and the fewest broken bonds a cell needs to be output.
  bool globalDecomposition = false;
  int minBrokenBonds = 1;
  // local Voronoi: validate faces by the empty-sphere test; a vertex fails
  // when a particle lies inside its sphere by more than tolerance * radius.
  bool validate = true;
  double validationTolerance = 0.1;
  // local Voronoi: also output the faces of intact bonds (the local
  // decomposition), with bond_state 0, for display.
  bool includeIntactFaces = false;
  // local Voronoi: the clipping domain; default: the bounding box of the
  // particle centres (see defaultDomain) grown by domainMargin times the
  // largest radius. A triangulated packing uses a margin of 1, so the faces
  // of bonds at the specimen's surface reach its particles' extent instead
  // of lying outside the centres' box.
  std::optional<Box> domain;
  double domainMargin = 0.0;
  // local Voronoi, when the input is one piece of a larger set (partition.hpp):
  // the whole set's reference centres' box and largest radius, from which
  // the default domain is made instead of the piece's, so that a piece clips
  // its cells as the whole set does.
  std::optional<Box> specimenCentres;
  double specimenLargestRadius = 0.0;
  // Add cell data "owner_particle" (appendOwnerParticles), which a piece
  // keeps its own primitives by (keepOwned).
  bool ownerParticles = false;
  // triangulation: the cells and edges to use instead of triangulating the
  // reference configuration. A piece of a larger set is given the whole
  // set's, restricted to its particles: at the specimen's surface a
  // triangulation is not local (flat cells there depend on particles far
  // along the surface), so the piece's own would differ from the whole's.
  std::shared_ptr<const Triangulation> triangulation;
  // cell centre: use the centroid of each whole octahedron instead of its two
  // pyramids (on an undeformed FCC lattice the faces are then the Voronoi faces).
  bool mergeOctahedra = false;

  // Equal options make equal meshes: an extractor is kept while they are.
  friend bool operator==(const ExtractOptions&, const ExtractOptions&) = default;
};

class CrackExtractor {
 public:
  virtual ~CrackExtractor() = default;
  virtual Method method() const = 0;
  // Extracts the crack geometry of one step into `out` (cleared first).
  virtual Status extract(const StepInput& step, CrackMesh& out) = 0;
  // Bytes held between steps (decomposition, caches), for the memory budget.
  virtual std::size_t memoryBytes() const = 0;
  // The cell decomposition, for methods that keep one (else nullptr).
  virtual const LatticeDecomposition* decomposition() const { return nullptr; }
  // Bonds the last step found inconsistent (local Voronoi only).
  virtual std::size_t inconsistentBondCount() const { return 0; }
  // What the extractor divides space with (lattice or triangulation) once
  // it has seen a step.
  virtual Decomposition decompositionKind() const { return Decomposition::kLattice; }
};

// Whether the bonds span lattice cells: at least 98 % of the bonds of a
// sample of particles lie on a lattice cell found from the graph alone. A
// random packing's bonds do not (its 4-cliques fill a small part of space).
bool isLatticeGraph(const BondGraph& graph, int dimension);
// isLatticeGraph of a lattice's whole bond graph, as a file's spatial index
// records it (dem::DemMetadata::decomposition) for readers of one piece.
dem::CellDecomposition decompositionOf(const dem::Lattice& lattice);

// `chosen` with kAuto settled by the decomposition a file records
// (/index@decomposition: its writer applied decompositionOf, kAuto's own rule,
// to the whole graph), so that opening a file does not decide it again
// (isLatticeGraph: 5-13 ms on cuboid A). kAuto stays when none is recorded.
Decomposition settledByFile(Decomposition chosen, dem::CellDecomposition recorded);

// The graph must outlive the extractor.
std::unique_ptr<CrackExtractor> makeExtractor(Method method, const BondGraph& graph, int dimension,
                                              const ExtractOptions& options = {});

// Checks array lengths of a step against the graph.
Status checkStepInput(const BondGraph& graph, const StepInput& step);

// Per-point or per-primitive bond attributes: bond_id, bond_state and, when
// the step has them, break_step and bond_force.
void appendBondAttributes(const StepInput& step, std::span<const dem::BondIndex> bonds,
                          std::vector<AttributeArray>& arrays);

}  // namespace crackvis::cracks
