// CGAL is used here alone, so its heavy headers are compiled once.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <vector>

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Regular_triangulation_2.h>
#include <CGAL/Regular_triangulation_3.h>
#include <CGAL/Regular_triangulation_vertex_base_2.h>
#include <CGAL/Regular_triangulation_vertex_base_3.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <fmt/format.h>

#include <crackvis/cracks/triangulation.hpp>

namespace crackvis::cracks {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Index = dem::ParticleIndex;

// Each cell and face carries one byte: whether it is peeled (peelHull).
using Mark = std::uint8_t;
using Delaunay3 = CGAL::Delaunay_triangulation_3<
    Kernel, CGAL::Triangulation_data_structure_3<
                CGAL::Triangulation_vertex_base_with_info_3<Index, Kernel>,
                CGAL::Triangulation_cell_base_with_info_3<
                    Mark, Kernel, CGAL::Delaunay_triangulation_cell_base_3<Kernel>>>>;
using Regular3 = CGAL::Regular_triangulation_3<
    Kernel, CGAL::Triangulation_data_structure_3<
                CGAL::Triangulation_vertex_base_with_info_3<
                    Index, Kernel, CGAL::Regular_triangulation_vertex_base_3<Kernel>>,
                CGAL::Triangulation_cell_base_with_info_3<
                    Mark, Kernel, CGAL::Regular_triangulation_cell_base_3<Kernel>>>>;
using Delaunay2 = CGAL::Delaunay_triangulation_2<
    Kernel,
    CGAL::Triangulation_data_structure_2<CGAL::Triangulation_vertex_base_with_info_2<Index, Kernel>,
                                         CGAL::Triangulation_face_base_with_info_2<Mark, Kernel>>>;
using Regular2 = CGAL::Regular_triangulation_2<
    Kernel, CGAL::Triangulation_data_structure_2<
                CGAL::Triangulation_vertex_base_with_info_2<
                    Index, Kernel, CGAL::Regular_triangulation_vertex_base_2<Kernel>>,
                CGAL::Triangulation_face_base_with_info_2<
                    Mark, Kernel, CGAL::Regular_triangulation_face_base_2<Kernel>>>>;

// The squared radius of the ball that holds every particle able to unmake
// the cell with these (point, weight) nodes: circumradius^2, or the power
// centre's power distance plus the largest weight.
double reachSquared(const std::array<Kernel::Point_3, 4>& p, const std::array<double, 4>& w,
                    int nodes, bool weighted, double largestWeight) {
  using Weighted = Kernel::Weighted_point_3;
  Kernel::Point_3 centre;
  if (nodes == 4) {
    centre = weighted ? Kernel().construct_weighted_circumcenter_3_object()(
                            Weighted(p[0], w[0]), Weighted(p[1], w[1]), Weighted(p[2], w[2]),
                            Weighted(p[3], w[3]))
                      : CGAL::circumcenter(p[0], p[1], p[2], p[3]);
  } else {
    const Kernel::Point_2 a(p[0].x(), p[0].y());
    const Kernel::Point_2 b(p[1].x(), p[1].y());
    const Kernel::Point_2 c(p[2].x(), p[2].y());
    using Weighted2 = Kernel::Weighted_point_2;
    const Kernel::Point_2 centre2 =
        weighted ? Kernel().construct_weighted_circumcenter_2_object()(
                       Weighted2(a, w[0]), Weighted2(b, w[1]), Weighted2(c, w[2]))
                 : CGAL::circumcenter(a, b, c);
    centre = Kernel::Point_3(centre2.x(), centre2.y(), 0.0);
  }
  double power = -std::numeric_limits<double>::infinity();
  for (int k = 0; k < nodes; ++k) {
    const auto at = static_cast<std::size_t>(k);
    power = std::max(power, CGAL::squared_distance(centre, p[at]) - (weighted ? w[at] : 0.0));
  }
  return power + (weighted ? largestWeight : 0.0);
}

template <typename T, typename Point>
T build(std::span<const dem::Vec3> positions, std::span<const double> radius, bool weighted) {
  std::vector<std::pair<Point, Index>> input;
  input.reserve(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const dem::Vec3 p = positions[i];
    if constexpr (std::is_same_v<Point, typename Kernel::Weighted_point_3>) {
      input.push_back(
          {Point({p.x, p.y, p.z}, weighted ? radius[i] * radius[i] : 0.0), static_cast<Index>(i)});
    } else if constexpr (std::is_same_v<Point, typename Kernel::Weighted_point_2>) {
      input.push_back(
          {Point({p.x, p.y}, weighted ? radius[i] * radius[i] : 0.0), static_cast<Index>(i)});
    } else if constexpr (std::is_same_v<Point, typename Kernel::Point_3>) {
      input.push_back({Point(p.x, p.y, p.z), static_cast<Index>(i)});
    } else {
      input.push_back({Point(p.x, p.y), static_cast<Index>(i)});
    }
  }
  // The range insertion sorts spatially first (Hilbert order): fast, and
  // the triangulation does not depend on the order anyway.
  return T(input.begin(), input.end());
}

void addEdge(Index a, Index b, std::vector<dem::Bond>& edges) {
  edges.push_back({std::min(a, b), std::max(a, b)});
}

const Kernel::Point_3& bare(const Kernel::Point_3& p) {
  return p;
}
const Kernel::Point_3& bare(const Kernel::Weighted_point_3& p) {
  return p.point();
}
const Kernel::Point_2& bare(const Kernel::Point_2& p) {
  return p;
}
const Kernel::Point_2& bare(const Kernel::Weighted_point_2& p) {
  return p.point();
}

template <typename CellHandle>
double quality3(CellHandle cell) {
  std::array<Kernel::Point_3, 4> p;
  for (int k = 0; k < 4; ++k) {
    p[static_cast<std::size_t>(k)] = bare(cell->vertex(k)->point());
  }
  std::array<double, 4> x{}, y{}, z{};
  for (std::size_t k = 0; k < 4; ++k) {
    x[k] = p[k].x();
    y[k] = p[k].y();
    z[k] = p[k].z();
  }
  return tetrahedronQuality(x, y, z);
}

template <typename FaceHandle>
double quality2(FaceHandle face) {
  std::array<double, 3> x{}, y{};
  for (int k = 0; k < 3; ++k) {
    const Kernel::Point_2& p = bare(face->vertex(k)->point());
    x[static_cast<std::size_t>(k)] = p.x();
    y[static_cast<std::size_t>(k)] = p.y();
  }
  return triangleQuality(x, y);
}

// Marks (info 1) the slivers reached from outside the hull through slivers,
// breadth first, and unmarks them all again when they are more than half
// the cells (a layer one particle thick is all slivers, and all it has).
// Works on cells (3D) and faces (2D) alike: `neighbours` is 4 or 3.
template <typename Handle, typename Quality, typename Finite>
void peel(const std::vector<Handle>& outer, int neighbours, std::size_t cellCount, Quality quality,
          Finite finite) {
  std::vector<Handle> peeled;
  auto consider = [&](Handle cell) {
    if (finite(cell) && cell->info() == 0 && quality(cell) < kSliverQuality) {
      cell->info() = 1;
      peeled.push_back(cell);
    }
  };
  for (Handle cell : outer) {
    consider(cell);
  }
  for (std::size_t next = 0; next < peeled.size(); ++next) {
    const Handle cell = peeled[next];
    for (int k = 0; k < neighbours; ++k) {
      consider(cell->neighbor(k));
    }
  }
  if (2 * peeled.size() > cellCount) {
    for (Handle cell : peeled) {
      cell->info() = 0;
    }
  }
}

template <typename Handle, typename Vertex>
std::array<Index, 4> sortedNodes(Handle cell, int count, Vertex vertex) {
  std::array<Index, 4> nodes{-1, -1, -1, -1};
  for (int k = 0; k < count; ++k) {
    nodes[static_cast<std::size_t>(k)] = vertex(cell, k);
  }
  std::sort(nodes.begin(), nodes.begin() + count);
  return nodes;
}

template <typename T>
void collect3(T& t, bool peelHull, Triangulation& out) {
  using Cell = typename T::Cell_handle;
  for (auto cell = t.all_cells_begin(); cell != t.all_cells_end(); ++cell) {
    cell->info() = 0;
  }
  if (peelHull && t.dimension() == 3) {
    // The cells outside the hull, then each one's finite neighbour.
    std::vector<Cell> outer;
    t.incident_cells(t.infinite_vertex(), std::back_inserter(outer));
    for (Cell& cell : outer) {
      cell = cell->neighbor(cell->index(t.infinite_vertex()));
    }
    peel(
        outer, 4, t.number_of_finite_cells(), [](Cell c) { return quality3(c); },
        [&](Cell c) { return !t.is_infinite(c); });
  }
  auto node = [](Cell cell, int k) { return cell->vertex(k)->info(); };
  for (auto cell = t.finite_cells_begin(); cell != t.finite_cells_end(); ++cell) {
    (cell->info() == 0 ? out.cells : out.peeled).push_back(sortedNodes(Cell(cell), 4, node));
  }
  for (auto edge = t.finite_edges_begin(); edge != t.finite_edges_end(); ++edge) {
    addEdge(edge->first->vertex(edge->second)->info(), edge->first->vertex(edge->third)->info(),
            out.edges);
  }
  out.hiddenParticles = out.hiddenParticles - t.number_of_vertices();
}

template <typename T>
void collect2(T& t, bool peelHull, Triangulation& out) {
  using Face = typename T::Face_handle;
  for (auto face = t.all_faces_begin(); face != t.all_faces_end(); ++face) {
    face->info() = 0;
  }
  if (peelHull && t.dimension() == 2) {
    std::vector<Face> outer;
    auto around = t.incident_faces(t.infinite_vertex());
    const auto start = around;
    do {
      outer.push_back(around->neighbor(around->index(t.infinite_vertex())));
    } while (++around != start);
    peel(
        outer, 3, t.number_of_faces(), [](Face f) { return quality2(f); },
        [&](Face f) { return !t.is_infinite(f); });
  }
  auto node = [](Face face, int k) { return face->vertex(k)->info(); };
  for (auto face = t.finite_faces_begin(); face != t.finite_faces_end(); ++face) {
    (face->info() == 0 ? out.cells : out.peeled).push_back(sortedNodes(Face(face), 3, node));
  }
  for (auto edge = t.finite_edges_begin(); edge != t.finite_edges_end(); ++edge) {
    const auto& face = edge->first;
    const int i = edge->second;
    addEdge(face->vertex(T::cw(i))->info(), face->vertex(T::ccw(i))->info(), out.edges);
  }
  out.hiddenParticles = out.hiddenParticles - t.number_of_vertices();
}

}  // namespace

