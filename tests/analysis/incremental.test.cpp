// The analyses kept across steps (issue 33 point 6) against the same
// analyses found anew at every step: the crack's components, the fragments,
// the normals and the break modes must not depend on how they were reached.
#include <algorithm>
#include <cmath>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include "analysis_fixtures.hpp"
#include <crackvis/analysis/bond_diff.hpp>
#include <crackvis/cracks/crack_components.hpp>

using namespace crackvis;
using namespace crackvis::analysis;

namespace {

// A planted crack with a lot of scattered damage: many small components
// beside the main one, and particles freed as dust.
struct Run {
  dem::LatticeBlock block;
  std::vector<dem::StepState> steps;
};

Run plantedRun(dem::LatticeKind kind, std::array<int, 3> sites, double scatter) {
  dem::BlockSpec spec;
  spec.kind = kind;
  spec.sites = sites;
  spec.radius = 0.5;
  Run run{dem::generateBlock(spec).value(), {}};
  dem::PlantedCrackSpec planted;
  planted.steps = 8;
  planted.scatter = scatter;
  planted.opening = 0.3;
  auto crack = dem::PlantedCrack::create(run.block.lattice, run.block.positions, planted);
  REQUIRE(crack);
  for (int k = 0; k < crack->stepCount(); ++k) {
    run.steps.push_back(crack->step(k));
  }
  return run;
}

cracks::StepInput inputOf(const Run& run, const dem::StepState& state) {
  return {state.positions,
          state.bondState,
          run.block.lattice.radius,
          {},
          {},
          run.block.positions,
          {},
          {}};
}

// The same components, with the same primitives and areas.
void requireSameAreas(const cracks::CrackComponents& kept, const cracks::CrackComponents& anew) {
  REQUIRE(kept.components.size() == anew.components.size());
  CHECK(kept.ofPrimitive == anew.ofPrimitive);
  for (std::size_t c = 0; c < anew.components.size(); ++c) {
    CHECK(kept.components[c].primitives == anew.components[c].primitives);
    CHECK(kept.components[c].area == anew.components[c].area);
  }
}

void requireSameComponents(const cracks::CrackComponents& kept,
                           const cracks::CrackComponents& anew) {
  requireSameAreas(kept, anew);
  for (std::size_t c = 0; c < anew.components.size(); ++c) {
    CHECK(dem::norm(kept.components[c].normal - anew.components[c].normal) == 0.0);
  }
}

// A tracker that sums areas only: the same components, areas and boxes, and
// componentPlane gives each one's centroid and plane to the last bit.
void requireSameAreasAndPlanes(const cracks::CrackMesh& mesh, const cracks::CrackComponents& kept,
                               const cracks::CrackComponents& anew) {
  requireSameAreas(kept, anew);
  for (std::size_t c = 0; c < anew.components.size(); ++c) {
    CHECK(dem::norm(kept.components[c].box.lo - anew.components[c].box.lo) == 0.0);
    CHECK(dem::norm(kept.components[c].box.hi - anew.components[c].box.hi) == 0.0);
    const cracks::ComponentPlane plane = cracks::componentPlane(mesh, kept, c);
    CHECK(dem::norm(plane.centroid - anew.components[c].centroid) == 0.0);
    CHECK(dem::norm(plane.normal - anew.components[c].normal) == 0.0);
  }
  CHECK(dem::norm(cracks::componentPlane(mesh, kept, anew.components.size()).normal) == 0.0);
}

// A planted crack with scattered damage in an FCC block (3D) and in a
// triangular one (2D).
std::vector<std::pair<dem::LatticeKind, Run>> plantedRunsIn3dAnd2d() {
  std::vector<std::pair<dem::LatticeKind, Run>> runs;
  runs.emplace_back(dem::LatticeKind::kFcc,
                    plantedRun(dem::LatticeKind::kFcc, dem::fccUnitCells(5, 4, 4), 0.03));
  runs.emplace_back(dem::LatticeKind::kTriangular,
                    plantedRun(dem::LatticeKind::kTriangular, {24, 20, 1}, 0.03));
  return runs;
}

}  // namespace

