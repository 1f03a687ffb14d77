// Distributed extraction (issue 19 point 2): the crackvis-dem reader asked for
// piece p of n (as each MPI rank of pvbatch or pvserver asks), through each
// crack filter, gives pieces that together equal the whole set's output face
// for face, on a lattice and on a random packing, each with a planted through
// crack that runs along the pieces' cut, at every step in order.
#include <algorithm>
#include <array>
#include <cmath>

#include <catch2/catch.hpp>
#include <vtkCellAttributeCrackFilter.h>
#include <vtkCellCentreCrackFilter.h>
#include <vtkCellCutCrackFilter.h>
#include <vtkCellData.h>
#include <vtkCrackvisDemReader.h>
#include <vtkDataArray.h>
#include <vtkDataSet.h>
#include <vtkDataSetAttributes.h>
#include <vtkIdList.h>
#include <vtkInformation.h>
#include <vtkLocalVoronoiCrackFilter.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include "support/temp_dir.hpp"
#include <crackvis/dem/dem_file.hpp>
#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/dem/planted_crack.hpp>
#include <crackvis/dem/random_packing.hpp>

using namespace crackvis;

namespace {

// A planted through crack (6 steps after the intact one) written as a file.
void writeSpecimen(const dem::Lattice& lattice, const std::vector<dem::Vec3>& positions,
                   const std::string& path) {
  dem::PlantedCrackSpec spec;
  spec.steps = 6;
  spec.opening = 1.0;
  spec.scatter = 0.01;
  auto crack = dem::PlantedCrack::create(lattice, positions, spec);
  REQUIRE(crack.isOk());
  dem::DemMetadata metadata;
  metadata.source = "vtk_pieces test";
  auto writer = dem::DemFileWriter::create(path, lattice, metadata);
  REQUIRE(writer.isOk());
  for (int k = 0; k < crack->stepCount(); ++k) {
    REQUIRE(writer->appendStep(crack->step(k)).isOk());
  }
  REQUIRE(writer->close().isOk());
}

std::string latticeFile(const testing::TempDir& dir) {
  dem::BlockSpec spec;
  spec.sites = {30, 8, 8};
  auto block = dem::generateBlock(spec);
  REQUIRE(block.isOk());
  const std::string path = dir.file("lattice.h5");
  writeSpecimen(block->lattice, block->positions, path);
  return path;
}

std::string randomFile(const testing::TempDir& dir) {
  dem::RandomPackingSpec spec;
  spec.box = {0.03, 0.008, 0.008};
  spec.radiusMin = 4e-4;
  spec.radiusMax = 6e-4;  // polydisperse: a regular triangulation
  auto packing = dem::generateRandomPacking(spec);
  REQUIRE(packing.isOk());
  const std::string path = dir.file("random.h5");
  writeSpecimen(packing->lattice, packing->positions, path);
  return path;
}

// One primitive as order-free numbers: its type, point count, and the mean
// and spread of its points, rounded to a grid far finer than any face but
// far coarser than rounding noise (a piece sums in another order).
using Signature = std::array<long long, 8>;

std::vector<Signature> signatures(vtkDataSet* data, double scale) {
  std::vector<Signature> result;
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < data->GetNumberOfCells(); ++c) {
    data->GetCellPoints(c, ids);
    double mean[3] = {0, 0, 0};
    double p[3];
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) {
      data->GetPoint(ids->GetId(k), p);
      for (int a = 0; a < 3; ++a) {
        mean[a] += p[a] / static_cast<double>(ids->GetNumberOfIds());
      }
    }
    double spread = 0.0;
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) {
      data->GetPoint(ids->GetId(k), p);
      for (int a = 0; a < 3; ++a) {
        spread += std::abs(p[a] - mean[a]);
      }
    }
    auto grid = [&](double v) { return std::llround(v / scale * 1e7); };
    result.push_back({data->GetCellType(c), ids->GetNumberOfIds(), grid(mean[0]), grid(mean[1]),
                      grid(mean[2]), grid(spread), 0, 0});
  }
  std::sort(result.begin(), result.end());
  return result;
}

