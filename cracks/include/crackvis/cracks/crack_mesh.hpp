// The one output type of every crack method: points, and primitives in VTK's
// order (vertices, lines, polygons, then volume cells), with per-primitive
// ("cell") and per-point attribute arrays.
//
// Surface methods fill polygons (3D) or lines (2D), and use lines and
// vertices where a crack ends inside a cell or a bond is inconsistent; the
// cell attribute method fills volume cells (tetrahedra, pyramids) in 3D.
// Attribute arrays attached to primitives hold one tuple per primitive in the
// order above, so they map 1:1 onto vtkPolyData / vtkUnstructuredGrid cell data.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <crackvis/dem/model.hpp>

namespace crackvis::cracks {

using dem::Vec3;

enum class AttributeType : std::uint8_t { kInt32, kFloat32, kFloat64 };

struct AttributeArray {
  std::string name;
  AttributeType type = AttributeType::kFloat64;
  int components = 1;
  std::vector<double> values;  // tuples * components; integers are exact in a double

  std::size_t tupleCount() const {
    return components > 0 ? values.size() / static_cast<std::size_t>(components) : 0;
  }
};

// Compressed primitive lists: item k uses connectivity[offsets[k] .. offsets[k+1]).
struct PrimitiveList {
  std::vector<std::int32_t> offsets{0};
  std::vector<std::int32_t> connectivity;

  std::size_t size() const { return offsets.size() - 1; }
  void add(std::initializer_list<std::int32_t> points) { addRange(points.begin(), points.end()); }
  template <typename It>
  void addRange(It first, It last) {
    connectivity.insert(connectivity.end(), first, last);
    offsets.push_back(static_cast<std::int32_t>(connectivity.size()));
  }
  void clear() {
    offsets.assign(1, 0);
    connectivity.clear();
  }
};

struct CrackMesh {
  int dimension = 3;
  std::vector<Vec3> points;
  std::vector<std::int32_t> vertices;  // one point each
  PrimitiveList lines;                 // polylines
  PrimitiveList polygons;
  PrimitiveList volumeCells;
  std::vector<std::uint8_t> volumeCellTypes;  // VTK type codes (10 tetra, 14 pyramid)
  std::vector<AttributeArray> cellData;       // per primitive, in VTK order
  std::vector<AttributeArray> pointData;

  std::size_t primitiveCount() const {
    return vertices.size() + lines.size() + polygons.size() + volumeCells.size();
  }
  bool hasVolumeCells() const { return volumeCells.size() > 0; }
  // Whether the mesh is the cell attribute method's cells (3D: volume cells;
  // 2D: triangles, the only 2D method that fills polygons) rather than a
  // surface.
  bool holdsCells() const { return dimension == 2 ? polygons.size() > 0 : hasVolumeCells(); }
  const AttributeArray* findCellData(const std::string& name) const;
  const AttributeArray* findPointData(const std::string& name) const;
  void clear();
};

// Area of a planar or nearly planar polygon (Newell's method).
double polygonArea(const std::vector<Vec3>& points, const std::int32_t* ids, std::size_t count);
Vec3 polygonNormal(const std::vector<Vec3>& points, const std::int32_t* ids, std::size_t count);
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

}  // namespace crackvis::cracks
