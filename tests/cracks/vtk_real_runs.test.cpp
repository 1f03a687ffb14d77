// The ParaView filters' opening and slip on runs of the real DEM codes
// (tests/data: Yade JCFpm, ESyS-Particle and LAMMPS notched bars, imported
// here): polydisperse random packings, triangulated, where the lattice tests'
// exact answers do not reach. Stepped through the run as a ParaView user plays
// it, each filter must give each surface element the opening and slip that
// `crackvis report` measures (its loop: DemSeries, the method's extractor and
// analysis::CrackAnalysis fed every step in order).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <vtkCellCentreCrackFilter.h>
#include <vtkCellCutCrackFilter.h>
#include <vtkCellData.h>
#include <vtkCrackvisDemReader.h>
#include <vtkDataArray.h>
#include <vtkLocalVoronoiCrackFilter.h>
#include <vtkNew.h>
#include <vtkPolyData.h>

#include "support/temp_dir.hpp"
#include <crackvis/analysis/growth.hpp>
#include <crackvis/cracks/dem_series.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/importers/importer.hpp>
#include <crackvis/importers/step_source.hpp>

using namespace crackvis;

namespace {

const std::string kTestData = CRACKVIS_TEST_DATA;

struct RealRun {
  const char* code;
  Result<std::unique_ptr<importers::StepSource>> (*open)(const std::vector<std::string>&);
  const char* folder;
};

std::string importRun(const RealRun& run, const testing::TempDir& dir) {
  const std::string out = dir.file(std::string(run.code) + ".h5");
  auto source = run.open({kTestData + "/" + run.folder});
  REQUIRE(source);
  importers::ImportOptions options;
  options.output = out;
  options.progress = false;
  options.invocation = "test";
  REQUIRE(importers::importSeries(**source, options));
  return out;
}

// Equal to rounding (the same library computes both), NaN with NaN.
bool sameValue(double a, double b, double scale) {
  if (std::isnan(a) || std::isnan(b)) {
    return std::isnan(a) && std::isnan(b);
  }
  return std::abs(a - b) <= 1e-9 * scale;
}

struct Compared {
  std::size_t elements = 0;   // with a bond, over the steps
  std::size_t differing = 0;  // cells whose opening or slip is not the report's
  double largestOpening = 0.0;
};

// One filter stepped through the file against the report's loop.
template <typename Filter>
Compared compareWithReport(const std::string& path, cracks::Method method) {
  auto series = cracks::DemSeries::open(path);
  REQUIRE(series);
  const dem::Lattice& lattice = (*series)->lattice();
  auto extractor = cracks::makeExtractor(method, (*series)->graph(), lattice.dimension, {});
  analysis::CrackAnalysis analysis(lattice, {});

  vtkNew<vtkCrackvisDemReader> reader;
  reader->SetFileName(path.c_str());
  reader->UpdateInformation();
  vtkNew<Filter> filter;
  filter->SetInputConnection(reader->GetOutputPort());

  Compared compared;
  cracks::CrackMesh mesh;
  for (int step = 0; step < (*series)->stepCount(); ++step) {
    auto input = (*series)->load(step);
    REQUIRE(input);
    REQUIRE(extractor->extract(*input, mesh));
    const double time = (*series)->info().steps[static_cast<std::size_t>(step)].time;
    analysis.analyse(step, time, *input, input->referencePositions, mesh);
    const analysis::ElementOpenings& expected = analysis.openings();
    // The report's values as the filters' cell arrays: every cell in VTK
    // order, NaN where a cell is no surface element.
    analysis::appendOpeningArrays(mesh, expected);
    const cracks::AttributeArray* reportOpening = mesh.findCellData("opening");
    const cracks::AttributeArray* reportSlip = mesh.findCellData("slip");
    REQUIRE(reportOpening != nullptr);
    REQUIRE(reportSlip != nullptr);

    filter->UpdateTimeStep(time);
    vtkPolyData* out = vtkPolyData::SafeDownCast(filter->GetOutputDataObject(0));
    REQUIRE(out != nullptr);
    vtkDataArray* opening = out->GetCellData()->GetArray("opening");
    vtkDataArray* slip = out->GetCellData()->GetArray("slip");
    INFO("step " << step);
    REQUIRE(opening != nullptr);
    REQUIRE(slip != nullptr);
    const auto cells = static_cast<vtkIdType>(reportOpening->values.size());
    REQUIRE(out->GetNumberOfCells() == cells);
    REQUIRE(opening->GetNumberOfTuples() == cells);
    REQUIRE(slip->GetNumberOfTuples() == cells);
    for (std::size_t e = 0; e < expected.size(); ++e) {
      if (!std::isnan(expected.opening[e])) {
        compared.largestOpening = std::max(compared.largestOpening, expected.opening[e]);
        ++compared.elements;
      }
    }
    const double scale = std::max(compared.largestOpening, 1e-12);
    for (vtkIdType c = 0; c < cells; ++c) {
      const auto at = static_cast<std::size_t>(c);
      if (!sameValue(opening->GetTuple1(c), reportOpening->values[at], scale) ||
          !sameValue(slip->GetTuple1(c), reportSlip->values[at], scale)) {
        ++compared.differing;
      }
    }
  }
  return compared;
}

}  // namespace

TEST_CASE(
    "on Yade, ESyS-Particle and LAMMPS runs the filters measure opening and slip as "
    "crackvis report does, element by element at every step",
    "[cracks][vtk][analysis][importers]") {
  testing::TempDir dir;
  for (const RealRun& run : {RealRun{"yade", importers::openYade, "yade/notched_bar"},
                             RealRun{"esys", importers::openEsys, "esys/notched_bar"},
                             RealRun{"lammps", importers::openLammps, "lammps/notched_bar"}}) {
    const std::string path = importRun(run, dir);
    INFO(run.code);
    const auto check = [&](const char* method, const Compared& compared) {
      INFO(method << ": " << compared.elements << " elements, " << compared.differing
                  << " differing, largest opening " << compared.largestOpening);
      CHECK(compared.elements > 0);
      CHECK(compared.largestOpening > 0.0);
      CHECK(compared.differing == 0);
    };
    check("local Voronoi",
          compareWithReport<vtkLocalVoronoiCrackFilter>(path, cracks::Method::kLocalVoronoi));
    check("cell centre",
          compareWithReport<vtkCellCentreCrackFilter>(path, cracks::Method::kCellCentre));
    check("cell cut", compareWithReport<vtkCellCutCrackFilter>(path, cracks::Method::kCellCut));
  }
}
