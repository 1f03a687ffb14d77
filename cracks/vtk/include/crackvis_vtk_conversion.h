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

void toPolyData(const CrackMesh& mesh, vtkPolyData* output);
void toUnstructuredGrid(const CrackMesh& mesh, vtkUnstructuredGrid* output);

}  // namespace crackvis::cracks::vtkadapter

#endif
