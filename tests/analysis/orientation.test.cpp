// Orientation of crack normals (rose diagram, equal-area net, mean) and the
// mode each bond broke in, on cases whose answers geometry gives.
#include <cmath>
#include <numbers>

#include "analysis_fixtures.hpp"

using namespace crackvis;
using namespace crackvis::analysis;

namespace {

// Elements with the given unit normals and areas, one component.
ElementOpenings elements(const std::vector<std::pair<Vec3, double>>& normals) {
  ElementOpenings out;
  for (const auto& [n, area] : normals) {
    out.area.push_back(area);
    out.centroid.push_back({});
    out.normal.push_back(n);
    out.opening.push_back(0.0);
    out.slip.push_back(0.0);
    out.component.push_back(0);
  }
  return out;
}

Vec3 degrees2D(double degrees) {
  const double a = degrees * std::numbers::pi / 180.0;
  return {std::cos(a), std::sin(a), 0.0};
}

}  // namespace

TEST_CASE("a rose diagram bins axial 2D normals by angle, weighted by length",
          "[analysis][orientation]") {
  // 35 and 215 degrees are one orientation; 125 another.
  const ElementOpenings e =
      elements({{degrees2D(35), 1.0}, {degrees2D(215), 2.0}, {degrees2D(125), 4.0}});
  const RoseDiagram rose = roseDiagram(e, -1, 18);  // 10 degree bins
  REQUIRE(rose.weight.size() == 18);
  CHECK(rose.binDegrees() == Approx(10.0));
  CHECK(rose.weight[3] == Approx(3.0));
  CHECK(rose.weight[12] == Approx(4.0));
  double total = 0.0;
  for (double w : rose.weight) {
    total += w;
  }
  CHECK(total == Approx(7.0));
  const MeanOrientation mean = meanOrientation(e, -1);
  CHECK(std::abs(dem::dot(mean.normal, degrees2D(125))) == Approx(1.0).epsilon(0.05));
}

TEST_CASE("the equal-area net: poles land where Lambert's projection puts them",
          "[analysis][orientation]") {
  const auto at = [](Vec3 n) { return equalAreaPoint((1.0 / dem::norm(n)) * n); };
  CHECK(at({0, 0, -1})[0] == Approx(0.0));
  CHECK(at({0, 0, 1})[1] == Approx(0.0));  // the upper pole is the lower one
  CHECK(at({1, 0, 0})[0] == Approx(1.0));
  CHECK(at({0, 1, 0})[1] == Approx(1.0));
  // Dip 45 degrees: r = sqrt(1 - cos 45) = 0.5412
  const auto dipping = at({std::sqrt(0.5), 0, -std::sqrt(0.5)});
  CHECK(dipping[0] == Approx(std::sqrt(1.0 - std::sqrt(0.5))));
  // n and -n fall on one point.
  const auto up = at({0.3, -0.4, 0.5});
  const auto down = at({-0.3, 0.4, -0.5});
  CHECK(up[0] == Approx(down[0]));
  CHECK(up[1] == Approx(down[1]));

  const ElementOpenings e = elements({{{0, 0, -1}, 2.0}, {{0, 0, 1}, 1.0}, {{1, 0, 0}, 5.0}});
  const Stereonet net = stereonet(e, -1, 10);
  CHECK(net.weight[5 * 10 + 5] == Approx(3.0));  // the centre cell (0, 0)
  CHECK(net.weight[5 * 10 + 9] == Approx(5.0));  // the rim at (1, 0)
}

TEST_CASE("a planted crack's normals all point across its plane", "[analysis][orientation]") {
  const auto specimen = testing::movedHalf(dem::LatticeKind::kFcc, dem::fccUnitCells(4, 4, 4),
                                           {0.3, 0, 0}, cracks::Method::kLocalVoronoi);
  const CrackComponents components = cracks::findComponents(specimen.mesh);
  const ElementOpenings openings =
      measureOpening(specimen.mesh, components, specimen.block.lattice.bonds,
                     specimen.block.positions, specimen.positions);
  const MeanOrientation mean = meanOrientation(openings, 0);
  CHECK(std::abs(mean.normal.x) == Approx(1.0).epsilon(1e-3));
  CHECK(mean.strength > 0.99);
  const Stereonet net = stereonet(openings, 0, 20);
  const double total = summariseOpening(openings, 0).area;
  // (+-1, 0): the rim cells of row 10 at either end.
  CHECK(net.weight[10 * 20 + 19] + net.weight[10 * 20 + 0] + net.weight[9 * 20 + 19] +
            net.weight[9 * 20 + 0] >
        0.98 * total);
}

TEST_CASE("break modes: tension when the bond lengthened, shear when it slid or was compressed",
          "[analysis][modes]") {
  const Vec3 d0{1, 0, 0};
  CHECK(classifyBreak(d0, {1.2, 0, 0}, std::nullopt).mode == BreakMode::kTension);
  CHECK(classifyBreak(d0, {0.9, 0, 0}, std::nullopt).mode == BreakMode::kShear);
  // Slid sideways by 1 %: longer only to second order (5e-5), shear.
  const BondBreak slid = classifyBreak(d0, {1.0, 0.01, 0}, std::nullopt);
  CHECK(slid.mode == BreakMode::kShear);
  CHECK(slid.stretch == Approx(0.5 * 0.01 * 0.01).epsilon(1e-3));
  CHECK(slid.shear == Approx(0.01));
  // Stretched and slid: tension once the stretch passes a twentieth of the slide.
  CHECK(classifyBreak(d0, {1.006, 0.1, 0}, std::nullopt).mode == BreakMode::kTension);
  CHECK(classifyBreak(d0, {0.996, 0.1, 0}, std::nullopt).mode == BreakMode::kShear);
  // A rigid rotation of the pair is no stretch: shear, not tension.
  const double turn = 0.3;
  const Vec3 rotated{std::cos(turn) * 1.001, std::sin(turn) * 1.001, 0};
  CHECK(classifyBreak(d0, rotated, std::nullopt).stretch == Approx(0.001));
  // Stretched, but the last force seen was compressive: shear.
  CHECK(classifyBreak(d0, {1.2, 0, 0}, -3.0).mode == BreakMode::kShear);
  CHECK(classifyBreak(d0, {1.2, 0, 0}, 2.0).mode == BreakMode::kTension);

  // The tracker decides each bond the step it first appears broken.
  const std::vector<dem::Bond> bonds{{0, 1}, {1, 2}, {2, 3}};
  const std::vector<Vec3> reference{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  BreakModeTracker tracker;
  std::vector<Vec3> now = reference;
  tracker.update(0, bonds, std::vector<std::uint8_t>{1, 0, 0}, reference, now, {});
  CHECK(tracker.breaks().empty());  // broken before the run
  now[2] = {2.5, 0, 0};
  now[3] = {3.5, 0, 0};
  tracker.update(1, bonds, std::vector<std::uint8_t>{1, 1, 0}, reference, now, {});
  now[3] = {3.5, 0.02, 0};
  tracker.update(2, bonds, std::vector<std::uint8_t>{1, 1, 1}, reference, now, {});
  REQUIRE(tracker.breaks().size() == 2);
  CHECK(tracker.breaks()[0].bond == 1);
  CHECK(tracker.breaks()[0].mode == BreakMode::kTension);
  CHECK(tracker.breaks()[1].bond == 2);
  CHECK(tracker.breaks()[1].step == 2);
  CHECK(tracker.breaks()[1].mode == BreakMode::kShear);
  CHECK(tracker.countUpTo(BreakMode::kShear, 1) == 0);
}
