// CrackMesh to VTK data, for code that builds VTK scenes from the core's
// output directly (the render server) rather than through the filters.
#ifndef crackvis_vtk_conversion_h
#define crackvis_vtk_conversion_h

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::cracks::vtkadapter {

void toPolyData(const CrackMesh& mesh, vtkPolyData* output);
void toUnstructuredGrid(const CrackMesh& mesh, vtkUnstructuredGrid* output);

}  // namespace crackvis::cracks::vtkadapter

#endif