TEST_CASE("components kept across steps equal the components found anew at each step",
          "[analysis][incremental]") {
  for (const auto& [kind, run] : plantedRunsIn3dAnd2d()) {
    const cracks::BondGraph graph(run.block.lattice.particleCount(), run.block.lattice.bonds);
    for (const cracks::Method method : {cracks::Method::kLocalVoronoi, cracks::Method::kCellCentre,
                                        cracks::Method::kCellCut, cracks::Method::kCellAttribute}) {
      const std::string what =
          std::string(dem::toString(kind)) + " " + std::string(cracks::toString(method));
      CAPTURE(what);
      auto extractor = cracks::makeExtractor(method, graph, dem::dimensionOf(kind));
      cracks::ComponentTracker tracker;
      cracks::ComponentTracker areas(cracks::ComponentDetail::kAreas);
      cracks::CrackMesh mesh;
      std::size_t largest = 0;
      for (const dem::StepState& state : run.steps) {
        REQUIRE(extractor->extract(inputOf(run, state), mesh));
        const cracks::CrackComponents anew = cracks::findComponents(mesh);
        requireSameComponents(tracker.update(mesh, true), anew);
        requireSameAreasAndPlanes(mesh, areas.update(mesh, true), anew);
        largest = std::max(largest, tracker.current().components.size());
      }
      // Kept surfaces hold no planes; those found anew (cells too) do.
      CHECK(areas.current().planes == (tracker.recomputations() > 0));
      // Local Voronoi and cell centre carry a bond per face: only the new
      // faces are welded, and there are many pieces to join or keep apart.
      // The others are found anew at every step.
      const bool kept =
          method == cracks::Method::kLocalVoronoi || method == cracks::Method::kCellCentre;
      CHECK((largest > 5 || !kept));
      CHECK(tracker.recomputations() == (kept ? 0u : run.steps.size()));

      // A viewer stepping back: faces leave, and the tracker starts over;
      // one step on, the areas-only tracker keeps areas only again.
      const std::size_t before = tracker.recomputations();
      REQUIRE(extractor->extract(inputOf(run, run.steps[3]), mesh));
      requireSameComponents(tracker.update(mesh, true), cracks::findComponents(mesh));
      requireSameAreasAndPlanes(mesh, areas.update(mesh, true), cracks::findComponents(mesh));
      CHECK(tracker.recomputations() == before + 1);
      CHECK(areas.current().planes);
      REQUIRE(extractor->extract(inputOf(run, run.steps[4]), mesh));
      requireSameAreasAndPlanes(mesh, areas.update(mesh, true), cracks::findComponents(mesh));
      CHECK(areas.current().planes == !kept);
    }
  }
}

TEST_CASE(
    "the openings measured in two halves equal one call's, areas and centroids from the "
    "components' pass",
    "[analysis][incremental]") {
  for (const auto& [kind, run] : plantedRunsIn3dAnd2d()) {
    const auto& lattice = run.block.lattice;
    const cracks::BondGraph graph(lattice.particleCount(), lattice.bonds);
    for (const cracks::Method method :
         {cracks::Method::kLocalVoronoi, cracks::Method::kCellCentre, cracks::Method::kCellCut}) {
      const std::string what =
          std::string(dem::toString(kind)) + " " + std::string(cracks::toString(method));
      CAPTURE(what);
      auto extractor = cracks::makeExtractor(method, graph, dem::dimensionOf(kind));
      CrackAnalysis analysis(lattice, {});
      cracks::ComponentTracker areas(cracks::ComponentDetail::kAreas);
      cracks::CrackMesh mesh;
      // Local Voronoi and cell centre are carried: the components measure
      // every face, and the openings take those figures.
      const bool carried =
          method == cracks::Method::kLocalVoronoi || method == cracks::Method::kCellCentre;
      for (std::size_t k = 0; k < run.steps.size(); ++k) {
        const dem::StepState& state = run.steps[k];
        REQUIRE(extractor->extract(inputOf(run, state), mesh));
        analysis.analyse(static_cast<int>(k), 0.0, inputOf(run, state), run.block.positions, mesh);
        areas.update(mesh, true);
        // The analysis kept its components (and so measured the faces) where
        // they are carried.
        CHECK(analysis.components().planes == !carried);
        const std::size_t primitives = cracks::surfacePrimitives(mesh).size();
        CHECK(areas.extents().size() == (carried ? primitives : 0u));
        const ElementOpenings direct =
            measureOpening(mesh, analysis.components(), lattice.bonds, run.block.positions,
                           state.positions, {}, &analysis.normals());
        const ElementOpenings& kept = analysis.openings();
        REQUIRE(direct.size() == kept.size());
        // The analysis measures an element in two halves (its bonds beside
        // the components, then where it lies): every field as one call's.
        const auto same = [](double a, double b) {
          return a == b || (std::isnan(a) && std::isnan(b));
        };
        std::size_t differ = 0;
        for (std::size_t e = 0; e < direct.size(); ++e) {
          const bool equal =
              direct.area[e] == kept.area[e] &&
              dem::norm(direct.centroid[e] - kept.centroid[e]) == 0.0 &&
              dem::norm(direct.normal[e] - kept.normal[e]) == 0.0 &&
              same(direct.opening[e], kept.opening[e]) && same(direct.slip[e], kept.slip[e]) &&
              direct.component[e] == kept.component[e] && direct.cell[e] == kept.cell[e];
          differ += equal ? 0 : 1;
        }
        CHECK(differ == 0);
      }
    }
  }
}

