// The VTK adapters against the core, and the writers read back by VTK's own
// XML readers.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>
#include <vtkCallbackCommand.h>
#include <vtkCellAttributeCrackFilter.h>
#include <vtkCellCentreCrackFilter.h>
#include <vtkCellCutCrackFilter.h>
#include <vtkCellData.h>
#include <vtkCrackvisDemReader.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkExecutive.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkInformation.h>
#include <vtkIntArray.h>
#include <vtkLocalVoronoiCrackFilter.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "crack_filter_state.h"
#include "crack_fixtures.hpp"
#include "support/paced_writer.hpp"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/cracks/mesh_writers.hpp>
#include <crackvis/dem/dem_file.hpp>

using namespace crackvis;
using namespace crackvis::cracks;

namespace {

vtkSmartPointer<vtkPolyData> latticePolyData(const testing::PlantedCrack& crack) {
  auto data = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  for (const dem::Vec3& p : crack.block.positions) {
    points->InsertNextPoint(p.x, p.y, p.z);
  }
  data->SetPoints(points);
  vtkNew<vtkCellArray> lines;
  vtkNew<vtkUnsignedCharArray> state;
  state->SetName("bond_state");
  for (std::size_t b = 0; b < crack.block.lattice.bonds.size(); ++b) {
    const dem::Bond& bond = crack.block.lattice.bonds[b];
    const vtkIdType ids[2] = {bond.first, bond.second};
    lines->InsertNextCell(2, ids);
    state->InsertNextValue(crack.state[b]);
  }
  data->SetLines(lines);
  data->GetCellData()->AddArray(state);
  vtkNew<vtkDoubleArray> radius;
  radius->SetName("radius");
  for (double r : crack.block.lattice.radius) {
    radius->InsertNextValue(r);
  }
  data->GetPointData()->AddArray(radius);
  return data;
}

CrackMesh core(Method method, const testing::PlantedCrack& crack) {
  auto extractor = makeExtractor(method, *crack.graph, crack.block.lattice.dimension);
  CrackMesh mesh;
  REQUIRE(extractor->extract(crack.input(), mesh).isOk());
  return mesh;
}

template <typename Filter>
vtkPolyData* runFilter(Filter* filter, vtkPolyData* input) {
  filter->SetInputData(input);
  filter->Update();
  return filter->GetOutput();
}

struct ErrorCounter {
  int errors = 0;
  vtkNew<vtkCallbackCommand> command;
  ErrorCounter() {
    command->SetClientData(this);
    command->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
      ++static_cast<ErrorCounter*>(self)->errors;
    });
  }
};

testing::PlantedCrack sampleCrack() {
  const double h = 1.0 / std::sqrt(2.0);
  return testing::fccPlaneCrack(3, {1, 1, 1}, 9 * h + 1.5, 0.02);
}

}  // namespace

TEST_CASE("each VTK filter outputs what the core extracts", "[cracks][vtk]") {
  const auto crack = sampleCrack();
  auto input = latticePolyData(crack);
  SECTION("cell cut") {
    vtkNew<vtkCellCutCrackFilter> filter;
    vtkPolyData* out = runFilter(filter.Get(), input);
    const CrackMesh mesh = core(Method::kCellCut, crack);
    CHECK(out->GetNumberOfPoints() == static_cast<vtkIdType>(mesh.points.size()));
    CHECK(out->GetNumberOfPolys() == static_cast<vtkIdType>(mesh.polygons.size()));
    CHECK(out->GetPointData()->GetArray("bond_id") != nullptr);
    double p[3];
    out->GetPoint(7, p);
    CHECK(dem::Vec3{p[0], p[1], p[2]} == mesh.points[7]);
  }
  SECTION("local Voronoi") {
    vtkNew<vtkLocalVoronoiCrackFilter> filter;
    vtkPolyData* out = runFilter(filter.Get(), input);
    const CrackMesh mesh = core(Method::kLocalVoronoi, crack);
    CHECK(out->GetNumberOfPolys() == static_cast<vtkIdType>(mesh.polygons.size()));
    CHECK(out->GetNumberOfLines() == static_cast<vtkIdType>(mesh.lines.size()));
    REQUIRE(out->GetCellData()->GetArray("inconsistent") != nullptr);
    CHECK(out->GetCellData()->GetArray("bond_id")->GetNumberOfTuples() == out->GetNumberOfCells());
  }
  SECTION("cell centre") {
    vtkNew<vtkCellCentreCrackFilter> filter;
    filter->MergeOctahedraOn();
    vtkPolyData* out = runFilter(filter.Get(), input);
    CHECK(out->GetNumberOfCells() == static_cast<vtkIdType>(crack.brokenCount()));
  }
  SECTION("cell attribute") {
    vtkNew<vtkCellAttributeCrackFilter> filter;
    filter->SetInputData(input);
    filter->Update();
    vtkUnstructuredGrid* out = filter->GetOutput();
    const CrackMesh mesh = core(Method::kCellAttribute, crack);
    CHECK(out->GetNumberOfCells() == static_cast<vtkIdType>(mesh.volumeCells.size()));
    CHECK(out->GetCellType(0) == mesh.volumeCellTypes[0]);
    CHECK(out->GetCellData()->GetArray("broken_bonds") != nullptr);
  }
}

