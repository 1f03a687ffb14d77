#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

#include <fmt/format.h>

#include <crackvis/dem/model.hpp>

namespace crackvis::dem {
namespace {

std::string describe(Vec3 p) {
  return fmt::format("({}, {}, {})", p.x, p.y, p.z);
}

Status checkSelfBonds(const Lattice& lattice) {
  for (std::size_t b = 0; b < lattice.bonds.size(); ++b) {
    const Bond bond = lattice.bonds[b];
    if (bond.first == bond.second) {
      return invalidArgument(fmt::format("bond {} is a self-bond of particle {}", b, bond.first));
    }
  }
  return Status::ok();
}

// The two lowest bonds joining particles `lo` < `hi`, reported as the
// duplicate (the higher index) of the original (the lower): a pass over all
// bonds, made only for a list that has one.
Status duplicateBondError(const Lattice& lattice, std::uint32_t lo, std::uint32_t hi) {
  std::optional<std::size_t> original;
  for (std::size_t b = 0; b < lattice.bonds.size(); ++b) {
    const Bond bond = lattice.bonds[b];
    if (static_cast<std::uint32_t>(std::min(bond.first, bond.second)) != lo ||
        static_cast<std::uint32_t>(std::max(bond.first, bond.second)) != hi) {
      continue;
    }
    if (original) {
      return invalidArgument(fmt::format("bond {} duplicates bond {} (particles {} and {})", b,
                                         *original, bond.first, bond.second));
    }
    original = b;
  }
  return internalError("a duplicate bond was found and then lost");  // not reached
}

// Each bond's higher particle goes into the bucket of its lower one (a
// counting sort, O(N + M)); a bucket names a particle twice when two bonds
// join the same pair, which a mark per particle (the bucket that named it
// last) finds without sorting. The first duplicate reported is the one with
// the smallest pair of particles, between its two lowest bond indices. A
// sort of all M bond indices by pair, as before, took about 0.4 s of a
// 1e6-particle view's first picture (5.9 million bonds, every comparison a
// cache miss); buckets of (particle, bond) pairs sorted one by one, after
// that, twice the memory of this (8 bytes a bond against 4: 475 MB at 1e7).
Status checkDuplicateBonds(const Lattice& lattice) {
  const std::size_t n = lattice.particleCount();
  std::vector<std::uint32_t> start(n + 1, 0);
  for (const Bond& bond : lattice.bonds) {
    // The callers checked the ends; one out of range must not index here.
    if (std::min(bond.first, bond.second) < 0 ||
        static_cast<std::size_t>(std::max(bond.first, bond.second)) >= n) {
      return checkBondEnds(lattice.bonds, static_cast<std::int64_t>(n));
    }
    ++start[static_cast<std::size_t>(std::min(bond.first, bond.second)) + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  // Filled through start[lo]++, which leaves start[p] at bucket p's end.
  std::vector<std::uint32_t> higher(lattice.bonds.size());
  for (const Bond& bond : lattice.bonds) {
    const auto lo = static_cast<std::size_t>(std::min(bond.first, bond.second));
    higher[start[lo]++] = static_cast<std::uint32_t>(std::max(bond.first, bond.second));
  }
  constexpr std::uint32_t kUnnamed = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> namedBy(n, kUnnamed);
  std::uint32_t begin = 0;
  for (std::size_t p = 0; p < n; ++p) {
    const std::uint32_t end = start[p];
    std::uint32_t twin = kUnnamed;  // the smallest partner named twice
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::uint32_t q = higher[k];
      if (namedBy[q] == p) {
        twin = std::min(twin, q);
      }
      namedBy[q] = static_cast<std::uint32_t>(p);
    }
    if (twin != kUnnamed) {
      return duplicateBondError(lattice, static_cast<std::uint32_t>(p), twin);
    }
    begin = end;
  }
  return Status::ok();
}

}  // namespace

Bounds boundingBox(std::span<const Vec3> points) {
  if (points.empty()) {
    return {};
  }
  Bounds box{points.front(), points.front()};
  for (const Vec3& p : points) {
    box.lo = {std::min(box.lo.x, p.x), std::min(box.lo.y, p.y), std::min(box.lo.z, p.z)};
    box.hi = {std::max(box.hi.x, p.x), std::max(box.hi.y, p.y), std::max(box.hi.z, p.z)};
  }
  return box;
}

std::size_t StepState::brokenBondCount() const {
  return static_cast<std::size_t>(std::count(bondState.begin(), bondState.end(),
                                             static_cast<std::uint8_t>(BondState::kBroken)));
}

Status validateTopology(const Lattice& lattice, BondEnds ends) {
  if (lattice.dimension != 2 && lattice.dimension != 3) {
    return invalidArgument(fmt::format("dimension is {}, expected 2 or 3", lattice.dimension));
  }
  for (std::size_t i = 0; i < lattice.radius.size(); ++i) {
    if (!std::isfinite(lattice.radius[i]) || lattice.radius[i] <= 0.0) {
      return invalidArgument(fmt::format(
          "radius of particle {} is {}, expected a positive finite value", i, lattice.radius[i]));
    }
    if (lattice.radius[i] > kMaxCoordinate) {
      return invalidArgument(fmt::format("radius of particle {} is {}, beyond {:g} m", i,
                                         lattice.radius[i], kMaxCoordinate));
    }
  }
  if (ends == BondEnds::kCheck) {
    CRACKVIS_RETURN_IF_ERROR(
        checkBondEnds(lattice.bonds, static_cast<std::int64_t>(lattice.particleCount())));
  }
  CRACKVIS_RETURN_IF_ERROR(checkSelfBonds(lattice));
  return checkDuplicateBonds(lattice);
}

// The common case, all in range, is one branch-free pass that vectorizes:
// read as unsigned, a negative index is larger than any particle count up
// to 2^31, so a single maximum checks both bounds (a min and a max pass took
// twice as long). Only a bad list pays for finding the first offending bond.
Status checkBondEnds(std::span<const Bond> bonds, std::int64_t particles, std::size_t first) {
  if (particles <= (std::int64_t{1} << 31)) {
    std::uint32_t highest = 0;
    for (const Bond& bond : bonds) {
      highest = std::max(highest, std::max(static_cast<std::uint32_t>(bond.first),
                                           static_cast<std::uint32_t>(bond.second)));
    }
    if (bonds.empty() || static_cast<std::int64_t>(highest) < particles) {
      return Status::ok();
    }
  }
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const Bond bond = bonds[b];
    if (bond.first < 0 || bond.second < 0 || bond.first >= particles || bond.second >= particles) {
      return invalidArgument(
          fmt::format("bond {} joins particles {} and {}: index out of range (N = {} particles)",
                      first + b, bond.first, bond.second, particles));
    }
  }
  return Status::ok();
}

namespace {

template <typename T>
Status checkOptionalLength(const std::vector<T>& values, std::size_t expected, const char* what,
                           const char* per) {
  if (values.empty() || values.size() == expected) {
    return Status::ok();
  }
  return invalidArgument(fmt::format("{} {} for {} {}", values.size(), what, expected, per));
}

Status checkUniqueIds(const std::vector<std::int64_t>& ids) {
  std::vector<std::size_t> order(ids.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return ids[a] != ids[b] ? ids[a] < ids[b] : a < b;
  });
  for (std::size_t i = 1; i < order.size(); ++i) {
    if (ids[order[i]] == ids[order[i - 1]]) {
      return invalidArgument(fmt::format("particles {} and {} have the same id {}", order[i - 1],
                                         order[i], ids[order[i]]));
    }
  }
  return Status::ok();
}

}  // namespace