TEST_CASE("components are found anew for a mesh not carried from a reference configuration",
          "[analysis][incremental]") {
  const Run run = plantedRun(dem::LatticeKind::kFcc, dem::fccUnitCells(4, 4, 4), 0.02);
  const cracks::BondGraph graph(run.block.lattice.particleCount(), run.block.lattice.bonds);
  auto extractor = cracks::makeExtractor(cracks::Method::kLocalVoronoi, graph, 3);
  cracks::ComponentTracker tracker;
  cracks::CrackMesh mesh;
  for (const dem::StepState& state : run.steps) {
    const cracks::StepInput input{
        state.positions, state.bondState, run.block.lattice.radius, {}, {}, {}, {}, {}};
    REQUIRE(extractor->extract(input, mesh));
    requireSameComponents(tracker.update(mesh, false), cracks::findComponents(mesh));
  }
  CHECK(tracker.recomputations() == run.steps.size());
}

TEST_CASE("fragments kept across steps equal the fragments found anew at each step",
          "[analysis][incremental]") {
  const Run run = plantedRun(dem::LatticeKind::kFcc, dem::fccUnitCells(5, 4, 4), 0.3);
  const auto& lattice = run.block.lattice;
  BondDiffer differ;
  FragmentTracker tracker;
  std::size_t most = 0;
  for (const dem::StepState& state : run.steps) {
    const BondDiff& diff = differ.update(state.bondState);
    const Fragments& kept =
        tracker.update(lattice.bonds, state.bondState, lattice.radius, 3, &diff);
    const Fragments anew = findFragments(lattice.bonds, state.bondState, lattice.radius, 3);
    REQUIRE(kept.fragments.size() == anew.fragments.size());
    CHECK(kept.ofParticle == anew.ofParticle);
    CHECK(kept.totalVolume == anew.totalVolume);
    most = std::max(most, anew.fragments.size());
  }
  // The last step splits the block in two; dust was freed on the way; yet
  // most steps with new breaks were decided near the breaks.
  CHECK(most > 2);
  CAPTURE(most, tracker.recomputations());
  CHECK(tracker.recomputations() < run.steps.size() - 1);
  CHECK(tracker.recomputations() >= 2);
}

TEST_CASE("a freed particle and a bond broken twice over are seen by the fragment floods",
          "[analysis][incremental]") {
  const Run run = plantedRun(dem::LatticeKind::kFcc, dem::fccUnitCells(3, 3, 3), 0.0);
  const auto& lattice = run.block.lattice;
  std::vector<std::uint8_t> state(lattice.bonds.size(), 0);
  BondDiffer differ;
  FragmentTracker tracker;
  tracker.update(lattice.bonds, state, lattice.radius, 3, &differ.update(state));
  // One bond of particle 7: it stays joined through its other bonds.
  std::vector<std::size_t> bondsOf7;
  for (std::size_t b = 0; b < lattice.bonds.size(); ++b) {
    if (lattice.bonds[b].first == 7 || lattice.bonds[b].second == 7) {
      bondsOf7.push_back(b);
    }
  }
  REQUIRE(bondsOf7.size() > 2);
  state[bondsOf7[0]] = 1;
  CHECK(tracker.update(lattice.bonds, state, lattice.radius, 3, &differ.update(state))
            .fragments.size() == 1);
  CHECK(tracker.recomputations() == 1);
  // All the others at once: particle 7 is a fragment of its own.
  for (std::size_t b : bondsOf7) {
    state[b] = 1;
  }
  const Fragments& freed =
      tracker.update(lattice.bonds, state, lattice.radius, 3, &differ.update(state));
  REQUIRE(freed.fragments.size() == 2);
  CHECK(freed.fragments.back().particles == 1);
  CHECK(freed.ofParticle[7] == 1);
  // A bond heals (a viewer going back): start over, still right.
  state[bondsOf7[1]] = 0;
  CHECK(tracker.update(lattice.bonds, state, lattice.radius, 3, &differ.update(state))
            .fragments.size() == 1);
}

