#include <algorithm>
#include <array>
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

// Sorts keys (depth bits << 32 | index, made in index order) by their depth
// bits: a stable LSD radix sort, four passes of 8 bits, so equal depths keep
// the index order std::sort of the whole key would give. At 1e6 spheres per
// frame it is several times faster than std::sort (docs/benchmarks.md).
void sortByDepth(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& scratch) {
  scratch.resize(keys.size());
  for (int shift = 32; shift < 64; shift += 8) {
    std::array<std::size_t, 257> start{};
    for (const std::uint64_t key : keys) {
      ++start[((key >> shift) & 0xffu) + 1];
    }
    if (start[1 + ((keys.empty() ? 0 : keys.front() >> shift) & 0xffu)] == keys.size()) {
      continue;  // one bucket: this byte orders nothing
    }
    for (std::size_t b = 1; b < start.size(); ++b) {
      start[b] += start[b - 1];
    }
    for (const std::uint64_t key : keys) {
      scratch[start[(key >> shift) & 0xffu]++] = key;
    }
    keys.swap(scratch);
  }
}

}  // namespace

double SphereOcclusion::project(const OcclusionView& view, const SphereSet& spheres) {
  m_view = view;
  m_spheres = spheres;
  const std::size_t n = spheres.radius.size();
  m_projected.resize(n);
  double largest = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    largest = projectOne(i, largest);
  }
  return largest;
}

double SphereOcclusion::projectOne(std::size_t i, double largest) {
  const OcclusionView& view = m_view;
  const SphereSet& spheres = m_spheres;
  const std::array<double, 3> c{spheres.x[i], spheres.y[i], spheres.z[i]};
  const double r = spheres.radius[i];
  const double diameter = spriteDiameter(c, r, view.parallel, view.rayScale);
  Projected& p = m_projected[i];
  p = Projected{};
  p.front = -c[2] - r;
  if (std::isinf(diameter)) {
    p.half = diameter;  // the GPU decides
    return diameter;
  }
  if (!(diameter > 0.0) || !(r > 0.0)) {
    return largest;  // behind the eye or nothing: no pixel
  }
  const double depth = -c[2];
  p.u = ((view.parallel ? c[0] : c[0] / depth) - view.rayOffset[0]) / view.rayScale[0];
  p.v = ((view.parallel ? c[1] : c[1] / depth) - view.rayOffset[1]) / view.rayScale[1];
  // The pixel centres (k + 0.5) the point covers, with a pixel to spare.
  p.half = 0.5 * diameter + 1.0;
  p.inView = p.u + p.half >= 0.5 && p.u - p.half <= view.width - 0.5 && p.v + p.half >= 0.5 &&
             p.v - p.half <= view.height - 0.5;
  return p.inView ? std::max(largest, diameter) : largest;
}

SphereOcclusion::PixelBox SphereOcclusion::pixelsIn(double uLo, double uHi, double vLo,
                                                    double vHi) const {
  // The pixel centres (k + 0.5) inside [lo, hi] on each axis.
  return {std::max(0, static_cast<int>(std::ceil(uLo - 0.5))),
          std::min(m_view.width - 1, static_cast<int>(std::floor(uHi - 0.5))),
          std::max(0, static_cast<int>(std::ceil(vLo - 0.5))),
          std::min(m_view.height - 1, static_cast<int>(std::floor(vHi - 0.5)))};
}

SphereOcclusion::PixelBox SphereOcclusion::pixelsOf(const Projected& p) const {
  return pixelsIn(p.u - p.half, p.u + p.half, p.v - p.half, p.v + p.half);
}

bool SphereOcclusion::covered(const PixelBox& box, float limit) const {
  const int width = m_view.width;
  const int tilesX = (width + kTile - 1) / kTile;
  // Whole tiles first, pixels where a tile is not enough.
  for (int tj = box.j0 / kTile; tj <= box.j1 / kTile; ++tj) {
    for (int ti = box.i0 / kTile; ti <= box.i1 / kTile; ++ti) {
      if (m_tileFarthest[static_cast<std::size_t>(tj) * tilesX + ti] < limit) {
        continue;
      }
      for (int j = std::max(box.j0, tj * kTile); j <= std::min(box.j1, tj * kTile + kTile - 1);
           ++j) {
        const float* row = m_nearest.data() + static_cast<std::size_t>(j) * width;
        for (int k = std::max(box.i0, ti * kTile); k <= std::min(box.i1, ti * kTile + kTile - 1);
             ++k) {
          if (!(row[k] < limit)) {
            return false;
          }
        }
      }
    }
  }
  return true;
}

