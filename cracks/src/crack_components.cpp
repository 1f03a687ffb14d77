#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <unordered_map>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::cracks {

namespace {

// The smallest eigenvalue from the trigonometric solution of the
// characteristic cubic (Smith 1961), and its eigenvector as the longest cross
// product of two rows of (a - lambda I). Empty where the two smallest
// eigenvalues are too close for that vector to be accurate (a line-like or
// round component, a multiple of I): Jacobi's rotations decide those.
std::optional<Vec3> closedFormSmallest(const Matrix3& a) {
  const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
  const double q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
  const double d0 = a[0][0] - q;
  const double d1 = a[1][1] - q;
  const double d2 = a[2][2] - q;
  const double p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
  if (!(p2 > 0.0) || !std::isfinite(p2)) {
    return std::nullopt;
  }
  const double p = std::sqrt(p2 / 6.0);
  // det((a - qI) / p) / 2
  const double b00 = d0 / p, b11 = d1 / p, b22 = d2 / p;
  const double b01 = a[0][1] / p, b02 = a[0][2] / p, b12 = a[1][2] / p;
  const double r = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) +
                          b02 * (b01 * b12 - b11 * b02));
  const double phi = std::acos(std::clamp(r, -1.0, 1.0)) / 3.0;
  const double largest = q + 2.0 * p * std::cos(phi);
  const double smallest = q + 2.0 * p * std::cos(phi + 2.0 * std::numbers::pi / 3.0);
  const double middle = 3.0 * q - largest - smallest;
  if (!(middle - smallest > 1e-6 * (largest - smallest))) {
    return std::nullopt;
  }
  const Vec3 r0{a[0][0] - smallest, a[0][1], a[0][2]};
  const Vec3 r1{a[1][0], a[1][1] - smallest, a[1][2]};
  const Vec3 r2{a[2][0], a[2][1], a[2][2] - smallest};
  Vec3 best = cross(r0, r1);
  for (const Vec3 c : {cross(r0, r2), cross(r1, r2)}) {
    if (dem::dot(c, c) > dem::dot(best, best)) {
      best = c;
    }
  }
  const double length = dem::norm(best);
  if (!(length > 0.0) || !std::isfinite(length)) {
    return std::nullopt;
  }
  return (1.0 / length) * best;
}

}  // namespace

// In closed form where that is accurate (a component's covariance is nearly
// always flat: one small eigenvalue well below the others), else cyclic
// Jacobi rotations: a few sweeps reach machine precision at this size.
Vec3 smallestEigenvector(Matrix3 a) {
  if (const std::optional<Vec3> closed = closedFormSmallest(a)) {
    return *closed;
  }
  Matrix3 v{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (int sweep = 0; sweep < 32; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    if (off < 1e-30 * (a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2]) || off == 0.0) {
      break;
    }
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) {
          continue;
        }
        const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0);
        const double s = t * c;
        for (int k = 0; k < 3; ++k) {
          const double akp = a[k][p];
          const double akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[p][k];
          const double aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p];
          const double vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
    }
  }
  int smallest = 0;
  for (int k = 1; k < 3; ++k) {
    if (a[k][k] < a[smallest][smallest]) {
      smallest = k;
    }
  }
  return {v[0][smallest], v[1][smallest], v[2][smallest]};
}

namespace {

// Area-weighted first and second moments of a component's surface.
struct Moments {
  double area = 0.0;
  Vec3 first{};
  Matrix3 second{};
  Vec3 newell{};  // the polygons' summed area vectors (times 2)

  void addTriangle(Vec3 a, Vec3 b, Vec3 c) {
    const double weight = 0.5 * dem::norm(cross(b - a, c - a));
    addWeighted(weight, {a, b, c});
  }
  void addSegment(Vec3 a, Vec3 b) { addWeighted(dem::norm(b - a), {a, b}); }
  // A polygon as the fan of triangles from its first vertex; returns its
  // area as polygonArea gives it (Newell's sum of the same cross products).
  // Written out for the triangle, as every face of a crack passes here
  // each step.
  double addPolygon(const std::vector<Vec3>& points, const std::int32_t* ids, std::size_t count) {
    const Vec3 a = points[static_cast<std::size_t>(ids[0])];
    Vec3 polygonNewell{};
    for (std::size_t k = 1; k + 1 < count; ++k) {
      const Vec3 b = points[static_cast<std::size_t>(ids[k])];
      const Vec3 c = points[static_cast<std::size_t>(ids[k + 1])];
      const Vec3 n = cross(b - a, c - a);
      polygonNewell = polygonNewell + n;
      const double weight = 0.5 * dem::norm(n);
      if (weight <= 0.0) {
        continue;
      }
      const Vec3 s = a + b + c;
      area += weight;
      first = first + (weight / 3.0) * s;
      const double scale = weight / 12.0;
      auto entry = [&](double ai, double aj, double bi, double bj, double ci, double cj, double si,
                       double sj) { return scale * (ai * aj + bi * bj + ci * cj + si * sj); };
      const double xx = entry(a.x, a.x, b.x, b.x, c.x, c.x, s.x, s.x);
      const double yy = entry(a.y, a.y, b.y, b.y, c.y, c.y, s.y, s.y);
      const double zz = entry(a.z, a.z, b.z, b.z, c.z, c.z, s.z, s.z);
      const double xy = entry(a.x, a.y, b.x, b.y, c.x, c.y, s.x, s.y);
      const double xz = entry(a.x, a.z, b.x, b.z, c.x, c.z, s.x, s.z);
      const double yz = entry(a.y, a.z, b.y, b.z, c.y, c.z, s.y, s.z);
      second[0][0] += xx;
      second[1][1] += yy;
      second[2][2] += zz;
      second[0][1] += xy;
      second[1][0] += xy;
      second[0][2] += xz;
      second[2][0] += xz;
      second[1][2] += yz;
      second[2][1] += yz;
    }
    newell = newell + polygonNewell;
    return 0.5 * dem::norm(polygonNewell);
  }
  void addTetrahedron(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    addWeighted(std::abs(dem::dot(b - a, cross(c - a, d - a))) / 6.0, {a, b, c, d});
  }

