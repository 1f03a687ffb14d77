#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include <crackvis/render/sphere_occlusion.hpp>

namespace crackvis::render {

double spriteDiameter(const std::array<double, 3>& centre, double radius, bool parallel,
                      const std::array<double, 2>& scale) {
  double hx = radius;
  double hy = radius;
  if (!parallel) {
    if (centre[2] >= 0.0) {
      return 0.0;
    }
    const double a = centre[2] * centre[2] - radius * radius;
    if (a <= 0.0) {
      return std::numeric_limits<double>::infinity();
    }
    // The touching planes through the eye and the y axis have x / -z = m +- s
    // with m = x |z| / a and s = r sqrt(x^2 + a) / a; the farther side from the
    // projected centre x / |z| is |m - x / |z|| + s.
    const double z = std::abs(centre[2]);
    const double cx = std::abs(centre[0]);
    const double cy = std::abs(centre[1]);
    hx = (cx * radius * radius / z + radius * std::sqrt(cx * cx + a)) / a;
    hy = (cy * radius * radius / z + radius * std::sqrt(cy * cy + a)) / a;
  }
  return std::max(2.0 * hx / std::abs(scale[0]), 2.0 * hy / std::abs(scale[1])) + 1.0;
}

namespace {

// Relative depth margin: far above float and 24-bit depth buffer precision,
// so that a sphere within it of what hides it is kept.
constexpr double kDepthMargin = 1e-4;
// A sphere hides others as one smaller by this fraction of its radius: the
// GPU's float arithmetic decides the pixels within about 1e-5 r of the rim.
constexpr double kRimMargin = 1e-3;
constexpr int kTile = 8;  // pixels; a tile keeps the farthest depth of its pixels

// Float bits that sort as the floats do, for a key of (depth, index).
std::uint32_t orderedBits(float value) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  return (bits & 0x80000000u) != 0 ? ~bits : bits | 0x80000000u;
}

}  // namespace

double SphereOcclusion::project(const OcclusionView& view, const SphereSet& spheres) {
  m_view = view;
  m_spheres = spheres;
  const std::size_t n = spheres.radius.size();
  m_projected.assign(n, Projected{});
  double largest = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::array<double, 3> c{spheres.x[i], spheres.y[i], spheres.z[i]};
    const double r = spheres.radius[i];
    const double diameter = spriteDiameter(c, r, view.parallel, view.rayScale);
    Projected& p = m_projected[i];
    p.front = -c[2] - r;
    if (std::isinf(diameter)) {
      largest = diameter;
      p.half = diameter;  // the GPU decides
      continue;
    }
    if (!(diameter > 0.0) || !(r > 0.0)) {
      continue;  // behind the eye or nothing: no pixel
    }
    const double depth = -c[2];
    p.u = ((view.parallel ? c[0] : c[0] / depth) - view.rayOffset[0]) / view.rayScale[0];
    p.v = ((view.parallel ? c[1] : c[1] / depth) - view.rayOffset[1]) / view.rayScale[1];
    // The pixel centres (k + 0.5) the point covers, with a pixel to spare.
    p.half = 0.5 * diameter + 1.0;
    p.inView = p.u + p.half >= 0.5 && p.u - p.half <= view.width - 0.5 && p.v + p.half >= 0.5 &&
               p.v - p.half <= view.height - 0.5;
    if (p.inView) {
      largest = std::max(largest, diameter);
    }
  }
  return largest;
}

