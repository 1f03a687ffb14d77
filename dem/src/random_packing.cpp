#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include <crackvis/common/random.hpp>
#include <crackvis/dem/neighbour_grid.hpp>
#include <crackvis/dem/random_packing.hpp>

namespace crackvis::dem {
namespace {

constexpr int kGrowthStages = 24;
constexpr int kSweepsPerStage = 400;
constexpr int kFinalSweeps = 4000;

double sphereMeasure(double r, int dimension) {
  return dimension == 3 ? 4.0 / 3.0 * std::numbers::pi * r * r * r : std::numbers::pi * r * r;
}

double boxMeasure(const RandomPackingSpec& spec) {
  return spec.dimension == 3 ? spec.box.x * spec.box.y * spec.box.z : spec.box.x * spec.box.y;
}

// Radii until their volume reaches the target fraction of the box.
std::vector<double> drawRadii(const RandomPackingSpec& spec, SplitMix64& random) {
  const double target = spec.solidFraction * boxMeasure(spec);
  std::vector<double> radius;
  double filled = 0.0;
  while (filled < target) {
    const double u = 0.5 * (random.symmetric() + 1.0);
    const double r = spec.radiusMin + u * (spec.radiusMax - spec.radiusMin);
    radius.push_back(r);
    filled += sphereMeasure(r, spec.dimension);
  }
  return radius;
}

// Overlap relaxation at one growth stage: sweeps over a Verlet list of pairs.
class Relaxation {
 public:
  Relaxation(const RandomPackingSpec& spec, const std::vector<double>& radius,
             std::vector<Vec3>& positions)
      : m_spec(spec), m_radius(radius), m_positions(positions) {
    m_largestRadius = *std::max_element(radius.begin(), radius.end());
    m_skin = 0.3 * spec.radiusMin;
  }

  // Sweeps until the largest overlap at `scale` is below `tolerance` (m) or
  // `maxSweeps` ran; returns the largest overlap left.
  double relax(double scale, double tolerance, int maxSweeps, int& sweeps) {
    double largest = 0.0;
    for (int sweep = 0; sweep < maxSweeps; ++sweep) {
      refreshCandidates(scale);
      largest = sweepOnce(scale);
      ++sweeps;
      if (largest <= tolerance) {
        break;
      }
    }
    return largest;
  }

 private:
  void refreshCandidates(double scale) {
    const double cutoff = 2.0 * m_largestRadius * scale + m_skin;
    if (!m_candidates.empty() && cutoff <= m_cutoff && movedSinceRebuild() < 0.5 * m_skin) {
      return;
    }
    m_cutoff = cutoff;
    m_candidates = NeighbourGrid(m_positions, cutoff).pairsWithin(cutoff);
    m_atRebuild = m_positions;
  }

  double movedSinceRebuild() const {
    double moved = 0.0;
    for (std::size_t i = 0; i < m_positions.size(); ++i) {
      const Vec3 d = m_positions[i] - m_atRebuild[i];
      moved = std::max(moved, dot(d, d));
    }
    return std::sqrt(moved);
  }

  // One Gauss-Seidel sweep: pairs in (i, j) order, each overlapping pair
  // pushed apart at once by a little more than its overlap (0.7 of it each
  // way), which settles jammed chains in fewer sweeps. Sequential, so the result is reproducible.
  double sweepOnce(double scale) {
    double largest = 0.0;
    for (const Bond& pair : m_candidates) {
      const auto i = static_cast<std::size_t>(pair.first);
      const auto j = static_cast<std::size_t>(pair.second);
      const Vec3 d = m_positions[i] - m_positions[j];
      const double distance = norm(d);
      const double overlap = scale * (m_radius[i] + m_radius[j]) - distance;
      if (overlap <= 0.0) {
        continue;
      }
      largest = std::max(largest, overlap);
      // Coincident centres (vanishingly rare) separate along x.
      const Vec3 unit = distance > 0.0 ? (1.0 / distance) * d : Vec3{1.0, 0.0, 0.0};
      const Vec3 push = (0.7 * overlap) * unit;
      m_positions[i] = insideWalls(m_positions[i] + push, scale * m_radius[i]);
      m_positions[j] = insideWalls(m_positions[j] - push, scale * m_radius[j]);
    }
    return largest;
  }

  Vec3 insideWalls(Vec3 p, double r) const {
    p.x = std::clamp(p.x, r, m_spec.box.x - r);
    p.y = std::clamp(p.y, r, m_spec.box.y - r);
    p.z = m_spec.dimension == 3 ? std::clamp(p.z, r, m_spec.box.z - r) : 0.0;
    return p;
  }

