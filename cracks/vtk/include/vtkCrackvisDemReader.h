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
// Under MPI (pvbatch, pvserver: more than one piece asked for) each piece is
// a slab of the reference configuration with equal particle counts plus a
// ghost layer GhostWidth longest bonds wide (crackvis/cracks/partition.hpp):
// points and bonds are then the piece's, in the file's order, with
// "vtkGhostType" marking ghost particles and bonds owned by another piece
// (a bond belongs to the piece owning its smaller-index end), global ids
// (the file's particle and bond indices), and field data with the whole
// set's box, largest radius and decomposition. The four filters output
// exactly the piece's own primitives of what the whole set gives, so the
// pieces together equal a single-process run face for face.
//
// A file that cannot be read is reported with vtkErrorMacro, naming the file
// and the defect, and leaves the output empty.
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

  // The ghost layer of a piece under MPI, in longest reference bonds: wide
  // enough for every method's neighbourhood (a cell, local Voronoi's
  // validation sphere, a triangulation's cells) around the piece's own
  // particles. Default 4.
  vtkSetClampMacro(GhostWidth, double, 1.0, 1000.0);
  vtkGetMacro(GhostWidth, double);

 protected:
  vtkCrackvisDemReader();
  ~vtkCrackvisDemReader() override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  double GhostWidth = 4.0;
  std::unique_ptr<crackvis::cracks::vtkadapter::DemReaderCache> Cache;

 private:
  vtkCrackvisDemReader(const vtkCrackvisDemReader&) = delete;
  void operator=(const vtkCrackvisDemReader&) = delete;
};

#endif  // vtkCrackvisDemReader_h