bool needsRegularTriangulation(std::span<const double> radius) {
  if (radius.empty()) {
    return false;
  }
  const auto [lo, hi] = std::minmax_element(radius.begin(), radius.end());
  return *hi - *lo > 1e-9 * *hi;
}

std::vector<double> cellReach(const Triangulation& triangulation,
                              std::span<const dem::Vec3> positions, std::span<const double> radius,
                              double largestRadius) {
  const int nodes = triangulation.dimension == 3 ? 4 : 3;
  const bool weighted = triangulation.weighted && radius.size() == positions.size();
  std::vector<double> reach;
  reach.reserve(triangulation.cells.size());
  for (const auto& cell : triangulation.cells) {
    std::array<Kernel::Point_3, 4> p;
    std::array<double, 4> w{};
    for (int k = 0; k < nodes; ++k) {
      const auto at = static_cast<std::size_t>(k);
      const auto i = static_cast<std::size_t>(cell[at]);
      p[at] = Kernel::Point_3(positions[i].x, positions[i].y, positions[i].z);
      w[at] = weighted ? radius[i] * radius[i] : 0.0;
    }
    const double squared = reachSquared(p, w, nodes, weighted, largestRadius * largestRadius);
    // NaN (a flat cell's centre at infinity) fails the test: +infinity.
    reach.push_back(squared >= 0.0 && std::isfinite(squared)
                        ? std::sqrt(squared)
                        : (squared < 0.0 ? 0.0 : std::numeric_limits<double>::infinity()));
  }
  return reach;
}

