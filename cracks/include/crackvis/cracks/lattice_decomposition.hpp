// The space decomposition spanned by the lattice's bonds, built from the bond
// graph alone (never from positions): tetrahedra (4-cliques) and octahedra
// (6 particles, 12 bonds, 3 absent diagonals, each split into two pyramids) in
// 3D; triangles (3-cliques) in 2D.
//
// Global: every cell. Local (the dissertation's augmentation strategy): the
// object is kept across time steps and `update` adds only the cells around
// particles that end a bond broken since the state it last saw. Cells are
// never removed; their broken-bond masks follow the state they are given, so
// stepping back in time stays correct (the decomposition is then a superset).
//
// Each cell knows its bonds; the cells of a particle or of a bond are found
// through per-particle lists (cellsOfParticle, cellsOfBond).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/lattice_cells.hpp>

namespace crackvis::cracks {

using CellIndex = std::int32_t;

class LatticeDecomposition {
 public:
  LatticeDecomposition(const BondGraph& graph, int dimension);

  // Every cell of the lattice.
  void buildGlobal(std::span<const std::uint8_t> bondState);

  // Brings the decomposition to `bondState`: adds the cells around the ends of
  // bonds broken since the last call (end particles not processed before),
  // and updates the broken masks of all affected cells. Returns the bonds
  // whose state changed, ascending.
  const std::vector<dem::BondIndex>& update(std::span<const std::uint8_t> bondState);

  // Adds every cell containing one of `particles` (those not processed yet).
  void addCellsAround(std::span<const dem::ParticleIndex> particles,
                      std::span<const std::uint8_t> bondState);

  const std::vector<LatticeCell>& cells() const { return m_cells; }
  std::size_t cellCount() const { return m_cells.size(); }
  const LatticeCell& cell(CellIndex c) const { return m_cells[static_cast<std::size_t>(c)]; }
  bool processed(dem::ParticleIndex p) const {
    return m_processed[static_cast<std::size_t>(p)] != 0;
  }
  int dimension() const { return m_dimension; }
  const BondGraph& graph() const { return m_graph; }
  // Cells added by the last update() or addCellsAround(): [first, cellCount()).
  CellIndex firstNewCell() const { return m_firstNewCell; }
  // Particles whose degree exceeded what cell enumeration supports (64).
  std::size_t skippedParticles() const { return m_skipped; }

  template <typename Visit>
  void forEachCellOf(dem::ParticleIndex p, Visit&& visit) const {
    for (std::int32_t slot = m_head[static_cast<std::size_t>(p)]; slot >= 0;
         slot = m_next[static_cast<std::size_t>(slot)]) {
      visit(static_cast<CellIndex>(slot / kMaxCellNodes));
    }
  }
  // Cells containing bond b, ascending.
  void cellsOfBond(dem::BondIndex b, std::vector<CellIndex>& out) const;

  std::size_t memoryBytes() const;

 private:
  struct Candidate {
    CellType type;
    std::array<dem::ParticleIndex, 6>
        nodes;  // tet/triangle sorted; octahedron: a b c d (cycle), v w (axis)
  };
  void enumerateCandidates(dem::ParticleIndex v, std::vector<Candidate>& out) const;
  void insertCandidate(const Candidate& candidate, std::span<const std::uint8_t> bondState);
  bool hasCell(const LatticeCell& probe) const;
  void appendCell(LatticeCell cell, std::span<const std::uint8_t> bondState);
  void setBrokenBit(dem::BondIndex b, bool broken);

  const BondGraph& m_graph;
  int m_dimension;
  std::vector<LatticeCell> m_cells;
  std::vector<std::int32_t> m_head;       // [N] first slot of each particle's list
  std::vector<std::int32_t> m_next;       // [cells * 5] next slot in the same particle's list
  std::vector<std::uint8_t> m_processed;  // [N]
  std::vector<std::uint8_t> m_seenState;  // [M] the bond state of the last update
  std::vector<dem::BondIndex> m_changed;
  CellIndex m_firstNewCell = 0;
  std::size_t m_skipped = 0;
};

}  // namespace crackvis::cracks