  // Exact moments of a uniform simplex (segment, triangle, tetrahedron) of
  // measure w with n vertices summing to s: w/(n(n+1)) (sum v v^T + s s^T).
  void addWeighted(double weight, std::initializer_list<Vec3> vertices) {
    if (weight <= 0.0) {
      return;
    }
    Vec3 sum{};
    for (const Vec3& v : vertices) {
      sum = sum + v;
    }
    const double n = static_cast<double>(vertices.size());
    area += weight;
    first = first + (weight / n) * sum;
    auto add = [&](Vec3 u, double scale) {
      const double c[3] = {u.x, u.y, u.z};
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          second[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] += scale * c[i] * c[j];
        }
      }
    };
    const double scale = weight / (n * (n + 1.0));
    for (const Vec3& v : vertices) {
      add(v, scale);
    }
    add(sum, scale);
  }

  Vec3 centroid() const { return area > 0.0 ? (1.0 / area) * first : Vec3{}; }
  Matrix3 covariance() const {
    const Vec3 c = centroid();
    const double m[3] = {c.x, c.y, c.z};
    Matrix3 out{};
    for (std::size_t i = 0; i < 3; ++i) {
      for (std::size_t j = 0; j < 3; ++j) {
        out[i][j] = area > 0.0 ? second[i][j] / area - m[i] * m[j] : 0.0;
      }
    }
    return out;
  }
};

Vec3 bestFitNormal(const Moments& moments, int dimension) {
  Matrix3 c = moments.covariance();
  if (dimension == 2) {
    // The best-fit line in the xy plane: its normal is the in-plane
    // direction of least spread.
    c[2] = {0.0, 0.0, 0.0};
    c[0][2] = c[1][2] = 0.0;
    c[2][2] = std::numeric_limits<double>::max();
  }
  Vec3 n = smallestEigenvector(c);
  const double length = dem::norm(n);
  return length > 0.0 ? (1.0 / length) * n : Vec3{0.0, 0.0, 1.0};
}

void grow(dem::Bounds& box, Vec3 p, bool first) {
  if (first) {
    box = {p, p};
    return;
  }
  box.lo = {std::min(box.lo.x, p.x), std::min(box.lo.y, p.y), std::min(box.lo.z, p.z)};
  box.hi = {std::max(box.hi.x, p.x), std::max(box.hi.y, p.y), std::max(box.hi.z, p.z)};
}

// `box` grown to hold `other` too.
void grow(dem::Bounds& box, const dem::Bounds& other) {
  grow(box, other.lo, false);
  grow(box, other.hi, false);
}

// A square raster on a plane (or a line, ny = 1), in the plane's (u, w)
// coordinates.
class Raster {
 public:
  Raster(double u0, double w0, double u1, double w1, double cell, bool line)
      : m_u0(u0), m_w0(w0), m_cell(cell) {
    m_nu = std::max(1, static_cast<int>(std::ceil((u1 - u0) / cell)));
    m_nw = line ? 1 : std::max(1, static_cast<int>(std::ceil((w1 - w0) / cell)));
    m_cells.assign(static_cast<std::size_t>(m_nu) * static_cast<std::size_t>(m_nw), 0);
  }
  // Marks the cells whose centres lie in the triangle (a, b, c).
  void fillTriangle(std::array<double, 2> a, std::array<double, 2> b, std::array<double, 2> c) {
    auto edge = [](std::array<double, 2> p, std::array<double, 2> q, double u, double w) {
      return (q[0] - p[0]) * (w - p[1]) - (q[1] - p[1]) * (u - p[0]);
    };
    const int u0 = index(std::min({a[0], b[0], c[0]}), m_u0, m_nu);
    const int u1 = index(std::max({a[0], b[0], c[0]}), m_u0, m_nu);
    const int w0 = index(std::min({a[1], b[1], c[1]}), m_w0, m_nw);
    const int w1 = index(std::max({a[1], b[1], c[1]}), m_w0, m_nw);
    for (int iw = w0; iw <= w1; ++iw) {
      for (int iu = u0; iu <= u1; ++iu) {
        const double u = m_u0 + (iu + 0.5) * m_cell;
        const double w = m_w0 + (iw + 0.5) * m_cell;
        const double e0 = edge(a, b, u, w);
        const double e1 = edge(b, c, u, w);
        const double e2 = edge(c, a, u, w);
        if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) {
          m_cells[cellIndex(iu, iw)] = 1;
        }
      }
    }
  }
  // Marks the cells whose centres lie in [a, b] along u (a line raster).
  void fillInterval(double a, double b) {
    for (int iu = index(std::min(a, b), m_u0, m_nu); iu <= index(std::max(a, b), m_u0, m_nu);
         ++iu) {
      const double u = m_u0 + (iu + 0.5) * m_cell;
      if (u >= std::min(a, b) && u <= std::max(a, b)) {
        m_cells[cellIndex(iu, 0)] = 1;
      }
    }
  }
  const std::vector<char>& cells() const { return m_cells; }

 private:
  int index(double x, double origin, int count) const {
    return std::clamp(static_cast<int>(std::floor((x - origin) / m_cell)), 0, count - 1);
  }
  std::size_t cellIndex(int iu, int iw) const {
    return static_cast<std::size_t>(iw) * static_cast<std::size_t>(m_nu) +
           static_cast<std::size_t>(iu);
  }
  double m_u0;
  double m_w0;
  double m_cell;
  int m_nu = 1;
  int m_nw = 1;
  std::vector<char> m_cells;
};

using Point2 = std::array<double, 2>;

