// The coarse stand-ins of a crowded server's drag frames: spheres and
// surfaces clustered by a grid, against answers worked out by hand.
#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include <catch2/catch.hpp>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

#include <crackvis/render/coarse_geometry.hpp>

using namespace crackvis;

namespace {

// Spheres of radius r at `centres`, one vertex cell each, with a "fragment"
// value per sphere, as the scene's particle actor makes them.
vtkSmartPointer<vtkPolyData> sphereSet(const std::vector<std::array<double, 3>>& centres, double r,
                                       const std::vector<double>& fragment) {
  auto data = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> vertices;
  vtkNew<vtkFloatArray> radius;
  radius->SetName("sphere_radius");
  vtkNew<vtkDoubleArray> values;
  values->SetName("fragment");
  for (std::size_t k = 0; k < centres.size(); ++k) {
    const vtkIdType id = points->InsertNextPoint(centres[k].data());
    vertices->InsertNextCell(1, &id);
    radius->InsertNextValue(static_cast<float>(r));
    values->InsertNextValue(fragment[k]);
  }
  data->SetPoints(points);
  data->SetVerts(vertices);
  data->GetPointData()->AddArray(radius);
  data->GetPointData()->AddArray(values);
  return data;
}

// The corners of every polygon of `data`, in order.
std::vector<std::vector<vtkIdType>> polygons(vtkPolyData& data) {
  std::vector<std::vector<vtkIdType>> out;
  auto it = vtk::TakeSmartPointer(data.GetPolys()->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
    vtkIdType count = 0;
    const vtkIdType* points = nullptr;
    it->GetCurrentCell(count, points);
    out.emplace_back(points, points + count);
  }
  return out;
}

}  // namespace

TEST_CASE("a cube of eight touching spheres becomes one that holds them", "[render][coarse]") {
  // Two 2 x 2 x 2 blocks of spheres of radius 1 at spacing 2, the second
  // 4 further along x: cells 4 wide put each block in a cell of its own.
  const double r = 1.0;
  std::vector<std::array<double, 3>> centres;
  std::vector<double> fragment;
  for (const double x0 : {1.0, 5.0}) {
    for (int k = 0; k < 8; ++k) {
      centres.push_back({x0 + 2.0 * (k & 1), 1.0 + 2.0 * ((k >> 1) & 1), 1.0 + 2.0 * (k >> 2)});
      fragment.push_back(x0 < 3.0 ? 7.0 + k : 20.0 + k);  // first member: 7, then 20
    }
  }
  const auto spheres = sphereSet(centres, r, fragment);
  const auto coarse = render::coarseSpheres(*spheres, "sphere_radius", 4.0);
  REQUIRE(coarse != nullptr);
  REQUIRE(coarse->GetNumberOfPoints() == 2);
  CHECK(coarse->GetNumberOfVerts() == 2);
  CHECK(coarse->GetNumberOfCells() == 2);
  vtkDataArray* radius = coarse->GetPointData()->GetArray("sphere_radius");
  vtkDataArray* values = coarse->GetPointData()->GetArray("fragment");
  REQUIRE(radius != nullptr);
  REQUIRE(values != nullptr);
  for (vtkIdType c = 0; c < 2; ++c) {
    double p[3];
    coarse->GetPoint(c, p);
    // The mean centre, and a radius from it to the far side of a corner
    // sphere: sqrt(3) + 1.
    CHECK(p[0] == Approx(c == 0 ? 2.0 : 6.0));
    CHECK(p[1] == Approx(2.0));
    CHECK(p[2] == Approx(2.0));
    CHECK(radius->GetTuple1(c) == Approx((1.0 + std::sqrt(3.0)) * r).epsilon(1e-6));
    // A member's own value, not a blend: the first member's.
    CHECK(values->GetTuple1(c) == (c == 0 ? 7.0 : 20.0));
  }
}

