#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <crackvis/dem/neighbour_grid.hpp>

namespace crackvis::dem {
NeighbourGrid::NeighbourGrid(const std::vector<Vec3>& positions, double cellSize)
    : m_positions(positions), m_cellSize(cellSize) {
  if (!(cellSize > 0.0)) {
    throw std::invalid_argument("NeighbourGrid: cell size must be positive");
  }
  const auto [lo, hi] = boundingBox(positions);
  m_origin = lo;
  for (int axis = 0; axis < 3; ++axis) {
    const double span = component(hi, axis) - component(lo, axis);
    m_dims[axis] = static_cast<std::int64_t>(std::floor(span / cellSize)) + 1;
  }
  const std::int64_t cellCount = m_dims[0] * m_dims[1] * m_dims[2];
  if (cellCount > std::int64_t{1} << 31) {
    throw std::invalid_argument("NeighbourGrid: cell size too small for the particles' extent");
  }
  // Counting sort of particles into cells (CSR), stable in particle order.
  std::vector<std::int64_t> cellOfParticle(positions.size());
  m_cellStart.assign(static_cast<size_t>(cellCount) + 1, 0);
  for (size_t i = 0; i < positions.size(); ++i) {
    const Vec3 p = positions[i];
    cellOfParticle[i] = linearCell(cellOf(p, 0), cellOf(p, 1), cellOf(p, 2));
    ++m_cellStart[static_cast<size_t>(cellOfParticle[i]) + 1];
  }
  for (size_t c = 1; c < m_cellStart.size(); ++c) {
    m_cellStart[c] += m_cellStart[c - 1];
  }
  m_particles.resize(positions.size());
  std::vector<std::int32_t> fill(m_cellStart.begin(), m_cellStart.end() - 1);
  for (size_t i = 0; i < positions.size(); ++i) {
    m_particles[static_cast<size_t>(fill[static_cast<size_t>(cellOfParticle[i])]++)] =
        static_cast<std::int32_t>(i);
  }
}

std::int64_t NeighbourGrid::cellOf(Vec3 p, int axis) const {
  const auto c = static_cast<std::int64_t>(
      std::floor((component(p, axis) - component(m_origin, axis)) / m_cellSize));
  return std::clamp<std::int64_t>(c, 0, m_dims[axis] - 1);
}

std::int64_t NeighbourGrid::linearCell(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
  return (cz * m_dims[1] + cy) * m_dims[0] + cx;
}

std::vector<Bond> NeighbourGrid::pairsWithin(double cutoff) const {
  const double cutoff2 = cutoff * cutoff;
  std::vector<Bond> pairs;
  for (size_t i = 0; i < m_positions.size(); ++i) {
    const Vec3 p = m_positions[i];
    const std::int64_t c[3] = {cellOf(p, 0), cellOf(p, 1), cellOf(p, 2)};
    for (std::int64_t z = std::max<std::int64_t>(c[2] - 1, 0);
         z <= std::min(c[2] + 1, m_dims[2] - 1); ++z) {
      for (std::int64_t y = std::max<std::int64_t>(c[1] - 1, 0);
           y <= std::min(c[1] + 1, m_dims[1] - 1); ++y) {
        for (std::int64_t x = std::max<std::int64_t>(c[0] - 1, 0);
             x <= std::min(c[0] + 1, m_dims[0] - 1); ++x) {
          const auto cell = static_cast<size_t>(linearCell(x, y, z));
          for (auto k = m_cellStart[cell]; k < m_cellStart[cell + 1]; ++k) {
            const auto j = static_cast<size_t>(m_particles[static_cast<size_t>(k)]);
            if (j <= i) {
              continue;
            }
            const Vec3 d = m_positions[j] - p;
            if (dot(d, d) < cutoff2) {
              pairs.push_back({static_cast<ParticleIndex>(i), static_cast<ParticleIndex>(j)});
            }
          }
        }
      }
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](Bond a, Bond b) {
    return a.first != b.first ? a.first < b.first : a.second < b.second;
  });
  return pairs;
}

}  // namespace crackvis::dem
