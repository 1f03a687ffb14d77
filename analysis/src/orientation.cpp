#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <crackvis/analysis/orientation.hpp>
#include <crackvis/analysis/tensor.hpp>

namespace crackvis::analysis {

namespace {

bool counts(const ElementOpenings& elements, std::size_t e, int component) {
  return dem::dot(elements.normal[e], elements.normal[e]) > 0.0 &&
         (component < 0 || elements.component[e] == component);
}

}  // namespace

RoseDiagram roseDiagram(const ElementOpenings& elements, int component, int bins) {
  RoseDiagram rose;
  rose.weight.assign(static_cast<std::size_t>(std::max(bins, 1)), 0.0);
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (!counts(elements, e, component)) {
      continue;
    }
    double degrees =
        std::atan2(elements.normal[e].y, elements.normal[e].x) * 180.0 / std::numbers::pi;
    degrees = std::fmod(degrees + 360.0, 180.0);
    const auto bin =
        std::min(rose.weight.size() - 1, static_cast<std::size_t>(degrees / rose.binDegrees()));
    rose.weight[bin] += elements.area[e];
  }
  return rose;
}

std::array<double, 2> equalAreaPoint(Vec3 n) {
  const double length = dem::norm(n);
  if (length == 0.0) {
    return {0.0, 0.0};
  }
  // The lower hemisphere's unit direction u = n / |n| (u.z = z <= 0) lands
  // at radius sqrt(1 + z) along its horizontal part, which is (u.x, u.y)
  // over sqrt(1 - z^2) = sqrt((1 - z)(1 + z)): so at (u.x, u.y) / sqrt(1 - z),
  // which is (n.x, n.y) / sqrt(|n| (|n| + |n.z|)). Two roots and one
  // quotient, not three of each: every element of every step passes here.
  const double scale = (n.z > 0.0 ? -1.0 : 1.0) / std::sqrt(length * (length + std::abs(n.z)));
  return {scale * n.x, scale * n.y};
}

Stereonet stereonet(const ElementOpenings& elements, int component, int size) {
  Stereonet net;
  net.size = std::max(size, 1);
  net.weight.assign(static_cast<std::size_t>(net.size) * static_cast<std::size_t>(net.size), 0.0);
  const auto cell = [&](double v) {
    return std::clamp(static_cast<int>(std::floor((v + 1.0) * 0.5 * net.size)), 0, net.size - 1);
  };
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (counts(elements, e, component)) {
      const auto [x, y] = equalAreaPoint(elements.normal[e]);
      net.weight[static_cast<std::size_t>(cell(y) * net.size + cell(x))] += elements.area[e];
    }
  }
  return net;
}

MeanOrientation meanOrientation(const ElementOpenings& elements, int component) {
  AxialTensor tensor;
  double total = 0.0;
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (counts(elements, e, component)) {
      tensor.add(elements.normal[e], elements.area[e]);
      total += elements.area[e];
    }
  }
  MeanOrientation mean;
  mean.normal = tensor.principalAxis();
  if (total > 0.0) {
    // sum(a (n . m)^2) is m^T T m: no second pass over the elements.
    mean.strength = tensor.along(mean.normal) / total;
  }
  const bool flip = mean.normal.z > 0.0 || (mean.normal.z == 0.0 && mean.normal.y < 0.0);
  if (flip) {
    mean.normal = -1.0 * mean.normal;
  }
  return mean;
}

const char* toString(BreakMode mode) {
  return mode == BreakMode::kTension ? "tension" : "shear";
}

BondBreak classifyBreak(Vec3 d0, Vec3 d, std::optional<double> forceBefore) {
  BondBreak result;
  const double length = dem::norm(d0);
  const Vec3 axis = length > 0.0 ? (1.0 / length) * d0 : Vec3{};
  const Vec3 jump = d - d0;
  result.stretch = dem::norm(d) - length;
  result.shear = dem::norm(jump - dem::dot(jump, axis) * axis);
  const bool compressed = forceBefore && *forceBefore < 0.0;
  result.mode = !compressed && result.stretch > kTensionShare * result.shear ? BreakMode::kTension
                                                                             : BreakMode::kShear;
  return result;
}

