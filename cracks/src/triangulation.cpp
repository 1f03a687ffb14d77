// CGAL is used here alone, so its heavy headers are compiled once.
#include <algorithm>
#include <cmath>
#include <limits>

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Regular_triangulation_2.h>
#include <CGAL/Regular_triangulation_3.h>
#include <CGAL/Regular_triangulation_vertex_base_2.h>
#include <CGAL/Regular_triangulation_vertex_base_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <fmt/format.h>

#include <crackvis/cracks/triangulation.hpp>

namespace crackvis::cracks {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Index = dem::ParticleIndex;

using Delaunay3 =
    CGAL::Delaunay_triangulation_3<Kernel,
                                   CGAL::Triangulation_data_structure_3<
                                       CGAL::Triangulation_vertex_base_with_info_3<Index, Kernel>>>;
using Regular3 = CGAL::Regular_triangulation_3<
    Kernel, CGAL::Triangulation_data_structure_3<
                CGAL::Triangulation_vertex_base_with_info_3<
                    Index, Kernel, CGAL::Regular_triangulation_vertex_base_3<Kernel>>,
                CGAL::Regular_triangulation_cell_base_3<Kernel>>>;
using Delaunay2 =
    CGAL::Delaunay_triangulation_2<Kernel,
                                   CGAL::Triangulation_data_structure_2<
                                       CGAL::Triangulation_vertex_base_with_info_2<Index, Kernel>>>;
using Regular2 = CGAL::Regular_triangulation_2<
    Kernel, CGAL::Triangulation_data_structure_2<
                CGAL::Triangulation_vertex_base_with_info_2<
                    Index, Kernel, CGAL::Regular_triangulation_vertex_base_2<Kernel>>,
                CGAL::Regular_triangulation_face_base_2<Kernel>>>;

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

template <typename T>
void collect3(const T& t, Triangulation& out) {
  for (auto cell = t.finite_cells_begin(); cell != t.finite_cells_end(); ++cell) {
    std::array<Index, 4> nodes{};
    for (int k = 0; k < 4; ++k) {
      nodes[static_cast<std::size_t>(k)] = cell->vertex(k)->info();
    }
    std::sort(nodes.begin(), nodes.end());
    out.cells.push_back(nodes);
  }
  for (auto edge = t.finite_edges_begin(); edge != t.finite_edges_end(); ++edge) {
    addEdge(edge->first->vertex(edge->second)->info(), edge->first->vertex(edge->third)->info(),
            out.edges);
  }
  out.hiddenParticles = out.hiddenParticles - t.number_of_vertices();
}

template <typename T>
void collect2(const T& t, Triangulation& out) {
  for (auto face = t.finite_faces_begin(); face != t.finite_faces_end(); ++face) {
    std::array<Index, 4> nodes{face->vertex(0)->info(), face->vertex(1)->info(),
                               face->vertex(2)->info(), -1};
    std::sort(nodes.begin(), nodes.begin() + 3);
    out.cells.push_back(nodes);
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

Result<Triangulation> triangulate(std::span<const dem::Vec3> positions,
                                  std::span<const double> radius, int dimension,
                                  std::optional<bool> weighted) {
  Triangulation out;
  out.dimension = dimension;
  out.weighted = weighted.value_or(needsRegularTriangulation(radius));
  out.hiddenParticles = positions.size();
  if (dimension == 3) {
    if (out.weighted) {
      collect3(build<Regular3, Kernel::Weighted_point_3>(positions, radius, true), out);
    } else {
      auto t = build<Delaunay3, Kernel::Point_3>(positions, radius, false);
      if (t.dimension() < 3) {
        return failedPrecondition(fmt::format(
            "cannot triangulate {} particle centres: they are all in one plane", positions.size()));
      }
      collect3(t, out);
    }
  } else {
    if (out.weighted) {
      collect2(build<Regular2, Kernel::Weighted_point_2>(positions, radius, true), out);
    } else {
      auto t = build<Delaunay2, Kernel::Point_2>(positions, radius, false);
      if (t.dimension() < 2) {
        return failedPrecondition(fmt::format(
            "cannot triangulate {} particle centres: they are all on one line", positions.size()));
      }
      collect2(t, out);
    }
  }
  if (out.cells.empty()) {
    return failedPrecondition(fmt::format(
        "cannot triangulate {} particle centres: no cell (too few particles, or all in one {})",
        positions.size(), dimension == 3 ? "plane" : "line"));
  }
  std::sort(out.cells.begin(), out.cells.end());
  std::sort(out.edges.begin(), out.edges.end(), [](dem::Bond a, dem::Bond b) {
    return a.first != b.first ? a.first < b.first : a.second < b.second;
  });
  return out;
}

}  // namespace crackvis::cracks
