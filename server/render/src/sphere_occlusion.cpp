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

void SphereOcclusion::clearDepth() {
  const int tilesX = (m_view.width + kTile - 1) / kTile;
  const int tilesY = (m_view.height + kTile - 1) / kTile;
  m_nearest.assign(static_cast<std::size_t>(m_view.width) * static_cast<std::size_t>(m_view.height),
                   std::numeric_limits<float>::infinity());
  m_tileFarthest.assign(static_cast<std::size_t>(tilesX) * static_cast<std::size_t>(tilesY),
                        std::numeric_limits<float>::infinity());
}

const std::vector<std::int32_t>& SphereOcclusion::unoccluded(int guard) {
  const std::size_t n = m_projected.size();
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
  clearDepth();
  sortByDepth(m_order, m_orderScratch);  // front to back by the nearest point
  for (const std::uint64_t key : m_order) {
    visit(static_cast<std::size_t>(key & 0xffffffffu), guard);
  }
  m_visible.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (m_keep[i] != 0) {
      m_visible.push_back(static_cast<std::int32_t>(i));
    }
  }
  return m_visible;
}

ClipTest clipCentre(std::span<const ClipPlane> planes, const std::array<double, 3>& p) {
  ClipTest test;
  for (const ClipPlane& e : planes) {
    const double distance = e[0] * p[0] + e[1] * p[1] + e[2] * p[2] + e[3];
    const double tolerance = 1e-5 * (std::abs(e[0] * p[0]) + std::abs(e[1] * p[1]) +
                                     std::abs(e[2] * p[2]) + std::abs(e[3]));
    test.clipped = test.clipped || distance < -tolerance;
    test.nearPlane = test.nearPlane || distance <= tolerance;
  }
  return test;
}

void SphereCells::build(std::span<const double> xyz, std::span<const float> radius) {
  const std::size_t n = radius.size();
  m_cells.clear();
  m_index.resize(n);
  m_centre.resize(n);
  m_radius.resize(n);
  if (n == 0) {
    return;
  }
  auto at = [&](std::size_t i) {
    return std::array<double, 3>{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
  };
  // The grid: about 64 spheres to a cell over the box of the centres. A flat
  // set (a 2D specimen) gets cells a thousandth of its size deep, not a grid
  // of millions of empty cells.
  std::array<double, 3> lo = at(0);
  std::array<double, 3> hi = lo;
  for (std::size_t i = 1; i < n; ++i) {
    const auto c = at(i);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a]);
      hi[a] = std::max(hi[a], c[a]);
    }
  }
  const double widest = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
  std::array<double, 3> extent{};
  for (int a = 0; a < 3; ++a) {
    extent[a] = std::max(hi[a] - lo[a], 1e-3 * widest);
  }
  // The side of a cube of the box's volume over the cells, by cube roots of
  // each factor: the volume itself underflows for coinciding centres.
  const double side = std::cbrt(extent[0]) * std::cbrt(extent[1]) * std::cbrt(extent[2]) /
                      std::cbrt(std::max(1.0, static_cast<double>(n) / 64.0));
  std::array<int, 3> count{};
  for (int a = 0; a < 3; ++a) {
    const double cells = side > 0.0 ? extent[a] / side : 1.0;
    count[a] = std::clamp(static_cast<int>(std::min(cells, 1024.0)) + 1, 1, 1024);
  }
  std::vector<std::int32_t> cellOf(n);
  std::vector<std::int32_t> start(static_cast<std::size_t>(count[0]) * count[1] * count[2] + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = at(i);
    std::array<int, 3> k{};
    for (int a = 0; a < 3; ++a) {
      k[a] = std::clamp(static_cast<int>((c[a] - lo[a]) / extent[a] * count[a]), 0, count[a] - 1);
    }
    cellOf[i] = (k[2] * count[1] + k[1]) * count[0] + k[0];
    ++start[static_cast<std::size_t>(cellOf[i]) + 1];
  }
  for (std::size_t c = 1; c < start.size(); ++c) {
    start[c] += start[c - 1];
  }
  // Members in cell order (a counting sort: input order within a cell).
  std::vector<std::int32_t> next(start.begin(), start.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    const auto member = static_cast<std::size_t>(next[static_cast<std::size_t>(cellOf[i])]++);
    m_index[member] = static_cast<std::int32_t>(i);
    m_centre[member] = at(i);
    m_radius[member] = radius[i];
  }
  for (std::size_t c = 0; c + 1 < start.size(); ++c) {
    if (start[c + 1] == start[c]) {
      continue;
    }
    Cell cell;
    cell.first = start[c];
    cell.count = start[c + 1] - start[c];
    std::array<double, 3> cellLo = m_centre[static_cast<std::size_t>(cell.first)];
    std::array<double, 3> cellHi = cellLo;
    for (std::int32_t m = cell.first; m < cell.first + cell.count; ++m) {
      const auto& p = m_centre[static_cast<std::size_t>(m)];
      for (int a = 0; a < 3; ++a) {
        cellLo[a] = std::min(cellLo[a], p[a]);
        cellHi[a] = std::max(cellHi[a], p[a]);
      }
      cell.largestRadius = std::max(cell.largestRadius, m_radius[static_cast<std::size_t>(m)]);
    }
    for (int a = 0; a < 3; ++a) {
      cell.centre[a] = 0.5 * (cellLo[a] + cellHi[a]);
    }
    double spread2 = 0.0;
    for (std::int32_t m = cell.first; m < cell.first + cell.count; ++m) {
      const auto& p = m_centre[static_cast<std::size_t>(m)];
      const double dx = p[0] - cell.centre[0];
      const double dy = p[1] - cell.centre[1];
      const double dz = p[2] - cell.centre[2];
      spread2 = std::max(spread2, dx * dx + dy * dy + dz * dz);
    }
    // A hair more than the farthest centre: the bound must hold after rounding.
    cell.spread = std::sqrt(spread2) * (1.0 + 1e-9) + 1e-300;
    m_cells.push_back(cell);
  }
}

