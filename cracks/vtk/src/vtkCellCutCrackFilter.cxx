#include "vtkCellCutCrackFilter.h"

#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "crack_filter_state.h"

vtkStandardNewMacro(vtkCellCutCrackFilter);

vtkCellCutCrackFilter::vtkCellCutCrackFilter()
    : State(std::make_unique<crackvis::cracks::vtkadapter::CrackFilterState>()) {}

vtkCellCutCrackFilter::~vtkCellCutCrackFilter() = default;

int vtkCellCutCrackFilter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  return 1;
}

int vtkCellCutCrackFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                       vtkInformationVector* outputVector) {
  vtkPolyData* input = vtkPolyData::GetData(inputVector[0]);
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  crackvis::cracks::ExtractOptions options;
  crackvis::cracks::CrackMesh mesh;
  std::string error;
  if (!this->State->run(input, crackvis::cracks::Method::kCellCut, options, this->RadiusDefault,
                        mesh, error)) {
    vtkErrorMacro(<< error);
    return 0;
  }
  crackvis::cracks::vtkadapter::toPolyData(mesh, output);
  this->State->reportStages(input, "cell-cut");
  return 1;
}

void vtkCellCutCrackFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "RadiusDefault: " << this->RadiusDefault << "\n";
}
