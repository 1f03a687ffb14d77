#include <algorithm>
#include <cmath>
#include <utility>

#include <crackvis/dem/spatial_index.hpp>

namespace crackvis::dem {

int longestAxis(const Bounds& box) {
  const Vec3 size = box.hi - box.lo;
  if (size.x >= size.y && size.x >= size.z) {
    return 0;
  }
  return size.y >= size.z ? 1 : 2;
}

namespace {

// How far the coordinate along `axis` falls in all, from one particle to the
// next in the file's order. Summed, not counted: jitter makes many tiny
// falls along the axis that runs slowest, a row's end one large fall along
// the fastest.
double descent(std::span<const Vec3> positions, int axis) {
  double fall = 0.0;
  for (std::size_t i = 1; i < positions.size(); ++i) {
    fall +=
        std::max(0.0, axisCoordinate(positions[i - 1], axis) - axisCoordinate(positions[i], axis));
  }
  return fall;
}

double extent(const Bounds& box, int axis) {
  return axisCoordinate(box.hi, axis) - axisCoordinate(box.lo, axis);
}

}  // namespace

int sliceAxis(std::span<const Vec3> reference) {
  const Bounds box = boundingBox(reference);
  const int longest = longestAxis(box);
  const double reach = (1.0 - kSliceAxisTolerance) * extent(box, longest);
  int best = -1;
  double least = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    if (extent(box, axis) >= reach && extent(box, axis) > 0.0) {
      const double fall = descent(reference, axis);
      if (best < 0 || fall < least) {
        best = axis;
        least = fall;
      }
    }
  }
  return best < 0 ? longest : best;
}

const char* decompositionName(CellDecomposition decomposition) {
  switch (decomposition) {
    case CellDecomposition::kLattice:
      return "lattice";
    case CellDecomposition::kTriangulation:
      return "triangulation";
    case CellDecomposition::kUnknown:
      break;
  }
  return "";
}

CellDecomposition decompositionNamed(std::string_view name) {
  for (const CellDecomposition known :
       {CellDecomposition::kLattice, CellDecomposition::kTriangulation}) {
    if (name == decompositionName(known)) {
      return known;
    }
  }
  return CellDecomposition::kUnknown;
}

double longestBond(std::span<const Vec3> positions, std::span<const Bond> bonds) {
  double longest = 0.0;
  for (const Bond& bond : bonds) {
    const Vec3 d = positions[static_cast<std::size_t>(bond.second)] -
                   positions[static_cast<std::size_t>(bond.first)];
    longest = std::max(longest, std::sqrt(dot(d, d)));
  }
  return longest;
}

namespace {

// bondStart of docs/data-format.md, or empty when the bonds are not sorted
// by their first end (a file another writer made).
std::vector<std::int64_t> bondStarts(std::size_t particleCount, std::span<const Bond> bonds) {
  for (std::size_t b = 1; b < bonds.size(); ++b) {
    if (bonds[b].first < bonds[b - 1].first) {
      return {};
    }
  }
  std::vector<std::int64_t> start(particleCount + 1, 0);
  std::size_t b = 0;
  for (std::size_t i = 0; i <= particleCount; ++i) {
    while (b < bonds.size() && static_cast<std::size_t>(bonds[b].first) < i) {
      ++b;
    }
    start[i] = static_cast<std::int64_t>(b);
  }
  return start;
}

}  // namespace

SpatialIndex buildSpatialIndex(std::span<const Vec3> reference, const Lattice& lattice,
                               CellDecomposition decomposition) {
  SpatialIndex index;
  SpatialIndexInfo& info = index.info;
  info.box = boundingBox(reference);
  info.axis = sliceAxis(reference);
  info.largestRadius = lattice.radius.empty()
                           ? 0.0
                           : *std::max_element(lattice.radius.begin(), lattice.radius.end());
  info.longestBond = longestBond(reference, lattice.bonds);
  info.decomposition = decomposition;
  // Sorted as (coordinate, index) pairs held side by side: a sort of
  // indices that looked the coordinates up would miss the cache at 1e7.
  std::vector<std::pair<double, ParticleIndex>> keyed(reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    keyed[i] = {axisCoordinate(reference[i], info.axis), static_cast<ParticleIndex>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  index.order.reserve(keyed.size());
  index.coordinate.reserve(keyed.size());
  for (const auto& [coordinate, particle] : keyed) {
    index.coordinate.push_back(coordinate);
    index.order.push_back(particle);
  }
  index.bondStart = bondStarts(reference.size(), lattice.bonds);
  info.hasBondStart = !index.bondStart.empty();
  return index;
}

}  // namespace crackvis::dem
