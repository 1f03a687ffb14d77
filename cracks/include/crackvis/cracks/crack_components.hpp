// Connected pieces of a crack surface, to tell the main crack from scattered
// damage: in a tension run most broken bonds are isolated, and each makes a
// small surface piece of its own away from the main crack.
//
// A component of a surface is a set of surface primitives (polygons in 3D,
// segments of lines not flagged inconsistent in 2D) connected through shared
// points, after welding points that coincide within 1e-9 of the mesh size
// (the same rule as SurfaceMetrics::components). For each: its area (2D:
// length), bounding box, area-weighted centroid and best-fit plane (the
// least-squares plane of the surface, through the second moments of its
// triangles; in 2D the best-fit line in the xy plane; for a component of
// one polygon its plane by Newell's normal, the same for a planar polygon,
// and of one segment its line).
//
// The cell attribute method gives cells, not a surface (CrackMesh::holdsCells):
// a component is a set of cells joined through shared faces (3D) or edges
// (2D), its centroid and best-fit plane those of its volume (2D: its area),
// and its area the crack the cells enclose: the cells projected onto that
// plane (2D: line), rasterised with a step of an eighth of the shortest cell edge.
//
// Coverage: the component's area projected onto its best-fit plane over the
// specimen's cross-section there. Both are rasterised on the plane with cells
// of a quarter of the smallest radius, so a folded or doubled surface counts
// once. The section is the convex hull of the centres of the particles the
// plane cuts (|distance| <= radius), projected onto it: the material the
// plane meets, out to the centres, where local Voronoi is defined (the cells
// of a decomposition end at the centres' hull, a triangulation's at the hull
// less the slivers it peels). It is taken of the reference
// configuration where the step has one: the plane of an opened crack runs
// through the gap, where it cuts no particle of the current step.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <crackvis/cracks/crack_mesh.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::cracks {

using Matrix3 = std::array<std::array<double, 3>, 3>;

// Eigenvector of the smallest eigenvalue of a symmetric 3x3 matrix (unit
// length). The largest one's is that of (trace * I - a).
Vec3 smallestEigenvector(Matrix3 a);

struct CrackComponent {
  std::size_t primitives = 0;
  double area = 0.0;  // m^2 (2D: length, m)
  dem::Bounds box;
  // Zero where only areas were summed (CrackComponents::planes false).
  Vec3 centroid;
  Vec3 normal;  // unit normal of the best-fit plane (2D: of the best-fit line, z = 0)
};

struct CrackComponents {
  std::vector<CrackComponent> components;  // largest area first
  // The component of each polygon (3D) or line (2D) of a surface, or of each
  // volume cell (3D) or triangle (2D) of a cell mesh, in mesh order, as an
  // index into `components`; -1 for inconsistency marks.
  std::vector<std::int32_t> ofPrimitive;
  // False where only each component's primitives, area and box were summed
  // (ComponentDetail::kAreas): componentPlane finds a centroid and plane.
  bool planes = true;
};

CrackComponents findComponents(const CrackMesh& mesh);

// findComponents kept across the steps of a run, for a viewer or an analysis
// that is fed the steps in order. Where a surface's every polygon (3D) or
// line (2D) carries one bond of its own (cell data bond_id: local Voronoi,
// cell centre) and the faces are made once per bond and carried with the
// particles (`carried`: the step has a reference configuration), two faces
// that shared a point keep sharing it, and faces only come as bonds break.
// So only the faces of bonds new since the last step are welded: against
// each other, and against the old faces' points that fall near them (within
// 1e-9 of the size of the box of its primitives' points: the mesh's, as
// findComponents takes it, unless some point of the mesh is on none). The
// components' areas, boxes and (ComponentDetail::kEvery) planes are summed
// anew each step (the faces move). Anything else (cells, cell cut's point
// bond ids, no reference configuration, a bond that left the mesh or holds
// two cells) is found anew by findComponents, and the tracker starts over.

// What the tracker sums of each component each step: everything (kEvery),
// or its primitives, area and box (kAreas: the analyses ask for one
// component's plane now and then, and the second moments of every face were
// most of a step's work).
enum class ComponentDetail { kEvery, kAreas };