Status validateExtras(std::span<const ExtraArray> extras, std::size_t particleCount,
                      std::size_t bondCount) {
  for (std::size_t i = 0; i < extras.size(); ++i) {
    const ExtraArray& extra = extras[i];
    CRACKVIS_RETURN_IF_ERROR(validateName("extra array", extra.name));
    for (std::size_t j = 0; j < i; ++j) {
      if (extras[j].name == extra.name && extras[j].owner == extra.owner) {
        return invalidArgument(fmt::format("extra array '{}' appears twice", extra.name));
      }
    }
    if (extra.components != 1 && extra.components != 3) {
      return invalidArgument(fmt::format("extra array '{}' has {} components, expected 1 or 3",
                                         extra.name, extra.components));
    }
    const bool perParticle = extra.owner == ExtraOwner::kParticles;
    const std::size_t rows = perParticle ? particleCount : bondCount;
    if (extra.values.size() != rows * static_cast<std::size_t>(extra.components)) {
      return invalidArgument(
          fmt::format("extra array '{}' has {} values, expected {} x {} ({} = {})", extra.name,
                      extra.values.size(), rows, extra.components, perParticle ? "N" : "M", rows));
    }
    const auto bad = std::find_if(extra.values.begin(), extra.values.end(),
                                  [](double v) { return !std::isfinite(v); });
    if (bad != extra.values.end()) {
      return invalidArgument(fmt::format("extra array '{}': value {} is not finite ({})",
                                         extra.name, bad - extra.values.begin(), *bad));
    }
  }
  return Status::ok();
}