std::size_t SphereCells::memoryBytes() const {
  return m_cells.capacity() * sizeof(Cell) + m_index.capacity() * sizeof(std::int32_t) +
         m_centre.capacity() * sizeof(std::array<double, 3>) + m_radius.capacity() * sizeof(float);
}

namespace {

// The largest factor by which the 3x3 part of `rows` stretches a length
// (its columns' largest norm times sqrt 3 bounds it; exact for a rotation
// times a uniform scale, the cameras and actors VTK makes, up to the sqrt 3).
double stretchBound(const ModelToView& transform) {
  double largest = 0.0;
  for (int column = 0; column < 3; ++column) {
    double sum = 0.0;
    for (int row = 0; row < 3; ++row) {
      sum += transform.rows[row][column] * transform.rows[row][column];
    }
    largest = std::max(largest, sum);
  }
  // A rotation's columns are orthonormal: the stretch is the column norm.
  bool orthogonal = true;
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      double dot = 0.0;
      for (int row = 0; row < 3; ++row) {
        dot += transform.rows[row][a] * transform.rows[row][b];
      }
      orthogonal = orthogonal && std::abs(dot) <= 1e-9 * largest;
    }
  }
  return std::sqrt(largest) * (orthogonal ? 1.0 + 1e-9 : std::sqrt(3.0));
}

}  // namespace