// Convex hull, counter-clockwise (Andrew's monotone chain).
std::vector<Point2> convexHull(std::vector<Point2> points) {
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) {
    return points;
  }
  auto turn = [](Point2 o, Point2 a, Point2 b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  std::vector<Point2> hull(2 * points.size());
  std::size_t k = 0;
  for (const Point2& p : points) {
    while (k >= 2 && turn(hull[k - 2], hull[k - 1], p) <= 0) {
      --k;
    }
    hull[k++] = p;
  }
  const std::size_t lower = k + 1;
  for (std::size_t i = points.size() - 1; i-- > 0;) {
    while (k >= lower && turn(hull[k - 2], hull[k - 1], points[i]) <= 0) {
      --k;
    }
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

// An orthonormal basis (u, w) of the plane with normal n.
std::pair<Vec3, Vec3> planeBasis(Vec3 n) {
  const Vec3 helper = std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  Vec3 u = cross(n, helper);
  u = (1.0 / dem::norm(u)) * u;
  return {u, cross(n, u)};
}

// Coordinates on a component's best-fit plane (3D) or along its best-fit
// line (2D, second coordinate 0), from its centroid.
class PlaneProjection {
 public:
  PlaneProjection(const CrackComponent& component, int dimension)
      : m_origin(component.centroid), m_line(dimension == 2) {
    const std::pair<Vec3, Vec3> basis = planeBasis(component.normal);
    // In 2D the line's direction is n x z.
    m_u = m_line ? Vec3{-component.normal.y, component.normal.x, 0.0} : basis.first;
    m_w = basis.second;
  }
  bool line() const { return m_line; }
  Point2 operator()(Vec3 p) const {
    const Vec3 d = p - m_origin;
    return {dem::dot(d, m_u), m_line ? 0.0 : dem::dot(d, m_w)};
  }

 private:
  Vec3 m_origin;
  bool m_line;
  Vec3 m_u;
  Vec3 m_w;
};

// The faces of a cell of the cell attribute method, as local node indices
// (VTK order; -1 pads): 2D triangles' edges, tetrahedra's and pyramids'
// faces. A cell's projection onto a plane is the union of its faces'.
using Face = std::array<int, 4>;
std::span<const Face> cellFaces(std::size_t nodes) {
  static constexpr std::array<Face, 3> kTriangle{{{0, 1, -1, -1}, {1, 2, -1, -1}, {2, 0, -1, -1}}};
  static constexpr std::array<Face, 4> kTetrahedron{
      {{0, 1, 2, -1}, {0, 1, 3, -1}, {0, 2, 3, -1}, {1, 2, 3, -1}}};
  static constexpr std::array<Face, 5> kPyramid{
      {{0, 1, 2, 3}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}}};
  switch (nodes) {
    case 3:
      return kTriangle;
    case 4:
      return kTetrahedron;
    case 5:
      return kPyramid;
    default:
      return {};
  }
}

// The primitives components are made of: a surface's polygons (3D) or lines
// (2D); a cell mesh's volume cells (3D) or triangles (2D).
const PrimitiveList& componentList(const CrackMesh& mesh) {
  if (mesh.holdsCells()) {
    return mesh.dimension == 2 ? mesh.polygons : mesh.volumeCells;
  }
  return mesh.dimension == 2 ? mesh.lines : mesh.polygons;
}
PrimitiveList& componentList(CrackMesh& mesh) {
  return const_cast<PrimitiveList&>(componentList(std::as_const(mesh)));
}

// Marks what primitive k of componentList(mesh) covers in projection.
void paintPrimitive(Raster& raster, const CrackMesh& mesh, std::size_t k,
                    const PlaneProjection& project) {
  const PrimitiveList& list = componentList(mesh);
  const std::int32_t* ids = list.connectivity.data() + list.offsets[k];
  const auto count = static_cast<std::size_t>(list.offsets[k + 1] - list.offsets[k]);
  auto at = [&](std::size_t v) { return project(mesh.points[static_cast<std::size_t>(ids[v])]); };
  if (mesh.holdsCells() && project.line()) {  // a 2D cell: the interval of its corners
    double lo = at(0)[0];
    double hi = lo;
    for (std::size_t v = 1; v < count; ++v) {
      lo = std::min(lo, at(v)[0]);
      hi = std::max(hi, at(v)[0]);
    }
    raster.fillInterval(lo, hi);
  } else if (mesh.holdsCells()) {
    for (const Face& face : cellFaces(count)) {
      const std::size_t corners = face[3] < 0 ? 3 : 4;
      for (std::size_t t = 1; t + 1 < corners; ++t) {
        raster.fillTriangle(at(static_cast<std::size_t>(face[0])),
                            at(static_cast<std::size_t>(face[t])),
                            at(static_cast<std::size_t>(face[t + 1])));
      }
    }
  } else if (project.line()) {
    for (std::size_t v = 0; v + 1 < count; ++v) {
      raster.fillInterval(at(v)[0], at(v + 1)[0]);
    }
  } else {
    for (std::size_t v = 1; v + 1 < count; ++v) {
      raster.fillTriangle(at(0), at(v), at(v + 1));
    }
  }
}

std::size_t countMarked(const std::vector<char>& cells) {
  return static_cast<std::size_t>(std::count(cells.begin(), cells.end(), char{1}));
}

// A sort key of an area, largest first: non-negative doubles order as their
// bit patterns, so the key runs down from that of infinity (an area is never
// negative; NaN last).
std::uint64_t largestFirstKey(double area) {
  constexpr std::uint64_t kInfinity = 0x7FF0000000000000ull;
  if (std::isnan(area)) {
    return kInfinity + 1;
  }
  return kInfinity - std::bit_cast<std::uint64_t>(area > 0.0 ? area : 0.0);
}

// The indices of `found`, largest area first, equal areas in their order of
// appearance: a stable radix sort of the keys, a byte at a time, skipping the
// bytes all keys share. A scattered crack has thousands of components, and a
// comparison sort of them was a fifth of the tracker's summing on cuboid A.
std::vector<std::int32_t> largestFirst(const std::vector<CrackComponent>& found) {
  const std::size_t n = found.size();
  std::vector<std::uint64_t> key(n);
  std::vector<std::int32_t> order(n);
  for (std::size_t c = 0; c < n; ++c) {
    key[c] = largestFirstKey(found[c].area);
    order[c] = static_cast<std::int32_t>(c);
  }
  std::vector<std::uint64_t> keyOut(n);
  std::vector<std::int32_t> orderOut(n);
  for (int shift = 0; shift < 64; shift += 8) {
    std::array<std::size_t, 257> start{};
    for (const std::uint64_t k : key) {
      ++start[((k >> shift) & 0xFF) + 1];
    }
    if (std::find(start.begin() + 1, start.end(), n) != start.end()) {
      continue;  // every key has the same byte here: the order stands
    }
    for (std::size_t b = 1; b < start.size(); ++b) {
      start[b] += start[b - 1];
    }
    for (std::size_t c = 0; c < n; ++c) {
      const std::size_t at = start[(key[c] >> shift) & 0xFF]++;
      keyOut[at] = key[c];
      orderOut[at] = order[c];
    }
    key.swap(keyOut);
    order.swap(orderOut);
  }
  return order;
}

// Numbers components largest first (ties by first appearance, so the order
// is deterministic) and relabels the primitives.
void sortLargestFirst(std::vector<CrackComponent>& found, CrackComponents& set) {
  const std::vector<std::int32_t> order = largestFirst(found);
  std::vector<std::int32_t> rank(found.size());
  set.components.reserve(found.size());
  for (std::size_t r = 0; r < order.size(); ++r) {
    rank[static_cast<std::size_t>(order[r])] = static_cast<std::int32_t>(r);
    set.components.push_back(found[static_cast<std::size_t>(order[r])]);
  }
  for (std::int32_t& c : set.ofPrimitive) {
    c = c < 0 ? c : rank[static_cast<std::size_t>(c)];
  }
}

// The best-fit plane of a component of one primitive, without the
// eigenvectors (most components of scattered damage are single faces): a
// segment's line (2D), a polygon's plane by Newell's normal, which is that
// plane for a planar polygon.
Vec3 singleNormal(const Moments& moments, const Primitive& primitive, const CrackMesh& mesh) {
  if (primitive.count == 2) {
    const Vec3 d = mesh.points[static_cast<std::size_t>(primitive.ids[1])] -
                   mesh.points[static_cast<std::size_t>(primitive.ids[0])];
    const double length = std::hypot(d.x, d.y);
    if (length > 0.0) {
      return {-d.y / length, d.x / length, 0.0};
    }
  } else if (const double length = dem::norm(moments.newell); length > 0.0) {
    return (1.0 / length) * moments.newell;
  }
  return bestFitNormal(moments, mesh.dimension);
}

// Adds a surface primitive to a component's moments; returns its area (a
// segment's length, a polygon's Newell area).
double addPrimitive(Moments& moments, const CrackMesh& mesh, const Primitive& primitive) {
  if (primitive.count == 2) {
    moments.addSegment(mesh.points[static_cast<std::size_t>(primitive.ids[0])],
                       mesh.points[static_cast<std::size_t>(primitive.ids[1])]);
    return measure(mesh, primitive);
  }
  return moments.addPolygon(mesh.points, primitive.ids, primitive.count);
}

// A component's plane from its summed moments: of one primitive its own,
// else the best fit.
Vec3 planeOf(const Moments& moments, std::size_t primitives, const Primitive& first,
             const CrackMesh& mesh) {
  return primitives == 1 ? singleNormal(moments, first, mesh)
                         : bestFitNormal(moments, mesh.dimension);
}

// Primitives per block of the passes that run on all cores: each block a
// few tens of microseconds, so that a step's few thousand faces still split.
constexpr std::size_t kPrimitiveBlock = 1024;

// A primitive's own box, and its area and centroid where `shape`, reading
// its points once; an empty polygon has none. The area is measure()'s: the
// same Newell sum about the first point, in the same order.
PrimitiveExtent extentOf(const CrackMesh& mesh, const Primitive& primitive, bool shape = true) {
  PrimitiveExtent extent;
  if (primitive.count == 0) {
    return extent;
  }
  const Vec3 origin = mesh.points[static_cast<std::size_t>(primitive.ids[0])];
  extent.box = {origin, origin};
  if (!shape) {
    for (std::size_t v = 1; v < primitive.count; ++v) {
      grow(extent.box, mesh.points[static_cast<std::size_t>(primitive.ids[v])], false);
    }
    return extent;
  }
  Vec3 sum = Vec3{} + origin;
  Vec3 newell{};
  Vec3 previous{};  // the last point less the origin
  for (std::size_t v = 1; v < primitive.count; ++v) {
    const Vec3 p = mesh.points[static_cast<std::size_t>(primitive.ids[v])];
    grow(extent.box, p, false);
    sum = sum + p;
    const Vec3 offset = p - origin;
    if (v >= 2) {
      newell = newell + cross(previous, offset);
    }
    previous = offset;
  }
  extent.centroid = (1.0 / static_cast<double>(primitive.count)) * sum;
  extent.area = primitive.count == 2 ? dem::norm(previous) : 0.5 * dem::norm(newell);
  return extent;
}

}  // namespace

