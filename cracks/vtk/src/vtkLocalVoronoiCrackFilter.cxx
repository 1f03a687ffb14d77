#include "vtkLocalVoronoiCrackFilter.h"

#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "crack_filter_state.h"

vtkStandardNewMacro(vtkLocalVoronoiCrackFilter);

vtkLocalVoronoiCrackFilter::vtkLocalVoronoiCrackFilter()
    : State(std::make_unique<crackvis::cracks::vtkadapter::CrackFilterState>()) {}

vtkLocalVoronoiCrackFilter::~vtkLocalVoronoiCrackFilter() = default;

int vtkLocalVoronoiCrackFilter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  return 1;
}

int vtkLocalVoronoiCrackFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                            vtkInformationVector* outputVector) {
  vtkPolyData* input = vtkPolyData::GetData(inputVector[0]);
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  crackvis::cracks::ExtractOptions options;
  options.validate = this->Validate;
  options.validationTolerance = this->ValidationTolerance;
  options.includeIntactFaces = this->IncludeIntactFaces;
  crackvis::cracks::CrackMesh mesh;
  std::string error;
  if (!this->State->run(input, crackvis::cracks::Method::kLocalVoronoi, options,
                        this->RadiusDefault, mesh, error)) {
    vtkErrorMacro(<< error);
    return 0;
  }
  crackvis::cracks::vtkadapter::toPolyData(mesh, output);
  this->State->reportStages(input, "local-voronoi");
  return 1;
}

void vtkLocalVoronoiCrackFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "RadiusDefault: " << this->RadiusDefault << "\n";
  os << indent << "Validate: " << this->Validate << "\n";
  os << indent << "ValidationTolerance: " << this->ValidationTolerance << "\n";
  os << indent << "IncludeIntactFaces: " << this->IncludeIntactFaces << "\n";
}