// Each cell as the coordinates of its points in order, with its type; sorted,
// since an incremental extractor may order the same cells differently.
std::vector<std::vector<double>> cellGeometry(vtkPolyData* data) {
  std::vector<std::vector<double>> cells;
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < data->GetNumberOfCells(); ++c) {
    data->GetCellPoints(c, ids);
    std::vector<double> cell{static_cast<double>(data->GetCellType(c))};
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) {
      double p[3];
      data->GetPoint(ids->GetId(k), p);
      cell.insert(cell.end(), {p[0], p[1], p[2]});
    }
    cells.push_back(std::move(cell));
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

TEST_CASE("a VTK filter stays incremental across updates and equals a fresh one", "[cracks][vtk]") {
  auto crack = sampleCrack();
  auto input = latticePolyData(crack);
  vtkNew<vtkCellCutCrackFilter> kept;
  const vtkIdType firstCells = runFilter(kept.Get(), input)->GetNumberOfCells();
  // More bonds break: the next "step".
  auto* state = vtkUnsignedCharArray::SafeDownCast(input->GetCellData()->GetArray("bond_state"));
  for (vtkIdType b = 0; b < state->GetNumberOfTuples(); b += 7) {
    state->SetValue(b, 1);
  }
  state->Modified();
  input->Modified();
  vtkPolyData* incremental = runFilter(kept.Get(), input);
  CHECK(incremental->GetNumberOfCells() > firstCells);  // the new step's cracks, not the old
  vtkNew<vtkCellCutCrackFilter> fresh;
  vtkPolyData* scratch = runFilter(fresh.Get(), input);
  REQUIRE(incremental->GetNumberOfCells() == scratch->GetNumberOfCells());
  const auto cells = cellGeometry(incremental);
  const auto fromScratch = cellGeometry(scratch);
  std::size_t different = 0;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    different += cells[c] != fromScratch[c] ? 1 : 0;
  }
  CHECK(different == 0);
}

TEST_CASE("a VTK filter refuses input without bond states, with an error", "[cracks][vtk]") {
  const auto crack = sampleCrack();
  auto input = latticePolyData(crack);
  input->GetCellData()->RemoveArray("bond_state");
  vtkNew<vtkLocalVoronoiCrackFilter> filter;
  ErrorCounter counter;
  filter->AddObserver(vtkCommand::ErrorEvent, counter.command);
  filter->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, counter.command);
  filter->SetInputData(input);
  filter->Update();
  CHECK(counter.errors >= 1);
  CHECK(filter->GetOutput()->GetNumberOfCells() == 0);
}