Status validateLattice(const Lattice& lattice) {
  CRACKVIS_RETURN_IF_ERROR(validateTopology(lattice));
  const std::size_t n = lattice.particleCount();
  const std::size_t m = lattice.bondCount();
  CRACKVIS_RETURN_IF_ERROR(checkOptionalLength(lattice.strength, m, "bond strengths", "bonds"));
  for (std::size_t b = 0; b < lattice.strength.size(); ++b) {
    if (std::isnan(lattice.strength[b]) || lattice.strength[b] < 0.0) {
      return invalidArgument(
          fmt::format("strength of bond {} is {}, expected >= 0", b, lattice.strength[b]));
    }
  }
  CRACKVIS_RETURN_IF_ERROR(checkOptionalLength(lattice.particleId, n, "particle ids", "particles"));
  CRACKVIS_RETURN_IF_ERROR(checkUniqueIds(lattice.particleId));
  CRACKVIS_RETURN_IF_ERROR(
      checkOptionalLength(lattice.particleGroup, n, "particle groups", "particles"));
  CRACKVIS_RETURN_IF_ERROR(checkOptionalLength(lattice.bondFlags, m, "bond flags", "bonds"));
  return validateExtras(lattice.extras, n, m);
}

Status validateStep(const Lattice& lattice, const StepState& step) {
  return validateStep(lattice.dimension, lattice.particleCount(), lattice.bondCount(), step);
}

Status validateStep(int dimension, std::size_t n, std::size_t m, const StepState& step) {
  if (step.positions.size() != n) {
    return invalidArgument(
        fmt::format("{} positions for N = {} particles", step.positions.size(), n));
  }
  if (step.bondState.size() != m) {
    return invalidArgument(
        fmt::format("{} bond states for M = {} bonds", step.bondState.size(), m));
  }
  if (!step.velocities.empty() && step.velocities.size() != n) {
    return invalidArgument(
        fmt::format("{} velocities for N = {} particles", step.velocities.size(), n));
  }
  if (!step.bondForce.empty() && step.bondForce.size() != m) {
    return invalidArgument(
        fmt::format("{} bond forces for M = {} bonds", step.bondForce.size(), m));
  }
  if (!std::isfinite(step.time)) {
    return invalidArgument("time is not finite");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p = step.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return invalidArgument(
          fmt::format("position of particle {} is not finite {}", i, describe(p)));
    }
    if (std::abs(p.x) > kMaxCoordinate || std::abs(p.y) > kMaxCoordinate ||
        std::abs(p.z) > kMaxCoordinate) {
      return invalidArgument(fmt::format("position of particle {} is {}, beyond {:g} m", i,
                                         describe(p), kMaxCoordinate));
    }
    if (dimension == 2 && p.z != 0.0) {
      return invalidArgument(
          fmt::format("2D data set but particle {} has z = {} (expected 0)", i, p.z));
    }
  }
  CRACKVIS_RETURN_IF_ERROR(validateBondStates(step.bondState));
  for (std::size_t i = 0; i < step.scalars.size(); ++i) {
    const StepScalar& scalar = step.scalars[i];
    CRACKVIS_RETURN_IF_ERROR(validateName("step scalar", scalar.name));
    if (scalar.name == "time") {
      return invalidArgument("step scalar 'time' is reserved (it is the step's time)");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (step.scalars[j].name == scalar.name) {
        return invalidArgument(fmt::format("step scalar '{}' appears twice", scalar.name));
      }
    }
    if (!std::isfinite(scalar.value)) {
      return invalidArgument(fmt::format("step scalar '{}' is not finite", scalar.name));
    }
  }
  return validateExtras(step.extras, n, m);
}

Status validateBondStates(std::span<const std::uint8_t> bondState) {
  for (std::size_t b = 0; b < bondState.size(); ++b) {
    if (bondState[b] > static_cast<std::uint8_t>(BondState::kBroken)) {
      return invalidArgument(fmt::format(
          "state of bond {} is {}, expected 0 (intact) or 1 (broken)", b, bondState[b]));
    }
  }
  return Status::ok();
}

}  // namespace crackvis::dem
