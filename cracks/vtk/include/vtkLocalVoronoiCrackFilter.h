// vtkLocalVoronoiCrackFilter: crack surfaces by the local Voronoi method
// (dissertation 2.2): the face of each broken bond in the Voronoi cells of its
// end particles, clipped by bonded neighbours and the domain box, validated by
// the empty-sphere test; bonds that fail are output as lines with cell data
// inconsistent = 1. Bond attributes are cell data of the faces.
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
#ifndef vtkLocalVoronoiCrackFilter_h
#define vtkLocalVoronoiCrackFilter_h

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

class vtkLocalVoronoiCrackFilter : public vtkPolyDataAlgorithm {
 public:
  static vtkLocalVoronoiCrackFilter* New();
  vtkTypeMacro(vtkLocalVoronoiCrackFilter, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  vtkSetMacro(RadiusDefault, double);
  vtkGetMacro(RadiusDefault, double);
  // Empty-sphere validation (default on) and its tolerance (default 0.1).
  vtkSetMacro(Validate, bool);
  vtkGetMacro(Validate, bool);
  vtkBooleanMacro(Validate, bool);
  vtkSetClampMacro(ValidationTolerance, double, 0.0, 1.0);
  vtkGetMacro(ValidationTolerance, double);
  // Also output the faces of intact bonds (the local decomposition).
  vtkSetMacro(IncludeIntactFaces, bool);
  vtkGetMacro(IncludeIntactFaces, bool);

 protected:
  vtkLocalVoronoiCrackFilter();
  ~vtkLocalVoronoiCrackFilter() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  double RadiusDefault = 0.5;
  bool Validate = true;
  double ValidationTolerance = 0.1;
  bool IncludeIntactFaces = false;
  std::unique_ptr<crackvis::cracks::vtkadapter::CrackFilterState> State;

 private:
  vtkLocalVoronoiCrackFilter(const vtkLocalVoronoiCrackFilter&) = delete;
  void operator=(const vtkLocalVoronoiCrackFilter&) = delete;
};

#endif  // vtkLocalVoronoiCrackFilter_h
