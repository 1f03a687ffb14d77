// The triangulation's hull peeling (TriangulateOptions::peelHull): what is
// peeled, checked against the rule recomputed here from the unpeeled cells
// by their shared faces, on point sets whose sides are slivers.
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include <catch2/catch.hpp>

#include <crackvis/cracks/triangulation.hpp>

using namespace crackvis;
using namespace crackvis::cracks;

namespace {

using Cell = std::array<dem::ParticleIndex, 4>;

// A jittered grid: its side faces are rows of nearly coplanar (collinear in
// 2D) points, which the triangulation joins by slivers.
std::vector<dem::Vec3> jitteredGrid(int nx, int ny, int nz, double jitter, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> offset(-jitter, jitter);
  std::vector<dem::Vec3> points;
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        points.push_back(
            {i + offset(random), j + offset(random), nz == 1 ? 0.0 : k + offset(random)});
      }
    }
  }
  return points;
}

double quality(const Cell& cell, const std::vector<dem::Vec3>& p, int dimension) {
  if (dimension == 3) {
    std::array<double, 4> x{}, y{}, z{};
    for (std::size_t k = 0; k < 4; ++k) {
      const dem::Vec3& q = p[static_cast<std::size_t>(cell[k])];
      x[k] = q.x;
      y[k] = q.y;
      z[k] = q.z;
    }
    return tetrahedronQuality(x, y, z);
  }
  std::array<double, 3> x{}, y{};
  for (std::size_t k = 0; k < 3; ++k) {
    const dem::Vec3& q = p[static_cast<std::size_t>(cell[k])];
    x[k] = q.x;
    y[k] = q.y;
  }
  return triangleQuality(x, y);
}

// A cell's faces (triangles in 3D, edges in 2D) as sorted node lists.
std::vector<std::vector<dem::ParticleIndex>> facesOf(const Cell& cell, int dimension) {
  const int nodes = dimension + 1;
  std::vector<std::vector<dem::ParticleIndex>> faces;
  for (int skip = 0; skip < nodes; ++skip) {
    std::vector<dem::ParticleIndex> face;
    for (int k = 0; k < nodes; ++k) {
      if (k != skip) {
        face.push_back(cell[static_cast<std::size_t>(k)]);
      }
    }
    faces.push_back(face);
  }
  return faces;
}

// The rule, recomputed from the unpeeled cells: from the cells with a face
// on the hull (a face no other cell shares), through shared faces, every
// cell of quality under kSliverQuality.
std::set<Cell> expectedPeel(const std::vector<Cell>& cells, const std::vector<dem::Vec3>& p,
                            int dimension) {
  std::map<std::vector<dem::ParticleIndex>, std::vector<std::size_t>> byFace;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    for (const auto& face : facesOf(cells[c], dimension)) {
      byFace[face].push_back(c);
    }
  }
  std::vector<char> peeled(cells.size(), 0);
  std::vector<std::size_t> todo;
  auto consider = [&](std::size_t c) {
    if (peeled[c] == 0 && quality(cells[c], p, dimension) < kSliverQuality) {
      peeled[c] = 1;
      todo.push_back(c);
    }
  };
  for (const auto& [face, owners] : byFace) {
    if (owners.size() == 1) {
      consider(owners[0]);
    }
  }
  while (!todo.empty()) {
    const std::size_t c = todo.back();
    todo.pop_back();
    for (const auto& face : facesOf(cells[c], dimension)) {
      for (std::size_t other : byFace[face]) {
        consider(other);
      }
    }
  }
  std::set<Cell> out;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (peeled[c] != 0) {
      out.insert(cells[c]);
    }
  }
  return out;
}

std::vector<dem::Bond> edgesOf(const std::vector<Cell>& cells, int dimension) {
  std::set<std::pair<dem::ParticleIndex, dem::ParticleIndex>> edges;
  for (const Cell& cell : cells) {
    for (int a = 0; a <= dimension; ++a) {
      for (int b = a + 1; b <= dimension; ++b) {
        edges.insert({cell[static_cast<std::size_t>(a)], cell[static_cast<std::size_t>(b)]});
      }
    }
  }
  std::vector<dem::Bond> out;
  for (const auto& [a, b] : edges) {
    out.push_back({a, b});
  }
  return out;
}

bool sameEdges(const std::vector<dem::Bond>& a, const std::vector<dem::Bond>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](dem::Bond x, dem::Bond y) {
    return x.first == y.first && x.second == y.second;
  });
}

}  // namespace