TEST_CASE("writers: VTK reads back .vtp and .vtu, STL and OBJ have every face", "[cracks][io]") {
  const auto crack = sampleCrack();
  testing::TempDir dir;
  SECTION("vtp") {
    const CrackMesh mesh = core(Method::kLocalVoronoi, crack);
    REQUIRE(writeMesh(mesh, dir.file("lv.vtp")).isOk());
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(dir.file("lv.vtp").c_str());
    reader->Update();
    vtkPolyData* read = reader->GetOutput();
    REQUIRE(read->GetNumberOfPoints() == static_cast<vtkIdType>(mesh.points.size()));
    CHECK(read->GetNumberOfPolys() == static_cast<vtkIdType>(mesh.polygons.size()));
    CHECK(read->GetNumberOfLines() == static_cast<vtkIdType>(mesh.lines.size()));
    double p[3];
    read->GetPoint(static_cast<vtkIdType>(mesh.points.size() - 1), p);
    CHECK(dem::Vec3{p[0], p[1], p[2]} == mesh.points.back());
    vtkDataArray* bondId = read->GetCellData()->GetArray("bond_id");
    REQUIRE(bondId != nullptr);
    CHECK(bondId->GetTuple1(3) == mesh.findCellData("bond_id")->values[3]);
  }
  SECTION("vtu with volume cells, and a pvd") {
    const CrackMesh mesh = core(Method::kCellAttribute, crack);
    REQUIRE(vtkExtensionFor(mesh) == "vtu");
    REQUIRE(writeMesh(mesh, dir.file("cells.vtu")).isOk());
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(dir.file("cells.vtu").c_str());
    reader->Update();
    CHECK(reader->GetOutput()->GetNumberOfCells() ==
          static_cast<vtkIdType>(mesh.volumeCells.size()));
    CHECK(reader->GetOutput()->GetCellType(0) == mesh.volumeCellTypes[0]);
    REQUIRE(writePvd({{0.5, "cells.vtu"}}, dir.file("series.pvd")).isOk());
    std::ifstream pvd(dir.file("series.pvd"));
    const std::string text((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
    CHECK_THAT(text, Catch::Contains(R"(timestep="0.5")"));
    CHECK_THAT(text, Catch::Contains(R"(file="cells.vtu")"));
  }
  SECTION("stl and obj") {
    const CrackMesh mesh = core(Method::kCellCut, crack);
    std::size_t triangles = 0;
    for (std::size_t k = 0; k < mesh.polygons.size(); ++k) {
      triangles +=
          static_cast<std::size_t>(mesh.polygons.offsets[k + 1] - mesh.polygons.offsets[k] - 2);
    }
    REQUIRE(writeMesh(mesh, dir.file("cut.stl")).isOk());
    CHECK(std::filesystem::file_size(dir.file("cut.stl")) == 84 + 50 * triangles);
    REQUIRE(writeMesh(mesh, dir.file("cut.obj")).isOk());
    std::ifstream obj(dir.file("cut.obj"));
    std::size_t v = 0;
    std::size_t f = 0;
    for (std::string line; std::getline(obj, line);) {
      v += line.rfind("v ", 0) == 0 ? 1 : 0;
      f += line.rfind("f ", 0) == 0 ? 1 : 0;
    }
    CHECK(v == mesh.points.size());
    CHECK(f == mesh.polygons.size());
    CHECK(writeMesh(mesh, dir.file("cut.ply")).message() ==
          dir.file("cut.ply") + ": unknown output format (expected .vtp, .vtu, .stl or .obj)");
  }
}

namespace {

// The planted crack as a crackvis-dem file of two steps: intact, then the
// crack (so the reader's time steps have something to choose).
void writePlantedCrack(const testing::PlantedCrack& crack, const std::string& path) {
  dem::DemMetadata metadata;
  metadata.source = "vtk_filters test";
  auto writer = dem::DemFileWriter::create(path, crack.block.lattice, metadata);
  REQUIRE(writer.isOk());
  dem::StepState intact;
  intact.time = 0.5;
  intact.positions = crack.block.positions;
  intact.bondState.assign(crack.state.size(), 0);
  REQUIRE(writer->appendStep(intact).isOk());
  dem::StepState cracked = intact;
  cracked.time = 1.5;
  cracked.bondState = crack.state;
  REQUIRE(writer->appendStep(cracked).isOk());
  REQUIRE(writer->close().isOk());
}

}  // namespace

TEST_CASE("the crackvis-dem reader gives the filters the lattice of the step asked for",
          "[cracks][vtk]") {
  const auto crack = sampleCrack();
  testing::TempDir dir;
  const std::string path = dir.file("planted.h5");
  writePlantedCrack(crack, path);
  vtkNew<vtkCrackvisDemReader> reader;
  CHECK(reader->CanReadFile(path.c_str()) == 1);
  CHECK(reader->CanReadFile(dir.file("missing.h5").c_str()) == 0);
  reader->SetFileName(path.c_str());
  reader->UpdateInformation();
  vtkInformation* info = reader->GetOutputInformation(0);
  REQUIRE(info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) == 2);
  CHECK(info->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS())[1] == 1.5);

  // A time between the steps shows the earlier one.
  reader->UpdateTimeStep(1.0);
  vtkPolyData* intact = reader->GetOutput();
  CHECK(intact->GetNumberOfPoints() == static_cast<vtkIdType>(crack.block.lattice.particleCount()));
  CHECK(intact->GetNumberOfLines() == static_cast<vtkIdType>(crack.block.lattice.bondCount()));
  CHECK(vtkIntArray::SafeDownCast(intact->GetFieldData()->GetArray("step"))->GetValue(0) == 0);
  CHECK(intact->GetCellData()->GetArray("bond_state")->GetRange()[1] == 0.0);

  reader->UpdateTimeStep(1.5);
  vtkPolyData* cracked = reader->GetOutput();
  CHECK(vtkIntArray::SafeDownCast(cracked->GetFieldData()->GetArray("step"))->GetValue(0) == 1);
  REQUIRE(cracked->GetCellData()->GetArray("break_step") != nullptr);
  double p[3];
  cracked->GetPoint(5, p);
  CHECK(dem::Vec3{p[0], p[1], p[2]} == crack.block.positions[5]);
  vtkIdType ends[2];
  const vtkIdType* ids = nullptr;
  vtkIdType count = 0;
  cracked->GetLines()->GetCellAtId(3, count, ids);
  REQUIRE(count == 2);
  std::copy(ids, ids + 2, ends);
  CHECK(ends[0] == crack.block.lattice.bonds[3].first);
  CHECK(ends[1] == crack.block.lattice.bonds[3].second);
  CHECK(cracked->GetPointData()->GetArray("radius")->GetTuple1(5) == crack.block.lattice.radius[5]);

  SECTION("into the local Voronoi filter: what the core extracts from the same step") {
    vtkNew<vtkLocalVoronoiCrackFilter> filter;
    filter->SetInputConnection(reader->GetOutputPort());
    filter->UpdateTimeStep(1.5);
    const CrackMesh mesh = core(Method::kLocalVoronoi, crack);
    CHECK(filter->GetOutput()->GetNumberOfPolys() == static_cast<vtkIdType>(mesh.polygons.size()));
    CHECK(mesh.polygons.size() > 0);
    filter->UpdateTimeStep(0.5);  // back to the intact step: no crack
    CHECK(filter->GetOutput()->GetNumberOfPolys() == 0);
  }
  SECTION("into the cell cut filter") {
    vtkNew<vtkCellCutCrackFilter> filter;
    filter->SetInputConnection(reader->GetOutputPort());
    filter->UpdateTimeStep(1.5);
    const CrackMesh mesh = core(Method::kCellCut, crack);
    CHECK(filter->GetOutput()->GetNumberOfPolys() == static_cast<vtkIdType>(mesh.polygons.size()));
  }
}

