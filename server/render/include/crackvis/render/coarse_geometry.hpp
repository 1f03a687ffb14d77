// Coarse stand-ins for a scene's heaviest layers,
// drawn in place of them in a drag's frames while the node is crowded
// (SceneRenderer::FrameDetail::kCoarse). llvmpipe's cost of a frame follows
// its primitives, not its pixels (docs/benchmarks.md, "Many users on one
// render node"): a reduced frame of cuboid A costs as much at factor 6 as at
// 2, so fewer pixels cannot make room for more sessions, fewer primitives can.
//
// Both stand-ins cluster by a grid of cubic cells (vertex clustering,
// Rossignac and Borrel's): what lies in one cell becomes one sphere or one
// vertex. A point that is not finite is in no cell: its sphere, and a cell
// with a corner there, are left out. A stand-in keeps every array of its input (each cluster takes
// its first member's values: a categorical colouring such as the fragment id stays one of its
// members', never a blend), so the mapper colours it as it does the layer itself.
#pragma once

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

namespace crackvis::render {

// Spheres (one vertex cell per point, `radiusArray` the radii) clustered by
// cells `cell` wide: one sphere per occupied cell, at its members' mean
// centre, just wide enough to hold them all (a cube of eight touching
// spheres of radius r becomes one of radius (1 + sqrt 3) r), so that no gap
// opens where the members closed the view. Null when the input is not such
// a sphere set.
vtkSmartPointer<vtkPolyData> coarseSpheres(vtkPolyData& spheres, const char* radiusArray,
                                           double cell);

// A surface's points clustered by cells `cell` wide (each to its cluster's
// mean): a polygon whose corners fall into fewer than three clusters, and a
// line into fewer than two, goes; the rest keep their cell data. Null for
// input with triangle strips (crack meshes have none).
vtkSmartPointer<vtkPolyData> coarseSurface(vtkPolyData& surface, double cell);

}  // namespace crackvis::render