// A surface primitive's own box, area (a segment's length, as measure()
// gives it) and centroid (the mean of its points).
struct PrimitiveExtent {
  dem::Bounds box;
  double area = 0.0;
  Vec3 centroid;
};
// One primitive's extent, reading its points once (none for an empty one).
PrimitiveExtent measureExtent(const CrackMesh& mesh, const Primitive& primitive);

class ComponentTracker {
 public:
  explicit ComponentTracker(ComponentDetail detail = ComponentDetail::kEvery) : m_detail(detail) {}
  const CrackComponents& update(const CrackMesh& mesh, bool carried);
  // The same with the mesh's surface primitives (surfacePrimitives(mesh))
  // made by the caller, who reads extents() with them.
  const CrackComponents& update(const CrackMesh& mesh, bool carried,
                                std::span<const Primitive> primitives);
  const CrackComponents& current() const { return m_components; }
  // How often update() found the components of the whole mesh anew.
  std::size_t recomputations() const { return m_recomputations; }
  // Each surface primitive's extent at the last update, in the order of its
  // primitives (surfacePrimitives order), where that update summed areas
  // (ComponentDetail::kAreas) of a carried surface; else empty. The openings
  // read the areas and centroids from here instead of the faces' points
  // again. Valid for the mesh given to that update only, until the next one.
  std::span<const PrimitiveExtent> extents() const {
    // Areas only were summed exactly where the tracker kept the surface.
    return m_components.planes ? std::span<const PrimitiveExtent>()
                               : std::span<const PrimitiveExtent>(m_extents);
  }

 private:
  bool updateCarried(const CrackMesh& mesh, std::span<const Primitive> primitives);
  void measureAndWeld(const CrackMesh& mesh, std::span<const Primitive> primitives,
                      const std::vector<std::int32_t>& slots, std::int32_t oldSlots);
  void unite(std::int32_t a, std::int32_t b);
  std::int32_t slotOf(std::size_t bond);
  void reset();

  std::vector<std::int32_t> m_slotOfBond;  // -1: no face yet
  std::vector<std::int32_t> m_parent;      // union-find over slots
  std::vector<std::int64_t> m_cellOfSlot;  // the slot's cell this step
  std::vector<std::uint32_t> m_seenAt;     // the step stamp a slot was last seen at
  std::uint32_t m_stamp = 0;
  ComponentDetail m_detail;
  // Each face's box, area and centroid at the last update (kAreas; with
  // kEvery boxes only, and not every step), kept from step to step for
  // their pages.
  std::vector<PrimitiveExtent> m_extents;
  CrackComponents m_components;
  std::size_t m_recomputations = 0;
};

// The index, among all the mesh's primitives in VTK order (cell data order),
// of the first one ofPrimitive numbers.
std::size_t componentPrimitiveBase(const CrackMesh& mesh);

// Fraction (0..1) of the specimen's section by component c's best-fit plane
// that the component covers in projection onto that plane; `positions` and
// `radius` ([N], or one for all) are the particles the section is taken of.
double sectionCoverage(const CrackMesh& mesh, const CrackComponents& set, std::size_t c,
                       std::span<const Vec3> positions, std::span<const double> radius);
// The same for a step: of its reference configuration, if it has one.
double sectionCoverage(const CrackMesh& mesh, const CrackComponents& set, std::size_t c,
                       const StepInput& step);

// Component c's centroid and best-fit plane as findComponents gives them
// (to the last bit: the same moments in the same order), also where `set`
// holds areas only; zero for a c it does not have.
struct ComponentPlane {
  Vec3 centroid;
  Vec3 normal;
};
ComponentPlane componentPlane(const CrackMesh& mesh, const CrackComponents& set, std::size_t c);

// Which components to keep: those of at least `minArea`, and of those the
// `largest` biggest (0: all).
struct ComponentFilter {
  double minArea = 0.0;
  int largest = 0;
  bool active() const { return minArea > 0.0 || largest > 0; }
};

// Drops the primitives of the components the filter does not keep (surface
// primitives, or a cell mesh's cells), with their cell data; inconsistency
// marks and vertices stay.
void keepComponents(CrackMesh& mesh, const CrackComponents& set, const ComponentFilter& filter);

}  // namespace crackvis::cracks
