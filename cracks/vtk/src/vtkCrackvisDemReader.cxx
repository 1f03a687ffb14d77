#include "vtkCrackvisDemReader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkTypeInt64Array.h>
#include <vtkUnsignedCharArray.h>

#include "crackvis_vtk_conversion.h"
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::cracks::vtkadapter {

// The open file and its time-independent part, kept while the file name
// stays the same: stepping through time reads only the step.
struct DemReaderCache {
  std::string fileName;
  std::optional<dem::DemFileReader> reader;
  dem::Lattice lattice;
  std::vector<std::int32_t> breakSteps;
  std::vector<double> times;
  std::vector<dem::Vec3> reference;  // the first step's positions
  bool loaded = false;               // lattice, breakSteps and reference read
};

namespace {

// The step shown at time `t`: the last one saved at or before it (the first
// when `t` comes before every step), as ParaView's "snap to time steps" does.
int stepAt(const std::vector<double>& times, double t) {
  const auto after = std::upper_bound(times.begin(), times.end(), t + 1e-12 * std::abs(t));
  return after == times.begin() ? 0 : static_cast<int>(after - times.begin()) - 1;
}

template <typename VtkArray, typename Value>
void addArray(vtkFieldData* data, const char* name, const std::vector<Value>& values,
              int components = 1) {
  if (values.empty()) {
    return;
  }
  vtkNew<VtkArray> array;
  array->SetName(name);
  array->SetNumberOfComponents(components);
  array->SetNumberOfTuples(static_cast<vtkIdType>(values.size() / components));
  std::copy(values.begin(), values.end(), array->GetPointer(0));
  data->AddArray(array);
}

void addExtras(const std::vector<dem::ExtraArray>& extras, vtkPolyData* output) {
  for (const dem::ExtraArray& extra : extras) {
    vtkFieldData* data = extra.owner == dem::ExtraOwner::kParticles
                             ? static_cast<vtkFieldData*>(output->GetPointData())
                             : static_cast<vtkFieldData*>(output->GetCellData());
    addArray<vtkDoubleArray>(data, extra.name.c_str(), extra.values, extra.components);
  }
}

vtkSmartPointer<vtkDoubleArray> toArray(const std::vector<dem::Vec3>& positions) {
  auto coordinates = vtkSmartPointer<vtkDoubleArray>::New();
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(static_cast<vtkIdType>(positions.size()));
  static_assert(sizeof(dem::Vec3) == 3 * sizeof(double));
  if (!positions.empty()) {
    std::memcpy(coordinates->GetPointer(0), positions.data(), positions.size() * sizeof(dem::Vec3));
  }
  return coordinates;
}

void addPoints(const dem::StepState& step, const std::vector<dem::Vec3>& reference,
               vtkPolyData* output) {
  vtkNew<vtkPoints> points;
  points->SetData(toArray(step.positions));
  output->SetPoints(points);
  // The filters make local Voronoi faces and triangulations in it, as
  // `crackvis extract` does in the file's first step.
  vtkSmartPointer<vtkDoubleArray> first = toArray(reference);
  first->SetName(kReferencePositionArray);
  output->GetPointData()->AddArray(first);
}

void addBonds(const std::vector<dem::Bond>& bonds, vtkPolyData* output) {
  vtkNew<vtkIdTypeArray> offsets;
  vtkNew<vtkIdTypeArray> connectivity;
  offsets->SetNumberOfTuples(static_cast<vtkIdType>(bonds.size() + 1));
  connectivity->SetNumberOfTuples(static_cast<vtkIdType>(2 * bonds.size()));
  for (std::size_t b = 0; b <= bonds.size(); ++b) {
    offsets->SetValue(static_cast<vtkIdType>(b), static_cast<vtkIdType>(2 * b));
  }
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    connectivity->SetValue(static_cast<vtkIdType>(2 * b), bonds[b].first);
    connectivity->SetValue(static_cast<vtkIdType>(2 * b + 1), bonds[b].second);
  }
  vtkNew<vtkCellArray> lines;
  lines->SetData(offsets, connectivity);
  output->SetLines(lines);
}

void addFieldData(int step, const dem::StepState& state, vtkPolyData* output) {
  vtkFieldData* field = output->GetFieldData();
  vtkNew<vtkIntArray> index;
  index->SetName("step");
  index->InsertNextValue(step);
  field->AddArray(index);
  vtkNew<vtkDoubleArray> time;
  time->SetName("time");
  time->InsertNextValue(state.time);
  field->AddArray(time);
  for (const dem::StepScalar& scalar : state.scalars) {
    vtkNew<vtkDoubleArray> value;
    value->SetName(scalar.name.c_str());
    value->InsertNextValue(scalar.value);
    field->AddArray(value);
  }
}

// The time-independent part and the reference configuration, read once by
// the piece that shows the data (under MPI the other ranks never need them).
Status loadLattice(DemReaderCache& cache) {
  if (cache.loaded) {
    return Status::ok();
  }
  auto lattice = cache.reader->readLattice();
  if (!lattice) {
    return lattice.status();
  }
  auto breakSteps = cache.reader->readBreakSteps();
  if (!breakSteps) {
    return breakSteps.status();
  }
  auto first = cache.reader->readStep(0);
  if (!first) {
    return first.status();
  }
  cache.lattice = std::move(*lattice);
  cache.breakSteps = std::move(*breakSteps);
  cache.reference = std::move(first->positions);
  cache.loaded = true;
  return Status::ok();
}

void fill(const DemReaderCache& cache, int step, const dem::StepState& state, vtkPolyData* output) {
  const dem::Lattice& lattice = cache.lattice;
  addPoints(state, cache.reference, output);
  addBonds(lattice.bonds, output);
  vtkPointData* points = output->GetPointData();
  addArray<vtkDoubleArray>(points, "radius", lattice.radius);
  std::vector<float> velocities;
  velocities.reserve(3 * state.velocities.size());
  for (const auto& v : state.velocities) {
    velocities.insert(velocities.end(), v.begin(), v.end());
  }
  addArray<vtkFloatArray>(points, "velocity", velocities, 3);
  addArray<vtkTypeInt64Array>(points, "particle_id", lattice.particleId);
  addArray<vtkIntArray>(points, "particle_group", lattice.particleGroup);
  vtkCellData* cells = output->GetCellData();
  addArray<vtkUnsignedCharArray>(cells, "bond_state", state.bondState);
  addArray<vtkIntArray>(cells, "break_step", cache.breakSteps);
  addArray<vtkFloatArray>(cells, "bond_force", state.bondForce);
  addArray<vtkDoubleArray>(cells, "strength", lattice.strength);
  addArray<vtkUnsignedCharArray>(cells, "bond_flags", lattice.bondFlags);
  addExtras(lattice.extras, output);
  addExtras(state.extras, output);
  addFieldData(step, state, output);
}

}  // namespace

}  // namespace crackvis::cracks::vtkadapter

