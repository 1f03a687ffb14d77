// Crack opening and slip on planted cracks whose halves move apart, or slide
// past each other, by a known vector.
#include <cmath>

#include "analysis_fixtures.hpp"

using namespace crackvis;
using namespace crackvis::analysis;

namespace {

ElementOpenings openingsOf(const testing::MovedHalf& specimen, CrackComponents& components) {
  components = cracks::findComponents(specimen.mesh);
  return measureOpening(specimen.mesh, components, specimen.block.lattice.bonds,
                        specimen.block.positions, specimen.positions);
}

}  // namespace

TEST_CASE("a planted crack opened by a known amount reads that opening within 1 %",
          "[analysis][opening]") {
  const double shift = 0.37;  // of a bond length of 1
  using Kind = dem::LatticeKind;
  struct Case {
    Kind kind;
    std::array<int, 3> sites;
    cracks::Method method;
  };
  const Case cases[] = {
      {Kind::kFcc, dem::fccUnitCells(4, 4, 4), cracks::Method::kLocalVoronoi},
      {Kind::kFcc, dem::fccUnitCells(4, 4, 4), cracks::Method::kCellCentre},
      {Kind::kFcc, dem::fccUnitCells(4, 4, 4), cracks::Method::kCellCut},
      {Kind::kTriangular, {24, 24, 1}, cracks::Method::kLocalVoronoi},
  };
  for (const Case& c : cases) {
    INFO(cracks::toString(c.method) << (c.kind == Kind::kTriangular ? " 2D" : " 3D"));
    const auto specimen = testing::movedHalf(c.kind, c.sites, {shift, 0, 0}, c.method);
    CrackComponents components;
    const ElementOpenings openings = openingsOf(specimen, components);
    REQUIRE(openings.size() > 0);
    const OpeningSummary main = summariseOpening(openings, 0);
    REQUIRE(main.elements > 0);
    CHECK(main.meanOpening == Approx(shift).epsilon(0.01));
    CHECK(main.maxOpening == Approx(shift).epsilon(0.05));
    CHECK(main.meanSlip < 0.01 * shift);
    // The cell data the renderer colours by carries the same numbers.
    cracks::CrackMesh coloured = specimen.mesh;
    appendOpeningArrays(coloured, openings);
    const cracks::AttributeArray* opening = coloured.findCellData("opening");
    REQUIRE(opening != nullptr);
    REQUIRE(opening->values.size() == coloured.primitiveCount());
    double sum = 0.0;
    std::size_t counted = 0;
    for (double v : opening->values) {
      if (!std::isnan(v)) {
        sum += v;
        ++counted;
      }
    }
    REQUIRE(counted > 0);
    CHECK(sum / static_cast<double>(counted) == Approx(shift).epsilon(0.05));
  }
}

TEST_CASE("a planted crack whose halves slide past each other reads slip, not opening",
          "[analysis][opening]") {
  const double shift = 0.25;
  for (const auto method : {cracks::Method::kLocalVoronoi, cracks::Method::kCellCentre}) {
    INFO(cracks::toString(method));
    const auto specimen = testing::movedHalf(dem::LatticeKind::kFcc, dem::fccUnitCells(4, 4, 4),
                                             {0, 0, shift}, method);
    CrackComponents components;
    const ElementOpenings openings = openingsOf(specimen, components);
    const OpeningSummary main = summariseOpening(openings, 0);
    REQUIRE(main.elements > 0);
    CHECK(std::abs(main.meanOpening) < 0.01 * shift);
    CHECK(main.meanSlip == Approx(shift).epsilon(0.01));
  }
}

