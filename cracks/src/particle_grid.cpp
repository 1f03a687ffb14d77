#include <algorithm>
#include <limits>

#include <crackvis/cracks/particle_grid.hpp>

namespace crackvis::cracks {
void ParticleGrid::build(std::span<const Vec3> positions, double cellSize) {
  m_positions = positions;
  const auto [lo, hi] = dem::boundingBox(positions);
  // Never more cells than about 2 per particle: a deformed specimen that
  // flies apart must not make the grid explode.
  double size = cellSize;
  for (;;) {
    std::int64_t cells = 1;
    for (int axis = 0; axis < 3; ++axis) {
      m_dims[axis] =
          static_cast<std::int64_t>((component(hi, axis) - component(lo, axis)) / size) + 1;
      cells *= m_dims[axis];
    }
    if (cells <= 2 * static_cast<std::int64_t>(positions.size()) + 64) {
      break;
    }
    size *= 1.5;
  }
  m_cellSize = size;
  m_origin = lo;
  const auto cellCount = static_cast<std::size_t>(m_dims[0] * m_dims[1] * m_dims[2]);
  m_cellStart.assign(cellCount + 1, 0);
  std::vector<std::int32_t> cellOf(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3 p = positions[i];
    const auto cell = (cellCoordinate(p.z, 2) * m_dims[1] + cellCoordinate(p.y, 1)) * m_dims[0] +
                      cellCoordinate(p.x, 0);
    cellOf[i] = static_cast<std::int32_t>(cell);
    ++m_cellStart[static_cast<std::size_t>(cell) + 1];
  }
  for (std::size_t c = 1; c < m_cellStart.size(); ++c) {
    m_cellStart[c] += m_cellStart[c - 1];
  }
  m_particles.resize(positions.size());
  std::vector<std::int32_t> fill(m_cellStart.begin(), m_cellStart.end() - 1);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    m_particles[static_cast<std::size_t>(fill[static_cast<std::size_t>(cellOf[i])]++)] =
        static_cast<std::int32_t>(i);
  }
}

std::int64_t ParticleGrid::cellCoordinate(double value, int axis) const {
  const double relative = (value - component(m_origin, axis)) / m_cellSize;
  if (!(relative > 0.0)) {
    return 0;
  }
  return std::min(static_cast<std::int64_t>(relative), m_dims[axis] - 1);
}

}  // namespace crackvis::cracks
