// The lattice's bond graph in compressed form: for each particle, the ids of
// its bonds sorted by the particle at their other end. Answers "which bond
// joins i and j" by binary search, which is how every crack method turns
// cell geometry back into bonds.
//
// Memory: one int32 per bond end plus one offset per particle; the pairs
// themselves stay in the caller's array, which must outlive the graph.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <crackvis/dem/model.hpp>

namespace crackvis::cracks {

using dem::BondIndex;
using dem::ParticleIndex;

class BondGraph {
 public:
  BondGraph(std::size_t particleCount, std::span<const dem::Bond> bonds);

  std::size_t particleCount() const { return m_offsets.size() - 1; }
  std::size_t bondCount() const { return m_bonds.size(); }
  const dem::Bond& bond(BondIndex b) const { return m_bonds[static_cast<std::size_t>(b)]; }
  std::span<const dem::Bond> bonds() const { return m_bonds; }

  // Bonds of particle i, ordered by the other end's index.
  std::span<const BondIndex> bondsOf(ParticleIndex i) const {
    return {m_bondIds.data() + m_offsets[static_cast<std::size_t>(i)],
            m_bondIds.data() + m_offsets[static_cast<std::size_t>(i) + 1]};
  }
  ParticleIndex otherEnd(BondIndex b, ParticleIndex i) const {
    const dem::Bond& pair = bond(b);
    return pair.first == i ? pair.second : pair.first;
  }
  // The bond joining i and j, or -1.
  BondIndex bondBetween(ParticleIndex i, ParticleIndex j) const;
  bool bonded(ParticleIndex i, ParticleIndex j) const { return bondBetween(i, j) >= 0; }

  std::size_t memoryBytes() const;

 private:
  std::span<const dem::Bond> m_bonds;
  std::vector<std::int32_t> m_offsets;  // [N + 1]
  std::vector<BondIndex> m_bondIds;     // [2M]
};

}  // namespace crackvis::cracks
