#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::cracks {

std::vector<Primitive> surfacePrimitives(const CrackMesh& mesh) {
  std::vector<Primitive> result;
  const AttributeArray* inconsistent = mesh.findCellData("inconsistent");
  const std::size_t lineBase = mesh.vertices.size();
  if (mesh.dimension == 2) {
    for (std::size_t k = 0; k < mesh.lines.size(); ++k) {
      if (inconsistent != nullptr && inconsistent->values[lineBase + k] != 0.0) {
        continue;
      }
      const auto begin = static_cast<std::size_t>(mesh.lines.offsets[k]);
      const auto end = static_cast<std::size_t>(mesh.lines.offsets[k + 1]);
      for (std::size_t s = begin; s + 1 < end; ++s) {
        result.push_back({mesh.lines.connectivity.data() + s, 2, k});
      }
    }
  }
  if (mesh.dimension == 2) {
    return result;  // 2D polygons are cells (cell attribute), not surface
  }
  for (std::size_t k = 0; k < mesh.polygons.size(); ++k) {
    const auto begin = static_cast<std::size_t>(mesh.polygons.offsets[k]);
    const auto end = static_cast<std::size_t>(mesh.polygons.offsets[k + 1]);
    result.push_back({mesh.polygons.connectivity.data() + begin, end - begin, k});
  }
  return result;
}

double measure(const CrackMesh& mesh, const Primitive& primitive) {
  if (primitive.count == 2) {
    return dem::norm(mesh.points[static_cast<std::size_t>(primitive.ids[1])] -
                     mesh.points[static_cast<std::size_t>(primitive.ids[0])]);
  }
  return polygonArea(mesh.points, primitive.ids, primitive.count);
}

// Welded point ids: points closer than `tolerance` (in a grid of that size)
// share an id.
std::vector<std::int32_t> weld(const std::vector<Vec3>& points, double tolerance) {
  // Each point's grid cell, rounded once: the sort compares them
  // n log n times (rounding in the comparison was most of a step's
  // component search on a large crack).
  std::vector<std::array<long long, 3>> keys(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3 p = points[i];
    keys[i] = {std::llround(p.x / tolerance), std::llround(p.y / tolerance),
               std::llround(p.z / tolerance)};
  }
  std::vector<std::int32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  const auto key = [&](std::int32_t i) -> const std::array<long long, 3>& {
    return keys[static_cast<std::size_t>(i)];
  };
  // Lexicographic by hand: std::array's operators compare through memcmp,
  // which was most of the sort's time.
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    const auto& ka = key(a);
    const auto& kb = key(b);
    for (int c = 0; c < 3; ++c) {
      if (ka[c] != kb[c]) {
        return ka[c] < kb[c];
      }
    }
    return a < b;
  });
  std::vector<std::int32_t> id(points.size());
  std::int32_t next = -1;
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (k == 0 || key(order[k]) != key(order[k - 1])) {
      ++next;
    }
    id[static_cast<std::size_t>(order[k])] = next;
  }
  return id;
}

std::int32_t findRoot(std::vector<std::int32_t>& parent, std::int32_t x) {
  while (parent[static_cast<std::size_t>(x)] != x) {
    parent[static_cast<std::size_t>(x)] =
        parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    x = parent[static_cast<std::size_t>(x)];
  }
  return x;
}

}  // namespace crackvis::cracks
