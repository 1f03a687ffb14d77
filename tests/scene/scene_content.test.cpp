// What a scene draws, checked without GL: culling, damage, crack layers, the
// decomposition's edges and the bonds shown.
#include <algorithm>
#include <deque>

#include <catch2/catch.hpp>

#include "cracks/crack_fixtures.hpp"
#include <crackvis/dem/random_packing.hpp>
#include <crackvis/scene_model/scene_content.hpp>

using namespace crackvis;

namespace {

scene::SceneInput inputOf(const testing::PlantedCrack& crack) {
  scene::SceneInput input;
  input.lattice = &crack.block.lattice;
  input.step = crack.input();
  return input;
}

// Bond hops from each particle to the nearest one on the boundary (fewer
// bonds than the most) or at a broken bond.
std::vector<int> hopsToSurface(const testing::PlantedCrack& crack) {
  const auto& bonds = crack.block.lattice.bonds;
  const std::size_t n = crack.block.positions.size();
  std::vector<std::vector<std::size_t>> neighbours(n);
  for (const dem::Bond& bond : bonds) {
    neighbours[static_cast<std::size_t>(bond.first)].push_back(
        static_cast<std::size_t>(bond.second));
    neighbours[static_cast<std::size_t>(bond.second)].push_back(
        static_cast<std::size_t>(bond.first));
  }
  std::size_t most = 0;
  for (const auto& list : neighbours) {
    most = std::max(most, list.size());
  }
  std::vector<int> hops(n, -1);
  std::deque<std::size_t> queue;
  for (std::size_t i = 0; i < n; ++i) {
    if (neighbours[i].size() < most) {
      hops[i] = 0;
      queue.push_back(i);
    }
  }
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    for (auto end : {bonds[b].first, bonds[b].second}) {
      const auto i = static_cast<std::size_t>(end);
      if (crack.state[b] != 0 && hops[i] != 0) {
        hops[i] = 0;
        queue.push_back(i);
      }
    }
  }
  while (!queue.empty()) {
    const std::size_t i = queue.front();
    queue.pop_front();
    for (std::size_t j : neighbours[i]) {
      if (hops[j] < 0) {
        hops[j] = hops[i] + 1;
        queue.push_back(j);
      }
    }
  }
  return hops;
}

}  // namespace

TEST_CASE("culling keeps the particles within two bonds of the surface or a crack",
          "[scene][culling]") {
  const auto crack = testing::fccPlaneCrack(9, {1, 0, 0}, 0.5 + 8.5 / std::sqrt(2.0));
  REQUIRE(crack.brokenCount() > 0);
  const auto input = inputOf(crack);
  pipeline::ParticlesDescription particles;
  const auto visible = scene::visibleParticles(particles, input);
  const std::vector<int> hops = hopsToSurface(crack);
  std::vector<dem::ParticleIndex> expected;
  for (std::size_t i = 0; i < hops.size(); ++i) {
    if (hops[i] >= 0 && hops[i] <= 2) {
      expected.push_back(static_cast<dem::ParticleIndex>(i));
    }
  }
  CHECK(visible == expected);
  // The block has an interior: a good share is culled.
  const std::size_t n = crack.block.positions.size();
  INFO(visible.size() << " of " << n << " particles visible");
  CHECK(n - visible.size() > n / 10);

  SECTION("translucent or clipped particles are all drawn") {
    particles.opacity = 0.5;
    CHECK(scene::visibleParticles(particles, input).size() == n);
    particles.opacity = 1.0;
    particles.clip = pipeline::ClipPlane{{0, 0, 0}, {1, 0, 0}};
    CHECK(scene::visibleParticles(particles, input).size() == n);
  }
}

TEST_CASE("damage is the share of a particle's bonds that are broken", "[scene]") {
  // A (100) plane between two atomic layers of FCC cuts 4 of the 12 bonds of
  // each particle beside it.
  const auto crack = testing::fccPlaneCrack(5, {1, 0, 0}, 0.5 + 4.5 / std::sqrt(2.0));
  pipeline::ParticlesDescription particles;
  particles.colourBy = pipeline::ParticleColourBy::kDamage;
  const auto values = scene::particleValues(particles, inputOf(crack));
  REQUIRE(values.size() == crack.block.positions.size());
  std::vector<int> degree(values.size(), 0);
  for (const dem::Bond& bond : crack.block.lattice.bonds) {
    ++degree[static_cast<std::size_t>(bond.first)];
    ++degree[static_cast<std::size_t>(bond.second)];
  }
  int beside = 0;
  int intact = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    CHECK(values[i] >= 0.0);
    CHECK(values[i] <= 1.0);
    if (degree[i] == 12) {
      CHECK((values[i] == 0.0 || values[i] == Approx(1.0 / 3.0)));
      (values[i] > 0.0 ? beside : intact) += 1;
    }
  }
  CHECK(beside > 0);
  CHECK(intact > 0);
  particles.colourBy = pipeline::ParticleColourBy::kSolid;
  const auto solid = scene::particleValues(particles, inputOf(crack));
  CHECK(std::all_of(solid.begin(), solid.end(), [](double v) { return v == 0.0; }));
}