  const RandomPackingSpec& m_spec;
  const std::vector<double>& m_radius;
  std::vector<Vec3>& m_positions;
  std::vector<Vec3> m_atRebuild;
  std::vector<Bond> m_candidates;
  double m_largestRadius = 0.0;
  double m_skin = 0.0;
  double m_cutoff = 0.0;
};

}  // namespace

Status validate(const RandomPackingSpec& spec) {
  if (spec.dimension != 2 && spec.dimension != 3) {
    return invalidArgument(fmt::format("dimension must be 2 or 3, not {}", spec.dimension));
  }
  if (!(spec.radiusMin > 0.0) || !(spec.radiusMax >= spec.radiusMin) ||
      !std::isfinite(spec.radiusMax)) {
    return invalidArgument(fmt::format("radii must satisfy 0 < min <= max, got {} and {}",
                                       spec.radiusMin, spec.radiusMax));
  }
  const double limit = spec.dimension == 3 ? 0.64 : 0.84;
  if (!(spec.solidFraction > 0.0) || spec.solidFraction > limit) {
    return invalidArgument(
        fmt::format("solid fraction {} is outside (0, {}]: a random {} packing cannot be denser",
                    spec.solidFraction, limit, spec.dimension == 3 ? "sphere" : "disk"));
  }
  if (!(spec.interactionRange >= 1.0) || spec.interactionRange > 2.0) {
    return invalidArgument(
        fmt::format("interaction range {} is outside [1, 2]", spec.interactionRange));
  }
  const double smallest =
      std::min(spec.box.x, spec.dimension == 3 ? std::min(spec.box.y, spec.box.z) : spec.box.y);
  if (!(smallest >= 4.0 * spec.radiusMax) || !std::isfinite(boxMeasure(spec))) {
    return invalidArgument(
        fmt::format("the box must be at least 4 largest radii ({} m) wide along every axis",
                    4.0 * spec.radiusMax));
  }
  const double count =
      spec.solidFraction * boxMeasure(spec) / sphereMeasure(spec.radiusMin, spec.dimension);
  if (count > 2.0e7) {
    return invalidArgument(
        fmt::format("the box holds about {:.3g} particles; at most 2e7 are generated", count));
  }
  return Status::ok();
}

Result<RandomPacking> generateRandomPacking(const RandomPackingSpec& spec,
                                            const PackingProgress& progress) {
  CRACKVIS_RETURN_IF_ERROR(validate(spec));
  SplitMix64 random(spec.seed);
  RandomPacking packing;
  packing.lattice.dimension = spec.dimension;
  packing.lattice.radius = drawRadii(spec, random);
  const std::vector<double>& radius = packing.lattice.radius;
  std::vector<Vec3>& positions = packing.positions;
  positions.resize(radius.size());
  for (std::size_t i = 0; i < radius.size(); ++i) {
    auto along = [&](double length) {
      return radius[i] + 0.5 * (random.symmetric() + 1.0) * (length - 2.0 * radius[i]);
    };
    const double x = along(spec.box.x);
    const double y = along(spec.box.y);
    positions[i] = {x, y, spec.dimension == 3 ? along(spec.box.z) : 0.0};
  }

  // Start where a random placement barely overlaps (a fraction of about 0.3),
  // then grow to full size.
  const double loose = spec.dimension == 3 ? 0.3 : 0.45;
  const double start = std::min(
      1.0, std::pow(loose / spec.solidFraction, 1.0 / static_cast<double>(spec.dimension)));
  const double tolerance = spec.overlapTolerance * spec.radiusMin;
  Relaxation relaxation(spec, radius, positions);
  for (int stage = 1; stage <= kGrowthStages; ++stage) {
    const double scale = start + (1.0 - start) * stage / kGrowthStages;
    const bool last = stage == kGrowthStages;
    packing.largestOverlap =
        relaxation.relax(scale, last ? tolerance : 10.0 * tolerance,
                         last ? kFinalSweeps : kSweepsPerStage, packing.relaxationSweeps);
    if (progress) {
      progress(static_cast<double>(stage) / kGrowthStages);
    }
  }
  if (packing.largestOverlap > tolerance) {
    return failedPrecondition(fmt::format(
        "could not relax the packing at solid fraction {}: overlaps of {:.3g} m remain after {} "
        "sweeps (try a lower --solid-fraction)",
        spec.solidFraction, packing.largestOverlap, packing.relaxationSweeps));
  }
  double filled = 0.0;
  for (double r : radius) {
    filled += sphereMeasure(r, spec.dimension);
  }
  packing.solidFraction = filled / boxMeasure(spec);
  packing.lattice.bonds = interactionRangeBonds(positions, radius, spec.interactionRange);
  packing.lattice.strength.assign(packing.lattice.bonds.size(), spec.strength);
  return packing;
}

std::vector<Bond> interactionRangeBonds(const std::vector<Vec3>& positions,
                                        const std::vector<double>& radius, double range) {
  if (positions.empty()) {
    return {};
  }
  const double largest = *std::max_element(radius.begin(), radius.end());
  const double cutoff = 2.0 * range * largest;
  std::vector<Bond> pairs = NeighbourGrid(positions, cutoff).pairsWithin(cutoff);
  std::erase_if(pairs, [&](const Bond& pair) {
    const auto i = static_cast<std::size_t>(pair.first);
    const auto j = static_cast<std::size_t>(pair.second);
    const double reach = range * (radius[i] + radius[j]);
    const Vec3 d = positions[i] - positions[j];
    return dot(d, d) > reach * reach;
  });
  return pairs;
}

}  // namespace crackvis::dem