PrimitiveExtent measureExtent(const CrackMesh& mesh, const Primitive& primitive) {
  return extentOf(mesh, primitive);
}

namespace {

// Every primitive's extent into `extents`, on all cores, and the box of
// all their points (none without a point): minima and maxima, the same in
// any order.
std::optional<dem::Bounds> measureExtents(const CrackMesh& mesh,
                                          std::span<const Primitive> primitives,
                                          std::vector<PrimitiveExtent>& extents,
                                          bool shape = true) {
  extents.resize(primitives.size());
  using Box = std::optional<dem::Bounds>;
  const auto merge = [](Box a, const Box& b) {
    if (!a || !b) {
      return a ? a : b;
    }
    grow(*a, *b);
    return a;
  };
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, primitives.size(), kPrimitiveBlock), Box{},
      [&](const auto& range, Box box) {
        dem::Bounds own;
        bool any = false;
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
          extents[k] = extentOf(mesh, primitives[k], shape);
          if (primitives[k].count > 0) {
            if (any) {
              grow(own, extents[k].box);
            } else {
              own = extents[k].box;
            }
            any = true;
          }
        }
        return any ? merge(box, own) : box;
      },
      merge);
}

// The components of a surface whose primitives are already grouped: each
// primitive's group (< groupCount) names its component. Components are
// numbered in order of first appearance, then summed up: every one's
// primitives, area and box, and with ComponentDetail::kEvery its centroid
// and plane. Without planes, each primitive's box and area (`extents`, in
// primitive order: ComponentTracker::measureAndWeld's) are summed in
// primitive order: the same sums as one pass.
CrackComponents summariseSurface(const CrackMesh& mesh, std::span<const Primitive> primitives,
                                 const std::vector<std::int32_t>& groupOf, std::size_t groupCount,
                                 ComponentDetail detail,
                                 const std::vector<PrimitiveExtent>& extents) {
  const bool planes = detail == ComponentDetail::kEvery;
  CrackComponents set;
  set.planes = planes;
  set.ofPrimitive.assign(componentList(mesh).size(), -1);
  std::vector<std::int32_t> label(groupCount, -1);
  std::vector<Moments> moments;
  std::vector<CrackComponent> found;
  std::vector<Primitive> singles;  // each component's first primitive
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    const Primitive& primitive = primitives[k];
    const auto group = static_cast<std::size_t>(groupOf[k]);
    if (label[group] < 0) {
      label[group] = static_cast<std::int32_t>(found.size());
      found.emplace_back();
      if (planes) {
        moments.emplace_back();
        singles.push_back(primitive);
      }
    }
    const auto c = static_cast<std::size_t>(label[group]);
    set.ofPrimitive[primitive.index] = label[group];
    CrackComponent& component = found[c];
    ++component.primitives;
    if (primitive.count == 0) {
      continue;  // an empty polygon: no point, no area
    }
    // The primitive's own box first: one merge per primitive, not per point.
    const dem::Bounds own = planes ? extentOf(mesh, primitive, false).box : extents[k].box;
    component.area += planes ? addPrimitive(moments[c], mesh, primitive) : extents[k].area;
    if (component.primitives == 1) {
      component.box = own;
    } else {
      grow(component.box, own);
    }
  }
  for (std::size_t c = 0; planes && c < found.size(); ++c) {
    found[c].centroid = moments[c].centroid();
    found[c].normal = planeOf(moments[c], found[c].primitives, singles[c], mesh);
  }
  sortLargestFirst(found, set);
  return set;
}

