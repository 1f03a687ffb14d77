#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include <tbb/parallel_for.h>

#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/metrics.hpp>
#include <crackvis/cracks/particle_grid.hpp>
#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::cracks {
namespace {

double distanceTo(const CrackMesh& mesh, const Primitive& primitive, Vec3 p) {
  const auto point = [&](std::size_t k) {
    return mesh.points[static_cast<std::size_t>(primitive.ids[k])];
  };
  if (primitive.count == 1) {
    return dem::norm(p - point(0));
  }
  if (primitive.count == 2) {
    return pointSegmentDistance(p, point(0), point(1));
  }
  // Fan from the centroid: exact for planar convex polygons, and a fair
  // surface for the slightly non-planar faces of deformed lattices.
  Vec3 centre{};
  for (std::size_t k = 0; k < primitive.count; ++k) {
    centre = centre + point(k);
  }
  centre = (1.0 / static_cast<double>(primitive.count)) * centre;
  double best = std::numeric_limits<double>::max();
  for (std::size_t k = 0; k < primitive.count; ++k) {
    best = std::min(best,
                    pointTriangleDistance(p, centre, point(k), point((k + 1) % primitive.count)));
  }
  return best;
}

void topology(const CrackMesh& mesh, const std::vector<Primitive>& primitives,
              SurfaceMetrics& metrics) {
  if (primitives.empty()) {
    return;
  }
  const auto [lo, hi] = dem::boundingBox(mesh.points);
  const double size = std::max(dem::norm(hi - lo), 1e-300);
  const std::vector<std::int32_t> welded = weld(mesh.points, 1e-9 * size);
  std::vector<std::int32_t> parent(
      welded.empty()
          ? 0
          : static_cast<std::size_t>(*std::max_element(welded.begin(), welded.end())) + 1);
  std::iota(parent.begin(), parent.end(), 0);
  std::map<std::pair<std::int32_t, std::int32_t>, int> edgeUse;
  std::vector<int> pointUse(parent.size(), 0);
  std::vector<char> used(parent.size(), 0);
  for (const Primitive& primitive : primitives) {
    const std::int32_t first = welded[static_cast<std::size_t>(primitive.ids[0])];
    for (std::size_t k = 0; k < primitive.count; ++k) {
      const std::int32_t a = welded[static_cast<std::size_t>(primitive.ids[k])];
      used[static_cast<std::size_t>(a)] = 1;
      parent[static_cast<std::size_t>(findRoot(parent, a))] = findRoot(parent, first);
      if (primitive.count >= 3) {
        const std::int32_t b =
            welded[static_cast<std::size_t>(primitive.ids[(k + 1) % primitive.count])];
        ++edgeUse[{std::min(a, b), std::max(a, b)}];
      } else {
        ++pointUse[static_cast<std::size_t>(a)];
      }
    }
  }
  for (std::size_t p = 0; p < parent.size(); ++p) {
    if (used[p] && findRoot(parent, static_cast<std::int32_t>(p)) == static_cast<std::int32_t>(p)) {
      ++metrics.components;
    }
    if (pointUse[p] > 2) {
      ++metrics.nonManifoldEdges;
    }
  }
  for (const auto& [edge, count] : edgeUse) {
    if (count > 2) {
      ++metrics.nonManifoldEdges;
    }
  }
}

}  // namespace

double pointSegmentDistance(Vec3 p, Vec3 a, Vec3 b) {
  const Vec3 ab = b - a;
  const double length2 = dem::dot(ab, ab);
  const double t = length2 > 0.0 ? std::clamp(dem::dot(p - a, ab) / length2, 0.0, 1.0) : 0.0;
  return dem::norm(p - (a + t * ab));
}

