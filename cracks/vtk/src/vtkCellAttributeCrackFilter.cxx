#include "vtkCellAttributeCrackFilter.h"

#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "crack_filter_state.h"

vtkStandardNewMacro(vtkCellAttributeCrackFilter);

vtkCellAttributeCrackFilter::vtkCellAttributeCrackFilter()
    : State(std::make_unique<crackvis::cracks::vtkadapter::CrackFilterState>()) {}

vtkCellAttributeCrackFilter::~vtkCellAttributeCrackFilter() = default;

int vtkCellAttributeCrackFilter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  return 1;
}

int vtkCellAttributeCrackFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                             vtkInformationVector* outputVector) {
  vtkPolyData* input = vtkPolyData::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  crackvis::cracks::ExtractOptions options;
  options.globalDecomposition = this->GlobalDecomposition;
  options.minBrokenBonds = this->MinimumBrokenBonds;
  crackvis::cracks::CrackMesh mesh;
  std::string error;
  if (!this->State->run(input, crackvis::cracks::Method::kCellAttribute, options,
                        this->RadiusDefault, mesh, error)) {
    vtkErrorMacro(<< error);
    return 0;
  }
  crackvis::cracks::vtkadapter::toUnstructuredGrid(mesh, output);
  this->State->reportStages(input, "cell-attribute");
  return 1;
}

void vtkCellAttributeCrackFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "RadiusDefault: " << this->RadiusDefault << "\n";
  os << indent << "GlobalDecomposition: " << this->GlobalDecomposition << "\n";
  os << indent << "MinimumBrokenBonds: " << this->MinimumBrokenBonds << "\n";
}