namespace {

// Whether `array` holds `values` (as doubles), value for value.
template <typename Value>
bool holds(vtkDataArray* array, const std::vector<Value>& values, int components) {
  if (array == nullptr && values.empty()) {
    return true;  // the step has none: neither has the output
  }
  if (array == nullptr || array->GetNumberOfComponents() != components ||
      array->GetNumberOfTuples() * components != static_cast<vtkIdType>(values.size())) {
    return false;
  }
  for (vtkIdType k = 0; k < array->GetNumberOfTuples() * components; ++k) {
    if (array->GetComponent(k / components, static_cast<int>(k % components)) !=
        static_cast<double>(values[static_cast<std::size_t>(k)])) {
      return false;
    }
  }
  return true;
}

// A step's positions and velocities as flat value lists.
std::vector<double> flat(const std::vector<dem::Vec3>& points) {
  std::vector<double> out;
  for (const dem::Vec3& p : points) {
    out.insert(out.end(), {p.x, p.y, p.z});
  }
  return out;
}
std::vector<float> flat(const std::vector<std::array<float, 3>>& vectors) {
  std::vector<float> out;
  for (const auto& v : vectors) {
    out.insert(out.end(), v.begin(), v.end());
  }
  return out;
}

// Whether the reader's output holds step `step` of `sample`.
bool showsStep(vtkPolyData* out, const dem::StepState& step) {
  return holds(out->GetPoints()->GetData(), flat(step.positions), 3) &&
         holds(out->GetCellData()->GetArray("bond_state"), step.bondState, 1) &&
         holds(out->GetCellData()->GetArray("bond_force"), step.bondForce, 1) &&
         holds(out->GetPointData()->GetArray("velocity"), flat(step.velocities), 3);
}

}  // namespace

