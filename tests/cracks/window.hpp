// Measuring a crack surface inside a window: the part of each primitive
// inside a convex prism (half-spaces dot(n, x) <= c). Planted plane cracks
// are compared with geometry in a window away from the block's faces, where
// the cells tile space completely.
#pragma once

#include <vector>

#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::testing {

struct HalfSpace {
  dem::Vec3 normal;
  double offset;
};

// Sutherland-Hodgman clipping of a polygon by half-spaces; a segment is
// clipped in its parameter instead.
inline std::vector<dem::Vec3> clipToWindow(std::vector<dem::Vec3> polygon,
                                           const std::vector<HalfSpace>& window) {
  if (polygon.size() == 2) {
    double t0 = 0.0;
    double t1 = 1.0;
    const dem::Vec3 a = polygon[0];
    const dem::Vec3 d = polygon[1] - polygon[0];
    for (const HalfSpace& h : window) {
      const double start = dem::dot(h.normal, a) - h.offset;
      const double rate = dem::dot(h.normal, d);
      if (rate == 0.0) {
        if (start > 0.0) {
          return {};
        }
        continue;
      }
      const double t = -start / rate;
      if (rate > 0.0) {
        t1 = std::min(t1, t);
      } else {
        t0 = std::max(t0, t);
      }
    }
    if (t1 <= t0) {
      return {};
    }
    return {a + t0 * d, a + t1 * d};
  }
  for (const HalfSpace& h : window) {
    std::vector<dem::Vec3> out;
    const std::size_t n = polygon.size();
    for (std::size_t k = 0; k < n; ++k) {
      const dem::Vec3 a = polygon[k];
      const dem::Vec3 b = polygon[(k + 1) % n];
      const double da = dem::dot(h.normal, a) - h.offset;
      const double db = dem::dot(h.normal, b) - h.offset;
      if (da <= 0) {
        out.push_back(a);
      }
      if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
        out.push_back(a + (da / (da - db)) * (b - a));
      }
    }
    polygon = out;
    if (polygon.size() < 2) {
      return {};
    }
  }
  return polygon;
}

// Total area (3D polygons) or length (2D segments) of a mesh inside the window.
inline double measureInWindow(const cracks::CrackMesh& mesh, const std::vector<HalfSpace>& window,
                              bool segments,
                              const std::vector<int>* keepPolygonsWithSize = nullptr) {
  double total = 0.0;
  const auto& list = segments ? mesh.lines : mesh.polygons;
  const cracks::AttributeArray* inconsistent = mesh.findCellData("inconsistent");
  const std::size_t base = mesh.vertices.size() + (segments ? 0 : mesh.lines.size());
  for (std::size_t k = 0; k < list.size(); ++k) {
    if (inconsistent != nullptr && inconsistent->values[base + k] != 0.0) {
      continue;
    }
    std::vector<dem::Vec3> polygon;
    for (auto i = list.offsets[k]; i < list.offsets[k + 1]; ++i) {
      polygon.push_back(
          mesh.points[static_cast<std::size_t>(list.connectivity[static_cast<std::size_t>(i)])]);
    }
    if (keepPolygonsWithSize != nullptr &&
        std::find(keepPolygonsWithSize->begin(), keepPolygonsWithSize->end(),
                  static_cast<int>(polygon.size())) == keepPolygonsWithSize->end()) {
      continue;
    }
    const auto clipped = clipToWindow(polygon, window);
    if (segments) {
      total += clipped.size() == 2 ? dem::norm(clipped[1] - clipped[0]) : 0.0;
    } else if (clipped.size() >= 3) {
      std::vector<std::int32_t> ids(clipped.size());
      for (std::size_t i = 0; i < ids.size(); ++i) {
        ids[i] = static_cast<std::int32_t>(i);
      }
      total += cracks::polygonArea(clipped, ids.data(), ids.size());
    }
  }
  return total;
}

// A square prism of half-width w around the axis through `centre` along `axis`.
inline std::vector<HalfSpace> prismWindow(dem::Vec3 centre, dem::Vec3 axis, double w) {
  const dem::Vec3 n = (1.0 / dem::norm(axis)) * axis;
  const dem::Vec3 helper = std::abs(n.x) < 0.9 ? dem::Vec3{1, 0, 0} : dem::Vec3{0, 1, 0};
  dem::Vec3 u = cracks::cross(n, helper);
  u = (1.0 / dem::norm(u)) * u;
  const dem::Vec3 v = cracks::cross(n, u);
  return {{u, dem::dot(u, centre) + w},
          {-1.0 * u, -dem::dot(u, centre) + w},
          {v, dem::dot(v, centre) + w},
          {-1.0 * v, -dem::dot(v, centre) + w}};
}

// Keeps the primitives whose polygon has one of the given sizes (to measure
// triangle cuts and quad cuts apart).
inline cracks::CrackMesh polygonsOfSize(const cracks::CrackMesh& mesh, int size) {
  cracks::CrackMesh out;
  out.dimension = mesh.dimension;
  out.points = mesh.points;
  for (std::size_t k = 0; k < mesh.polygons.size(); ++k) {
    if (mesh.polygons.offsets[k + 1] - mesh.polygons.offsets[k] == size) {
      out.polygons.addRange(mesh.polygons.connectivity.begin() + mesh.polygons.offsets[k],
                            mesh.polygons.connectivity.begin() + mesh.polygons.offsets[k + 1]);
    }
  }
  return out;
}

}  // namespace crackvis::testing
