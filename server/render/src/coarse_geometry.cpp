#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkIdTypeArray.h>
#include <vtkMath.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

#include <crackvis/render/coarse_geometry.hpp>

namespace crackvis::render {
namespace {

// At most this many grid cells (a cluster slot of 4 bytes each): a wider
// cell than asked where the points spread far.
constexpr std::int64_t kMostCells = std::int64_t{1} << 22;

// Cubic cells over the finite points' box, at most kMostCells of them (a
// box too wide for `cell` gets wider cells). A coordinate outside the box
// falls in the nearest cell.
class ClusterGrid {
 public:
  ClusterGrid(const std::array<double, 6>& box, double cell) : m_origin{box[0], box[2], box[4]} {
    std::array<double, 3> extent{};
    for (std::size_t a = 0; a < 3; ++a) {
      const double e = box[2 * a + 1] - box[2 * a];
      extent[a] = std::isfinite(e) && e > 0.0 ? e : 0.0;
      m_origin[a] = std::isfinite(m_origin[a]) ? m_origin[a] : 0.0;
    }
    for (;;) {
      double cells = 1.0;
      for (std::size_t a = 0; a < 3; ++a) {
        cells *= std::floor(extent[a] / cell) + 1.0;
      }
      if (cells <= static_cast<double>(kMostCells)) {
        break;
      }
      cell *= std::max(1.25, std::cbrt(cells / static_cast<double>(kMostCells)));
    }
    m_cell = cell;
    m_cells = 1;
    for (std::size_t a = 0; a < 3; ++a) {
      m_dims[a] = static_cast<std::int64_t>(std::floor(extent[a] / cell)) + 1;
      m_cells *= m_dims[a];
    }
  }
  std::int64_t cells() const { return m_cells; }
  std::int64_t cellOf(const double p[3]) const {
    std::array<std::int64_t, 3> at{};
    for (std::size_t a = 0; a < 3; ++a) {
      const double t = (p[a] - m_origin[a]) / m_cell;
      const auto last = static_cast<double>(m_dims[a] - 1);
      at[a] = !(t > 0.0) ? 0 : static_cast<std::int64_t>(std::min(t, last));
    }
    return (at[2] * m_dims[1] + at[1]) * m_dims[0] + at[0];
  }