TEST_CASE("crack primitives go into the layer the description shows them in", "[scene]") {
  cracks::CrackMesh mesh;
  mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  mesh.vertices = {3};
  mesh.lines.add({0, 1});
  for (int k = 0; k < 4; ++k) {
    mesh.polygons.add({0, 1, 2});
  }
  // Primitive k: the vertex, the line, then the four polygons.
  mesh.cellData.push_back({"bond_id", cracks::AttributeType::kInt32, 1, {10, 11, 12, 13, 14, 15}});
  mesh.cellData.push_back({"bond_state", cracks::AttributeType::kInt32, 1, {1, 0, 1, 0, 1, 0}});
  mesh.cellData.push_back({"inconsistent", cracks::AttributeType::kInt32, 1, {0, 0, 0, 0, 1, 0}});
  auto ids = [](const cracks::CrackMesh& m) { return m.findCellData("bond_id")->values; };

  pipeline::PipelineDescription d;
  auto layers = scene::crackLayers(d, mesh);
  CHECK(ids(layers.cracks) == std::vector<double>{10, 12});
  CHECK(layers.cracks.vertices == std::vector<std::int32_t>{3});
  CHECK(layers.cracks.lines.size() == 0);
  CHECK(layers.cracks.polygons.size() == 1);
  CHECK(layers.cracks.points == mesh.points);
  CHECK(layers.marks.primitiveCount() == 0);
  CHECK(layers.intact.primitiveCount() == 0);

  d.showInconsistent = true;
  d.showDecomposition = true;
  layers = scene::crackLayers(d, mesh);
  CHECK(ids(layers.marks) == std::vector<double>{14});
  CHECK(ids(layers.intact) == std::vector<double>{11, 13, 15});
  CHECK(layers.intact.lines.size() == 1);
  CHECK(layers.intact.polygons.size() == 2);
}

TEST_CASE("the decomposition's edges and the bonds shown", "[scene]") {
  const auto crack = testing::fccPlaneCrack(5, {1, 0, 0}, 0.5 + 4.5 / std::sqrt(2.0));
  auto input = inputOf(crack);
  CHECK(scene::decompositionBonds(input).empty());
  auto extractor = cracks::makeExtractor(cracks::Method::kCellCut, *crack.graph, 3);
  cracks::CrackMesh mesh;
  REQUIRE(extractor->extract(crack.input(), mesh));
  input.decomposition = extractor->decomposition();
  REQUIRE(input.decomposition != nullptr);
  const auto edges = scene::decompositionBonds(input);
  CHECK(std::is_sorted(edges.begin(), edges.end()));
  CHECK(std::adjacent_find(edges.begin(), edges.end()) == edges.end());
  // The cells around the crack: its broken bonds are among their edges.
  std::vector<dem::BondIndex> broken;
  for (std::size_t b = 0; b < crack.state.size(); ++b) {
    if (crack.state[b] != 0) {
      broken.push_back(static_cast<dem::BondIndex>(b));
    }
  }
  CHECK(std::includes(edges.begin(), edges.end(), broken.begin(), broken.end()));
  CHECK(edges.size() > broken.size());
  CHECK(edges.size() < crack.state.size());

  pipeline::BondsDescription bonds;
  CHECK(scene::bondLines(bonds, input).bonds.empty());  // kNone
  bonds.show = pipeline::BondSelection::kBroken;
  auto shown = scene::bondLines(bonds, input);
  CHECK(shown.bonds == broken);
  CHECK(std::all_of(shown.values.begin(), shown.values.end(), [](double v) { return v == 1.0; }));
  bonds.show = pipeline::BondSelection::kAll;
  bonds.colourBy = pipeline::BondColourBy::kForce;
  std::vector<float> force(crack.state.size());
  for (std::size_t b = 0; b < force.size(); ++b) {
    force[b] = static_cast<float>(b) * 0.5f;
  }
  input.step.bondForce = force;
  shown = scene::bondLines(bonds, input);
  REQUIRE(shown.bonds.size() == crack.state.size());
  CHECK(shown.values[7] == 3.5);
}