// The step arrays view the memory they were read into, and that memory is
// read into again once VTK lets go of them (DemFileReader::readStep's reuse
// of it is tested in tests/dem): arrays someone still holds must keep their
// values, the next step must not land in them, and steps read into memory
// given back must be right.
TEST_CASE(
    "the crackvis-dem reader's step arrays keep their values while held, and steps read "
    "into memory given back are right",
    "[cracks][vtk]") {
  testing::TempDir dir;
  const std::string path = dir.file("steps.h5");
  const testing::SampleData sample = testing::writeSampleFile(path, 3, 4);
  const auto& steps = sample.steps;
  REQUIRE_FALSE(steps[1].velocities.empty());
  REQUIRE_FALSE(steps[1].bondForce.empty());
  vtkNew<vtkCrackvisDemReader> reader;
  reader->SetFileName(path.c_str());
  reader->UpdateTimeStep(steps[1].time);
  REQUIRE(showsStep(reader->GetOutput(), steps[1]));
  // A consumer keeps step 1's output.
  vtkNew<vtkPolyData> kept;
  kept->ShallowCopy(reader->GetOutput());
  reader->UpdateTimeStep(steps[2].time);
  CHECK(showsStep(reader->GetOutput(), steps[2]));
  CHECK(showsStep(kept, steps[1]));
  CHECK(kept->GetPoints()->GetData()->GetVoidPointer(0) !=
        reader->GetOutput()->GetPoints()->GetData()->GetVoidPointer(0));
  // Let go of step 1: its memory goes back to the reader.
  kept->Initialize();
  for (int k : {3, 0, 2, 1}) {
    reader->UpdateTimeStep(steps[static_cast<std::size_t>(k)].time);
    CHECK(showsStep(reader->GetOutput(), steps[static_cast<std::size_t>(k)]));
  }
}

TEST_CASE("the crackvis-dem reader reports a file it cannot read, naming it", "[cracks][vtk]") {
  testing::TempDir dir;
  const std::string path = dir.file("not-hdf5.h5");
  std::ofstream(path) << "not an HDF5 file\n";
  vtkNew<vtkCrackvisDemReader> reader;
  ErrorCounter counter;
  reader->AddObserver(vtkCommand::ErrorEvent, counter.command);
  reader->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, counter.command);
  reader->SetFileName(path.c_str());
  reader->Update();
  CHECK(counter.errors > 0);
  CHECK(reader->GetOutput()->GetNumberOfPoints() == 0);
  CHECK(reader->CanReadFile(path.c_str()) == 0);
}

TEST_CASE("the crack filters pass an empty piece through without an error", "[cracks][vtk]") {
  // Under MPI the reader gives every rank but the first an empty piece.
  vtkNew<vtkPolyData> empty;
  ErrorCounter counter;
  auto check = [&](vtkAlgorithm* filter) {
    filter->AddObserver(vtkCommand::ErrorEvent, counter.command);
    filter->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, counter.command);
    filter->SetInputDataObject(0, empty);
    filter->Update();
    CHECK(vtkDataSet::SafeDownCast(filter->GetOutputDataObject(0))->GetNumberOfCells() == 0);
  };
  vtkNew<vtkCellCutCrackFilter> cut;
  vtkNew<vtkLocalVoronoiCrackFilter> voronoi;
  vtkNew<vtkCellCentreCrackFilter> centre;
  vtkNew<vtkCellAttributeCrackFilter> attribute;
  check(cut);
  check(voronoi);
  check(centre);
  check(attribute);
  CHECK(counter.errors == 0);
}