// dem::boundingBox of the points on all cores (minima and maxima: the same
// in any order).
dem::Bounds pointsBox(const std::vector<Vec3>& points) {
  if (points.empty()) {
    return dem::boundingBox(points);
  }
  constexpr std::size_t kPointBlock = 16384;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), kPointBlock),
      dem::Bounds{points.front(), points.front()},
      [&](const auto& range, dem::Bounds box) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
          grow(box, points[i], false);
        }
        return box;
      },
      [](dem::Bounds a, const dem::Bounds& b) {
        grow(a, b);
        return a;
      });
}

double weldTolerance(const CrackMesh& mesh) {
  const auto [lo, hi] = pointsBox(mesh.points);
  return 1e-9 * std::max(dem::norm(hi - lo), 1e-300);
}

CrackComponents surfaceComponents(const CrackMesh& mesh) {
  const std::vector<Primitive> primitives = surfacePrimitives(mesh);
  if (primitives.empty()) {
    CrackComponents set;
    set.ofPrimitive.assign(componentList(mesh).size(), -1);
    return set;
  }
  const std::vector<std::int32_t> welded = weld(mesh.points, weldTolerance(mesh));
  std::vector<std::int32_t> parent(
      static_cast<std::size_t>(*std::max_element(welded.begin(), welded.end())) + 1);
  std::iota(parent.begin(), parent.end(), 0);
  for (const Primitive& primitive : primitives) {
    const std::int32_t first = findRoot(parent, welded[static_cast<std::size_t>(primitive.ids[0])]);
    for (std::size_t k = 1; k < primitive.count; ++k) {
      const std::int32_t other =
          findRoot(parent, welded[static_cast<std::size_t>(primitive.ids[k])]);
      parent[static_cast<std::size_t>(other)] = findRoot(parent, first);
    }
  }
  std::vector<std::int32_t> groupOf(primitives.size());
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    groupOf[k] = findRoot(parent, welded[static_cast<std::size_t>(primitives[k].ids[0])]);
  }
  return summariseSurface(mesh, primitives, groupOf, parent.size(), ComponentDetail::kEvery, {});
}

// Cells sharing a face (3D: a triangle or quad; 2D: an edge) are one
// component: cells that only touch at a corner enclose no common crack.
std::vector<std::int32_t> joinCellsByFaces(const PrimitiveList& cells) {
  std::vector<std::pair<std::array<std::int32_t, 4>, std::int32_t>> faces;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const std::int32_t* ids = cells.connectivity.data() + cells.offsets[k];
    const auto count = static_cast<std::size_t>(cells.offsets[k + 1] - cells.offsets[k]);
    for (const Face& face : cellFaces(count)) {
      std::array<std::int32_t, 4> key{-1, -1, -1, -1};
      for (std::size_t v = 0; v < 4 && face[v] >= 0; ++v) {
        key[v] = ids[face[v]];
      }
      std::sort(key.begin(), key.end());
      faces.push_back({key, static_cast<std::int32_t>(k)});
    }
  }
  std::sort(faces.begin(), faces.end());
  std::vector<std::int32_t> parent(cells.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t f = 1; f < faces.size(); ++f) {
    if (faces[f].first == faces[f - 1].first) {
      parent[static_cast<std::size_t>(findRoot(parent, faces[f].second))] =
          findRoot(parent, faces[f - 1].second);
    }
  }
  return parent;
}

void addCellMoments(Moments& moments, const CrackMesh& mesh, const std::int32_t* ids,
                    std::size_t count) {
  auto point = [&](std::size_t v) { return mesh.points[static_cast<std::size_t>(ids[v])]; };
  if (count == 3) {
    moments.addTriangle(point(0), point(1), point(2));
  } else if (count == 4) {
    moments.addTetrahedron(point(0), point(1), point(2), point(3));
  } else if (count == 5) {  // a pyramid: two tetrahedra on its base's diagonal
    moments.addTetrahedron(point(0), point(1), point(2), point(4));
    moments.addTetrahedron(point(0), point(2), point(3), point(4));
  }
}

// The raster step for a cell mesh's areas: an eighth of its shortest cell
// edge (a quarter of the smallest radius where the edges join touching
// particles, the step sectionCoverage uses), and no finer than a 4096th of
// the mesh's extent, so coincident points cannot make the raster huge.
double cellRasterStep(const CrackMesh& mesh, const PrimitiveList& cells) {
  double shortest = std::numeric_limits<double>::max();
  for (std::size_t k = 0; k < cells.size(); ++k) {
    for (auto i = cells.offsets[k]; i < cells.offsets[k + 1]; ++i) {
      for (auto j = i + 1; j < cells.offsets[k + 1]; ++j) {
        const auto a = static_cast<std::size_t>(cells.connectivity[static_cast<std::size_t>(i)]);
        const auto b = static_cast<std::size_t>(cells.connectivity[static_cast<std::size_t>(j)]);
        shortest = std::min(shortest, dem::norm(mesh.points[a] - mesh.points[b]));
      }
    }
  }
  const auto [lo, hi] = dem::boundingBox(mesh.points);
  return std::max({shortest / 8.0, dem::norm(hi - lo) / 4096.0, 1e-300});
}

// A cell component's area: its cells projected onto its best-fit plane (2D:
// line), the crack they enclose, rasterised.
double projectedArea(const CrackMesh& mesh, const CrackComponent& component,
                     const std::vector<std::size_t>& members, double step) {
  const PlaneProjection project(component, mesh.dimension);
  const PrimitiveList& cells = componentList(mesh);
  double u0 = std::numeric_limits<double>::max();
  double u1 = -u0;
  double w0 = u0;
  double w1 = -u0;
  for (std::size_t k : members) {
    for (auto v = cells.offsets[k]; v < cells.offsets[k + 1]; ++v) {
      const auto point = static_cast<std::size_t>(cells.connectivity[static_cast<std::size_t>(v)]);
      const Point2 p = project(mesh.points[point]);
      u0 = std::min(u0, p[0]);
      u1 = std::max(u1, p[0]);
      w0 = std::min(w0, p[1]);
      w1 = std::max(w1, p[1]);
    }
  }
  Raster raster(u0, w0, u1, w1, step, project.line());
  for (std::size_t k : members) {
    paintPrimitive(raster, mesh, k, project);
  }
  const auto marked = static_cast<double>(countMarked(raster.cells()));
  return project.line() ? marked * step : marked * step * step;
}