 private:
  std::array<double, 3> m_origin;
  std::array<std::int64_t, 3> m_dims{};
  std::int64_t m_cells = 0;
  double m_cell = 0.0;
};

constexpr vtkIdType kNoCluster = -1;

bool finite(const double p[3]) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// Which cluster each point falls in, in order of first appearance, with
// each cluster's first member and the sum of its members' positions. A
// point that is not finite is in none (kNoCluster): nowhere to draw it.
struct Clusters {
  std::vector<vtkIdType> of;     // by point
  std::vector<vtkIdType> first;  // by cluster
  std::vector<std::array<double, 3>> sum;
  std::vector<vtkIdType> count;
};

Clusters cluster(vtkPoints& points, double cell) {
  Clusters c;
  const vtkIdType n = points.GetNumberOfPoints();
  // The finite points' box (vtkPoints::GetBounds would take infinities in).
  std::array<double, 6> box{0, 0, 0, 0, 0, 0};
  bool any = false;
  for (vtkIdType i = 0; i < n; ++i) {
    double p[3];
    points.GetPoint(i, p);
    if (finite(p)) {
      for (std::size_t a = 0; a < 3; ++a) {
        box[2 * a] = any ? std::min(box[2 * a], p[a]) : p[a];
        box[2 * a + 1] = any ? std::max(box[2 * a + 1], p[a]) : p[a];
      }
      any = true;
    }
  }
  const ClusterGrid grid(box, cell);
  std::vector<std::int32_t> slot(static_cast<std::size_t>(grid.cells()), -1);
  c.of.assign(static_cast<std::size_t>(n), kNoCluster);
  for (vtkIdType i = 0; i < n; ++i) {
    double p[3];
    points.GetPoint(i, p);
    if (!finite(p)) {
      continue;
    }
    std::int32_t& s = slot[static_cast<std::size_t>(grid.cellOf(p))];
    if (s < 0) {
      s = static_cast<std::int32_t>(c.first.size());
      c.first.push_back(i);
      c.sum.push_back({0.0, 0.0, 0.0});
      c.count.push_back(0);
    }
    const auto k = static_cast<std::size_t>(s);
    c.of[static_cast<std::size_t>(i)] = s;
    for (int a = 0; a < 3; ++a) {
      c.sum[k][static_cast<std::size_t>(a)] += p[a];
    }
    ++c.count[k];
  }
  return c;
}

// The clusters' mean positions, with each cluster's first member's point
// data.
void setClusterPoints(vtkPolyData& in, const Clusters& c, vtkPolyData& out) {
  const auto n = static_cast<vtkIdType>(c.first.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  for (vtkIdType k = 0; k < n; ++k) {
    const auto& sum = c.sum[static_cast<std::size_t>(k)];
    const auto count = static_cast<double>(c.count[static_cast<std::size_t>(k)]);
    points->SetPoint(k, sum[0] / count, sum[1] / count, sum[2] / count);
  }
  out.SetPoints(points);
  vtkPointData* to = out.GetPointData();
  to->CopyAllocate(in.GetPointData(), n);
  for (vtkIdType k = 0; k < n; ++k) {
    to->CopyData(in.GetPointData(), c.first[static_cast<std::size_t>(k)], k);
  }
}

// `cells` with their points mapped to clusters: kept when they touch at
// least `least` clusters (consecutive repeats dropped, and for a closed
// polygon the last corner's repeat of the first), their cell data copied
// from `firstId` on (their ids in the input) to `nextId` on.
vtkSmartPointer<vtkCellArray> clusterCells(vtkCellArray* cells, const Clusters& c,
                                           std::size_t least, bool closed, vtkCellData* from,
                                           vtkIdType firstId, vtkCellData* to, vtkIdType& nextId) {
  auto kept = vtkSmartPointer<vtkCellArray>::New();
  if (cells == nullptr) {
    return kept;
  }
  std::vector<vtkIdType> corners;
  vtkIdType id = firstId;
  auto it = vtk::TakeSmartPointer(cells->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), ++id) {
    vtkIdType count = 0;
    const vtkIdType* points = nullptr;
    it->GetCurrentCell(count, points);
    corners.clear();
    bool placed = true;
    for (vtkIdType j = 0; j < count && placed; ++j) {
      const vtkIdType k = c.of[static_cast<std::size_t>(points[j])];
      placed = k != kNoCluster;
      if (corners.empty() || corners.back() != k) {
        corners.push_back(k);
      }
    }
    if (!placed) {
      continue;  // a corner nowhere: the cell goes
    }
    if (closed && corners.size() > 1 && corners.back() == corners.front()) {
      corners.pop_back();
    }
    if (corners.size() < least) {
      continue;
    }
    kept->InsertNextCell(static_cast<vtkIdType>(corners.size()), corners.data());
    to->CopyData(from, id, nextId++);
  }
  return kept;
}

}  // namespace

vtkSmartPointer<vtkPolyData> coarseSpheres(vtkPolyData& spheres, const char* radiusArray,
                                           double cell) {
  vtkPoints* points = spheres.GetPoints();
  vtkDataArray* radii = spheres.GetPointData()->GetArray(radiusArray);
  const vtkIdType n = spheres.GetNumberOfPoints();
  if (points == nullptr || radii == nullptr || radii->GetNumberOfComponents() != 1 ||
      radii->GetNumberOfTuples() != n || spheres.GetNumberOfVerts() != n ||
      spheres.GetNumberOfCells() != n || !(cell > 0.0) || !std::isfinite(cell)) {
    return nullptr;
  }
  const Clusters c = cluster(*points, cell);
  auto out = vtkSmartPointer<vtkPolyData>::New();
  setClusterPoints(spheres, c, *out);
  // Each cluster's sphere reaches as far as its farthest member does.
  std::vector<double> reach(c.first.size(), 0.0);
  vtkPoints* centres = out->GetPoints();
  for (vtkIdType i = 0; i < n; ++i) {
    const auto k = c.of[static_cast<std::size_t>(i)];
    if (k == kNoCluster) {
      continue;
    }
    double p[3];
    double centre[3];
    points->GetPoint(i, p);
    centres->GetPoint(k, centre);
    const double far = std::sqrt(vtkMath::Distance2BetweenPoints(p, centre)) + radii->GetTuple1(i);
    double& r = reach[static_cast<std::size_t>(k)];
    r = std::max(r, far);
  }
  vtkDataArray* radius = out->GetPointData()->GetArray(radiusArray);
  const auto clusters = static_cast<vtkIdType>(c.first.size());
  vtkNew<vtkIdTypeArray> offsets;
  offsets->SetNumberOfValues(clusters + 1);
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfValues(clusters);
  for (vtkIdType k = 0; k < clusters; ++k) {
    radius->SetTuple1(k, reach[static_cast<std::size_t>(k)]);
    offsets->SetValue(k, k);
    connectivity->SetValue(k, k);
  }
  offsets->SetValue(clusters, clusters);
  vtkNew<vtkCellArray> vertices;
  vertices->SetData(offsets, connectivity);
  out->SetVerts(vertices);
  return out;
}

vtkSmartPointer<vtkPolyData> coarseSurface(vtkPolyData& surface, double cell) {
  vtkPoints* points = surface.GetPoints();
  if (points == nullptr || surface.GetNumberOfStrips() > 0 || !(cell > 0.0) ||
      !std::isfinite(cell)) {
    return nullptr;
  }
  const Clusters c = cluster(*points, cell);
  auto out = vtkSmartPointer<vtkPolyData>::New();
  setClusterPoints(surface, c, *out);
  // Cell ids run through the vertices, then the lines, then the polygons.
  vtkCellData* from = surface.GetCellData();
  vtkCellData* to = out->GetCellData();
  to->CopyAllocate(from, surface.GetNumberOfCells());
  vtkIdType nextId = 0;
  const vtkIdType verts = surface.GetNumberOfVerts();
  const vtkIdType lines = surface.GetNumberOfLines();
  out->SetVerts(clusterCells(surface.GetVerts(), c, 1, false, from, 0, to, nextId));
  out->SetLines(clusterCells(surface.GetLines(), c, 2, false, from, verts, to, nextId));
  out->SetPolys(clusterCells(surface.GetPolys(), c, 3, true, from, verts + lines, to, nextId));
  to->Squeeze();
  return out;
}

}  // namespace crackvis::render