void SphereOcclusion::visit(std::size_t i, int guard) {
  const Projected& p = m_projected[i];
  const PixelBox box = pixelsOf(p);
  // Hidden when everything drawn under its point is nearer than its nearest
  // point.
  if (covered(box, static_cast<float>(p.front - kDepthMargin * std::abs(p.front)))) {
    return;
  }
  m_keep[i] = 1;
  drawSphere(i, box, guard);
}

void SphereOcclusion::drawSphere(std::size_t i, const PixelBox& box, int guard) {
  const OcclusionView& view = m_view;
  const SphereSet& spheres = m_spheres;
  const Projected& p = m_projected[i];
  const int width = view.width;
  const int height = view.height;
  const int tilesX = (width + kTile - 1) / kTile;
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
    return;
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
  for (int j = box.j0; j <= box.j1; ++j) {
    float* row = m_nearest.data() + static_cast<std::size_t>(j) * width;
    const auto qy = static_cast<float>((j + 0.5) * view.rayScale[1] + view.rayOffset[1]);
    // Ray o + t d with d.z = -1: t is a depth.
    const float oy = parallel * qy;
    const float dy = (1.0f - parallel) * qy;
    const float my = oy - fy;
    for (int k = box.i0; k <= box.i1; ++k) {
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
  for (int tj = box.j0 / kTile; tj <= box.j1 / kTile; ++tj) {
    for (int ti = box.i0 / kTile; ti <= box.i1 / kTile; ++ti) {
      float farthest = -std::numeric_limits<float>::infinity();
      for (int j = tj * kTile; j < std::min(height, tj * kTile + kTile); ++j) {
        const float* row = m_nearest.data() + static_cast<std::size_t>(j) * width;
        for (int k = ti * kTile; k < std::min(width, ti * kTile + kTile); ++k) {
          farthest = row[k] > farthest ? row[k] : farthest;
        }
      }
      m_tileFarthest[static_cast<std::size_t>(tj) * tilesX + ti] = farthest;
    }
  }
}

// Cells of a view-space grid front to back (SphereOcclusion's comment).
void SphereOcclusion::cellOrder(int guard) {
  // The grid: about 64 spheres to a cell over the box of the centres in view.
  double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double hi[3] = {-lo[0], -lo[1], -lo[2]};
  for (const std::uint64_t key : m_order) {
    const auto i = static_cast<std::size_t>(key & 0xffffffffu);
    const double c[3] = {m_spheres.x[i], m_spheres.y[i], m_spheres.z[i]};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a]);
      hi[a] = std::max(hi[a], c[a]);
    }
  }
  const double cells = std::max(1.0, static_cast<double>(m_order.size()) / 64.0);
  // A flat set (a 2D specimen seen face on) gets cells a thousandth of its
  // size deep, not a grid of millions of empty cells.
  const double widest = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
  double extent[3];
  double volume = 1.0;
  for (int a = 0; a < 3; ++a) {
    extent[a] = std::max(hi[a] - lo[a], 1e-3 * widest);
    volume *= extent[a];
  }
  const double side = std::cbrt(volume / cells);
  int count[3];
  for (int a = 0; a < 3; ++a) {
    count[a] = std::clamp(static_cast<int>(extent[a] / side) + 1, 1, 1024);
  }
  m_cells.assign(static_cast<std::size_t>(count[0]) * count[1] * count[2], Cell{});
  m_cellOf.resize(m_order.size());
  for (std::size_t k = 0; k < m_order.size(); ++k) {
    const auto i = static_cast<std::size_t>(m_order[k] & 0xffffffffu);
    const double c[3] = {m_spheres.x[i], m_spheres.y[i], m_spheres.z[i]};
    int at[3];
    for (int a = 0; a < 3; ++a) {
      at[a] = std::min(count[a] - 1, static_cast<int>((c[a] - lo[a]) / extent[a] * count[a]));
    }
    const auto id = static_cast<std::int32_t>((at[2] * count[1] + at[1]) * count[0] + at[0]);
    m_cellOf[k] = id;
    Cell& cell = m_cells[static_cast<std::size_t>(id)];
    const Projected& p = m_projected[i];
    // The same sums pixelsOf makes, so the union holds each sphere's pixels.
    cell.lo[0] = std::min(cell.lo[0], p.u - p.half);
    cell.hi[0] = std::max(cell.hi[0], p.u + p.half);
    cell.lo[1] = std::min(cell.lo[1], p.v - p.half);
    cell.hi[1] = std::max(cell.hi[1], p.v + p.half);
    cell.front = std::min(cell.front, static_cast<float>(p.front));
    ++cell.count;
  }
  // Each cell's pixels: the union of its spheres' (ceil and floor keep order).
  for (Cell& cell : m_cells) {
    if (cell.count > 0) {
      cell.box = pixelsIn(cell.lo[0], cell.hi[0], cell.lo[1], cell.hi[1]);
    }
  }
  // The spheres grouped by cell (counting sort, index order kept within).
  std::int32_t start = 0;
  for (Cell& cell : m_cells) {
    cell.first = start;
    start += cell.count;
    cell.count = 0;
  }
  m_cellSpheres.resize(m_order.size());
  for (std::size_t k = 0; k < m_order.size(); ++k) {
    Cell& cell = m_cells[static_cast<std::size_t>(m_cellOf[k])];
    m_cellSpheres[static_cast<std::size_t>(cell.first + cell.count++)] =
        static_cast<std::int32_t>(m_order[k] & 0xffffffffu);
  }
  m_cellOrder.clear();
  for (std::size_t c = 0; c < m_cells.size(); ++c) {
    if (m_cells[c].count > 0) {
      m_cellOrder.push_back(static_cast<std::int32_t>(c));
    }
  }
  std::sort(m_cellOrder.begin(), m_cellOrder.end(), [&](std::int32_t a, std::int32_t b) {
    const float fa = m_cells[static_cast<std::size_t>(a)].front;
    const float fb = m_cells[static_cast<std::size_t>(b)].front;
    return fa < fb || (fa == fb && a < b);
  });
  for (const std::int32_t c : m_cellOrder) {
    const Cell& cell = m_cells[static_cast<std::size_t>(c)];
    // A cell hidden whole: every sphere in it is nearer-bounded by its front.
    if (covered(cell.box, cell.front - static_cast<float>(kDepthMargin) * std::abs(cell.front))) {
      continue;
    }
    const auto first = m_cellSpheres.begin() + cell.first;
    std::sort(first, first + cell.count, [&](std::int32_t a, std::int32_t b) {
      const double fa = m_projected[static_cast<std::size_t>(a)].front;
      const double fb = m_projected[static_cast<std::size_t>(b)].front;
      return fa < fb || (fa == fb && a < b);
    });
    for (auto it = first; it != first + cell.count; ++it) {
      visit(static_cast<std::size_t>(*it), guard);
    }
  }
}

const std::vector<std::int32_t>& SphereOcclusion::unoccluded(int guard) {
  const std::size_t n = m_projected.size();
  const int tilesX = (m_view.width + kTile - 1) / kTile;
  const int tilesY = (m_view.height + kTile - 1) / kTile;
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
  m_nearest.assign(static_cast<std::size_t>(m_view.width) * static_cast<std::size_t>(m_view.height),
                   std::numeric_limits<float>::infinity());
  m_tileFarthest.assign(static_cast<std::size_t>(tilesX) * static_cast<std::size_t>(tilesY),
                        std::numeric_limits<float>::infinity());
  if (m_order.size() >= m_cellThreshold) {
    cellOrder(guard);
  } else {
    sortByDepth(m_order, m_orderScratch);  // front to back by the nearest point
    for (const std::uint64_t key : m_order) {
      visit(static_cast<std::size_t>(key & 0xffffffffu), guard);
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
