#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <crackvis/common/random.hpp>
#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/dem/neighbour_grid.hpp>

namespace crackvis::dem {
namespace {

std::vector<Vec3> fccSites(const std::array<int, 3>& sites, double radius) {
  const auto spacing = siteSpacing(LatticeKind::kFcc, radius);
  std::vector<Vec3> positions;
  for (int k = 0; k < sites[2]; ++k) {
    for (int j = 0; j < sites[1]; ++j) {
      for (int i = 0; i < sites[0]; ++i) {
        if ((i + j + k) % 2 == 0) {
          positions.push_back(
              {radius + i * spacing[0], radius + j * spacing[1], radius + k * spacing[2]});
        }
      }
    }
  }
  return positions;
}

// HCP and the triangular lattice: A layers, and B layers shifted by
// (d/2, d/(2 sqrt 3)) onto the hollows of the A layer beneath.
std::vector<Vec3> closePackedSites(const std::array<int, 3>& sites, double radius, int layers) {
  const double d = 2.0 * radius;
  const auto spacing = siteSpacing(LatticeKind::kHcp, radius);
  std::vector<Vec3> positions;
  for (int k = 0; k < layers; ++k) {
    const bool layerB = k % 2 == 1;
    for (int j = 0; j < sites[1]; ++j) {
      for (int i = 0; i < sites[0]; ++i) {
        const double x = i * d + (j % 2) * 0.5 * d + (layerB ? 0.5 * d : 0.0);
        const double y = j * spacing[1] + (layerB ? d / (2.0 * std::sqrt(3.0)) : 0.0);
        const double z = layers > 1 ? k * spacing[2] : 0.0;
        positions.push_back({radius + x, radius + y, layers > 1 ? radius + z : 0.0});
      }
    }
  }
  return positions;
}

Vec3 extentOf(const std::vector<Vec3>& positions, double radius, int dimension) {
  Vec3 hi{};
  for (const Vec3& p : positions) {
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  return {hi.x + radius, hi.y + radius, dimension == 3 ? hi.z + radius : 0.0};
}

}  // namespace

std::string_view toString(LatticeKind kind) {
  switch (kind) {
    case LatticeKind::kFcc:
      return "fcc";
    case LatticeKind::kHcp:
      return "hcp";
    case LatticeKind::kTriangular:
      return "triangular";
  }
  return "unknown";
}

Result<LatticeKind> parseLatticeKind(std::string_view name) {
  for (auto kind : {LatticeKind::kFcc, LatticeKind::kHcp, LatticeKind::kTriangular}) {
    if (name == toString(kind)) {
      return kind;
    }
  }
  return invalidArgument(
      fmt::format("unknown lattice '{}' (expected fcc, hcp or triangular)", name));
}

std::array<double, 3> siteSpacing(LatticeKind kind, double radius) {
  const double d = 2.0 * radius;
  if (kind == LatticeKind::kFcc) {
    const double half = d / std::sqrt(2.0);
    return {half, half, half};
  }
  return {d, d * std::sqrt(3.0) / 2.0, kind == LatticeKind::kHcp ? d * std::sqrt(2.0 / 3.0) : 0.0};
}

std::array<int, 3> sitesForBox(LatticeKind kind, Vec3 box, double radius) {
  const auto spacing = siteSpacing(kind, radius);
  const double d = 2.0 * radius;
  auto fit = [](double room, double step) {
    return room < 0.0 ? 0 : static_cast<int>(std::floor(room / step + 1e-9)) + 1;
  };
  if (kind == LatticeKind::kFcc) {
    return {fit(box.x - d, spacing[0]), fit(box.y - d, spacing[1]), fit(box.z - d, spacing[2])};
  }
  // Odd rows and B layers are shifted; leave room for the shifts.
  const int layers = kind == LatticeKind::kHcp ? fit(box.z - d, spacing[2]) : 1;
  const int rows = fit(box.y - d - (layers > 1 ? d / (2.0 * std::sqrt(3.0)) : 0.0), spacing[1]);
  const double shiftX = (rows > 1 ? 0.5 * d : 0.0) + (layers > 1 ? 0.5 * d : 0.0);
  return {fit(box.x - d - shiftX, spacing[0]), rows, layers};
}

Result<LatticeBlock> generateBlock(const BlockSpec& spec) {
  const int dimension = dimensionOf(spec.kind);
  if (!(spec.radius > 0.0) || !std::isfinite(spec.radius)) {
    return invalidArgument(fmt::format("radius must be positive, got {}", spec.radius));
  }
  if (!(spec.jitter >= 0.0 && spec.jitter < 0.5)) {
    return invalidArgument(fmt::format(
        "jitter must be in [0, 0.5) of the radius (larger would let spheres overlap), got {}",
        spec.jitter));
  }
  if (!(spec.strength >= 0.0)) {
    return invalidArgument(fmt::format("strength must be >= 0, got {}", spec.strength));
  }
  const int axes = dimension;
  double count = 1.0;
  for (int axis = 0; axis < axes; ++axis) {
    if (spec.sites[static_cast<size_t>(axis)] < 1) {
      return invalidArgument(fmt::format("sites along axis {} must be >= 1, got {}", "xyz"[axis],
                                         spec.sites[static_cast<size_t>(axis)]));
    }
    count *= spec.sites[static_cast<size_t>(axis)];
  }
  if (count > 2.0e8) {
    return invalidArgument(
        fmt::format("{:.0f} sites is more than this generator supports (2e8)", count));
  }

  LatticeBlock block;
  switch (spec.kind) {
    case LatticeKind::kFcc:
      block.positions = fccSites(spec.sites, spec.radius);
      break;
    case LatticeKind::kHcp:
      block.positions = closePackedSites(spec.sites, spec.radius, spec.sites[2]);
      break;
    case LatticeKind::kTriangular:
      block.positions = closePackedSites(spec.sites, spec.radius, 1);
      break;
  }
  block.extent = extentOf(block.positions, spec.radius, dimension);
  Lattice& lattice = block.lattice;
  lattice.dimension = dimension;
  lattice.radius.assign(block.positions.size(), spec.radius);
  lattice.bonds = nearestNeighbourBonds(block.positions, spec.radius);
  lattice.strength.assign(lattice.bonds.size(), spec.strength);

  if (spec.jitter > 0.0) {
    SplitMix64 random(spec.seed);
    const double amplitude = spec.jitter * spec.radius;
    for (Vec3& p : block.positions) {
      p.x += amplitude * random.symmetric();
      p.y += amplitude * random.symmetric();
      if (dimension == 3) {
        p.z += amplitude * random.symmetric();
      }
    }
  }
  return block;
}

std::vector<Bond> nearestNeighbourBonds(const std::vector<Vec3>& positions, double radius,
                                        double tolerance) {
  const double cutoff = 2.0 * radius * tolerance;
  const NeighbourGrid grid(positions, cutoff);
  return grid.pairsWithin(cutoff);
}

std::vector<int> coordination(const Lattice& lattice) {
  std::vector<int> count(lattice.particleCount(), 0);
  for (const Bond& bond : lattice.bonds) {
    ++count[static_cast<size_t>(bond.first)];
    ++count[static_cast<size_t>(bond.second)];
  }
  return count;
}

}  // namespace crackvis::dem