TEST_CASE("the crackvis-dem reader shows a live file's new steps on the next update",
          "[cracks][vtk][live]") {
  // The writer runs in a child, as a simulation beside ParaView would: HDF5
  // shares one open file between the opens of a process.
  const auto crack = sampleCrack();
  testing::TempDir dir;
  const std::string path = dir.file("live.h5");
  testing::PacedWriter writer([&](const testing::PacedWriter::Pause& pause) {
    dem::DemMetadata metadata = dem::metadataFrom("vtk_filters test");
    metadata.stepLayout = dem::StepLayout::kAppendable;
    auto file = dem::DemFileWriter::create(path, crack.block.lattice, metadata);
    dem::StepState step;
    step.positions = crack.block.positions;
    step.bondState.assign(crack.state.size(), 0);
    // Each step, then a pause.
    for (int k = 0; k < 3 && file; ++k) {
      step.time = 0.5 + k;
      if (k == 2) {
        step.bondState = crack.state;
      }
      if (!file->appendStep(step) || !pause()) {
        return false;
      }
    }
    return file && file->close();
  });
  REQUIRE(writer.started());
  auto nextStep = [&] {
    REQUIRE(writer.resume());
    REQUIRE(writer.waitForPause());
  };
  REQUIRE(writer.waitForPause());  // step 0 is in
  nextStep();                      // and step 1
  vtkNew<vtkCrackvisDemReader> reader;
  reader->SetFileName(path.c_str());
  reader->UpdateInformation();
  vtkInformation* info = reader->GetOutputInformation(0);
  CHECK(info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) == 2);
  // Step 1 shown before step 2 exists: no bond has broken yet.
  reader->UpdateTimeStep(1.5);
  CHECK(reader->GetOutput()->GetCellData()->GetArray("break_step")->GetRange()[1] == -1.0);
  nextStep();  // step 2, the cracked one
  // ParaView's Reload Files: the reader is modified, its information asked again.
  reader->Modified();
  reader->UpdateInformation();
  REQUIRE(info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()) == 3);
  CHECK(info->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS())[2] == 2.5);
  reader->UpdateTimeStep(2.5);
  vtkPolyData* cracked = reader->GetOutput();
  CHECK(vtkIntArray::SafeDownCast(cracked->GetFieldData()->GetArray("step"))->GetValue(0) == 2);
  CHECK(cracked->GetCellData()->GetArray("bond_state")->GetRange()[1] == 1.0);
  // The bonds broken at step 2 say so, though the lattice was read before.
  CHECK(cracked->GetCellData()->GetArray("break_step")->GetRange()[1] == 2.0);
  REQUIRE(writer.resume());
  CHECK(writer.finish());
}

namespace {

// An FCC block with a planted crack over 8 steps in a file, and a reader of it.
struct PlantedRun {
  testing::TempDir dir;
  std::string path = dir.file("planted.h5");
  testing::SampleData sample = testing::writePlantedLattice(path, 8);
  vtkNew<vtkCrackvisDemReader> reader;

  PlantedRun() {
    reader->SetFileName(path.c_str());
    reader->UpdateInformation();
  }
};

}  // namespace

TEST_CASE("the crack filters give each surface element its opening and slip as cell data",
          "[cracks][vtk][analysis]") {
  PlantedRun run;
  auto& reader = run.reader;
  const double last = run.sample.steps.back().time;
  vtkNew<vtkCellCentreCrackFilter> filter;
  filter->SetInputConnection(reader->GetOutputPort());
  filter->UpdateTimeStep(last);
  vtkPolyData* out = vtkPolyData::SafeDownCast(filter->GetOutputDataObject(0));
  REQUIRE(out != nullptr);
  vtkDataArray* opening = out->GetCellData()->GetArray("opening");
  vtkDataArray* slip = out->GetCellData()->GetArray("slip");
  REQUIRE(opening != nullptr);
  REQUIRE(slip != nullptr);
  REQUIRE(opening->GetNumberOfTuples() == out->GetNumberOfCells());
  double sum = 0.0;
  vtkIdType counted = 0;
  for (vtkIdType c = 0; c < opening->GetNumberOfTuples(); ++c) {
    if (!std::isnan(opening->GetTuple1(c))) {
      sum += opening->GetTuple1(c);
      ++counted;
      CHECK(slip->GetTuple1(c) < 2e-4);
    }
  }
  REQUIRE(counted > 0);
  // The right half moved one bond length, 2 mm, by the last step.
  CHECK(sum / static_cast<double>(counted) == Approx(2e-3).epsilon(0.02));
}

