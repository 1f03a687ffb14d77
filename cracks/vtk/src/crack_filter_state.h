// What the four crack filters share: turning the lattice polydata into the
// core's arrays (checked), keeping the bond graph and the extractor while the
// bonds stay the same, and turning a CrackMesh back into VTK data.
#ifndef crackvis_crack_filter_state_h
#define crackvis_crack_filter_state_h

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <vtkDataArray.h>
#include <vtkSmartPointer.h>
#include <vtkType.h>

#include "crackvis_vtk_conversion.h"
#include <crackvis/cracks/extractor.hpp>

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

class CrackFilterState {
 public:
  // Extracts one step from `input`. On bad input returns false and says why
  // in `error` (the filter reports it with vtkErrorMacro).
  bool run(vtkPolyData* input, Method method, const ExtractOptions& options, double radiusDefault,
           CrackMesh& mesh, std::string& error);

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
  Method m_method = Method::kCellCut;
  ExtractOptions m_options;
  int m_dimension = 3;
};

}  // namespace crackvis::cracks::vtkadapter

#endif
