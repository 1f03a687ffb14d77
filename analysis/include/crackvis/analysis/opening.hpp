// Crack opening: how far a crack surface has opened, and how far its sides
// have slid, element by element.
//
// A surface element stands for one bond (local Voronoi, cell centre: cell
// data bond_id) or for the bonds of its points (cell cut: point data
// bond_id). Its displacement jump is the bond's current separation minus its
// separation in the reference configuration, d - d0 with d = x_j - x_i,
// averaged over the element's bonds. The jump splits along the crack's
// normal there: opening = jump . n (positive when the sides move apart),
// slip = |jump - opening n|.
//
// Which normal: the crack's local normal at the element's bonds
// (bond_normals.hpp: the plane through the reference midpoints of the
// broken bonds nearby), not the face's own, which zig-zags about the crack
// and leans over as it opens. An element of several bonds (cell cut) takes
// their mean.
//
// Elements that carry no bond of the file (cell attribute's cells, virtual
// bonds of a triangulation, inconsistency marks) have no opening: NaN.
#pragma once

#include <span>
#include <vector>

#include <crackvis/analysis/bond_normals.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/crack_mesh.hpp>
#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::analysis {

using cracks::CrackComponents;
using cracks::CrackMesh;
using dem::Vec3;

struct OpeningOptions {
  // Radius of the neighbourhood whose plane gives a bond's normal, m; 0:
  // three times the mean reference length of the bonds.
  double smoothingRadius = 0.0;
};

// One entry per surface primitive (cracks::surfacePrimitives order).
struct ElementOpenings {
  std::vector<double> area;             // m^2 (2D: length, m)
  std::vector<Vec3> centroid;           // m
  std::vector<Vec3> normal;             // the crack's local unit normal, along the bond
  std::vector<double> opening;          // m, NaN without a bond
  std::vector<double> slip;             // m, NaN without a bond
  std::vector<std::int32_t> component;  // CrackComponents index, -1 none
  std::vector<std::size_t> cell;        // the primitive among all, in VTK (cell data) order
  double smoothingRadius = 0.0;         // the radius used, m

  std::size_t size() const { return area.size(); }
};

// `reference` and `current` are the particle centres [N]; `bonds` the
// lattice's pairs [M]; `normals`, kept across steps by the caller, has every
// bond the mesh carries (else the normals of those bonds are found here,
// with options.smoothingRadius).
ElementOpenings measureOpening(const CrackMesh& mesh, const CrackComponents& components,
                               std::span<const dem::Bond> bonds, std::span<const Vec3> reference,
                               std::span<const Vec3> current, const OpeningOptions& options = {},
                               const BondNormals* normals = nullptr);

// measureOpening in two halves, for a caller that finds the components
// beside the first (CrackAnalysis); `primitives` are surfacePrimitives(mesh)
// and `out`'s arrays keep their memory from call to call. First the bonds'
// part of every element: its cell, normal, opening and slip (`normals` has
// every bond the mesh carries); `out` is sized to the primitives.
void measureBondOpenings(const CrackMesh& mesh, std::span<const cracks::Primitive> primitives,
                         std::span<const dem::Bond> bonds, std::span<const Vec3> reference,
                         std::span<const Vec3> current, const BondNormals& normals,
                         ElementOpenings& out);
// Then where each element lies: its area and centroid (from `extents`, one
// per primitive of these, as ComponentTracker::extents() gives them; or
// where empty, or of another length, from its points) and its component.
void placeOpenings(const CrackMesh& mesh, std::span<const cracks::Primitive> primitives,
                   const CrackComponents& components,
                   std::span<const cracks::PrimitiveExtent> extents, ElementOpenings& out);

// Cell data "opening" and "slip" over all the mesh's primitives in VTK order
// (NaN for those that are no surface element), appended to mesh.cellData.
void appendOpeningArrays(CrackMesh& mesh, const ElementOpenings& openings);

// Area-weighted statistics of one component (or of all: component < 0).
struct OpeningSummary {
  std::size_t elements = 0;  // with a bond
  double area = 0.0;         // of those elements
  double meanOpening = 0.0;  // area-weighted
  double maxOpening = 0.0;
  double meanSlip = 0.0;
  double maxSlip = 0.0;
};
OpeningSummary summariseOpening(const ElementOpenings& openings, int component);
// The same for components 0 .. components-1 in one pass over the elements
// (a crack of 10,000 pieces would otherwise be read 10,000 times).
std::vector<OpeningSummary> summariseByComponent(const ElementOpenings& openings,
                                                 std::size_t components);

// Area-weighted histogram of opening over [lo, hi) in `bins` bins: area per
// bin (values outside the range go to the end bins).
struct Histogram {
  double lo = 0.0;
  double hi = 0.0;
  std::vector<double> weight;
  double binWidth() const {
    return weight.empty() ? 0.0 : (hi - lo) / static_cast<double>(weight.size());
  }
};
Histogram openingHistogram(const ElementOpenings& openings, int component, double lo, double hi,
                           int bins);

// The opening profile along a component: its elements binned by position
// along `axis` (a unit vector in the crack's plane), with the area-weighted
// mean opening and slip per bin; bins without elements are left out.
struct ProfileBin {
  double position = 0.0;  // bin centre along the axis, m
  double area = 0.0;
  double opening = 0.0;
  double slip = 0.0;
};
std::vector<ProfileBin> openingProfile(const ElementOpenings& openings, int component, Vec3 axis,
                                       int bins);

// The in-plane axis along which a component extends furthest: of the two
// axes of its best-fit plane (2D: the line's direction).
Vec3 longestAxis(const ElementOpenings& openings, int component, Vec3 planeNormal);

}  // namespace crackvis::analysis