CrackComponents cellComponents(const CrackMesh& mesh) {
  CrackComponents set;
  const PrimitiveList& cells = componentList(mesh);
  set.ofPrimitive.assign(cells.size(), -1);
  std::vector<std::int32_t> parent = joinCellsByFaces(cells);
  std::vector<CrackComponent> found;
  std::vector<Moments> moments;
  std::vector<std::vector<std::size_t>> members;
  std::vector<std::int32_t> label(cells.size(), -1);
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const auto root = static_cast<std::size_t>(findRoot(parent, static_cast<std::int32_t>(k)));
    if (label[root] < 0) {
      label[root] = static_cast<std::int32_t>(found.size());
      found.emplace_back();
      moments.emplace_back();
      members.emplace_back();
    }
    const auto c = static_cast<std::size_t>(label[root]);
    set.ofPrimitive[k] = label[root];
    members[c].push_back(k);
    const std::int32_t* ids = cells.connectivity.data() + cells.offsets[k];
    const auto count = static_cast<std::size_t>(cells.offsets[k + 1] - cells.offsets[k]);
    ++found[c].primitives;
    for (std::size_t v = 0; v < count; ++v) {
      grow(found[c].box, mesh.points[static_cast<std::size_t>(ids[v])],
           found[c].primitives == 1 && v == 0);
    }
    addCellMoments(moments[c], mesh, ids, count);
  }
  const double step = cellRasterStep(mesh, cells);
  for (std::size_t c = 0; c < found.size(); ++c) {
    found[c].centroid = moments[c].centroid();
    found[c].normal = bestFitNormal(moments[c], mesh.dimension);
    found[c].area = projectedArea(mesh, found[c], members[c], step);
  }
  sortLargestFirst(found, set);
  return set;
}

// The specimen's section by a component's plane (2D: line), in the plane's
// coordinates: the convex hull of the projected centres of the particles the
// plane cuts (a convex polygon, counter-clockwise), or in 2D the two ends of
// their interval along the line.
std::vector<Point2> specimenSection(std::span<const Vec3> positions, std::span<const double> radius,
                                    const CrackComponent& component,
                                    const PlaneProjection& project) {
  std::vector<Point2> cut;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const double r = radius[radius.size() == 1 ? 0 : k];
    if (std::abs(dem::dot(positions[k] - component.centroid, component.normal)) <= r) {
      cut.push_back(project(positions[k]));
    }
  }
  if (!project.line()) {
    return convexHull(std::move(cut));
  }
  if (cut.empty()) {
    return cut;
  }
  const auto [lo, hi] = std::minmax_element(cut.begin(), cut.end());
  return {*lo, *hi};
}

}  // namespace

std::size_t componentPrimitiveBase(const CrackMesh& mesh) {
  const std::size_t base = mesh.vertices.size();
  if (mesh.holdsCells()) {
    return base + mesh.lines.size() + (mesh.dimension == 2 ? 0 : mesh.polygons.size());
  }
  return base + (mesh.dimension == 2 ? 0 : mesh.lines.size());
}

CrackComponents findComponents(const CrackMesh& mesh) {
  return mesh.holdsCells() ? cellComponents(mesh) : surfaceComponents(mesh);
}

namespace {

using WeldKey = std::array<long long, 3>;

struct WeldKeyHash {
  std::size_t operator()(const WeldKey& k) const {
    std::uint64_t h = static_cast<std::uint64_t>(k[0]) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(k[1]) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(k[2]) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

// weld()'s key of a point: its cell of the grid of size `tolerance`.
WeldKey weldKey(Vec3 p, double tolerance) {
  return {std::llround(p.x / tolerance), std::llround(p.y / tolerance),
          std::llround(p.z / tolerance)};
}

// A coarse occupancy grid over a box: a point that welds to a marked point
// lies in a marked cell, so most points need no key and no hash lookup.
class CoarseMarks {
 public:
  CoarseMarks(dem::Bounds box, double margin) : m_lo(box.lo - Vec3{margin, margin, margin}) {
    const Vec3 size = box.hi - box.lo + Vec3{2 * margin, 2 * margin, 2 * margin};
    const double largest = std::max({size.x, size.y, size.z, 1e-300});
    m_perCell = kCells / largest;
    m_cells.assign(static_cast<std::size_t>(kCells) * kCells * kCells, 0);
  }
  // Marks the cells of the box [p - margin, p + margin].
  void mark(Vec3 p, double margin) {
    const std::array<int, 3> lo = cellOf(p - Vec3{margin, margin, margin});
    const std::array<int, 3> hi = cellOf(p + Vec3{margin, margin, margin});
    for (int x = lo[0]; x <= hi[0]; ++x) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int z = lo[2]; z <= hi[2]; ++z) {
          m_cells[index({x, y, z})] = 1;
        }
      }
    }
  }
  bool marked(Vec3 p) const { return m_cells[index(cellOf(p))] != 0; }

 private:
  static constexpr int kCells = 64;
  std::array<int, 3> cellOf(Vec3 p) const {
    // A product, not a quotient: every point of the crack passes here.
    // Clamped before the conversion: a point far outside the grid (an old
    // face's, tested because its box reaches the new faces') or NaN would
    // overflow an int.
    auto at = [&](double v) {
      const double c = v * m_perCell;
      return c >= 0.0 ? (c < kCells - 1 ? static_cast<int>(c) : kCells - 1) : 0;
    };
    return {at(p.x - m_lo.x), at(p.y - m_lo.y), at(p.z - m_lo.z)};
  }
  static std::size_t index(std::array<int, 3> c) {
    return (static_cast<std::size_t>(c[0]) * kCells + static_cast<std::size_t>(c[1])) * kCells +
           static_cast<std::size_t>(c[2]);
  }
  Vec3 m_lo;
  double m_perCell = 1.0;  // cells per metre
  std::vector<char> m_cells;
};

}  // namespace

void ComponentTracker::reset() {
  m_slotOfBond.clear();
  m_parent.clear();
  m_cellOfSlot.clear();
  m_seenAt.clear();
}