std::span<const double> recordedBreakModes(std::span<const dem::ExtraArray> extras) {
  for (const dem::ExtraArray& extra : extras) {
    if (extra.owner == dem::ExtraOwner::kBonds && extra.name == dem::kBreakModeArray &&
        extra.components == 1) {
      return extra.values;
    }
  }
  return {};
}

// A bond first seen broken: its mode by the rule (the force is the one it
// carried at the previous step, when it was intact), or the recorded one.
void BreakModeTracker::classify(int step, std::size_t b, std::span<const dem::Bond> bonds,
                                std::span<const Vec3> reference, std::span<const Vec3> current,
                                std::span<const double> recorded) {
  m_seen[b] = 1;
  const std::size_t n = std::min(reference.size(), current.size());
  const auto i = static_cast<std::size_t>(bonds[b].first);
  const auto j = static_cast<std::size_t>(bonds[b].second);
  if (i >= n || j >= n) {
    return;
  }
  const float before =
      b < m_previousForce.size() ? m_previousForce[b] : std::numeric_limits<float>::quiet_NaN();
  const std::optional<double> force =
      std::isnan(before) ? std::nullopt : std::optional<double>(before);
  BondBreak found = classifyBreak(reference[j] - reference[i], current[j] - current[i], force);
  found.bond = static_cast<std::int32_t>(b);
  found.step = step;
  found.rule = found.mode;
  if (b < recorded.size() && (recorded[b] == 1.0 || recorded[b] == 2.0)) {
    found.recorded = true;
    found.mode = recorded[b] == 1.0 ? BreakMode::kTension : BreakMode::kShear;
  }
  ++(found.mode == BreakMode::kTension ? m_tension : m_shear);
  m_breaks.push_back(found);
}

void BreakModeTracker::rememberForce(std::span<const float> bondForce, std::size_t bondCount) {
  // Without forces nothing is kept: a bond past the end reads as no force.
  m_previousForce.assign(
      bondForce.begin(),
      bondForce.begin() + static_cast<std::ptrdiff_t>(std::min(bondForce.size(), bondCount)));
}

void BreakModeTracker::update(int step, std::span<const dem::Bond> bonds,
                              std::span<const std::uint8_t> bondState,
                              std::span<const Vec3> reference, std::span<const Vec3> current,
                              std::span<const float> bondForce, std::span<const double> recorded) {
  const std::size_t m = std::min(bonds.size(), bondState.size());
  if (m_first || m_seen.size() != m) {
    m_seen.assign(bondState.begin(), bondState.begin() + static_cast<std::ptrdiff_t>(m));
    m_first = false;
  } else {
    for (std::size_t b = 0; b < m; ++b) {
      if (bondState[b] != 0 && m_seen[b] == 0) {
        classify(step, b, bonds, reference, current, recorded);
      }
    }
  }
  rememberForce(bondForce, m);
}

void BreakModeTracker::update(int step, std::span<const dem::Bond> bonds, const BondDiff& diff,
                              std::span<const std::uint8_t> bondState,
                              std::span<const Vec3> reference, std::span<const Vec3> current,
                              std::span<const float> bondForce, std::span<const double> recorded) {
  const std::size_t m = std::min(bonds.size(), bondState.size());
  if (m_first || diff.restart || m_seen.size() != m) {
    update(step, bonds, bondState, reference, current, bondForce, recorded);
    return;
  }
  for (const std::int32_t bond : diff.fresh) {
    const auto b = static_cast<std::size_t>(bond);
    if (b < m && m_seen[b] == 0) {
      classify(step, b, bonds, reference, current, recorded);
    }
  }
  rememberForce(bondForce, m);
}

std::size_t BreakModeTracker::count(BreakMode mode) const {
  return mode == BreakMode::kTension ? m_tension : m_shear;
}

std::size_t BreakModeTracker::countUpTo(BreakMode mode, int step) const {
  return static_cast<std::size_t>(
      std::count_if(m_breaks.begin(), m_breaks.end(),
                    [&](const BondBreak& b) { return b.mode == mode && b.step <= step; }));
}

}  // namespace crackvis::analysis
