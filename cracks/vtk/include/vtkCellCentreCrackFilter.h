// vtkCellCentreCrackFilter: crack surfaces by the cell centre method
// (dissertation 2.3): for each broken bond, the polygon through the centroids
// of the cells around it; bond attributes as cell data.
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
#ifndef vtkCellCentreCrackFilter_h
#define vtkCellCentreCrackFilter_h

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

class vtkCellCentreCrackFilter : public vtkPolyDataAlgorithm {
 public:
  static vtkCellCentreCrackFilter* New();
  vtkTypeMacro(vtkCellCentreCrackFilter, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  vtkSetMacro(RadiusDefault, double);
  vtkGetMacro(RadiusDefault, double);
  // One centre per octahedron instead of one per pyramid (default off).
  vtkSetMacro(MergeOctahedra, bool);
  vtkGetMacro(MergeOctahedra, bool);
  vtkBooleanMacro(MergeOctahedra, bool);

 protected:
  vtkCellCentreCrackFilter();
  ~vtkCellCentreCrackFilter() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  double RadiusDefault = 0.5;
  bool MergeOctahedra = false;
  std::unique_ptr<crackvis::cracks::vtkadapter::CrackFilterState> State;

 private:
  vtkCellCentreCrackFilter(const vtkCellCentreCrackFilter&) = delete;
  void operator=(const vtkCellCentreCrackFilter&) = delete;
};

#endif  // vtkCellCentreCrackFilter_h