std::int32_t ComponentTracker::slotOf(std::size_t bond) {
  if (bond >= m_slotOfBond.size()) {
    m_slotOfBond.resize(std::max(bond + 1, 2 * m_slotOfBond.size()), -1);
  }
  std::int32_t& slot = m_slotOfBond[bond];
  if (slot < 0) {
    slot = static_cast<std::int32_t>(m_parent.size());
    m_parent.push_back(slot);
    m_cellOfSlot.push_back(-1);
    m_seenAt.push_back(0);
  }
  return slot;
}

void ComponentTracker::unite(std::int32_t a, std::int32_t b) {
  a = findRoot(m_parent, a);
  b = findRoot(m_parent, b);
  m_parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
}

// Every face's extent (m_extents: box, area and centroid with kAreas; with
// kEvery only the boxes the search below needs), and the faces of the slots
// from `oldSlots` on, new this step, welded: to each other through a hash of
// their points' weld keys, and to an old face where one of its points has a
// key of theirs. The weld tolerance is 1e-9 of the box of the primitives'
// points, which the extents' pass gives for the faces: reading every point
// of the mesh again for it was a tenth of the tracker's step on cuboid A. The old faces are then
// searched on all cores: a face whose box lies beyond the new faces' by more than a key's cell is
// turned away by six comparisons, and the coarse marks spare most points of the rest the key and
// the lookup. Each block keeps the pairs it finds; they are united after, and the components a set
// of unions makes do not depend on their order.
void ComponentTracker::measureAndWeld(const CrackMesh& mesh, std::span<const Primitive> primitives,
                                      const std::vector<std::int32_t>& slots,
                                      std::int32_t oldSlots) {
  // Areas only where summariseSurface reads them; kEvery sums its moments.
  const bool areas = m_detail == ComponentDetail::kAreas;
  const bool welding = static_cast<std::int32_t>(m_parent.size()) != oldSlots;
  if (!welding && !areas) {
    return;
  }
  std::optional<dem::Bounds> faces = measureExtents(mesh, primitives, m_extents, areas);
  if (!welding || !faces) {
    return;
  }
  // The other primitives' points too (few: a 3D mesh's inconsistency
  // lines, end to end between particle centres, reach beyond the faces),
  // so that the tolerance is findComponents' wherever every point of the
  // mesh is some primitive's.
  for (const std::vector<std::int32_t>* ids : {&mesh.lines.connectivity, &mesh.vertices}) {
    for (const std::int32_t id : *ids) {
      grow(*faces, mesh.points[static_cast<std::size_t>(id)], false);
    }
  }
  const double tolerance = 1e-9 * std::max(dem::norm(faces->hi - faces->lo), 1e-300);
  std::unordered_map<WeldKey, std::int32_t, WeldKeyHash> newKeys;
  dem::Bounds box;
  bool first = true;
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    if (slots[k] < oldSlots) {
      continue;
    }
    for (std::size_t v = 0; v < primitives[k].count; ++v) {
      const Vec3 p = mesh.points[static_cast<std::size_t>(primitives[k].ids[v])];
      grow(box, p, first);
      first = false;
      const auto [at, inserted] = newKeys.try_emplace(weldKey(p, tolerance), slots[k]);
      if (!inserted) {
        unite(at->second, slots[k]);
      }
    }
  }
  if (oldSlots == 0 || first) {
    return;  // no old face, or the new ones have no point
  }
  const double margin = 2.0 * tolerance;
  CoarseMarks marks(box, margin);
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    for (std::size_t v = 0; slots[k] >= oldSlots && v < primitives[k].count; ++v) {
      marks.mark(mesh.points[static_cast<std::size_t>(primitives[k].ids[v])], margin);
    }
  }
  const Vec3 reachLo = box.lo - Vec3{margin, margin, margin};
  const Vec3 reachHi = box.hi + Vec3{margin, margin, margin};
  auto reaches = [&](const dem::Bounds& b) {
    return b.hi.x >= reachLo.x && b.lo.x <= reachHi.x && b.hi.y >= reachLo.y &&
           b.lo.y <= reachHi.y && b.hi.z >= reachLo.z && b.lo.z <= reachHi.z;
  };
  using Weld = std::pair<std::int32_t, std::int32_t>;
  tbb::enumerable_thread_specific<std::vector<Weld>> found;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, primitives.size(), kPrimitiveBlock),
      [&](const auto& range) {
        std::vector<Weld>& welds = found.local();
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
          const Primitive& primitive = primitives[k];
          if (slots[k] >= oldSlots || primitive.count == 0 || !reaches(m_extents[k].box)) {
            continue;
          }
          for (std::size_t v = 0; v < primitive.count; ++v) {
            const Vec3 p = mesh.points[static_cast<std::size_t>(primitive.ids[v])];
            if (!marks.marked(p)) {
              continue;
            }
            const auto at = newKeys.find(weldKey(p, tolerance));
            if (at != newKeys.end()) {
              welds.emplace_back(at->second, slots[k]);
            }
          }
        }
      });
  for (const std::vector<Weld>& welds : found) {
    for (const auto& [a, b] : welds) {
      unite(a, b);
    }
  }
}

const CrackComponents& ComponentTracker::update(const CrackMesh& mesh, bool carried) {
  // Only a surface that may be kept needs them here; findComponents makes its own.
  const bool keepable = carried && !mesh.holdsCells();
  return update(mesh, carried, keepable ? surfacePrimitives(mesh) : std::vector<Primitive>());
}

const CrackComponents& ComponentTracker::update(const CrackMesh& mesh, bool carried,
                                                std::span<const Primitive> primitives) {
  if (carried && !mesh.holdsCells() && updateCarried(mesh, primitives)) {
    return m_components;
  }
  reset();
  m_components = findComponents(mesh);
  ++m_recomputations;
  return m_components;
}

