// Which way cracks run, and how bonds broke.
//
// Orientation: the distribution of the crack's local normals (the smoothed
// normals of opening.hpp: a lattice's single-bond faces zig-zag around the
// crack, and their own normals would show the lattice, not the crack),
// weighted by element area. Normals are axial (n and -n are one
// orientation):
//  - 2D: a rose diagram of the normal's angle from +x, in [0, 180) degrees;
//  - 3D: a lower-hemisphere Lambert equal-area (Schmidt) projection of the
//    poles, x = sqrt(1 + n_z) n_x / |n_xy| (same for y) with n_z <= 0, on a
//    square grid over [-1, 1]^2; equal areas of the sphere map to equal
//    areas of the disc, so a grid cell's weight is a density.
//
// Mode of a broken bond, at the first step it is seen broken: its stretch
// s = |d| - |d0| (how much longer it is than in the reference; free of any
// rigid rotation of the pair) and its sideways jump t = |j - (j . a) a|,
// with j = d - d0 and a = d0 / |d0|. Tension when s > 0.05 t: the bond
// lengthened, by more than a twentieth of its sideways jump (a bond normal
// to a slide lengthens only to second order, s = t^2 / 2|d0|, and counts as
// shear). Where the file has bond forces (the normal force, positive in
// tension) and the bond was in compression at the last step it was seen
// intact, it broke in shear: a bond cannot fail in tension under
// compression. On Yade's JCFpm notched bar (tests/data/yade) the rule
// agrees with the code's own crack file bond for bond (docs/methods.md);
// a rule on the angle of j alone (tension within 45 degrees of the bond)
// called 15 of its 27 tensile breaks shear: the pairs rotate as the bar
// bends before they break.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <vector>

#include <crackvis/analysis/bond_diff.hpp>
#include <crackvis/analysis/opening.hpp>

namespace crackvis::analysis {

struct RoseDiagram {
  std::vector<double> weight;  // bin k: angles [k, k + 1) * 180 / bins degrees
  double binDegrees() const {
    return weight.empty() ? 0.0 : 180.0 / static_cast<double>(weight.size());
  }
};
RoseDiagram roseDiagram(const ElementOpenings& elements, int component, int bins);

struct Stereonet {
  int size = 0;                // cells per side over [-1, 1]
  std::vector<double> weight;  // [row y][column x], size * size
  double cellCentre(int k) const { return -1.0 + (k + 0.5) * 2.0 / size; }
};
// The projected point of an axial unit direction (lower hemisphere).
std::array<double, 2> equalAreaPoint(Vec3 n);
Stereonet stereonet(const ElementOpenings& elements, int component, int size);

// The area-weighted mean orientation (principal axis of sum(area n n^T)),
// with z <= 0 in 3D and y >= 0 in 2D, and its strength: the principal
// eigenvalue's share of the trace (1: all parallel).
struct MeanOrientation {
  Vec3 normal;
  double strength = 0.0;
};
MeanOrientation meanOrientation(const ElementOpenings& elements, int component);

enum class BreakMode : std::uint8_t { kTension, kShear };
// Tension: stretch > kTensionShare * sideways jump (see above).
inline constexpr double kTensionShare = 0.05;
const char* toString(BreakMode mode);

struct BondBreak {
  std::int32_t bond = -1;
  int step = 0;
  BreakMode mode = BreakMode::kTension;  // the mode counted: the recorded one, else the rule's
  BreakMode rule = BreakMode::kTension;  // what the rule above says
  bool recorded = false;                 // whether `mode` is the code's own record
  double stretch = 0.0;                  // |d| - |d0|, m
  double shear = 0.0;                    // sideways jump, m
};

// The per-bond modes a code recorded (dem::kBreakModeArray among a step's
// extra arrays, as `crackvis import` writes it), or empty.
std::span<const double> recordedBreakModes(std::span<const dem::ExtraArray> extras);

// d0, d: the bond's separation (second end minus first) in the reference
// and at its break; forceBefore: its normal force at the last step it was
// intact, when the file has one.
BondBreak classifyBreak(Vec3 d0, Vec3 d, std::optional<double> forceBefore);

// Follows a run step by step and classifies each bond the step it is first
// seen broken; bonds broken at the first step seen were broken before the
// run and are not classified.
class BreakModeTracker {
 public:
  // `bondForce` may be empty. `recorded`: per bond, the mode the code
  // recorded (dem::kBreakModeArray: 1 tension, 2 shear, 0 none), or empty;
  // a recorded mode is counted instead of the rule's.
  void update(int step, std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
              std::span<const Vec3> reference, std::span<const Vec3> current,
              std::span<const float> bondForce, std::span<const double> recorded = {});
  // The same, where the bonds new since the last step are known (`diff`,
  // of these states): only those are read.
  void update(int step, std::span<const dem::Bond> bonds, const BondDiff& diff,
              std::span<const std::uint8_t> bondState, std::span<const Vec3> reference,
              std::span<const Vec3> current, std::span<const float> bondForce,
              std::span<const double> recorded = {});
  const std::vector<BondBreak>& breaks() const { return m_breaks; }
  std::size_t count(BreakMode mode) const;
  std::size_t countUpTo(BreakMode mode, int step) const;

 private:
  void classify(int step, std::size_t b, std::span<const dem::Bond> bonds,
                std::span<const Vec3> reference, std::span<const Vec3> current,
                std::span<const double> recorded);
  void rememberForce(std::span<const float> bondForce, std::size_t bondCount);

  std::vector<std::uint8_t> m_seen;    // 1: broken at a step seen (classified or before the run)
  std::vector<float> m_previousForce;  // the previous step's force (NaN: none)
  bool m_first = true;
  std::vector<BondBreak> m_breaks;
  std::size_t m_tension = 0;
  std::size_t m_shear = 0;
};

}  // namespace crackvis::analysis