double tetrahedronQuality(const std::array<double, 4>& x, const std::array<double, 4>& y,
                          const std::array<double, 4>& z) {
  const Kernel::Point_3 a(x[0], y[0], z[0]);
  const Kernel::Point_3 b(x[1], y[1], z[1]);
  const Kernel::Point_3 c(x[2], y[2], z[2]);
  const Kernel::Point_3 d(x[3], y[3], z[3]);
  const double squares = CGAL::squared_distance(a, b) + CGAL::squared_distance(a, c) +
                         CGAL::squared_distance(a, d) + CGAL::squared_distance(b, c) +
                         CGAL::squared_distance(b, d) + CGAL::squared_distance(c, d);
  const double rms = std::sqrt(squares / 6.0);
  return rms > 0.0 ? 6.0 * std::sqrt(2.0) * std::abs(CGAL::volume(a, b, c, d)) / (rms * rms * rms)
                   : 0.0;
}

double triangleQuality(const std::array<double, 3>& x, const std::array<double, 3>& y) {
  const double twiceArea = std::abs((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]));
  double squares = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    const std::size_t next = (k + 1) % 3;
    squares += (x[next] - x[k]) * (x[next] - x[k]) + (y[next] - y[k]) * (y[next] - y[k]);
  }
  return squares > 0.0 ? 2.0 * std::sqrt(3.0) * twiceArea / squares : 0.0;
}

