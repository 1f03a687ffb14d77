#include <algorithm>

#include <crackvis/cracks/bond_graph.hpp>

namespace crackvis::cracks {

BondGraph::BondGraph(std::size_t particleCount, std::span<const dem::Bond> bonds)
    : m_bonds(bonds), m_offsets(particleCount + 1, 0), m_bondIds(2 * bonds.size()) {
  for (const dem::Bond& bond : bonds) {
    ++m_offsets[static_cast<std::size_t>(bond.first) + 1];
    ++m_offsets[static_cast<std::size_t>(bond.second) + 1];
  }
  for (std::size_t i = 1; i < m_offsets.size(); ++i) {
    m_offsets[i] += m_offsets[i - 1];
  }
  std::vector<std::int32_t> fill(m_offsets.begin(), m_offsets.end() - 1);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    m_bondIds[static_cast<std::size_t>(fill[static_cast<std::size_t>(bonds[b].first)]++)] =
        static_cast<BondIndex>(b);
    m_bondIds[static_cast<std::size_t>(fill[static_cast<std::size_t>(bonds[b].second)]++)] =
        static_cast<BondIndex>(b);
  }
  for (std::size_t i = 0; i + 1 < m_offsets.size(); ++i) {
    const auto self = static_cast<ParticleIndex>(i);
    std::sort(m_bondIds.begin() + m_offsets[i], m_bondIds.begin() + m_offsets[i + 1],
              [&](BondIndex a, BondIndex b) { return otherEnd(a, self) < otherEnd(b, self); });
  }
}

BondIndex BondGraph::bondBetween(ParticleIndex i, ParticleIndex j) const {
  const auto ids = bondsOf(i);
  auto it = std::lower_bound(ids.begin(), ids.end(), j, [&](BondIndex b, ParticleIndex value) {
    return otherEnd(b, i) < value;
  });
  return it != ids.end() && otherEnd(*it, i) == j ? *it : -1;
}

std::size_t BondGraph::memoryBytes() const {
  return m_offsets.capacity() * sizeof(std::int32_t) + m_bondIds.capacity() * sizeof(BondIndex);
}

}  // namespace crackvis::cracks
