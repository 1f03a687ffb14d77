// vtkCellCutCrackFilter: crack surfaces by the cell cut method (dissertation
// 2.1.2): in each cut cell of the local decomposition, the case table's
// polygons (lines in 2D) through the midpoints of broken bonds; one point per
// broken bond, shared between cells, with the bond's attributes as point data.
//
// Input (port 0): the lattice as vtkPolyData: points = particle centres,
// lines = the bonds (one 2-point line per bond, in bond order), point data
// "radius" (optional: RadiusDefault otherwise), cell data "bond_state"
// (1 broken) and optionally "bond_force" and "break_step".
//
// The filters keep their state between updates while the bonds stay the
// same: a viewer stepping through time gets the incremental decomposition.
// Changing the bond topology (another lattice) starts over.
//
// vtkCellCutCrackFilter, vtkLocalVoronoiCrackFilter and
// vtkCellCentreCrackFilter produce vtkPolyData; vtkCellAttributeCrackFilter
// produces a vtkUnstructuredGrid of tetrahedra and pyramids (triangles in 2D)
// with cell data "broken_bonds".
#ifndef vtkCellCutCrackFilter_h
#define vtkCellCutCrackFilter_h

#include <memory>

#include <vtkPolyDataAlgorithm.h>

// Nested the C++14 way: VTK 9.1-9.2 wrappers (ParaView) cannot parse a::b.
namespace crackvis {
namespace cracks {
namespace vtkadapter {
class CrackFilterState;
}  // namespace vtkadapter
}  // namespace cracks
}  // namespace crackvis

class vtkCellCutCrackFilter : public vtkPolyDataAlgorithm {
 public:
  static vtkCellCutCrackFilter* New();
  vtkTypeMacro(vtkCellCutCrackFilter, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  vtkSetMacro(RadiusDefault, double);
  vtkGetMacro(RadiusDefault, double);

 protected:
  vtkCellCutCrackFilter();
  ~vtkCellCutCrackFilter() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  double RadiusDefault = 0.5;
  std::unique_ptr<crackvis::cracks::vtkadapter::CrackFilterState> State;

 private:
  vtkCellCutCrackFilter(const vtkCellCutCrackFilter&) = delete;
  void operator=(const vtkCellCutCrackFilter&) = delete;
};

#endif  // vtkCellCutCrackFilter_h