double SphereOcclusion::projectCells(const OcclusionView& view, const SphereCells& cells,
                                     const ModelToView& transform, double pointLimit) {
  m_view = view;
  m_cellSet = &cells;
  m_planes.assign(transform.planes.begin(), transform.planes.end());
  m_transform = transform;
  m_transform.planes = m_planes;
  m_cellsInView.clear();
  m_x.clear();
  m_y.clear();
  m_z.clear();
  m_radius.clear();
  m_mayHide.clear();
  m_source.clear();
  m_projected.clear();
  const double stretch = stretchBound(transform);
  double largest = 0.0;
  const auto& all = cells.cells();
  for (std::size_t c = 0; c < all.size(); ++c) {
    const SphereCells::Cell& cell = all[c];
    CellInView inView;
    inView.cell = static_cast<std::int32_t>(c);
    // Cells every sphere of which a plane removes are left out; cells near a
    // plane test their spheres (clipCentre's tolerance, bounded over the cell).
    bool removed = false;
    for (const ClipPlane& e : m_planes) {
      const double distance =
          e[0] * cell.centre[0] + e[1] * cell.centre[1] + e[2] * cell.centre[2] + e[3];
      const double tolerance =
          1e-5 * (std::abs(e[0]) * (std::abs(cell.centre[0]) + cell.spread) +
                  std::abs(e[1]) * (std::abs(cell.centre[1]) + cell.spread) +
                  std::abs(e[2]) * (std::abs(cell.centre[2]) + cell.spread) + std::abs(e[3]));
      const double margin =
          std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) * cell.spread + tolerance;
      removed = removed || distance < -margin;
      inView.clip = distance <= margin ? Clip::kSome : inView.clip;
    }
    if (removed) {
      continue;
    }
    // The bounding sphere in view coordinates holds every sphere of the cell.
    const std::array<double, 3> centre = transform.apply(cell.centre);
    const double reach = stretch * cell.spread + cell.largestRadius;
    const double depth = -centre[2];
    if (!view.parallel && depth + reach <= 0.0) {
      continue;  // every centre behind the eye: no pixel (as projectOne)
    }
    const double diameter = view.parallel || depth - reach > 0.0
                                ? spriteDiameter(centre, reach, view.parallel, view.rayScale)
                                : std::numeric_limits<double>::infinity();
    // A sphere inside has its point centred within the bounding silhouette
    // and no wider than that silhouette: at most twice the bounding point.
    const double innerPoint = 2.0 * (diameter - 1.0) + 1.0;
    if (std::isinf(diameter) || innerPoint > pointLimit) {
      // The eye plane cuts it, or its spheres may be too wide for points:
      // its spheres one by one, projected now for the exact widest point.
      inView.open = true;
      inView.front = static_cast<float>(depth - reach);
      inView.first = static_cast<std::int32_t>(m_x.size());
      largest = appendCell(inView, largest);
      inView.count = static_cast<std::int32_t>(m_x.size()) - inView.first;
      if (inView.count > 0) {
        m_cellsInView.push_back(inView);
      }
      continue;
    }
    const double u =
        ((view.parallel ? centre[0] : centre[0] / depth) - view.rayOffset[0]) / view.rayScale[0];
    const double v =
        ((view.parallel ? centre[1] : centre[1] / depth) - view.rayOffset[1]) / view.rayScale[1];
    // In view when an inner sphere's point may reach the viewport (as
    // projectOne decides for each).
    const double half = 0.5 * diameter + 1.0;
    const double pointReach = half + 0.5 * innerPoint + 1.0;
    if (u + pointReach < 0.5 || u - pointReach > view.width - 0.5 || v + pointReach < 0.5 ||
        v - pointReach > view.height - 0.5) {
      continue;
    }
    // Hidden when the bounding silhouette's pixels (with one to spare) are.
    inView.box = pixelsIn(u - half, u + half, v - half, v + half);
    inView.front = static_cast<float>(depth - reach);
    largest = std::max(largest, innerPoint);
    m_cellsInView.push_back(inView);
  }
  return largest;
}

double SphereOcclusion::appendCell(const CellInView& cell, double largest) {
  const SphereCells::Cell& c = m_cellSet->cells()[static_cast<std::size_t>(cell.cell)];
  const auto first = m_x.size();
  for (std::int32_t m = c.first; m < c.first + c.count; ++m) {
    const auto member = static_cast<std::size_t>(m);
    const std::array<double, 3>& p = m_cellSet->centre(member);
    std::uint8_t mayHide = 1;
    if (cell.clip == Clip::kSome) {
      const ClipTest test = clipCentre(m_planes, p);
      if (test.clipped) {
        continue;
      }
      mayHide = test.nearPlane ? 0 : 1;
    }
    const std::array<double, 3> q = m_transform.apply(p);
    m_x.push_back(q[0]);
    m_y.push_back(q[1]);
    m_z.push_back(q[2]);
    m_radius.push_back(m_cellSet->radius(member));
    m_mayHide.push_back(mayHide);
    m_source.push_back(m_cellSet->index(member));
  }
  m_spheres = SphereSet{m_x, m_y, m_z, m_radius, m_mayHide};
  m_projected.resize(m_x.size());
  for (std::size_t i = first; i < m_x.size(); ++i) {
    largest = projectOne(i, largest);
  }
  return largest;
}

