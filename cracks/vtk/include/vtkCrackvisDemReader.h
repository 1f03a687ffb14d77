// vtkCrackvisDemReader: a crackvis-dem file (v1.0 and v1.1,
// docs/data-format.md) as the lattice polydata the four crack filters take,
// one output per saved step, with the steps' simulated times as VTK time
// steps (ParaView's time controls step through them).
//
// Output: points = particle centres at the step; lines = the bonds, one
// 2-point line per bond in the file's bond order; point data "radius",
// "reference_position" (the first step's positions, in which the filters make
// material surfaces and triangulations, as `crackvis extract` does) and, when
// the file holds them, "velocity", "particle_id", "particle_group" and the
// per-particle extra arrays; cell data "bond_state", "break_step" and, when
// present, "bond_force", "strength", "bond_flags" and the per-bond extra
// arrays; field data "step" (the index read), "time" and the step scalars.
//
// Under MPI (pvbatch, pvserver) the whole data set is produced by piece 0 and
// the other pieces are empty (a spatial partition with ghosts is issue 19
// point 2). A file that cannot be read is reported with vtkErrorMacro, naming
// the file and the defect, and leaves the output empty.
#ifndef vtkCrackvisDemReader_h
#define vtkCrackvisDemReader_h

#include <memory>
#include <string>
#include <vector>

#include <vtkPolyDataAlgorithm.h>

// Nested the C++14 way: VTK 9.1-9.2 wrappers (ParaView) cannot parse a::b.
namespace crackvis {
namespace cracks {
namespace vtkadapter {
struct DemReaderCache;
}  // namespace vtkadapter
}  // namespace cracks
}  // namespace crackvis

class vtkCrackvisDemReader : public vtkPolyDataAlgorithm {
 public:
  static vtkCrackvisDemReader* New();
  vtkTypeMacro(vtkCrackvisDemReader, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);
  // Whether the file looks like a crackvis-dem file (HDF5 with the format
  // attribute); ParaView asks this to pick a reader for an .h5 file.
  int CanReadFile(const char* fileName);

 protected:
  vtkCrackvisDemReader();
  ~vtkCrackvisDemReader() override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  std::unique_ptr<crackvis::cracks::vtkadapter::DemReaderCache> Cache;

 private:
  vtkCrackvisDemReader(const vtkCrackvisDemReader&) = delete;
  void operator=(const vtkCrackvisDemReader&) = delete;
};

#endif  // vtkCrackvisDemReader_h
