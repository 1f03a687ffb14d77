// The crack methods over a real simulated fracture series (a scaled cuboid A
// from crackvis::sim), step by step as a viewer runs them.
#include <set>

#include <catch2/catch.hpp>

#include "support/simulated_cuboid.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/cracks/dem_series.hpp>

using namespace crackvis;
using namespace crackvis::cracks;

namespace {

// One scaled run shared by the test cases of this process.
const std::string& simulatedFile() {
  static testing::TempDir dir;
  static const std::string path = [&] {
    testing::writeSimulatedCuboidA(dir.file("cuboidA-scaled.h5"));
    return dir.file("cuboidA-scaled.h5");
  }();
  return path;
}

std::set<std::vector<int>> cellSet(const LatticeDecomposition& decomposition) {
  std::set<std::vector<int>> cells;
  for (const LatticeCell& cell : decomposition.cells()) {
    std::vector<int> key(cell.nodes.begin(), cell.nodes.begin() + cell.nodeCount());
    key.push_back(static_cast<int>(cell.type));
    cells.insert(key);
  }
  return cells;
}

std::set<int> brokenBonds(const StepInput& step) {
  std::set<int> broken;
  for (std::size_t b = 0; b < step.bondState.size(); ++b) {
    if (step.bondState[b] != 0) {
      broken.insert(static_cast<int>(b));
    }
  }
  return broken;
}

}  // namespace

TEST_CASE("simulated series: incremental and from-scratch decompositions agree at every step",
          "[cracks][decomposition][sim]") {
  auto series = DemSeries::open(simulatedFile());
  REQUIRE(series.isOk());
  LatticeDecomposition incremental((*series)->graph(), 3);
  std::size_t finalBroken = 0;
  for (int step = 0; step < (*series)->stepCount(); step += 5) {
    auto input = (*series)->load(step);
    REQUIRE(input.isOk());
    incremental.update(input->bondState);
    LatticeDecomposition scratch((*series)->graph(), 3);
    scratch.update(input->bondState);
    REQUIRE(cellSet(incremental) == cellSet(scratch));
    finalBroken = brokenBonds(*input).size();
  }
  CHECK(finalBroken > 50);  // the series did fracture
}

TEST_CASE("simulated series: every primitive maps to a broken bond and no broken bond is missed",
          "[cracks][sim]") {
  auto series = DemSeries::open(simulatedFile());
  REQUIRE(series.isOk());
  const int steps = (*series)->stepCount();
  for (Method method : {Method::kCellCut, Method::kLocalVoronoi, Method::kCellCentre}) {
    auto extractor = makeExtractor(method, (*series)->graph(), 3);
    CrackMesh mesh;
    for (int step : {0, steps / 2, steps - 1}) {
      auto input = (*series)->load(step);
      REQUIRE(input.isOk());
      REQUIRE(extractor->extract(*input, mesh).isOk());
      const std::set<int> broken = brokenBonds(*input);
      INFO(toString(method) << " at step " << step);
      if (method == Method::kCellCut) {
        // One point per broken bond, each used by some primitive.
        const AttributeArray* bondId = mesh.findPointData("bond_id");
        REQUIRE(bondId != nullptr);
        CHECK(std::set<int>(bondId->values.begin(), bondId->values.end()) == broken);
        std::vector<char> used(mesh.points.size(), 0);
        for (auto id : mesh.vertices)
          used[static_cast<std::size_t>(id)] = 1;
        for (auto id : mesh.lines.connectivity)
          used[static_cast<std::size_t>(id)] = 1;
        for (auto id : mesh.polygons.connectivity)
          used[static_cast<std::size_t>(id)] = 1;
        CHECK(std::count(used.begin(), used.end(), 1) == static_cast<std::ptrdiff_t>(used.size()));
      } else {
        // Exactly one primitive (face, or inconsistency mark) per broken bond.
        const AttributeArray* bondId = mesh.findCellData("bond_id");
        REQUIRE(bondId != nullptr);
        CHECK(mesh.primitiveCount() == broken.size());
        CHECK(std::set<int>(bondId->values.begin(), bondId->values.end()) == broken);
      }
    }
  }
}

namespace {

// Two meshes hold the same points (bit for bit), primitives and bond ids.
void requireSameMesh(const CrackMesh& a, const CrackMesh& b) {
  REQUIRE(a.points.size() == b.points.size());
  for (std::size_t k = 0; k < a.points.size(); ++k) {
    REQUIRE(a.points[k].x == b.points[k].x);
    REQUIRE(a.points[k].y == b.points[k].y);
    REQUIRE(a.points[k].z == b.points[k].z);
  }
  REQUIRE(a.polygons.connectivity == b.polygons.connectivity);
  REQUIRE(a.polygons.offsets == b.polygons.offsets);
  REQUIRE(a.lines.connectivity == b.lines.connectivity);
  const AttributeArray* idsA = a.findCellData("bond_id");
  const AttributeArray* idsB = b.findCellData("bond_id");
  REQUIRE(idsA != nullptr);
  REQUIRE(idsB != nullptr);
  REQUIRE(idsA->values == idsB->values);
}

}  // namespace

TEST_CASE(
    "simulated series: local Voronoi's carried faces are the same incrementally, from "
    "scratch and after stepping back",
    "[cracks][local-voronoi][sim]") {
  auto series = DemSeries::open(simulatedFile());
  REQUIRE(series.isOk());
  const int steps = (*series)->stepCount();
  auto incremental = makeExtractor(Method::kLocalVoronoi, (*series)->graph(), 3);
  CrackMesh running;
  CrackMesh scratch;
  std::size_t facesSeen = 0;
  auto compareAt = [&](int step) {
    INFO("step " << step);
    auto input = (*series)->load(step);
    REQUIRE(input.isOk());
    REQUIRE(!input->referencePositions.empty());  // the carried (material) faces
    REQUIRE(incremental->extract(*input, running).isOk());
    auto fresh = makeExtractor(Method::kLocalVoronoi, (*series)->graph(), 3);
    REQUIRE(fresh->extract(*input, scratch).isOk());
    requireSameMesh(running, scratch);
    CHECK(incremental->inconsistentBondCount() == fresh->inconsistentBondCount());
    CHECK(running.primitiveCount() == brokenBonds(*input).size());
    facesSeen = std::max(facesSeen, running.polygons.size());
  };
  for (int step = 0; step < steps; step += 3) {
    compareAt(step);
  }
  compareAt(steps - 1);
  // Back in time: bonds broken later are intact again and must go.
  compareAt(steps / 3);
  compareAt(steps - 1);
  CHECK(facesSeen > 50);
}