TEST_CASE("coarse spheres: every sphere in some cluster that holds it", "[render][coarse]") {
  // A 6 x 5 x 4 lattice with uneven radii, cells not aligned with it.
  std::vector<std::array<double, 3>> centres;
  std::vector<double> fragment;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 5; ++j) {
      for (int k = 0; k < 4; ++k) {
        centres.push_back({0.3 + 2.0 * i, -1.1 + 2.0 * j, 0.7 + 2.0 * k});
        fragment.push_back(i);
      }
    }
  }
  auto spheres = sphereSet(centres, 1.0, fragment);
  vtkDataArray* radii = spheres->GetPointData()->GetArray("sphere_radius");
  for (vtkIdType k = 0; k < radii->GetNumberOfTuples(); ++k) {
    radii->SetTuple1(k, 0.6 + 0.1 * static_cast<double>(k % 5));
  }
  const auto coarse = render::coarseSpheres(*spheres, "sphere_radius", 3.0);
  REQUIRE(coarse != nullptr);
  CHECK(coarse->GetNumberOfPoints() < static_cast<vtkIdType>(centres.size()) / 3);
  vtkDataArray* coarseRadii = coarse->GetPointData()->GetArray("sphere_radius");
  for (std::size_t k = 0; k < centres.size(); ++k) {
    bool held = false;
    for (vtkIdType c = 0; c < coarse->GetNumberOfPoints() && !held; ++c) {
      double p[3];
      coarse->GetPoint(c, p);
      const double d =
          std::sqrt(std::pow(p[0] - centres[k][0], 2) + std::pow(p[1] - centres[k][1], 2) +
                    std::pow(p[2] - centres[k][2], 2));
      // The radii are floats, as the scene's.
      held = d + radii->GetTuple1(static_cast<vtkIdType>(k)) <= coarseRadii->GetTuple1(c) + 1e-5;
    }
    INFO("sphere " << k);
    CHECK(held);
  }
}

TEST_CASE("coarse spheres: what is not a sphere set has none", "[render][coarse]") {
  auto spheres = sphereSet({{0, 0, 0}, {1, 0, 0}}, 1.0, {0, 1});
  CHECK(render::coarseSpheres(*spheres, "no such array", 2.0) == nullptr);
  CHECK(render::coarseSpheres(*spheres, "sphere_radius", 0.0) == nullptr);
  CHECK(render::coarseSpheres(*spheres, "sphere_radius", std::nan("")) == nullptr);
  vtkNew<vtkCellArray> line;
  const vtkIdType ends[2] = {0, 1};
  line->InsertNextCell(2, ends);
  spheres->SetLines(line);  // a cell that is no sphere
  CHECK(render::coarseSpheres(*spheres, "sphere_radius", 2.0) == nullptr);
}

TEST_CASE(
    "coarse spheres: points far apart are clustered on a grid of bounded size, and "
    "points not finite left out",
    "[render][coarse]") {
  // A grid over 1e30 at cells 1 wide would have 1e30 cells: it widens
  // them instead (the first two spheres share one). The NaN and infinite
  // centres are nowhere, and do not spoil the finite spheres' clusters.
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  auto spheres = sphereSet({{0, 0, 0}, {1e30, 0, 0}, {nan, 0, 0}, {0.5, 0, 0}, {inf, 0, 0}}, 1.0,
                           {1, 2, 3, 4, 5});
  const auto coarse = render::coarseSpheres(*spheres, "sphere_radius", 1.0);
  REQUIRE(coarse != nullptr);
  REQUIRE(coarse->GetNumberOfPoints() == 2);
  CHECK(coarse->GetNumberOfVerts() == 2);
  vtkDataArray* radius = coarse->GetPointData()->GetArray("sphere_radius");
  double p[3];
  coarse->GetPoint(0, p);
  CHECK(p[0] == Approx(0.25));
  CHECK(radius->GetTuple1(0) == Approx(1.25));
  coarse->GetPoint(1, p);
  CHECK(p[0] == Approx(1e30));  // stored as a float
  CHECK(radius->GetTuple1(1) == Approx(1.0));
}