// False where the mesh is not one whose components can be kept (the
// caller then finds them anew).
bool ComponentTracker::updateCarried(const CrackMesh& mesh, std::span<const Primitive> primitives) {
  const AttributeArray* bondIds = mesh.findCellData("bond_id");
  if (bondIds == nullptr) {
    return false;
  }
  const std::size_t base = componentPrimitiveBase(mesh);
  const auto oldSlots = static_cast<std::int32_t>(m_parent.size());
  ++m_stamp;
  std::size_t oldSeen = 0;
  std::vector<std::int32_t> groupOf(primitives.size());
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    const std::size_t cell = base + primitives[k].index;
    const double id = cell < bondIds->values.size() ? bondIds->values[cell] : -1.0;
    if (!(id >= 0.0 && id < 2147483647.0 && id == std::floor(id))) {
      return false;
    }
    const std::int32_t slot = slotOf(static_cast<std::size_t>(id));
    const auto s = static_cast<std::size_t>(slot);
    if (m_seenAt[s] == m_stamp) {
      if (m_cellOfSlot[s] != static_cast<std::int64_t>(primitives[k].index)) {
        return false;  // a bond with two cells: its faces need not touch
      }
    } else {
      m_seenAt[s] = m_stamp;
      m_cellOfSlot[s] = static_cast<std::int64_t>(primitives[k].index);
      oldSeen += slot < oldSlots ? 1 : 0;
    }
    groupOf[k] = slot;
  }
  if (oldSeen != static_cast<std::size_t>(oldSlots)) {
    return false;  // a face left: a bond healed, or the viewer went back
  }
  measureAndWeld(mesh, primitives, groupOf, oldSlots);
  for (std::int32_t& group : groupOf) {
    group = findRoot(m_parent, group);
  }
  m_components = summariseSurface(mesh, primitives, groupOf, m_parent.size(), m_detail, m_extents);
  return true;
}

double sectionCoverage(const CrackMesh& mesh, const CrackComponents& set, std::size_t c,
                       std::span<const Vec3> positions, std::span<const double> radius) {
  if (c >= set.components.size() || positions.empty() || radius.empty() ||
      (radius.size() != 1 && radius.size() != positions.size())) {
    return 0.0;
  }
  const CrackComponent& component = set.components[c];
  const PlaneProjection project(component, mesh.dimension);
  const std::vector<Point2> section = specimenSection(positions, radius, component, project);
  if (section.size() < (project.line() ? 2u : 3u)) {
    return 0.0;
  }
  double u0 = section[0][0];
  double u1 = u0;
  double w0 = section[0][1];
  double w1 = w0;
  for (const Point2& p : section) {
    u0 = std::min(u0, p[0]);
    u1 = std::max(u1, p[0]);
    w0 = std::min(w0, p[1]);
    w1 = std::max(w1, p[1]);
  }
  const double cell = 0.25 * *std::min_element(radius.begin(), radius.end());
  Raster specimen(u0, w0, u1, w1, cell, project.line());
  Raster crack(u0, w0, u1, w1, cell, project.line());
  if (project.line()) {
    specimen.fillInterval(u0, u1);
  } else {
    for (std::size_t k = 1; k + 1 < section.size(); ++k) {
      specimen.fillTriangle(section[0], section[k], section[k + 1]);
    }
  }
  for (std::size_t k = 0; k < set.ofPrimitive.size(); ++k) {
    if (set.ofPrimitive[k] == static_cast<std::int32_t>(c)) {
      paintPrimitive(crack, mesh, k, project);
    }
  }
  std::size_t inside = 0;
  std::size_t covered = 0;
  for (std::size_t k = 0; k < specimen.cells().size(); ++k) {
    if (specimen.cells()[k] != 0) {
      ++inside;
      covered += crack.cells()[k] != 0 ? 1 : 0;
    }
  }
  return inside == 0 ? 0.0 : static_cast<double>(covered) / static_cast<double>(inside);
}

double sectionCoverage(const CrackMesh& mesh, const CrackComponents& set, std::size_t c,
                       const StepInput& step) {
  const bool reference = step.referencePositions.size() == step.positions.size();
  return sectionCoverage(mesh, set, c, reference ? step.referencePositions : step.positions,
                         step.radius);
}

ComponentPlane componentPlane(const CrackMesh& mesh, const CrackComponents& set, std::size_t c) {
  if (c >= set.components.size()) {
    return {};
  }
  if (set.planes || mesh.holdsCells()) {
    return {set.components[c].centroid, set.components[c].normal};
  }
  // The moments summariseSurface sums, over the same primitives in its order.
  Moments moments;
  std::size_t count = 0;
  Primitive single{};
  for (const Primitive& primitive : surfacePrimitives(mesh)) {
    if (primitive.index >= set.ofPrimitive.size() ||
        set.ofPrimitive[primitive.index] != static_cast<std::int32_t>(c)) {
      continue;
    }
    single = count++ == 0 ? primitive : single;
    addPrimitive(moments, mesh, primitive);
  }
  if (count == 0) {
    return {};
  }
  return {moments.centroid(), planeOf(moments, count, single, mesh)};
}

void keepComponents(CrackMesh& mesh, const CrackComponents& set, const ComponentFilter& filter) {
  if (!filter.active()) {
    return;
  }
  std::vector<char> keepComponent(set.components.size(), 0);
  for (std::size_t c = 0; c < set.components.size(); ++c) {
    const bool bigEnough = set.components[c].area >= filter.minArea;
    const bool amongLargest = filter.largest <= 0 || c < static_cast<std::size_t>(filter.largest);
    keepComponent[c] = bigEnough && amongLargest ? 1 : 0;
  }
  PrimitiveList& list = componentList(mesh);
  const bool volumeCells = &list == &mesh.volumeCells;
  const std::size_t base = componentPrimitiveBase(mesh);
  std::vector<char> keepPrimitive(mesh.primitiveCount(), 1);
  PrimitiveList kept;
  std::vector<std::uint8_t> keptTypes;
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::int32_t c = set.ofPrimitive[k];
    const bool keep = c < 0 || keepComponent[static_cast<std::size_t>(c)] != 0;
    keepPrimitive[base + k] = keep ? 1 : 0;
    if (keep) {
      kept.addRange(list.connectivity.begin() + list.offsets[k],
                    list.connectivity.begin() + list.offsets[k + 1]);
      if (volumeCells) {
        keptTypes.push_back(mesh.volumeCellTypes[k]);
      }
    }
  }
  list = std::move(kept);
  if (volumeCells) {
    mesh.volumeCellTypes = std::move(keptTypes);
  }
  for (AttributeArray& array : mesh.cellData) {
    std::vector<double> values;
    const auto width = static_cast<std::size_t>(array.components);
    for (std::size_t p = 0; p < keepPrimitive.size(); ++p) {
      if (keepPrimitive[p] != 0) {
        values.insert(values.end(), array.values.begin() + static_cast<std::ptrdiff_t>(p * width),
                      array.values.begin() + static_cast<std::ptrdiff_t>((p + 1) * width));
      }
    }
    array.values = std::move(values);
  }
}

}  // namespace crackvis::cracks
