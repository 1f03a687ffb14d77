#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "surface_primitives.hpp"
#include <crackvis/cracks/crack_components.hpp>

namespace crackvis::cracks {
namespace {

using Matrix3 = std::array<std::array<double, 3>, 3>;

// Eigenvector of the smallest eigenvalue of a symmetric 3x3 matrix (cyclic
// Jacobi rotations: a few sweeps reach machine precision at this size).
Vec3 smallestEigenvector(Matrix3 a) {
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

// Area-weighted first and second moments of a component's surface.
struct Moments {
  double area = 0.0;
  Vec3 first{};
  Matrix3 second{};

  void addTriangle(Vec3 a, Vec3 b, Vec3 c) {
    const double weight = 0.5 * dem::norm(cross(b - a, c - a));
    addWeighted(weight, {a, b, c});
  }
  void addSegment(Vec3 a, Vec3 b) { addWeighted(dem::norm(b - a), {a, b}); }

  // Exact moments of a uniform triangle or segment of measure w, s the sum
  // of its vertices: triangle w/12 (sum v v^T + s s^T), segment
  // w/6 (a a^T + b b^T + s s^T).
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
    if (n == 3) {
      for (const Vec3& v : vertices) {
        add(v, weight / 12.0);
      }
      add(sum, weight / 12.0);
    } else {
      for (const Vec3& v : vertices) {
        add(v, weight / 6.0);
      }
      add(sum, weight / 6.0);
    }
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

}  // namespace

CrackComponents findComponents(const CrackMesh& mesh) {
  CrackComponents set;
  const std::size_t surfaceCount = mesh.dimension == 2 ? mesh.lines.size() : mesh.polygons.size();
  set.ofPrimitive.assign(surfaceCount, -1);
  const std::vector<Primitive> primitives = surfacePrimitives(mesh);
  if (primitives.empty()) {
    return set;
  }
  const auto [lo, hi] = dem::boundingBox(mesh.points);
  const std::vector<std::int32_t> welded =
      weld(mesh.points, 1e-9 * std::max(dem::norm(hi - lo), 1e-300));
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
  // Components numbered in order of first appearance, then summed up.
  std::vector<std::int32_t> label(parent.size(), -1);
  std::vector<Moments> moments;
  std::vector<CrackComponent> found;
  for (const Primitive& primitive : primitives) {
    const auto root = static_cast<std::size_t>(
        findRoot(parent, welded[static_cast<std::size_t>(primitive.ids[0])]));
    if (label[root] < 0) {
      label[root] = static_cast<std::int32_t>(found.size());
      found.emplace_back();
      moments.emplace_back();
    }
    const auto c = static_cast<std::size_t>(label[root]);
    set.ofPrimitive[primitive.index] = label[root];
    auto point = [&](std::size_t k) {
      return mesh.points[static_cast<std::size_t>(primitive.ids[k])];
    };
    ++found[c].primitives;
    found[c].area += measure(mesh, primitive);
    for (std::size_t k = 0; k < primitive.count; ++k) {
      grow(found[c].box, point(k), found[c].primitives == 1 && k == 0);
    }
    if (primitive.count == 2) {
      moments[c].addSegment(point(0), point(1));
    } else {
      for (std::size_t k = 1; k + 1 < primitive.count; ++k) {
        moments[c].addTriangle(point(0), point(k), point(k + 1));
      }
    }
  }
  for (std::size_t c = 0; c < found.size(); ++c) {
    found[c].centroid = moments[c].centroid();
    found[c].normal = bestFitNormal(moments[c], mesh.dimension);
  }
  // Largest first (ties by first appearance, so the order is deterministic).
  std::vector<std::int32_t> order(found.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return found[static_cast<std::size_t>(a)].area > found[static_cast<std::size_t>(b)].area;
  });
  std::vector<std::int32_t> rank(found.size());
  for (std::size_t r = 0; r < order.size(); ++r) {
    rank[static_cast<std::size_t>(order[r])] = static_cast<std::int32_t>(r);
    set.components.push_back(found[static_cast<std::size_t>(order[r])]);
  }
  for (std::int32_t& c : set.ofPrimitive) {
    c = c < 0 ? c : rank[static_cast<std::size_t>(c)];
  }
  return set;
}

double sectionCoverage(const CrackMesh& mesh, const CrackComponents& set, std::size_t c,
                       std::span<const Vec3> positions, std::span<const double> radius) {
  if (c >= set.components.size() || positions.empty() || radius.empty()) {
    return 0.0;
  }
  const CrackComponent& component = set.components[c];
  const Vec3 n = component.normal;
  // Not a structured binding: lambdas below capture w (clang 14 cannot).
  const std::pair<Vec3, Vec3> basis = planeBasis(n);
  const Vec3 u = basis.first;
  const Vec3 w = basis.second;
  const bool line = mesh.dimension == 2;
  // In 2D the section is an interval along the line's direction, which is
  // n x z.
  const Vec3 along = line ? Vec3{-n.y, n.x, 0.0} : u;
  const auto [rmin, rmax] = std::minmax_element(radius.begin(), radius.end());
  std::vector<Point2> section;
  for (const Vec3& p : positions) {
    const Vec3 d = p - component.centroid;
    if (std::abs(dem::dot(d, n)) <= 2.0 * *rmax) {
      section.push_back({dem::dot(d, along), line ? 0.0 : dem::dot(d, w)});
    }
  }
  if (section.empty()) {
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
  const double cell = 0.25 * *rmin;
  Raster specimen(u0, w0, u1, w1, cell, line);
  Raster crack(u0, w0, u1, w1, cell, line);
  auto project = [&](std::int32_t id) -> Point2 {
    const Vec3 d = mesh.points[static_cast<std::size_t>(id)] - component.centroid;
    return {dem::dot(d, along), line ? 0.0 : dem::dot(d, w)};
  };
  if (line) {
    specimen.fillInterval(u0, u1);
  } else {
    const std::vector<Point2> hull = convexHull(section);
    for (std::size_t k = 1; k + 1 < hull.size(); ++k) {
      specimen.fillTriangle(hull[0], hull[k], hull[k + 1]);
    }
  }
  const auto& kind = line ? mesh.lines : mesh.polygons;
  for (std::size_t k = 0; k < kind.size(); ++k) {
    if (set.ofPrimitive[k] != static_cast<std::int32_t>(c)) {
      continue;
    }
    const auto first = static_cast<std::size_t>(kind.offsets[k]);
    const auto last = static_cast<std::size_t>(kind.offsets[k + 1]);
    if (line) {
      for (std::size_t s = first; s + 1 < last; ++s) {
        crack.fillInterval(project(kind.connectivity[s])[0], project(kind.connectivity[s + 1])[0]);
      }
      continue;
    }
    const Point2 a = project(kind.connectivity[first]);
    for (std::size_t v = first + 1; v + 1 < last; ++v) {
      crack.fillTriangle(a, project(kind.connectivity[v]), project(kind.connectivity[v + 1]));
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
  PrimitiveList& surface = mesh.dimension == 2 ? mesh.lines : mesh.polygons;
  const std::size_t base = mesh.vertices.size() + (mesh.dimension == 2 ? 0 : mesh.lines.size());
  std::vector<char> keepPrimitive(mesh.primitiveCount(), 1);
  PrimitiveList kept;
  for (std::size_t k = 0; k < surface.size(); ++k) {
    const std::int32_t c = set.ofPrimitive[k];
    const bool keep = c < 0 || keepComponent[static_cast<std::size_t>(c)] != 0;
    keepPrimitive[base + k] = keep ? 1 : 0;
    if (keep) {
      kept.addRange(surface.connectivity.begin() + surface.offsets[k],
                    surface.connectivity.begin() + surface.offsets[k + 1]);
    }
  }
  surface = std::move(kept);
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