// The file's bond ids the output names (cell or point data "bond_id"), sorted.
std::vector<double> bondIds(vtkDataSet* data) {
  std::vector<double> ids;
  for (vtkDataSetAttributes* attributes :
       {static_cast<vtkDataSetAttributes*>(data->GetCellData()),
        static_cast<vtkDataSetAttributes*>(data->GetPointData())}) {
    if (vtkDataArray* array = attributes->GetArray("bond_id")) {
      for (vtkIdType k = 0; k < array->GetNumberOfTuples(); ++k) {
        ids.push_back(array->GetComponent(k, 0));
      }
    }
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

struct Run {
  vtkSmartPointer<vtkCrackvisDemReader> reader;
  vtkSmartPointer<vtkAlgorithm> filter;
};

template <typename Filter>
Run makeRun(const std::string& path) {
  Run run{vtkSmartPointer<vtkCrackvisDemReader>::New(), vtkSmartPointer<Filter>::New()};
  run.reader->SetFileName(path.c_str());
  run.filter->SetInputConnection(run.reader->GetOutputPort());
  return run;
}

vtkDataSet* update(Run& run, double time, int piece, int pieces) {
  run.filter->UpdateTimeStep(time, piece, pieces, 0);
  return vtkDataSet::SafeDownCast(run.filter->GetOutputDataObject(0));
}

template <typename Filter>
void checkPiecesAddUp(const std::string& path, int pieces) {
  Run whole = makeRun<Filter>(path);
  std::vector<Run> parts;
  for (int p = 0; p < pieces; ++p) {
    parts.push_back(makeRun<Filter>(path));
  }
  whole.reader->UpdateInformation();
  vtkInformation* info = whole.reader->GetOutputInformation(0);
  const int steps = info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  const double* times = info->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  const double scale = 0.01;
  std::size_t lastCells = 0;
  // Every step in order: each piece's filter is incremental across them.
  for (int step = 0; step < steps; ++step) {
    vtkDataSet* reference = update(whole, times[step], 0, 1);
    const auto expected = signatures(reference, scale);
    const auto expectedBonds = bondIds(reference);
    std::vector<Signature> merged;
    std::vector<double> mergedBonds;
    int piecesWithCells = 0;
    for (int p = 0; p < pieces; ++p) {
      vtkDataSet* out = update(parts[static_cast<std::size_t>(p)], times[step], p, pieces);
      const auto own = signatures(out, scale);
      merged.insert(merged.end(), own.begin(), own.end());
      const auto bonds = bondIds(out);
      mergedBonds.insert(mergedBonds.end(), bonds.begin(), bonds.end());
      piecesWithCells += own.empty() ? 0 : 1;
    }
    std::sort(merged.begin(), merged.end());
    std::sort(mergedBonds.begin(), mergedBonds.end());
    INFO("step " << step << " of " << steps << ", " << pieces << " pieces");
    CHECK(merged.size() == expected.size());
    CHECK(merged == expected);
    if (expectedBonds.size() > 0) {
      // Point bond ids repeat where pieces share a point; compare the set.
      auto unique = [](std::vector<double> v) {
        v.erase(std::unique(v.begin(), v.end()), v.end());
        return v;
      };
      CHECK(unique(mergedBonds) == unique(expectedBonds));
    }
    if (step == steps - 1) {
      CHECK(piecesWithCells == pieces);  // the crack and the scattered breaks span every piece
    }
    lastCells = expected.size();
  }
  CHECK(lastCells > 100);
}

}  // namespace

TEST_CASE("the reader's pieces through each filter add up to the whole set, face for face",
          "[cracks][vtk][pieces]") {
  testing::TempDir dir;
  const bool random = GENERATE(false, true);
  const std::string path = random ? randomFile(dir) : latticeFile(dir);
  const int pieces = GENERATE(2, 3);
  INFO((random ? "random packing" : "FCC lattice") << ", " << pieces << " pieces");
  SECTION("cell cut") {
    checkPiecesAddUp<vtkCellCutCrackFilter>(path, pieces);
  }
  SECTION("local Voronoi") {
    checkPiecesAddUp<vtkLocalVoronoiCrackFilter>(path, pieces);
  }
  SECTION("cell centre") {
    checkPiecesAddUp<vtkCellCentreCrackFilter>(path, pieces);
  }
  SECTION("cell attribute") {
    checkPiecesAddUp<vtkCellAttributeCrackFilter>(path, pieces);
  }
}

TEST_CASE("a piece holds its slab and a ghost layer, marked, with the file's ids",
          "[cracks][vtk][pieces]") {
  testing::TempDir dir;
  const std::string path = latticeFile(dir);
  vtkNew<vtkCrackvisDemReader> reader;
  reader->SetFileName(path.c_str());
  reader->UpdateInformation();
  reader->UpdatePiece(0, 1, 0);
  const vtkIdType n = reader->GetOutput()->GetNumberOfPoints();
  const vtkIdType m = reader->GetOutput()->GetNumberOfLines();
  CHECK(reader->GetOutput()->GetPointData()->GetGlobalIds() == nullptr);
  vtkIdType owned = 0;
  vtkIdType ownedBonds = 0;
  for (int p = 0; p < 2; ++p) {
    reader->UpdatePiece(p, 2, 0);
    vtkPolyData* piece = reader->GetOutput();
    CHECK(piece->GetNumberOfPoints() < n);
    vtkDataArray* ghost = piece->GetPointData()->GetArray(vtkDataSetAttributes::GhostArrayName());
    vtkDataArray* ids = piece->GetPointData()->GetGlobalIds();
    REQUIRE(ghost != nullptr);
    REQUIRE(ids != nullptr);
    vtkIdType ghosts = 0;
    for (vtkIdType i = 0; i < piece->GetNumberOfPoints(); ++i) {
      ghosts += ghost->GetComponent(i, 0) != 0.0 ? 1 : 0;
      if (i > 0) {
        CHECK(ids->GetComponent(i, 0) > ids->GetComponent(i - 1, 0));  // the file's order
      }
    }
    CHECK(ghosts > 0);
    owned += piece->GetNumberOfPoints() - ghosts;
    vtkDataArray* bondGhost =
        piece->GetCellData()->GetArray(vtkDataSetAttributes::GhostArrayName());
    REQUIRE(bondGhost != nullptr);
    for (vtkIdType b = 0; b < piece->GetNumberOfLines(); ++b) {
      ownedBonds += bondGhost->GetComponent(b, 0) == 0.0 ? 1 : 0;
    }
  }
  CHECK(owned == n);       // every particle is owned by exactly one piece
  CHECK(ownedBonds == m);  // and every bond
}
