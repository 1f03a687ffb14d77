#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::cracks {

const AttributeArray* CrackMesh::findCellData(const std::string& name) const {
  for (const auto& array : cellData) {
    if (array.name == name) {
      return &array;
    }
  }
  return nullptr;
}

const AttributeArray* CrackMesh::findPointData(const std::string& name) const {
  for (const auto& array : pointData) {
    if (array.name == name) {
      return &array;
    }
  }
  return nullptr;
}

void CrackMesh::clear() {
  points.clear();
  vertices.clear();
  lines.clear();
  polygons.clear();
  volumeCells.clear();
  volumeCellTypes.clear();
  cellData.clear();
  pointData.clear();
}

Vec3 polygonNormal(const std::vector<Vec3>& points, const std::int32_t* ids, std::size_t count) {
  Vec3 sum{};
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3 a = points[static_cast<std::size_t>(ids[k])];
    const Vec3 b = points[static_cast<std::size_t>(ids[(k + 1) % count])];
    sum = sum + cross(a, b);
  }
  return 0.5 * sum;
}

double polygonArea(const std::vector<Vec3>& points, const std::int32_t* ids, std::size_t count) {
  // Newell's sum relative to the first vertex keeps precision for polygons
  // far from the origin.
  if (count < 3) {
    return 0.0;
  }
  const Vec3 origin = points[static_cast<std::size_t>(ids[0])];
  Vec3 sum{};
  for (std::size_t k = 1; k + 1 < count; ++k) {
    const Vec3 a = points[static_cast<std::size_t>(ids[k])] - origin;
    const Vec3 b = points[static_cast<std::size_t>(ids[k + 1])] - origin;
    sum = sum + cross(a, b);
  }
  return 0.5 * dem::norm(sum);
}

}  // namespace crackvis::cracks
