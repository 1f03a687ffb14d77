// What the four crack filters share: turning the lattice polydata into the
// core's arrays (checked), keeping the bond graph and the extractor while the
// bonds stay the same, and turning a CrackMesh back into VTK data.
#ifndef crackvis_crack_filter_state_h
#define crackvis_crack_filter_state_h

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <typeinfo>
#include <utility>
#include <vector>

#include <vtkDataArray.h>
#include <vtkSmartPointer.h>
#include <vtkType.h>

#include "crackvis_vtk_conversion.h"
#include <crackvis/cracks/extractor.hpp>

namespace crackvis::analysis {
class BondNormals;
}

class vtkCellArray;
class vtkFieldData;
class vtkObject;
class vtkPolyData;
class vtkUnstructuredGrid;

namespace crackvis::cracks::vtkadapter {

// Which VTK object a cached copy was read from. The reader hands the same
// time-independent arrays at every step; the same object with the same
// modification time holds the same values (VTK's modification counter is
// global, so a new array at a freed one's address has another time).
class ArrayStamp {
 public:
  bool matches(vtkObject* object) const;
  void set(vtkObject* object);

 private:
  const vtkObject* m_object = nullptr;
  vtkMTimeType m_time = 0;
};

// A VTK array of `type` (VTK_DOUBLE, VTK_INT, ...) viewing `tuples` x
// `components` values at `memory`, which `owner` keeps alive, instead of a
// copy: VTK releases `owner` when the last array using the memory lets it go
// (its deleter may then recycle the memory). Read-only by contract: nothing
// downstream may write into the values. Empty (no memory viewed) for no
// tuples.
vtkSmartPointer<vtkDataArray> viewingArray(int type, const char* name, const void* memory,
                                           vtkIdType tuples, int components,
                                           std::shared_ptr<const void> owner,
                                           const std::type_info& ownerType);
template <typename Owner>
vtkSmartPointer<vtkDataArray> viewingArray(int type, const char* name, const void* memory,
                                           vtkIdType tuples, int components,
                                           std::shared_ptr<Owner> owner) {
  return viewingArray(type, name, memory, tuples, components,
                      std::shared_ptr<const void>(std::move(owner)), typeid(Owner));
}

// A piece's triangulation as its two field arrays (kTriangulationCellsArray,
// kTriangulationEdgesArray). The arrays view the triangulation's memory
// rather than copy it, and keep it alive while they do; a filter in the same
// process takes it back from them (viewedTriangulation) and shares it with
// its extractor. Copies were two of the three a rank held of its cells and
// edges (about 90 MB each at 10^6 particles on 2 ranks). The arrays are
// read-only: nothing may write into them. Nothing is added for a
// triangulation without cells.
void addTriangulationArrays(std::shared_ptr<const Triangulation> triangulation,
                            vtkFieldData* field);
// The triangulation that `cells` and `edges` view, when both were made by
// addTriangulationArrays from the same one and still view it; else null (the
// values must then be copied).
std::shared_ptr<const Triangulation> viewedTriangulation(vtkDataArray* cells, vtkDataArray* edges);

// Where one update's time went, stage by stage, for the plugin's benchmarks
// under MPI (tools/bench/mpi-ranks.sh): rank 0's clock around an update says
// nothing of the other ranks' parts. With CRACKVIS_VTK_TIMINGS set in the
// environment, report() prints one line on standard error, tagged with the
// process id, its MPI rank, the stages' start and end on the monotonic
// clock, and the process's resident and peak memory after them; otherwise
// marks cost a clock read and nothing is printed.
class StageLog {
 public:
  StageLog();
  // The time since the last mark (or since construction) goes to `stage`.
  void mark(const char* stage);
  // `time`: the step's time value, as the pipeline asked for it; `out`:
  // where the line goes (standard error but in tests).
  void report(const char* what, double time, std::FILE* out = stderr) const;

 private:
  bool m_enabled = false;
  std::chrono::steady_clock::time_point m_start;
  std::chrono::steady_clock::time_point m_last;
  std::string m_stages;
};

class CrackFilterState {
 public:
  CrackFilterState();
  ~CrackFilterState();  // where BondNormals is complete
  CrackFilterState(const CrackFilterState&) = delete;
  CrackFilterState& operator=(const CrackFilterState&) = delete;

  // Extracts one step from `input`. On bad input returns false and says why
  // in `error` (the filter reports it with vtkErrorMacro).
  bool run(vtkPolyData* input, Method method, const ExtractOptions& options, double radiusDefault,
           CrackMesh& mesh, std::string& error);
  // Ends the last run's stages with the filter's output (made since run
  // returned) and reports them (StageLog) as `what`, at the input's time.
  void reportStages(vtkPolyData* input, const char* what);

 private:
  bool readLattice(vtkPolyData* input, double radiusDefault, std::string& error);
  static bool readBonds(vtkCellArray* lines, vtkIdType n, std::vector<dem::Bond>& bonds,
                        std::string& error);
  void readRadius(vtkPolyData* input, vtkIdType n, double radiusDefault);
  void readBreakSteps(vtkPolyData* input, vtkIdType m);
  void readReference(vtkPolyData* input, vtkIdType n);
  // A piece of a larger set (the reader under MPI): what makes its output
  // the piece's own share of the whole set's. False for a whole set.
  bool readPiece(vtkPolyData* input, ExtractOptions& options);
  void readTriangulation(vtkPolyData* input, ExtractOptions& options);
  std::shared_ptr<const Triangulation> copyTriangulation(vtkDataArray* cells,
                                                         vtkDataArray* edges) const;
  void toWholeSet(CrackMesh& mesh) const;

  std::vector<dem::Bond> m_bonds;
  // What the time-independent copies below were read from: unchanged, they
  // are not read again at the next step.
  ArrayStamp m_linesStamp;
  ArrayStamp m_radiusStamp;
  ArrayStamp m_breakStepStamp;
  ArrayStamp m_referenceStamp;
  ArrayStamp m_ghostStamp;
  std::vector<Vec3> m_positions;
  std::vector<double> m_radius;
  std::vector<std::uint8_t> m_state;
  std::vector<float> m_force;
  std::vector<std::int32_t> m_breakStep;
  std::vector<Vec3> m_reference;  // empty: the input has no reference configuration
  // A piece's: 1 for its own particles, and the whole set's indices.
  std::vector<std::uint8_t> m_owned;
  vtkSmartPointer<vtkDataArray> m_globalParticle;  // the input's global ids
  vtkSmartPointer<vtkDataArray> m_globalBond;
  std::shared_ptr<const Triangulation> m_triangulation;  // a piece's, kept while it is the same
  std::pair<vtkMTimeType, vtkMTimeType> m_triangulationStamp{0, 0};  // its arrays' times
  std::vector<std::int32_t> m_components;  // a piece's (StepInput), else empty
  std::vector<std::int32_t> m_intactComponents;
  std::unique_ptr<BondGraph> m_graph;
  std::unique_ptr<CrackExtractor> m_extractor;
  // The broken bonds' normals for the opening arrays, kept across steps
  // while the bonds and the reference stay the same.
  std::unique_ptr<analysis::BondNormals> m_normals;
  Method m_method = Method::kCellCut;
  ExtractOptions m_options;
  int m_dimension = 3;
  StageLog m_stages;
};

}  // namespace crackvis::cracks::vtkadapter

#endif