TEST_CASE("a coarse surface keeps the polygons across three clusters, with their cell data",
          "[render][coarse]") {
  // A 4 x 4 grid of unit squares in z = 0.5, each with its index as cell
  // data, two lines and a vertex cell; cells 2 wide cluster the corners'
  // x and y each into [0, 2), [2, 4) and 4.
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  for (int j = 0; j <= 4; ++j) {
    for (int i = 0; i <= 4; ++i) {
      points->InsertNextPoint(i, j, 0.5);
    }
  }
  const auto at = [](int i, int j) { return static_cast<vtkIdType>(j * 5 + i); };
  vtkNew<vtkCellArray> vertices;
  const vtkIdType vertex = at(4, 4);
  vertices->InsertNextCell(1, &vertex);
  vtkNew<vtkCellArray> lines;
  const vtkIdType shortLine[2] = {at(0, 0), at(1, 1)};  // within one cluster: goes
  const vtkIdType longLine[2] = {at(0, 0), at(4, 0)};   // across two: stays
  lines->InsertNextCell(2, shortLine);
  lines->InsertNextCell(2, longLine);
  vtkNew<vtkCellArray> squares;
  vtkNew<vtkDoubleArray> index;
  index->SetName("index");
  index->InsertNextValue(-1.0);  // the vertex cell
  index->InsertNextValue(-2.0);  // the lines
  index->InsertNextValue(-3.0);
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) {
      const vtkIdType corners[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      squares->InsertNextCell(4, corners);
      index->InsertNextValue(j * 4 + i);
    }
  }
  surface->SetPoints(points);
  surface->SetVerts(vertices);
  surface->SetLines(lines);
  surface->SetPolys(squares);
  surface->GetCellData()->AddArray(index);

  const auto coarse = render::coarseSurface(*surface, 2.0);
  REQUIRE(coarse != nullptr);
  // 9 clusters of the 25 points. A square spans a cell edge in x where
  // i is 1 or 3 (its corners i and i + 1 fall in two cells), and so in y:
  // the squares (1, 1), (3, 1), (1, 3) and (3, 3) span both, 4 clusters;
  // every other one 2 or 1, and goes.
  CHECK(coarse->GetNumberOfPoints() == 9);
  CHECK(coarse->GetNumberOfVerts() == 1);
  CHECK(coarse->GetNumberOfLines() == 1);
  const auto kept = polygons(*coarse);
  REQUIRE(kept.size() == 4);
  for (const auto& polygon : kept) {
    CHECK(std::set<vtkIdType>(polygon.begin(), polygon.end()).size() >= 3);
  }
  vtkDataArray* values = coarse->GetCellData()->GetArray("index");
  REQUIRE(values != nullptr);
  REQUIRE(values->GetNumberOfTuples() == 6);
  CHECK(values->GetTuple1(0) == -1.0);
  CHECK(values->GetTuple1(1) == -3.0);  // the line that stays
  std::vector<double> squaresKept;
  for (vtkIdType k = 2; k < 6; ++k) {
    squaresKept.push_back(values->GetTuple1(k));
  }
  CHECK(squaresKept == std::vector<double>{5.0, 7.0, 13.0, 15.0});
  // Each cluster's point is its members' mean: the cluster of x, y in
  // [0, 2) holds x, y in {0, 1}.
  double first[3];
  coarse->GetPoint(0, first);
  CHECK(first[0] == Approx(0.5));
  CHECK(first[1] == Approx(0.5));
  CHECK(first[2] == Approx(0.5));
}

TEST_CASE("a surface with triangle strips has no coarse stand-in", "[render][coarse]") {
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  for (int k = 0; k < 4; ++k) {
    points->InsertNextPoint(k, k % 2, 0);
  }
  vtkNew<vtkCellArray> strips;
  const vtkIdType strip[4] = {0, 1, 2, 3};
  strips->InsertNextCell(4, strip);
  surface->SetPoints(points);
  surface->SetStrips(strips);
  CHECK(render::coarseSurface(*surface, 1.0) == nullptr);
  surface->SetStrips(nullptr);
  CHECK(render::coarseSurface(*surface, 0.0) == nullptr);
}
