// The analyses of a whole run: a planted crack that grows from the bottom
// face to the top while its right half moves away.
#include <algorithm>
#include <cmath>

#include "analysis_fixtures.hpp"

using namespace crackvis;
using namespace crackvis::analysis;

TEST_CASE("a planted crack's growth: area, front, opening and fragments step by step",
          "[analysis][growth]") {
  dem::BlockSpec spec;
  spec.kind = dem::LatticeKind::kFcc;
  spec.sites = dem::fccUnitCells(4, 4, 4);
  spec.radius = 0.5;
  const dem::LatticeBlock block = dem::generateBlock(spec).value();
  dem::PlantedCrackSpec planted;
  planted.steps = 8;
  planted.scatter = 0.0;
  planted.opening = 0.4;
  auto crack = dem::PlantedCrack::create(block.lattice, block.positions, planted);
  REQUIRE(crack);
  const cracks::BondGraph graph(block.lattice.particleCount(), block.lattice.bonds);
  auto extractor = cracks::makeExtractor(cracks::Method::kLocalVoronoi, graph, 3);
  CrackAnalysis analysis(block.lattice, {});
  AnalysisOptions planeEachStep;
  planeEachStep.mainPlaneEachStep = true;
  CrackAnalysis planed(block.lattice, planeEachStep);
  std::vector<StepAnalysis> steps;
  std::vector<StepAnalysis> planedSteps;
  cracks::CrackMesh mesh;
  std::vector<dem::StepState> states;
  for (int k = 0; k < crack->stepCount(); ++k) {
    const dem::StepState state = crack->step(k);
    const cracks::StepInput input{
        state.positions, state.bondState, block.lattice.radius, {}, {}, block.positions, {}, {}};
    REQUIRE(extractor->extract(input, mesh));
    steps.push_back(analysis.analyse(k, state.time, input, block.positions, mesh));
    planedSteps.push_back(planed.analyse(k, state.time, input, block.positions, mesh));
    // The main crack's plane only when asked: the same as found anew.
    CHECK(dem::norm(steps.back().mainNormal) == 0.0);
    if (steps.back().hasMain) {
      const cracks::CrackComponents anew = cracks::findComponents(mesh);
      CHECK(dem::norm(analysis.mainPlane(mesh).normal - anew.components[0].normal) == 0.0);
      CHECK(dem::norm(analysis.mainPlane(mesh).centroid - anew.components[0].centroid) == 0.0);
      CHECK(dem::norm(planedSteps.back().mainNormal - anew.components[0].normal) == 0.0);
      CHECK(std::abs(planedSteps.back().mainNormal.x) > 0.99);  // the cut is a plane x = const
    }
  }
  // Intact at step 0; one piece until the crack is through, two after.
  CHECK_FALSE(steps.front().hasMain);
  CHECK(steps.front().fragments == 1);
  CHECK(steps.back().fragments == 2);
  const auto right = std::count_if(block.positions.begin(), block.positions.end(),
                                   [&](dem::Vec3 p) { return p.x > crack->cut(); });
  const auto larger = std::max<std::size_t>(
      static_cast<std::size_t>(right), block.positions.size() - static_cast<std::size_t>(right));
  CHECK(steps.back().largestFragmentShare ==
        Approx(static_cast<double>(larger) / static_cast<double>(block.positions.size())));
  for (std::size_t k = 1; k < steps.size(); ++k) {
    CHECK(steps[k].mainArea >= steps[k - 1].mainArea - 1e-9);
    CHECK(steps[k].totalArea >= steps[k].mainArea - 1e-9);
  }
  // The front runs up (z) and reaches the top at 3/4 of the steps.
  const CrackFront front = crackFront(steps, 3);
  CHECK(front.axis == 2);
  // Without planes, the front's normal axis is the one the main crack's box
  // is thinnest along (x here); with them, the plane's: the same front.
  CHECK(crackFront(planedSteps, 3).axis == 2);
  CHECK(crackFront(planedSteps, 3).extent == front.extent);
  CHECK(front.extent[2] < front.extent[4]);
  CHECK(front.extent[6] == Approx(front.extent.back()));
  CHECK(front.speed[3] > 0.0);
  CHECK(front.speed.back() == Approx(0.0).margin(1e-9));
  // The opening at the last step: `opening` mean bond lengths (1 here).
  const auto far = static_cast<std::size_t>(
      std::max_element(block.positions.begin(), block.positions.end(),
                       [](dem::Vec3 a, dem::Vec3 b) { return a.x < b.x; }) -
      block.positions.begin());
  const double shift = crack->step(planted.steps).positions[far].x - block.positions[far].x;
  CHECK(steps.back().mainOpening.meanOpening == Approx(shift).epsilon(0.01));
  // Every bond that broke during the run has a mode; fragments were found
  // again only when bonds broke.
  CHECK(steps.back().tension + steps.back().shear == steps.back().broken);
  CHECK(analysis.fragmentTracker().recomputations() <= static_cast<std::size_t>(planted.steps));
}

TEST_CASE("the crack front's normal axis: the last plane given, else the thinnest side of the box",
          "[analysis][growth]") {
  // A main crack thin along y that grows along z from step 1 to step 2 and
  // along x more from step 0 to step 2.
  std::vector<StepAnalysis> steps(3);
  const dem::Vec3 lo{0.0, 0.0, 0.0};
  const dem::Vec3 his[] = {{1.0, 0.1, 1.0}, {2.0, 0.1, 1.5}, {4.0, 0.1, 3.0}};
  for (std::size_t k = 0; k < steps.size(); ++k) {
    steps[k].step = static_cast<int>(k);
    steps[k].time = static_cast<double>(k);
    steps[k].hasMain = true;
    steps[k].mainBox = {lo, his[k]};
  }
  // No plane: y is the normal axis; of x and z, x grew most.
  CrackFront front = crackFront(steps, 3);
  CHECK(front.axis == 0);
  CHECK(front.extent == std::vector<double>{1.0, 2.0, 4.0});
  CHECK(front.speed == std::vector<double>{0.0, 1.0, 2.0});
  // A plane facing x at the first step only: the last plane given rules.
  steps[0].mainNormal = {1.0, 0.0, 0.0};
  front = crackFront(steps, 3);
  CHECK(front.axis == 2);  // of y and z, z grew (2), y did not
  CHECK(front.extent == std::vector<double>{1.0, 1.5, 3.0});
}