namespace {

// A broken bond's normal found directly, two passes over its whole window:
// every broken bond whose reference midpoint lies within R.
dem::Vec3 windowNormal(const dem::Lattice& lattice, std::span<const std::uint8_t> state,
                       std::span<const dem::Vec3> reference, std::size_t bond, double radius,
                       bool flat, std::size_t& window, bool& wellPosed) {
  auto mid = [&](std::size_t b) {
    return 0.5 * (reference[static_cast<std::size_t>(lattice.bonds[b].first)] +
                  reference[static_cast<std::size_t>(lattice.bonds[b].second)]);
  };
  auto axis = [&](std::size_t b) {
    const dem::Vec3 d = reference[static_cast<std::size_t>(lattice.bonds[b].second)] -
                        reference[static_cast<std::size_t>(lattice.bonds[b].first)];
    return (1.0 / dem::norm(d)) * d;
  };
  std::vector<std::pair<std::size_t, double>> near;
  for (std::size_t b = 0; b < state.size(); ++b) {
    const dem::Vec3 d = mid(b) - mid(bond);
    const double q = dem::dot(d, d) / (radius * radius);
    if (state[b] != 0 && q < 1.0) {
      near.emplace_back(b, (1.0 - q) * (1.0 - q));
    }
  }
  window = near.size();
  double weight = 0.0;
  dem::Vec3 mean{};
  for (const auto& [b, w] : near) {
    weight += w;
    mean = mean + w * mid(b);
  }
  mean = (1.0 / weight) * mean;
  AxialTensor spread;
  AxialTensor directions;
  for (const auto& [b, w] : near) {
    spread.add(mid(b) - mean, w);
    directions.add(axis(b), w);
  }
  // Well posed: the axis taken stands apart from the others (by a millionth
  // of the trace), and the plane test is not a tie. A thread of collinear
  // midpoints has no one plane: rounding picks among them.
  auto gaps = [](const AxialTensor& t) {
    const double smallest = t.along(t.smallestAxis());
    const double largest = t.along(t.principalAxis());
    const double middle = t.trace() - smallest - largest;
    return std::pair{(middle - smallest) / t.trace(), (largest - middle) / t.trace()};
  };
  dem::Vec3 n = directions.principalAxis();
  wellPosed = gaps(directions).second > 1e-6;
  if (near.size() >= (flat ? 2u : 3u)) {
    const double total = spread.trace();
    if (flat) {
      spread.addZ(total + 1.0);
    }
    const dem::Vec3 across = spread.smallestAxis();
    const double a = spread.along(across);
    const double inPlane = flat ? total - a : (total - a) / 2.0;
    if (a < 0.1 * inPlane) {
      n = across;
      wellPosed = gaps(spread).first > 1e-6;
    }
    wellPosed = wellPosed && std::abs(a - 0.1 * inPlane) > 1e-6 * total;
  }
  return dem::dot(n, axis(bond)) < 0.0 ? -1.0 * n : n;
}

}  // namespace