TEST_CASE("a triangulated packing's decomposition edges include its never-bonded pairs",
          "[scene]") {
  dem::RandomPackingSpec spec;
  spec.box = {0.006, 0.004, 0.004};
  spec.radiusMin = 3e-4;
  spec.radiusMax = 3e-4;
  auto packing = dem::generateRandomPacking(spec);
  REQUIRE(packing);
  const cracks::BondGraph graph(packing->lattice.particleCount(), packing->lattice.bonds);
  const auto state = testing::bondsAcross(packing->lattice.bonds, packing->positions, 0.003);
  auto extractor = cracks::makeExtractor(cracks::Method::kCellCut, graph, 3);
  cracks::CrackMesh mesh;
  const cracks::StepInput step{
      packing->positions, state, packing->lattice.radius, {}, {}, {}, {}, {}};
  REQUIRE(extractor->extract(step, mesh));
  scene::SceneInput input;
  input.lattice = &packing->lattice;
  input.step = step;
  input.decomposition = extractor->decomposition();
  REQUIRE(input.decomposition != nullptr);
  const auto edges = scene::decompositionBonds(input);
  REQUIRE(!edges.empty());
  // Indices into the decomposition's graph, some beyond the file's bonds:
  // the renderer draws them through that graph, never through the lattice.
  const auto total = static_cast<dem::BondIndex>(input.decomposition->graph().bondCount());
  const auto fileBonds = static_cast<dem::BondIndex>(packing->lattice.bondCount());
  CHECK(edges.back() < total);
  CHECK(edges.back() >= fileBonds);
}

TEST_CASE("legend labels are round numbers written for their quantity", "[scene][legend]") {
  // Break steps 0..199: whole numbers, no "199." nor "-0".
  auto steps = scene::legendTicks({0, 199}, true, 5);
  CHECK(steps.values == std::vector<double>{0, 50, 100, 150});
  for (double v : steps.values) {
    const std::string label = scene::formatTick(steps, v);
    CHECK(label.find('.') == std::string::npos);
    CHECK(label.find('e') == std::string::npos);
    CHECK(label.front() != '-');
  }
  // A narrow integral range gets steps of one, not fractions.
  CHECK(scene::legendTicks({0, 3}, true, 6).values == std::vector<double>{0, 1, 2, 3});
  // Displacements in metres: every tick distinct, exact, no exponent, no trailing point.
  auto metres = scene::legendTicks({0, 2.6e-4}, false, 4);
  CHECK(metres.values == std::vector<double>{0, 1e-4, 2e-4});
  std::vector<std::string> labels;
  for (double v : metres.values) {
    labels.push_back(scene::formatTick(metres, v));
  }
  CHECK(labels == std::vector<std::string>{"0", "0.0001", "0.0002"});
  // Forces of tens of newtons: "-20", not "-2e+01".
  auto force = scene::legendTicks({-28.3, 0.4}, false, 4);
  labels.clear();
  for (double v : force.values) {
    labels.push_back(scene::formatTick(force, v));
  }
  CHECK(labels == std::vector<std::string>{"-20", "-10", "0"});
  auto fine = scene::legendTicks({0.1, 0.35}, false, 6);
  labels.clear();
  for (double v : fine.values) {
    labels.push_back(scene::formatTick(fine, v));
  }
  CHECK(labels == std::vector<std::string>{"0.1", "0.15", "0.2", "0.25", "0.3", "0.35"});
}

TEST_CASE("legend titles wrap at spaces to stay within the strip", "[scene][legend]") {
  CHECK(scene::wrapTitle("particles: damage (broken bond share)", 20) ==
        "particles: damage\n(broken bond share)");
  CHECK(scene::wrapTitle("crack: break step", 40) == "crack: break step");
  // A word longer than a line stands alone; spaces do not pile up.
  CHECK(scene::wrapTitle("a  verylongwordindeed b", 6) == "a\nverylongwordindeed\nb");
  for (const std::string& line : {std::string("particles: damage"), std::string("(broken")}) {
    CHECK(line.size() <= 20);
  }
}

TEST_CASE("the length scale bar is a round length in metres", "[scene][legend]") {
  auto bar = scene::scaleBar(0.2e-3, 300);  // 0.2 mm per pixel, at most 300 px: 60 mm
  CHECK(bar.metres == Approx(0.05));
  CHECK(bar.pixels == Approx(250));
  CHECK(bar.label == "50 mm");
  CHECK(scene::scaleBar(1e-6, 150).label == "100 µm");
  CHECK(scene::scaleBar(0.01, 250).label == "2 m");
  CHECK(scene::scaleBar(0.0, 250).pixels == 0.0);
}

