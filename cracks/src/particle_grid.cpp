#include <algorithm>
#include <cmath>
#include <limits>

#include <crackvis/cracks/particle_grid.hpp>

namespace crackvis::cracks {
namespace {

// Cells along one axis for an extent, in double so that no extent (a
// specimen flown apart, or an infinite one from a position that slipped
// past validation) overflows an integer.
double cellsAlong(double extent, double size) {
  if (!std::isfinite(extent) || !(extent > 0.0)) {
    return 1.0;  // non-finite extents collapse to one cell; callers check distances
  }
  return std::floor(extent / size) + 1.0;
}

}  // namespace

void ParticleGrid::build(std::span<const Vec3> positions, double cellSize) {
  m_positions = positions;
  const auto [lo, hi] = dem::boundingBox(positions);
  // Never more cells than about 2 per particle: a deformed specimen that
  // flies apart must not make the grid explode.
  const double limit = 2.0 * static_cast<double>(positions.size()) + 64.0;
  double size = std::isfinite(cellSize) && cellSize > 0.0 ? cellSize : 1.0;
  double cells[3] = {1.0, 1.0, 1.0};
  for (;;) {
    for (int axis = 0; axis < 3; ++axis) {
      cells[axis] = cellsAlong(component(hi, axis) - component(lo, axis), size);
    }
    const double total = cells[0] * cells[1] * cells[2];
    if (total <= limit) {
      break;
    }
    // Grow by at least 1.5, in one go when the box is far too large.
    size *= std::max(1.5, std::cbrt(total / limit));
    if (!std::isfinite(size)) {
      cells[0] = cells[1] = cells[2] = 1.0;
      size = std::numeric_limits<double>::max();
      break;
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    m_dims[axis] = static_cast<std::int64_t>(cells[axis]);
  }
  m_cellSize = size;
  m_origin = {std::isfinite(lo.x) ? lo.x : 0.0, std::isfinite(lo.y) ? lo.y : 0.0,
              std::isfinite(lo.z) ? lo.z : 0.0};
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
  // Compared in double before the cast: an infinite or NaN value, or one far
  // outside the grid, must not reach an integer conversion.
  const double relative = (value - component(m_origin, axis)) / m_cellSize;
  if (!(relative > 0.0)) {
    return 0;
  }
  const auto last = m_dims[axis] - 1;
  if (!(relative < static_cast<double>(last))) {
    return last;
  }
  return static_cast<std::int64_t>(relative);
}

}  // namespace crackvis::cracks