TEST_CASE("a sparse window's normal, from sums its new breaks added, is the window's own plane",
          "[analysis][incremental]") {
  struct Case {
    dem::LatticeKind kind;
    std::array<int, 3> sites;
    bool jump;  // from step 2 straight to the last: many blocks of new breaks at once
  };
  for (const Case& c : {Case{dem::LatticeKind::kFcc, dem::fccUnitCells(5, 4, 4), false},
                        Case{dem::LatticeKind::kFcc, dem::fccUnitCells(7, 6, 6), true},
                        Case{dem::LatticeKind::kTriangular, {40, 34, 1}, false}}) {
    const Run run = plantedRun(c.kind, c.sites, 0.05);
    const auto& lattice = run.block.lattice;
    const bool flat = c.kind == dem::LatticeKind::kTriangular;
    CAPTURE(dem::toString(c.kind), c.jump);
    // A window of 1.5 bond lengths: more of them stay sparse.
    BondNormals normals(flat ? 2 : 3, 1.5);
    for (std::size_t k = c.jump ? 2 : 0; k < run.steps.size(); k += c.jump ? run.steps.size() : 1) {
      normals.update(lattice.bonds, run.steps[k].bondState, run.block.positions);
    }
    normals.update(lattice.bonds, run.steps.back().bondState, run.block.positions);
    const auto& last = run.steps.back().bondState;
    std::size_t sparse = 0;
    std::size_t settled = 0;
    std::size_t illPosed = 0;
    for (std::size_t b = 0; b < lattice.bonds.size(); ++b) {
      if (last[b] == 0) {
        continue;
      }
      if (normals.window(b) >= BondNormals::kSettledWindow) {
        ++settled;  // found no more once settled: its window has grown since
        continue;
      }
      std::size_t window = 0;
      bool wellPosed = false;
      const dem::Vec3 direct = windowNormal(lattice, last, run.block.positions, b, normals.radius(),
                                            flat, window, wellPosed);
      CAPTURE(b);
      CHECK(normals.window(b) == window);
      if (!wellPosed) {
        ++illPosed;
        continue;
      }
      ++sparse;
      // The same axis; the same way round unless it lies across the bond
      // (then which way is a matter of rounding).
      const dem::Vec3 n = normals.normal(b);
      CHECK(std::min(dem::norm(n - direct), dem::norm(n + direct)) < 1e-9);
      const dem::Bond& pair = lattice.bonds[b];
      const dem::Vec3 d0 = run.block.positions[static_cast<std::size_t>(pair.second)] -
                           run.block.positions[static_cast<std::size_t>(pair.first)];
      if (std::abs(dem::dot(direct, d0)) > 1e-6 * dem::norm(d0)) {
        CHECK(dem::norm(n - direct) < 1e-9);
      }
    }
    // Scattered breaks give sparse windows; the crack's plane, settled ones
    // (in 2D a window of 1.5 bond lengths never fills).
    CHECK(sparse > 50);
    CHECK(illPosed * 20 < sparse);
    CHECK(settled >= (flat ? 0u : 50u));
  }
}

TEST_CASE("normals found on one core and on all are the same to the last bit",
          "[analysis][incremental]") {
  // A viewer jumping from an early step to the last: the jump's breaks fill
  // several of add()'s blocks, and enter windows left sparse before it.
  const Run run = plantedRun(dem::LatticeKind::kFcc, dem::fccUnitCells(7, 6, 6), 0.05);
  const auto& lattice = run.block.lattice;
  const auto brokenAt = [&](std::size_t k) {
    const auto& state = run.steps[k].bondState;
    return static_cast<std::size_t>(
        std::count_if(state.begin(), state.end(), [](auto s) { return s != 0; }));
  };
  const std::size_t early = 2;
  REQUIRE(brokenAt(run.steps.size() - 1) - brokenAt(early) > BondNormals::kSearchBlock);
  auto normalsOn = [&](std::size_t cores) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, cores);
    BondNormals normals(3, 1.5);
    normals.update(lattice.bonds, run.steps[early].bondState, run.block.positions);
    const std::size_t before = normals.computed();
    normals.update(lattice.bonds, run.steps.back().bondState, run.block.positions);
    std::vector<dem::Vec3> out;
    for (std::size_t b = 0; b < lattice.bonds.size(); ++b) {
      out.push_back(normals.normal(b));
    }
    return std::tuple{out, before, normals.computed()};
  };
  const auto [one, oneBefore, oneComputed] = normalsOn(1);
  const auto [all, allBefore, allComputed] = normalsOn(4);
  // The jump found old windows again, not only its own breaks.
  CHECK(oneComputed - oneBefore > brokenAt(run.steps.size() - 1) - brokenAt(early));
  CHECK(oneComputed == allComputed);
  REQUIRE(one.size() == all.size());
  std::size_t differ = 0;
  for (std::size_t b = 0; b < one.size(); ++b) {
    differ += dem::norm(one[b] - all[b]) == 0.0 ? 0 : 1;
  }
  CHECK(differ == 0);
}

