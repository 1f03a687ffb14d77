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
// With ExplicitCells (a triangulation of a packing that is no lattice; every
// cell edge must then be an edge of the graph), the cells come from that list
// instead of the graph's cliques; everything else works the same.
//
// Each cell knows its bonds (bondOf); the cells of a bond are found through
// per-particle lists in which each cell is linked under its lowest particle
// (cellsOfBond).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/lattice_cells.hpp>

namespace crackvis::cracks {

using CellIndex = std::int32_t;

// Cells given as node lists (tetrahedra, or triangles with the fourth node
// -1), with the cells of each particle in CSR form. The list is held, not
// copied: a triangulation that its maker keeps too (an MPI rank's piece, at
// 10^6 particles 60 MB of cells) exists once.
struct ExplicitCells {
  using CellList = std::vector<std::array<dem::ParticleIndex, 4>>;
  std::shared_ptr<const CellList> list;       // nodes ascending in each cell
  std::vector<std::int32_t> offsets;          // [N + 1]
  std::vector<std::int32_t> cellsOfParticle;  // ids into the list

  ExplicitCells() = default;
  ExplicitCells(std::size_t particleCount, std::shared_ptr<const CellList> shared);
  ExplicitCells(std::size_t particleCount, CellList owned)
      : ExplicitCells(particleCount, std::make_shared<const CellList>(std::move(owned))) {}
  std::span<const std::array<dem::ParticleIndex, 4>> cells() const {
    return list ? std::span<const std::array<dem::ParticleIndex, 4>>(*list)
                : std::span<const std::array<dem::ParticleIndex, 4>>();
  }
  std::span<const std::int32_t> of(dem::ParticleIndex p) const {
    return {cellsOfParticle.data() + offsets[static_cast<std::size_t>(p)],
            cellsOfParticle.data() + offsets[static_cast<std::size_t>(p) + 1]};
  }
  std::size_t memoryBytes() const;
};

class LatticeDecomposition {
 public:
  // `explicitCells`, when given, must outlive the decomposition.
  LatticeDecomposition(const BondGraph& graph, int dimension,
                       const ExplicitCells* explicitCells = nullptr);

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
    return m_processed.test(static_cast<std::size_t>(p));
  }
  dem::BondIndex bondOf(const LatticeCell& cell, int edge) const {
    const auto& e = shapeOf(cell.type).edges[static_cast<std::size_t>(edge)];
    return m_graph.bondsOf(cell.nodes[e[0]])[cell.edgeSlots[static_cast<std::size_t>(edge)]];
  }
  int dimension() const { return m_dimension; }
  const BondGraph& graph() const { return m_graph; }
  // Cells added by the last update() or addCellsAround(): [first, cellCount()).
  CellIndex firstNewCell() const { return m_firstNewCell; }
  // Particles whose degree exceeded what cell enumeration supports (64).
  std::size_t skippedParticles() const { return m_skipped; }
  // Explicit cells left out because a node has more than 256 bonds (the
  // byte of LatticeCell::edgeSlots): fans on a triangulation's hull.
  std::size_t skippedCells() const { return m_skippedCells; }

  // Cells whose lowest particle is p.
  template <typename Visit>
  void forEachCellOwnedBy(dem::ParticleIndex p, Visit&& visit) const {
    for (CellIndex c = m_head[static_cast<std::size_t>(p)]; c >= 0;
         c = m_next[static_cast<std::size_t>(c)]) {
      visit(c);
    }
  }
  // Cells containing bond b, ascending (safe to call from several threads).
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
  template <typename Visit>
  void forEachCellWithBond(dem::BondIndex b, Visit&& visit) const;

  const BondGraph& m_graph;
  int m_dimension;
  const ExplicitCells* m_explicit;
  std::vector<LatticeCell> m_cells;
  // One bit per particle or bond.
  class Bits {
   public:
    explicit Bits(std::size_t size) : m_words((size + 63) / 64, 0) {}
    bool test(std::size_t i) const { return (m_words[i / 64] >> (i % 64)) & 1u; }
    void set(std::size_t i, bool value) {
      const std::uint64_t bit = std::uint64_t{1} << (i % 64);
      m_words[i / 64] = value ? m_words[i / 64] | bit : m_words[i / 64] & ~bit;
    }
    std::size_t bytes() const { return m_words.capacity() * sizeof(std::uint64_t); }
    std::uint64_t word(std::size_t w) const { return m_words[w]; }

   private:
    std::vector<std::uint64_t> m_words;
  };

  std::vector<CellIndex> m_head;  // [N] first cell owned by each particle (its lowest)
  std::vector<CellIndex> m_next;  // [cells] next cell with the same owner
  Bits m_processed;               // [N]
  Bits m_seenState;               // [M] the bond state of the last update
  std::vector<dem::BondIndex> m_changed;
  CellIndex m_firstNewCell = 0;
  std::size_t m_skipped = 0;
  std::size_t m_skippedCells = 0;
};

}  // namespace crackvis::cracks
