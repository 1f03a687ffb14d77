// CrackMesh to VTK data, for code that builds VTK scenes from the core's
// output directly (the render server) rather than through the filters.
#ifndef crackvis_vtk_conversion_h
#define crackvis_vtk_conversion_h

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::cracks::vtkadapter {

// Point data of the lattice polydata holding the reference configuration
// (the first step's positions, 3 components): the crackvis-dem reader writes
// it and the crack filters use it as `crackvis extract` uses the first step.
inline constexpr const char* kReferencePositionArray = "reference_position";

// Field data of a piece of a larger set (the reader under MPI, partition.hpp):
// the whole set's reference centres' box (6 values: lo x y z, hi x y z), its
// largest radius, and how space is divided for it (0 lattice, 1
// triangulation, decided on the whole bond graph). With them, and the
// piece's "vtkGhostType" and global ids, a filter outputs exactly the
// primitives the piece owns of what the whole set gives.
inline constexpr const char* kSpecimenCentresArray = "crackvis_specimen_centres";
inline constexpr const char* kLargestRadiusArray = "crackvis_largest_radius";
inline constexpr const char* kDecompositionArray = "crackvis_decomposition";
// ... and, for a triangulation, the whole set's cells (4 piece particle
// indices each, the fourth -1 in 2D) and edges (2 each) that lie in the piece.
inline constexpr const char* kTriangulationCellsArray = "crackvis_triangulation_cells";
inline constexpr const char* kTriangulationEdgesArray = "crackvis_triangulation_edges";
// ... and point data: each particle's connected component by intact bonds in
// the whole set, at the step and in the intact packing (StepInput).
inline constexpr const char* kComponentArray = "crackvis_component";
inline constexpr const char* kIntactComponentArray = "crackvis_intact_component";

void toPolyData(const CrackMesh& mesh, vtkPolyData* output);
void toUnstructuredGrid(const CrackMesh& mesh, vtkUnstructuredGrid* output);

}  // namespace crackvis::cracks::vtkadapter

#endif