namespace {

// Every figure of a step's analysis, as numbers in a fixed order.
std::vector<double> figuresOf(const StepAnalysis& s) {
  const auto summary = [](const OpeningSummary& o) {
    return std::vector<double>{static_cast<double>(o.elements),
                               o.area,
                               o.meanOpening,
                               o.maxOpening,
                               o.meanSlip,
                               o.maxSlip};
  };
  std::vector<double> out{s.totalArea,
                          static_cast<double>(s.components),
                          s.mainArea,
                          s.mainBox.lo.x,
                          s.mainBox.lo.y,
                          s.mainBox.lo.z,
                          s.mainBox.hi.x,
                          s.mainBox.hi.y,
                          s.mainBox.hi.z,
                          static_cast<double>(s.fragments),
                          s.largestFragmentShare,
                          static_cast<double>(s.tension),
                          static_cast<double>(s.shear)};
  for (const OpeningSummary& o : {s.mainOpening, s.allOpening}) {
    const std::vector<double> part = summary(o);
    out.insert(out.end(), part.begin(), part.end());
  }
  return out;
}

}  // namespace

TEST_CASE("a run's analyses on one core and on four are the same to the last bit",
          "[analysis][incremental]") {
  // Enough scattered damage that the components' passes over the faces
  // (welding, areas and boxes) and the openings run in several blocks.
  const Run run = plantedRun(dem::LatticeKind::kFcc, dem::fccUnitCells(11, 10, 10), 0.12);
  const auto& lattice = run.block.lattice;
  const cracks::BondGraph graph(lattice.particleCount(), lattice.bonds);
  auto analyseOn = [&](std::size_t cores) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, cores);
    auto extractor = cracks::makeExtractor(cracks::Method::kLocalVoronoi, graph, 3);
    CrackAnalysis analysis(lattice, {});
    cracks::CrackMesh mesh;
    std::vector<double> figures;
    for (std::size_t k = 0; k < run.steps.size(); ++k) {
      const cracks::StepInput input = inputOf(run, run.steps[k]);
      REQUIRE(extractor->extract(input, mesh));
      const StepAnalysis step =
          analysis.analyse(static_cast<int>(k), 0.0, input, run.block.positions, mesh);
      // In several blocks, against the same figures found without the
      // tracker: the components, and each element's area and centroid.
      requireSameAreasAndPlanes(mesh, analysis.components(), cracks::findComponents(mesh));
      const ElementOpenings direct = measureOpening(mesh, analysis.components(), lattice.bonds,
                                                    run.block.positions, run.steps[k].positions);
      REQUIRE(direct.size() == analysis.openings().size());
      for (std::size_t e = 0; e < direct.size(); ++e) {
        REQUIRE(direct.area[e] == analysis.openings().area[e]);
        REQUIRE(dem::norm(direct.centroid[e] - analysis.openings().centroid[e]) == 0.0);
      }
      const std::vector<double> own = figuresOf(step);
      figures.insert(figures.end(), own.begin(), own.end());
    }
    const ElementOpenings& last = analysis.openings();
    for (std::size_t e = 0; e < last.size(); ++e) {
      figures.insert(figures.end(), {last.area[e], last.opening[e], last.slip[e],
                                     static_cast<double>(last.component[e])});
    }
    const MeanOrientation mean = meanOrientation(last, -1);
    figures.insert(figures.end(), {mean.normal.x, mean.normal.y, mean.normal.z, mean.strength});
    const Stereonet net = stereonet(last, -1, 20);
    figures.insert(figures.end(), net.weight.begin(), net.weight.end());
    return std::pair{figures, last.size()};
  };
  if (tbb::info::default_concurrency() < 2) {
    WARN("one core here: both runs below run on one thread");
  }
  const auto [one, elements] = analyseOn(1);
  const auto [all, allElements] = analyseOn(4);
  CHECK(elements > 3000);  // three blocks of the passes over the faces
  REQUIRE(elements == allElements);
  REQUIRE(one.size() == all.size());
  std::size_t differ = 0;
  for (std::size_t k = 0; k < one.size(); ++k) {
    // NaN (an element without a bond) equals itself here.
    differ += one[k] == all[k] || (std::isnan(one[k]) && std::isnan(all[k])) ? 0 : 1;
  }
  CHECK(differ == 0);
}