double pointTriangleDistance(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  // Closest point on a triangle (Ericson, Real-Time Collision Detection 5.1.5).
  const Vec3 ab = b - a;
  const Vec3 ac = c - a;
  const Vec3 ap = p - a;
  const double d1 = dem::dot(ab, ap);
  const double d2 = dem::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    return dem::norm(ap);
  }
  const Vec3 bp = p - b;
  const double d3 = dem::dot(ab, bp);
  const double d4 = dem::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) {
    return dem::norm(bp);
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    return dem::norm(p - (a + (d1 / (d1 - d3)) * ab));
  }
  const Vec3 cp = p - c;
  const double d5 = dem::dot(ab, cp);
  const double d6 = dem::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) {
    return dem::norm(cp);
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    return dem::norm(p - (a + (d2 / (d2 - d6)) * ac));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return dem::norm(p - (b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)));
  }
  const double denominator = 1.0 / (va + vb + vc);
  const double v = vb * denominator;
  const double w = vc * denominator;
  return dem::norm(p - (a + v * ab + w * ac));
}

SurfaceMetrics computeMetrics(const CrackMesh& mesh, std::span<const Vec3> positions,
                              std::span<const double> radius) {
  SurfaceMetrics metrics;
  metrics.points = mesh.points.size();
  metrics.polygons = mesh.polygons.size();
  metrics.lines = mesh.lines.size();
  metrics.vertices = mesh.vertices.size();
  if (const AttributeArray* flag = mesh.findCellData("inconsistent")) {
    metrics.inconsistentBonds = static_cast<std::size_t>(
        std::count_if(flag->values.begin(), flag->values.end(), [](double v) { return v != 0.0; }));
  }
  const std::vector<Primitive> primitives = surfacePrimitives(mesh);
  for (const Primitive& primitive : primitives) {
    metrics.area += measure(mesh, primitive);
  }
  double largestRadius = 0.0;
  for (double r : radius) {
    largestRadius = std::max(largestRadius, r);
  }
  // Deepest cut per particle, primitives in parallel; the per-particle
  // maximum is order-independent, so the result is deterministic.
  std::vector<double> deepest(positions.size(), 0.0);
  if (!primitives.empty() && !positions.empty()) {
    const ParticleGrid grid(positions, 2.0 * largestRadius);
    std::vector<std::vector<std::pair<std::int32_t, double>>> cuts(primitives.size());
    tbb::parallel_for(std::size_t{0}, primitives.size(), [&](std::size_t k) {
      const Primitive& primitive = primitives[k];
      Vec3 centre{};
      for (std::size_t v = 0; v < primitive.count; ++v) {
        centre = centre + mesh.points[static_cast<std::size_t>(primitive.ids[v])];
      }
      centre = (1.0 / static_cast<double>(primitive.count)) * centre;
      double reach = 0.0;
      for (std::size_t v = 0; v < primitive.count; ++v) {
        reach = std::max(
            reach, dem::norm(mesh.points[static_cast<std::size_t>(primitive.ids[v])] - centre));
      }
      grid.forEachNear(centre, reach + largestRadius, [&](std::int32_t particle) {
        const double depth =
            radius[static_cast<std::size_t>(particle)] -
            distanceTo(mesh, primitive, positions[static_cast<std::size_t>(particle)]);
        if (depth > 0.0) {
          cuts[k].push_back({particle, depth});
        }
      });
    });
    for (const auto& list : cuts) {
      for (const auto& [particle, depth] : list) {
        deepest[static_cast<std::size_t>(particle)] =
            std::max(deepest[static_cast<std::size_t>(particle)], depth);
      }
    }
  }
  for (std::size_t i = 0; i < deepest.size(); ++i) {
    if (deepest[i] > 0.0) {
      ++metrics.cutParticles;
      metrics.totalDepth += deepest[i];
      if (deepest[i] > metrics.maxDepth) {
        metrics.maxDepth = deepest[i];
        metrics.maxRelativeDepth = deepest[i] / radius[i];
      }
    }
  }
  topology(mesh, primitives, metrics);
  if (mesh.holdsCells()) {
    const CrackComponents set = findComponents(mesh);
    metrics.components = set.components.size();
    for (const CrackComponent& component : set.components) {
      metrics.area += component.area;
    }
  }
  return metrics;
}

}  // namespace crackvis::cracks
