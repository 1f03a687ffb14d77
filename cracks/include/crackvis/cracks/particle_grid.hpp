// A uniform grid over particle centres for "which particles lie within R of
// this point" queries: the empty-sphere validation of local Voronoi vertices
// and the cut-depth metric. Rebuilt per step in O(N) (counting sort).
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::cracks {

class ParticleGrid {
 public:
  ParticleGrid() = default;
  ParticleGrid(std::span<const Vec3> positions, double cellSize) { build(positions, cellSize); }
  void build(std::span<const Vec3> positions, double cellSize);

  // Calls visit(index) for every particle whose centre is within `radius` of
  // `centre` (and possibly a few more: callers check the distance).
  template <typename Visit>
  void forEachNear(Vec3 centre, double radius, Visit&& visit) const;

  std::size_t memoryBytes() const {
    return (m_cellStart.capacity() + m_particles.capacity()) * sizeof(std::int32_t);
  }

 private:
  std::int64_t cellCoordinate(double value, int axis) const;

  std::span<const Vec3> m_positions;
  Vec3 m_origin;
  double m_cellSize = 1.0;
  std::int64_t m_dims[3] = {1, 1, 1};
  std::vector<std::int32_t> m_cellStart;
  std::vector<std::int32_t> m_particles;
};

template <typename Visit>
void ParticleGrid::forEachNear(Vec3 centre, double radius, Visit&& visit) const {
  const std::int64_t lo[3] = {cellCoordinate(centre.x - radius, 0),
                              cellCoordinate(centre.y - radius, 1),
                              cellCoordinate(centre.z - radius, 2)};
  const std::int64_t hi[3] = {cellCoordinate(centre.x + radius, 0),
                              cellCoordinate(centre.y + radius, 1),
                              cellCoordinate(centre.z + radius, 2)};
  for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
    for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
      for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
        const auto cell = static_cast<std::size_t>((z * m_dims[1] + y) * m_dims[0] + x);
        for (std::int32_t k = m_cellStart[cell]; k < m_cellStart[cell + 1]; ++k) {
          visit(m_particles[static_cast<std::size_t>(k)]);
        }
      }
    }
  }
}

}  // namespace crackvis::cracks