TEST_CASE("normals and break modes read from the new breaks equal those from all bond states",
          "[analysis][incremental]") {
  const Run run = plantedRun(dem::LatticeKind::kFcc, dem::fccUnitCells(5, 4, 4), 0.03);
  const auto& lattice = run.block.lattice;
  BondDiffer differ;
  BondNormals fromDiff(3);
  BondNormals fromStates(3);
  BreakModeTracker modesFromDiff;
  BreakModeTracker modesFromStates;
  std::vector<float> force(lattice.bonds.size());
  for (std::size_t k = 0; k < run.steps.size(); ++k) {
    const dem::StepState& state = run.steps[k];
    // A made-up force: compressive on every third bond, so the rule's
    // force branch is taken too.
    for (std::size_t b = 0; b < force.size(); ++b) {
      force[b] = static_cast<float>((b % 3 == 0 ? -1.0 : 1.0) * static_cast<double>(k + 1));
    }
    const BondDiff& diff = differ.update(state.bondState);
    fromDiff.update(lattice.bonds, diff, state.bondState, run.block.positions);
    fromStates.update(lattice.bonds, state.bondState, run.block.positions);
    modesFromDiff.update(static_cast<int>(k), lattice.bonds, diff, state.bondState,
                         run.block.positions, state.positions, force);
    modesFromStates.update(static_cast<int>(k), lattice.bonds, state.bondState, run.block.positions,
                           state.positions, force);
    CHECK(diff.broken ==
          static_cast<std::size_t>(std::count_if(state.bondState.begin(), state.bondState.end(),
                                                 [](auto s) { return s != 0; })));
  }
  std::size_t broken = 0;
  for (std::size_t b = 0; b < lattice.bonds.size(); ++b) {
    if (run.steps.back().bondState[b] != 0) {
      ++broken;
      CHECK(dem::norm(fromDiff.normal(b) - fromStates.normal(b)) == 0.0);
      CHECK(dem::norm(fromDiff.normal(b)) == Approx(1.0));
    }
  }
  CHECK(broken > 100);
  REQUIRE(modesFromDiff.breaks().size() == modesFromStates.breaks().size());
  CHECK(modesFromDiff.breaks().size() > 100);
  for (std::size_t k = 0; k < modesFromDiff.breaks().size(); ++k) {
    CHECK(modesFromDiff.breaks()[k].bond == modesFromStates.breaks()[k].bond);
    CHECK(modesFromDiff.breaks()[k].mode == modesFromStates.breaks()[k].mode);
  }
  CHECK(modesFromDiff.count(BreakMode::kShear) > 0);
  CHECK(modesFromDiff.count(BreakMode::kTension) > 0);
  CHECK(modesFromDiff.count(BreakMode::kShear) == modesFromStates.count(BreakMode::kShear));
}

TEST_CASE("the smallest eigenvector in closed form, and by rotations where that is inaccurate",
          "[analysis][incremental]") {
  // R diag(l0, l1, l2) R^T for a rotation R about a tilted axis.
  const auto rotated = [](std::array<double, 3> eigen) {
    const double c = std::cos(0.7);
    const double s = std::sin(0.7);
    const cracks::Matrix3 r{{{c, -s, 0.0}, {s * 0.6, c * 0.6, -0.8}, {s * 0.8, c * 0.8, 0.6}}};
    cracks::Matrix3 a{};
    for (std::size_t i = 0; i < 3; ++i) {
      for (std::size_t j = 0; j < 3; ++j) {
        for (std::size_t k = 0; k < 3; ++k) {
          a[i][j] += r[i][k] * eigen[k] * r[j][k];
        }
      }
    }
    return std::pair{a, dem::Vec3{r[0][0], r[1][0], r[2][0]}};  // the first column: eigen[0]'s
  };
  // A flat crack: one small eigenvalue far below the others.
  for (const double small : {0.0, 1e-9, 1e-3, 0.2}) {
    const auto [a, expected] = rotated({small, 1.0, 2.5});
    const dem::Vec3 v = cracks::smallestEigenvector(a);
    CHECK(std::abs(dem::dot(v, expected)) == Approx(1.0).epsilon(1e-10));
  }
  // Two equal small eigenvalues (a line-like component): any unit vector of
  // their plane, which is what the rotations give.
  const auto [a, expected] = rotated({1.0, 1.0, 3.0});
  const dem::Vec3 v = cracks::smallestEigenvector(a);
  CHECK(dem::norm(v) == Approx(1.0));
  const dem::Vec3 third{a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z,
                        a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
                        a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z};
  CHECK(dem::norm(third - v) == Approx(0.0).margin(1e-9));  // A v = 1 v
}
