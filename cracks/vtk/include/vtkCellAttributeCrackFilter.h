// vtkCellAttributeCrackFilter: the cell attribute method (dissertation 2.1.1):
// the cells of the decomposition with their number of broken bonds as cell
// data "broken_bonds", as a vtkUnstructuredGrid.
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
#ifndef vtkCellAttributeCrackFilter_h
#define vtkCellAttributeCrackFilter_h

#include <memory>

#include <vtkUnstructuredGridAlgorithm.h>

// Nested the C++14 way: VTK 9.1-9.2 wrappers (ParaView) cannot parse a::b.
namespace crackvis {
namespace cracks {
namespace vtkadapter {
class CrackFilterState;
}  // namespace vtkadapter
}  // namespace cracks
}  // namespace crackvis

class vtkCellAttributeCrackFilter : public vtkUnstructuredGridAlgorithm {
 public:
  static vtkCellAttributeCrackFilter* New();
  vtkTypeMacro(vtkCellAttributeCrackFilter, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  vtkSetMacro(RadiusDefault, double);
  vtkGetMacro(RadiusDefault, double);
  // Decompose the whole lattice (default: the fractured region only).
  vtkSetMacro(GlobalDecomposition, bool);
  vtkGetMacro(GlobalDecomposition, bool);
  // Fewest broken bonds a cell needs to be output (default 1).
  vtkSetClampMacro(MinimumBrokenBonds, int, 0, 8);
  vtkGetMacro(MinimumBrokenBonds, int);

 protected:
  vtkCellAttributeCrackFilter();
  ~vtkCellAttributeCrackFilter() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  double RadiusDefault = 0.5;
  bool GlobalDecomposition = false;
  int MinimumBrokenBonds = 1;
  std::unique_ptr<crackvis::cracks::vtkadapter::CrackFilterState> State;

 private:
  vtkCellAttributeCrackFilter(const vtkCellAttributeCrackFilter&) = delete;
  void operator=(const vtkCellAttributeCrackFilter&) = delete;
};

#endif  // vtkCellAttributeCrackFilter_h
