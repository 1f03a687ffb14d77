// The names of the four crack surface methods and of the ways space is
// divided into cells: what a pipeline description, the CLI and the client
// say. The methods themselves are crackvis/cracks/extractor.hpp.
#pragma once

#include <string_view>

#include <crackvis/common/status.hpp>

namespace crackvis::cracks {

enum class Method { kCellAttribute, kCellCut, kLocalVoronoi, kCellCentre };

std::string_view toString(Method method);
Result<Method> parseMethod(std::string_view name);

// How space is divided into cells (docs/methods.md, "Any packing"):
//  - lattice: the cells the bonds span (tetrahedra and octahedra in 3D,
//    triangles in 2D), found from the bond graph alone;
//  - triangulation: the Delaunay triangulation of the reference
//    configuration's centres, regular (weighted by r^2) for unequal radii;
//    triangulation edges that were never bonded count as bonded through
//    their common bonded neighbours;
//  - auto: lattice when the bonds span lattice cells (isLatticeGraph), else
//    triangulation.
enum class Decomposition { kAuto, kLattice, kTriangulation };

std::string_view toString(Decomposition decomposition);
Result<Decomposition> parseDecomposition(std::string_view name);

}  // namespace crackvis::cracks