TEST_CASE("opening statistics: histogram by area, profile along the crack, no bond no opening",
          "[analysis][opening]") {
  const double shift = 0.5;
  const auto specimen = testing::movedHalf(dem::LatticeKind::kFcc, dem::fccUnitCells(4, 4, 4),
                                           {shift, 0, 0}, cracks::Method::kLocalVoronoi);
  CrackComponents components;
  const ElementOpenings openings = openingsOf(specimen, components);
  const OpeningSummary main = summariseOpening(openings, 0);
  const Histogram histogram = openingHistogram(openings, 0, 0.0, 1.05, 10);
  double total = 0.0;
  for (double w : histogram.weight) {
    total += w;
  }
  CHECK(total == Approx(main.area));
  CHECK(histogram.weight[4] > 0.9 * total);  // [0.42, 0.525) holds the opening 0.5
  const Vec3 axis = longestAxis(openings, 0, components.components[0].normal);
  CHECK(std::abs(axis.x) < 1e-6);  // in the plane x = cut
  const std::vector<ProfileBin> profile = openingProfile(openings, 0, axis, 8);
  REQUIRE(profile.size() == 8);
  for (const ProfileBin& bin : profile) {
    CHECK(bin.opening == Approx(shift).epsilon(0.03));
  }

  // Cell attribute's cells carry no bond: there is no opening to report.
  const auto cells = testing::movedHalf(dem::LatticeKind::kFcc, dem::fccUnitCells(3, 3, 3),
                                        {shift, 0, 0}, cracks::Method::kCellAttribute);
  CrackComponents cellComponents;
  const ElementOpenings none = openingsOf(cells, cellComponents);
  CHECK(summariseOpening(none, -1).elements == 0);
}

TEST_CASE("an element without a bond has its face's unit normal and no opening",
          "[analysis][opening]") {
  auto specimen = testing::movedHalf(dem::LatticeKind::kFcc, dem::fccUnitCells(3, 3, 3),
                                     {0.4, 0, 0}, cracks::Method::kLocalVoronoi);
  // The faces without their bonds: each keeps its own plane (the cut is
  // x = const, so every face's normal has some x) at unit length, whatever
  // its area (a face's Newell vector is as long as its area).
  auto& cells = specimen.mesh.cellData;
  std::erase_if(cells, [](const cracks::AttributeArray& a) { return a.name == "bond_id"; });
  CrackComponents components;
  const ElementOpenings openings = openingsOf(specimen, components);
  REQUIRE(openings.size() > 0);
  std::size_t notUnit = 0;
  std::size_t withOpening = 0;
  for (std::size_t e = 0; e < openings.size(); ++e) {
    notUnit += std::abs(dem::norm(openings.normal[e]) - 1.0) < 1e-12 ? 0 : 1;
    withOpening += std::isnan(openings.opening[e]) ? 0 : 1;
  }
  CHECK(notUnit == 0);
  CHECK(withOpening == 0);
  CHECK(openings.area[0] != Approx(1.0));  // so a length of 1 is no face's area by chance
}

TEST_CASE("per-component opening summaries in one pass equal each component's own",
          "[analysis][opening]") {
  // Elements of components 2, 0, 1, 0, none and 2, one without a bond.
  ElementOpenings openings;
  openings.area = {1.0, 2.0, 3.0, 1.0, 5.0, 3.0, 2.0};
  openings.opening = {0.1, 0.4, 0.2, 0.0, 0.9, 0.3, std::nan("")};
  openings.slip = {0.01, 0.02, 0.0, 0.05, 0.1, 0.03, std::nan("")};
  openings.component = {2, 0, 1, 0, -1, 2, 1};
  const auto all = summariseByComponent(openings, 3);
  REQUIRE(all.size() == 3);
  for (int c = 0; c < 3; ++c) {
    INFO("component " << c);
    const OpeningSummary one = summariseOpening(openings, c);
    const OpeningSummary& together = all[static_cast<std::size_t>(c)];
    CHECK(together.elements == one.elements);
    CHECK(together.area == one.area);
    CHECK(together.meanOpening == one.meanOpening);
    CHECK(together.maxOpening == one.maxOpening);
    CHECK(together.meanSlip == one.meanSlip);
    CHECK(together.maxSlip == one.maxSlip);
  }
  // Component 0 by hand: areas 2 and 1, openings 0.4 and 0.0.
  CHECK(all[0].meanOpening == Approx(0.8 / 3.0));
  CHECK(all[0].maxSlip == 0.05);
  CHECK(all[1].elements == 1);  // the element without a bond is not counted
}