TEST_CASE("a cell's quality is 1 for a regular one and falls to 0 as it flattens",
          "[cracks][triangulation][peel]") {
  const double h = std::sqrt(2.0 / 3.0);  // a regular tetrahedron's height, edge 1
  CHECK(tetrahedronQuality({0, 1, 0.5, 0.5}, {0, 0, std::sqrt(3.0) / 2, std::sqrt(3.0) / 6},
                           {0, 0, 0, h}) == Approx(1.0).epsilon(1e-12));
  CHECK(tetrahedronQuality({0, 1, 0, 1}, {0, 0, 1, 1}, {0, 0, 0, 0}) == 0.0);  // a square
  // The unit corner tetrahedron: V = 1/6, l_rms^2 = 1.5.
  CHECK(tetrahedronQuality({0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}) ==
        Approx(std::sqrt(2.0) / std::pow(1.5, 1.5)).epsilon(1e-12));
  CHECK(triangleQuality({0, 1, 0.5}, {0, 0, std::sqrt(3.0) / 2}) == Approx(1.0).epsilon(1e-12));
  CHECK(triangleQuality({0, 1, 2}, {0, 0, 0}) == 0.0);
  // An isosceles triangle of base 1 and height 0.02: 4 sqrt(3) 0.01 / 1.5008.
  CHECK(triangleQuality({0, 1, 0.5}, {0, 0, 0.02}) ==
        Approx(4 * std::sqrt(3.0) * 0.01 / 1.5008).epsilon(1e-12));
}

TEST_CASE("the triangulation peels the slivers reached from its hull, and nothing else",
          "[cracks][triangulation][peel]") {
  const int dimension = GENERATE(3, 2);
  const bool weighted = GENERATE(false, true);
  INFO(dimension << "D, " << (weighted ? "regular" : "Delaunay"));
  const std::vector<dem::Vec3> points =
      dimension == 3 ? jitteredGrid(7, 6, 5, 0.05, 7) : jitteredGrid(14, 11, 1, 0.05, 7);
  std::vector<double> radius(points.size(), 0.45);
  if (weighted) {
    for (std::size_t i = 0; i < radius.size(); i += 3) {
      radius[i] = 0.4;
    }
  }
  auto whole =
      triangulate(points, radius, dimension, {.weighted = std::nullopt, .peelHull = false});
  auto peeled = triangulate(points, radius, dimension);
  REQUIRE(whole.isOk());
  REQUIRE(peeled.isOk());
  REQUIRE(peeled->weighted == weighted);
  CHECK(whole->peeled.empty());
  // Every cell is kept or peeled, once.
  std::vector<Cell> both = peeled->cells;
  both.insert(both.end(), peeled->peeled.begin(), peeled->peeled.end());
  std::sort(both.begin(), both.end());
  REQUIRE(both == whole->cells);
  // The sides' slivers are peeled, by the rule, and they are a few.
  const std::set<Cell> expected = expectedPeel(whole->cells, points, dimension);
  CHECK_FALSE(expected.empty());
  CHECK(std::set<Cell>(peeled->peeled.begin(), peeled->peeled.end()) == expected);
  CHECK(2 * peeled->peeled.size() < whole->cells.size());
  // Nothing inside: every peeled cell has a node on the grid's outer layer.
  auto outer = [&](dem::ParticleIndex i) {
    const dem::Vec3& q = points[static_cast<std::size_t>(i)];
    const double size[3] = {dimension == 3 ? 6.0 : 13.0, dimension == 3 ? 5.0 : 10.0, 4.0};
    const double c[3] = {q.x, q.y, q.z};
    for (int a = 0; a < dimension; ++a) {
      if (std::round(c[a]) == 0.0 || std::round(c[a]) == size[a]) {
        return true;
      }
    }
    return false;
  };
  for (const Cell& cell : peeled->peeled) {
    CHECK(std::any_of(cell.begin(), cell.begin() + dimension + 1, outer));
  }
  // The edges stay, the peeled cells' too: they are the pairs of particles
  // whose Voronoi cells meet, for local Voronoi, peeled or not.
  CHECK(sameEdges(peeled->edges, whole->edges));
  CHECK(sameEdges(whole->edges, edgesOf(whole->cells, dimension)));
  CHECK_FALSE(sameEdges(peeled->edges, edgesOf(peeled->cells, dimension)));
}

TEST_CASE("a layer one particle thick keeps its slivers: they are all it has",
          "[cracks][triangulation][peel]") {
  // Centres within 1e-3 of a plane: every cell is a sliver.
  std::vector<dem::Vec3> points = jitteredGrid(8, 8, 1, 0.05, 3);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> lift(-1e-3, 1e-3);
  for (dem::Vec3& p : points) {
    p.z = lift(random);
  }
  const std::vector<double> radius(points.size(), 0.45);
  auto whole = triangulate(points, radius, 3, {.weighted = std::nullopt, .peelHull = false});
  auto peeled = triangulate(points, radius, 3);
  REQUIRE(whole.isOk());
  REQUIRE(peeled.isOk());
  REQUIRE_FALSE(whole->cells.empty());
  CHECK(expectedPeel(whole->cells, points, 3).size() * 2 > whole->cells.size());
  CHECK(peeled->peeled.empty());
  CHECK(peeled->cells == whole->cells);
  CHECK(sameEdges(peeled->edges, whole->edges));
}