TEST_CASE("annotations name the step, its time and the crack method", "[scene][legend]") {
  const auto crack = testing::fccPlaneCrack(3, {1, 0, 0}, 0.5 + 2.5 / std::sqrt(2.0));
  auto input = inputOf(crack);
  CHECK(scene::stepAnnotation(input).empty());  // no step known
  input.stepIndex = 120;
  input.stepCount = 200;
  input.time = 1.25e-3;
  CHECK(scene::stepAnnotation(input) == "step 120 of 0..199   t = 0.00125 s");
  // A file whose code wrote no time (time_unit "iteration"): no seconds.
  input.time = 18950;
  input.timeInIterations = true;
  CHECK(scene::stepAnnotation(input) == "step 120 of 0..199   iteration 18950");
  pipeline::CracksDescription cracks;
  CHECK(scene::methodAnnotation(cracks) == "cracks: local Voronoi, validated (tolerance 0.1)");
  cracks.method = cracks::Method::kCellCentre;
  cracks.mergeOctahedra = true;
  CHECK(scene::methodAnnotation(cracks) == "cracks: cell centre, octahedra merged");
  cracks.visible = false;
  CHECK(scene::methodAnnotation(cracks).empty());
}

TEST_CASE("legend titles carry units, cell attribute has its own quantities", "[scene][legend]") {
  pipeline::ParticlesDescription particles;
  particles.colourBy = pipeline::ParticleColourBy::kVelocity;
  CHECK(scene::particleQuantity(particles).title == "velocity [m/s]");
  CHECK_FALSE(scene::particleQuantity(particles).integral);
  CHECK(scene::crackQuantity(pipeline::CrackColourBy::kBreakStep).integral);
  CHECK(scene::crackQuantity(pipeline::CrackColourBy::kForce).title == "bond force [N]");
  CHECK(std::string(scene::crackArrayName(pipeline::CrackColourBy::kState,
                                          cracks::Method::kCellAttribute)) == "broken_bonds");
  CHECK(std::string(scene::crackArrayName(pipeline::CrackColourBy::kBondId,
                                          cracks::Method::kCellAttribute)) == "first_broken_bond");
  CHECK(scene::crackArrayName(pipeline::CrackColourBy::kSolid) == nullptr);
}

TEST_CASE("colour ranges: the step's, the series', or the user's", "[scene][legend]") {
  pipeline::ColourRange range;
  const scene::ValueRange values{2, 5};
  const std::optional<scene::ValueRange> series = scene::ValueRange{0, 9};
  CHECK(scene::colourRange(range, series, values) == values);
  range.mode = pipeline::RangeMode::kSeries;
  CHECK(scene::colourRange(range, series, values) == *series);
  CHECK(scene::colourRange(range, std::nullopt, values) == values);  // not scanned: the step's
  range = {pipeline::RangeMode::kUser, -1, 1};
  CHECK(scene::colourRange(range, series, values) == scene::ValueRange{-1, 1});
  // One value only: a unit wide, not a zero-width (NaN-making) range.
  CHECK(scene::colourRange({}, std::nullopt, {3, 3}) == scene::ValueRange{3, 4});
}

TEST_CASE("thresholds keep the particles, crack faces and bonds within them", "[scene]") {
  const auto crack = testing::fccPlaneCrack(5, {1, 0, 0}, 0.5 + 4.5 / std::sqrt(2.0));
  auto input = inputOf(crack);
  // Particles: damage > 0 keeps exactly the particles beside the crack.
  pipeline::ParticlesDescription particles;
  particles.threshold = pipeline::Threshold<pipeline::ParticleColourBy>{
      pipeline::ParticleColourBy::kDamage, "", 0.01};
  const auto damage = scene::particleValues(pipeline::ParticleColourBy::kDamage, input);
  const auto kept = scene::visibleParticles(particles, input);
  const auto damaged = std::count_if(damage.begin(), damage.end(), [](double v) { return v > 0; });
  CHECK(static_cast<long>(kept.size()) == damaged);
  CHECK(damaged > 0);
  for (auto p : kept) {
    CHECK(damage[static_cast<std::size_t>(p)] > 0.0);
  }
  // Crack faces by bond id.
  cracks::CrackMesh mesh;
  mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int k = 0; k < 4; ++k) {
    mesh.polygons.add({0, 1, 2});
  }
  mesh.cellData.push_back({"bond_id", cracks::AttributeType::kInt32, 1, {10, 11, 12, 13}});
  pipeline::PipelineDescription d;
  d.cracks.threshold =
      pipeline::Threshold<pipeline::CrackColourBy>{pipeline::CrackColourBy::kBondId, "", 11, 12};
  CHECK(scene::crackLayers(d, mesh).cracks.findCellData("bond_id")->values ==
        std::vector<double>{11, 12});
  // Bonds by force.
  pipeline::BondsDescription bonds;
  bonds.show = pipeline::BondSelection::kAll;
  std::vector<float> force(crack.state.size());
  for (std::size_t b = 0; b < force.size(); ++b) {
    force[b] = static_cast<float>(b);
  }
  input.step.bondForce = force;
  bonds.threshold =
      pipeline::Threshold<pipeline::BondColourBy>{pipeline::BondColourBy::kForce, "", 5, 9};
  CHECK(scene::bondLines(bonds, input).bonds == std::vector<dem::BondIndex>{5, 6, 7, 8, 9});
}