namespace {

// The "opening" cell array of a filter's output at `time`, in cell order.
std::vector<double> openingsAt(vtkLocalVoronoiCrackFilter* filter, double time) {
  filter->UpdateTimeStep(time);
  vtkPolyData* out = vtkPolyData::SafeDownCast(filter->GetOutputDataObject(0));
  REQUIRE(out != nullptr);
  vtkDataArray* opening = out->GetCellData()->GetArray("opening");
  REQUIRE(opening != nullptr);
  std::vector<double> values;
  for (vtkIdType c = 0; c < opening->GetNumberOfTuples(); ++c) {
    values.push_back(opening->GetTuple1(c));
  }
  return values;
}

// Whether two openings agree cell by cell within `tolerance` (NaN with NaN).
bool sameOpenings(const std::vector<double>& a, const std::vector<double>& b, double tolerance) {
  if (a.size() != b.size()) {
    return false;
  }
  for (std::size_t c = 0; c < a.size(); ++c) {
    const bool bothNaN = std::isnan(a[c]) && std::isnan(b[c]);
    if (!bothNaN && !(std::abs(a[c] - b[c]) <= tolerance)) {
      return false;
    }
  }
  return true;
}

}  // namespace

// The filters keep the broken bonds' normals across steps (a step finds its
// new breaks' normals, as the render server does); a filter that stepped
// through the run measures what a fresh one measures at the step, and one that
// steps back, where bonds heal, starts its normals over.
TEST_CASE("a crack filter stepping through a run measures the openings a fresh one measures",
          "[cracks][vtk][analysis]") {
  PlantedRun run;
  auto& reader = run.reader;
  const auto& sample = run.sample;
  const auto freshAt = [&](double time) {
    vtkNew<vtkLocalVoronoiCrackFilter> fresh;
    fresh->SetInputConnection(reader->GetOutputPort());
    return openingsAt(fresh.Get(), time);
  };
  vtkNew<vtkLocalVoronoiCrackFilter> stepping;
  stepping->SetInputConnection(reader->GetOutputPort());
  std::vector<double> last;
  for (const auto& step : sample.steps) {
    last = openingsAt(stepping.Get(), step.time);
  }
  const std::vector<double> lastFresh = freshAt(sample.steps.back().time);
  REQUIRE(std::count_if(lastFresh.begin(), lastFresh.end(),
                        [](double v) { return !std::isnan(v); }) > 0);
  // 1 % of the opening at the end (2 mm): the normals of windows that were
  // already full when more breaks came are not found again.
  CHECK(sameOpenings(last, lastFresh, 2e-5));
  // Back to the middle of the run: bonds heal, the normals start over.
  const double middle = sample.steps[sample.steps.size() / 2].time;
  const std::vector<double> back = openingsAt(stepping.Get(), middle);
  CHECK(sameOpenings(back, freshAt(middle), 0.0));
}

// The stage log the plugin's benchmarks read per rank: silent unless
// CRACKVIS_VTK_TIMINGS is set; then one line with each stage in order, the
// total, and start <= end on the monotonic clock.
TEST_CASE("a stage log prints its stages only when CRACKVIS_VTK_TIMINGS is set", "[cracks][vtk]") {
  const auto printed = [](bool enabled) {
    if (enabled) {
      ::setenv("CRACKVIS_VTK_TIMINGS", "1", 1);
    } else {
      ::unsetenv("CRACKVIS_VTK_TIMINGS");
    }
    vtkadapter::StageLog log;
    log.mark("read");
    log.mark("fill");
    std::FILE* out = std::tmpfile();
    REQUIRE(out != nullptr);
    log.report("reader", 1.5, out);
    std::rewind(out);
    std::string text;
    for (int c = std::fgetc(out); c != EOF; c = std::fgetc(out)) {
      text.push_back(static_cast<char>(c));
    }
    std::fclose(out);
    ::unsetenv("CRACKVIS_VTK_TIMINGS");
    return text;
  };
  CHECK(printed(false).empty());
  const std::string line = printed(true);
  CHECK(line.rfind("crackvis-vtk-timings pid=", 0) == 0);
  CHECK_THAT(line, Catch::Contains(" reader time=1.5 read_ms="));
  CHECK(line.find("read_ms=") < line.find("fill_ms="));
  CHECK(line.find("fill_ms=") < line.find("total_ms="));
  const auto number = [&](const char* key) {
    return std::stod(line.substr(line.find(key) + std::strlen(key)));
  };
  CHECK(number(" start=") <= number(" end="));
  CHECK(number(" rss_mib=") > 0.0);
  CHECK(number(" peak_mib=") >= number(" rss_mib="));
  CHECK(line.back() == '\n');
}
