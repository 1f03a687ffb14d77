// The analyses of a whole run: a planted crack that grows from the bottom
// face to the top while its right half moves away.
#include <algorithm>

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
  std::vector<StepAnalysis> steps;
  cracks::CrackMesh mesh;
  std::vector<dem::StepState> states;
  for (int k = 0; k < crack->stepCount(); ++k) {
    const dem::StepState state = crack->step(k);
    const cracks::StepInput input{
        state.positions, state.bondState, block.lattice.radius, {}, {}, block.positions, {}, {}};
    REQUIRE(extractor->extract(input, mesh));
    steps.push_back(analysis.analyse(k, state.time, input, block.positions, mesh));
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