Result<Triangulation> triangulate(std::span<const dem::Vec3> positions,
                                  std::span<const double> radius, int dimension,
                                  const TriangulateOptions& options) {
  Triangulation out;
  out.dimension = dimension;
  out.weighted = options.weighted.value_or(needsRegularTriangulation(radius));
  out.hiddenParticles = positions.size();
  if (dimension == 3) {
    if (out.weighted) {
      auto t = build<Regular3, Kernel::Weighted_point_3>(positions, radius, true);
      collect3(t, options.peelHull, out);
    } else {
      auto t = build<Delaunay3, Kernel::Point_3>(positions, radius, false);
      if (t.dimension() < 3) {
        return failedPrecondition(fmt::format(
            "cannot triangulate {} particle centres: they are all in one plane", positions.size()));
      }
      collect3(t, options.peelHull, out);
    }
  } else {
    if (out.weighted) {
      auto t = build<Regular2, Kernel::Weighted_point_2>(positions, radius, true);
      collect2(t, options.peelHull, out);
    } else {
      auto t = build<Delaunay2, Kernel::Point_2>(positions, radius, false);
      if (t.dimension() < 2) {
        return failedPrecondition(fmt::format(
            "cannot triangulate {} particle centres: they are all on one line", positions.size()));
      }
      collect2(t, options.peelHull, out);
    }
  }
  if (out.cells.empty()) {
    return failedPrecondition(fmt::format(
        "cannot triangulate {} particle centres: no cell (too few particles, or all in one {})",
        positions.size(), dimension == 3 ? "plane" : "line"));
  }
  std::sort(out.cells.begin(), out.cells.end());
  std::sort(out.peeled.begin(), out.peeled.end());
  std::sort(out.edges.begin(), out.edges.end(), [](dem::Bond a, dem::Bond b) {
    return a.first != b.first ? a.first < b.first : a.second < b.second;
  });
  return out;
}

}  // namespace crackvis::cracks
