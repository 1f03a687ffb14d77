// A uniform cell grid over particle centres for fixed-radius neighbour
// queries: bond detection in the lattice generators now, contact search in
// the simulator later.
//
// Cells are at least `cellSize` wide, so every pair closer than cellSize lies
// in the same or an adjacent cell. Pairs come out in a deterministic order
// (by first index, then second), whatever the input order.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <crackvis/dem/model.hpp>

namespace crackvis::dem {

class NeighbourGrid {
 public:
  NeighbourGrid(const std::vector<Vec3>& positions, double cellSize);

  // Every unordered pair (i < j) with |p_i - p_j| < cutoff (cutoff <= cellSize),
  // sorted by (i, j).
  std::vector<Bond> pairsWithin(double cutoff) const;

 private:
  std::int64_t cellOf(Vec3 p, int axis) const;
  std::int64_t linearCell(std::int64_t cx, std::int64_t cy, std::int64_t cz) const;

  const std::vector<Vec3>& m_positions;
  double m_cellSize;
  Vec3 m_origin;
  std::int64_t m_dims[3] = {1, 1, 1};
  std::vector<std::int32_t> m_cellStart;  // CSR: particles of cell c are
  std::vector<std::int32_t> m_particles;  // m_particles[m_cellStart[c] .. m_cellStart[c+1])
};

}  // namespace crackvis::dem