const std::vector<std::int32_t>& SphereOcclusion::unoccluded(int guard) {
  const OcclusionView& view = m_view;
  const SphereSet& spheres = m_spheres;
  const std::size_t n = m_projected.size();
  const int width = view.width;
  const int height = view.height;
  const int tilesX = (width + kTile - 1) / kTile;
  const int tilesY = (height + kTile - 1) / kTile;
  m_keep.assign(n, 0);
  m_order.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const Projected& p = m_projected[i];
    if (std::isinf(p.half)) {
      m_keep[i] = 1;
    } else if (p.inView) {
      m_order.push_back(static_cast<std::uint64_t>(orderedBits(static_cast<float>(p.front))) << 32 |
                        static_cast<std::uint32_t>(i));
    }
  }
  // Front to back by the nearest point.
  std::sort(m_order.begin(), m_order.end());
  m_nearest.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height),
                   std::numeric_limits<float>::infinity());
  m_tileFarthest.assign(static_cast<std::size_t>(tilesX) * static_cast<std::size_t>(tilesY),
                        std::numeric_limits<float>::infinity());
  auto nearestRow = [&](int j) { return m_nearest.data() + static_cast<std::size_t>(j) * width; };

  for (const std::uint64_t key : m_order) {
    const auto i = static_cast<std::size_t>(key & 0xffffffffu);
    const Projected& p = m_projected[i];
    const int i0 = std::max(0, static_cast<int>(std::ceil(p.u - p.half - 0.5)));
    const int i1 = std::min(width - 1, static_cast<int>(std::floor(p.u + p.half - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::ceil(p.v - p.half - 0.5)));
    const int j1 = std::min(height - 1, static_cast<int>(std::floor(p.v + p.half - 0.5)));
    // Hidden when everything drawn under its point is nearer than its
    // nearest point: whole tiles first, pixels where a tile is not enough.
    const auto limit = static_cast<float>(p.front - kDepthMargin * std::abs(p.front));
    bool hidden = true;
    for (int tj = j0 / kTile; tj <= j1 / kTile && hidden; ++tj) {
      for (int ti = i0 / kTile; ti <= i1 / kTile && hidden; ++ti) {
        if (m_tileFarthest[static_cast<std::size_t>(tj) * tilesX + ti] < limit) {
          continue;
        }
        for (int j = std::max(j0, tj * kTile); j <= std::min(j1, tj * kTile + kTile - 1) && hidden;
             ++j) {
          const float* row = nearestRow(j);
          for (int k = std::max(i0, ti * kTile); k <= std::min(i1, ti * kTile + kTile - 1); ++k) {
            if (!(row[k] < limit)) {
              hidden = false;
              break;
            }
          }
        }
      }
    }
    if (hidden) {
      continue;
    }
    m_keep[i] = 1;
    // Only a sphere drawn whole hides: inside the clipping range, its centre
    // where GL draws its point.
    const double cx = spheres.x[i];
    const double cy = spheres.y[i];
    const double cz = spheres.z[i];
    const double r = spheres.radius[i];
    const double depth = -cz;
    if ((!spheres.mayHide.empty() && spheres.mayHide[i] == 0) || depth - r <= view.nearDepth ||
        depth + r >= view.farDepth || p.u < -guard || p.v < -guard || p.u > width + guard ||
        p.v > height + guard) {
      continue;
    }
    // A slightly smaller sphere, so that it covers no pixel the GPU's sphere
    // leaves out (nor one the geometry shader's billboard, a little smaller
    // than the silhouette in perspective, leaves out). Its depth at a pixel:
    // that of the ray's point nearest the centre, never nearer than the hit.
    const double shrink =
        view.parallel ? 1.0 : 1.0 / std::sqrt(1.0 + r * r / (cx * cx + cy * cy + cz * cz));
    const double rHide = r * shrink * (1.0 - kRimMargin);
    // In floats, to vectorize: rounding moves the rim by about 1e-6 r.
    const auto r2 = static_cast<float>(rHide * rHide);
    const auto scaleX = static_cast<float>(view.rayScale[0]);
    const auto offsetX = static_cast<float>(view.rayOffset[0]);
    const float parallel = view.parallel ? 1.0f : 0.0f;
    const auto fx = static_cast<float>(cx);
    const auto fy = static_cast<float>(cy);
    const auto fz = static_cast<float>(cz);
    for (int j = j0; j <= j1; ++j) {
      float* row = nearestRow(j);
      const auto qy = static_cast<float>((j + 0.5) * view.rayScale[1] + view.rayOffset[1]);
      // Ray o + t d with d.z = -1: t is a depth.
      const float oy = parallel * qy;
      const float dy = (1.0f - parallel) * qy;
      const float my = oy - fy;
      for (int k = i0; k <= i1; ++k) {
        const float qx = (static_cast<float>(k) + 0.5f) * scaleX + offsetX;
        const float ox = parallel * qx;
        const float dx = (1.0f - parallel) * qx;
        const float mx = ox - fx;
        const float mz = -fz;
        const float dd = dx * dx + dy * dy + 1.0f;
        const float closest = -(dx * mx + dy * my - mz) / dd;
        const float bx = mx + closest * dx;
        const float by = my + closest * dy;
        const float bz = mz - closest;
        const bool inside = bx * bx + by * by + bz * bz <= r2;
        row[k] = inside && closest < row[k] ? closest : row[k];
      }
    }
    for (int tj = j0 / kTile; tj <= j1 / kTile; ++tj) {
      for (int ti = i0 / kTile; ti <= i1 / kTile; ++ti) {
        float farthest = -std::numeric_limits<float>::infinity();
        for (int j = tj * kTile; j < std::min(height, tj * kTile + kTile); ++j) {
          const float* row = nearestRow(j);
          for (int k = ti * kTile; k < std::min(width, ti * kTile + kTile); ++k) {
            farthest = row[k] > farthest ? row[k] : farthest;
          }
        }
        m_tileFarthest[static_cast<std::size_t>(tj) * tilesX + ti] = farthest;
      }
    }
  }
  m_visible.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (m_keep[i] != 0) {
      m_visible.push_back(static_cast<std::int32_t>(i));
    }
  }
  return m_visible;
}

std::vector<std::int32_t> unoccludedSpheres(const OcclusionView& view, const SphereSet& spheres) {
  SphereOcclusion occlusion;
  occlusion.project(view, spheres);
  return occlusion.unoccluded(0);
}

}  // namespace crackvis::render