void SphereOcclusion::visitInOrder(std::int32_t first, std::int32_t count, int guard) {
  m_cellSpheres.clear();
  for (std::int32_t i = first; i < first + count; ++i) {
    const Projected& p = m_projected[static_cast<std::size_t>(i)];
    if (std::isinf(p.half)) {
      m_keep[static_cast<std::size_t>(i)] = 1;  // the GPU decides
    } else if (p.inView) {
      m_cellSpheres.push_back(i);
    }
  }
  std::sort(m_cellSpheres.begin(), m_cellSpheres.end(), [&](std::int32_t a, std::int32_t b) {
    const double fa = m_projected[static_cast<std::size_t>(a)].front;
    const double fb = m_projected[static_cast<std::size_t>(b)].front;
    return fa < fb || (fa == fb && a < b);
  });
  for (const std::int32_t i : m_cellSpheres) {
    visit(static_cast<std::size_t>(i), guard);
  }
}

const std::vector<std::int32_t>& SphereOcclusion::unoccludedInCells(int guard) {
  clearDepth();
  m_keep.assign(m_x.size(), 0);
  m_order.clear();
  for (std::size_t k = 0; k < m_cellsInView.size(); ++k) {
    m_order.push_back(static_cast<std::uint64_t>(orderedBits(m_cellsInView[k].front)) << 32 |
                      static_cast<std::uint32_t>(k));
  }
  sortByDepth(m_order, m_orderScratch);  // cells front to back
  for (const std::uint64_t key : m_order) {
    CellInView& cell = m_cellsInView[static_cast<std::size_t>(key & 0xffffffffu)];
    if (!cell.open) {
      // A cell hidden whole: every sphere in it lies behind its front.
      if (covered(cell.box, cell.front - static_cast<float>(kDepthMargin) * std::abs(cell.front))) {
        continue;
      }
      cell.first = static_cast<std::int32_t>(m_x.size());
      appendCell(cell, 0.0);
      cell.count = static_cast<std::int32_t>(m_x.size()) - cell.first;
      m_keep.resize(m_x.size(), 0);
    }
    visitInOrder(cell.first, cell.count, guard);
  }
  m_visible.clear();
  for (std::size_t i = 0; i < m_keep.size(); ++i) {
    if (m_keep[i] != 0) {
      m_visible.push_back(m_source[i]);
    }
  }
  std::sort(m_visible.begin(), m_visible.end());
  return m_visible;
}

const std::vector<std::int32_t>& SphereOcclusion::inViewCells() {
  // A mark per sphere and one ascending pass: no sort of up to every index.
  m_inView.assign(m_cellSet != nullptr ? m_cellSet->sphereCount() : 0, 0);
  for (const CellInView& cell : m_cellsInView) {
    if (cell.open) {  // projected already, clipped spheres left out
      for (std::int32_t i = cell.first; i < cell.first + cell.count; ++i) {
        m_inView[static_cast<std::size_t>(m_source[static_cast<std::size_t>(i)])] = 1;
      }
      continue;
    }
    const SphereCells::Cell& c = m_cellSet->cells()[static_cast<std::size_t>(cell.cell)];
    for (std::int32_t m = c.first; m < c.first + c.count; ++m) {
      const auto member = static_cast<std::size_t>(m);
      if (cell.clip == Clip::kSome && clipCentre(m_planes, m_cellSet->centre(member)).clipped) {
        continue;
      }
      m_inView[static_cast<std::size_t>(m_cellSet->index(member))] = 1;
    }
  }
  m_visible.clear();
  for (std::size_t i = 0; i < m_inView.size(); ++i) {
    if (m_inView[i] != 0) {
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