using crackvis::cracks::vtkadapter::DemReaderCache;

vtkStandardNewMacro(vtkCrackvisDemReader);

vtkCrackvisDemReader::vtkCrackvisDemReader() : Cache(std::make_unique<DemReaderCache>()) {
  this->SetNumberOfInputPorts(0);
}

vtkCrackvisDemReader::~vtkCrackvisDemReader() {
  this->SetFileName(nullptr);
}

void vtkCrackvisDemReader::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName != nullptr ? this->FileName : "(none)") << "\n";
}

int vtkCrackvisDemReader::CanReadFile(const char* fileName) {
  if (fileName == nullptr) {
    return 0;
  }
  return crackvis::dem::DemFileReader::open(fileName).isOk() ? 1 : 0;
}

int vtkCrackvisDemReader::RequestInformation(vtkInformation*, vtkInformationVector**,
                                             vtkInformationVector* outputVector) {
  if (this->FileName == nullptr || *this->FileName == '\0') {
    vtkErrorMacro("no FileName: name a crackvis-dem file (.h5)");
    return 0;
  }
  DemReaderCache& cache = *this->Cache;
  if (cache.fileName != this->FileName || !cache.reader) {
    cache = DemReaderCache{};
    auto reader = crackvis::dem::DemFileReader::open(this->FileName);
    if (!reader) {
      vtkErrorMacro(<< reader.status().message());
      return 0;
    }
    if (reader->stepCount() == 0) {
      vtkErrorMacro(<< this->FileName << ": the file holds no complete step");
      return 0;
    }
    for (const crackvis::dem::StepInfo& step : reader->info().steps) {
      cache.times.push_back(step.time);
    }
    cache.reader.emplace(std::move(*reader));
    cache.fileName = this->FileName;
  }
  vtkInformation* out = outputVector->GetInformationObject(0);
  out->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), cache.times.data(),
           static_cast<int>(cache.times.size()));
  const double range[2] = {cache.times.front(), cache.times.back()};
  out->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  out->Set(vtkAlgorithm::CAN_HANDLE_PIECE_REQUEST(), 1);
  return 1;
}

int vtkCrackvisDemReader::RequestData(vtkInformation*, vtkInformationVector**,
                                      vtkInformationVector* outputVector) {
  vtkInformation* out = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(out);
  DemReaderCache& cache = *this->Cache;
  if (!cache.reader) {
    return 0;  // RequestInformation reported why
  }
  if (out->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) &&
      out->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) > 0) {
    return 1;  // piece 0 holds the whole data set
  }
  if (crackvis::Status loaded = crackvis::cracks::vtkadapter::loadLattice(cache); !loaded) {
    vtkErrorMacro(<< loaded.message());
    return 0;
  }
  const int step =
      out->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
          ? crackvis::cracks::vtkadapter::stepAt(
                cache.times, out->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
          : 0;
  auto state = cache.reader->readStep(step);
  if (!state) {
    vtkErrorMacro(<< state.status().message());
    return 0;
  }
  crackvis::cracks::vtkadapter::fill(cache, step, *state, output);
  output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), state->time);
  return 1;
}
