#include <algorithm>
#include <bit>

#include <tbb/parallel_for.h>

#include <crackvis/cracks/lattice_decomposition.hpp>

namespace crackvis::cracks {
namespace {

using dem::BondIndex;
using dem::ParticleIndex;

constexpr std::size_t kMaxDegree = 64;

// Bonds among the neighbours of a particle, as one bitmask row per neighbour.
struct NeighbourGraph {
  std::vector<ParticleIndex> nodes;  // ascending
  std::array<std::uint64_t, kMaxDegree> adjacent{};
};

bool buildNeighbourGraph(const BondGraph& graph, ParticleIndex v, NeighbourGraph& out) {
  out.nodes.clear();
  for (BondIndex b : graph.bondsOf(v)) {
    out.nodes.push_back(graph.otherEnd(b, v));
  }
  if (out.nodes.size() > kMaxDegree) {
    return false;
  }
  const std::size_t n = out.nodes.size();
  for (std::size_t a = 0; a < n; ++a) {
    out.adjacent[a] = 0;
  }
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      if (graph.bonded(out.nodes[a], out.nodes[b])) {
        out.adjacent[a] |= std::uint64_t{1} << b;
        out.adjacent[b] |= std::uint64_t{1} << a;
      }
    }
  }
  return true;
}

std::uint64_t above(std::size_t index) {
  return index >= 63 ? 0 : ~((std::uint64_t{2} << index) - 1);
}

}  // namespace

ExplicitCells::ExplicitCells(std::size_t particleCount, std::shared_ptr<const CellList> shared)
    : list(std::move(shared)), offsets(particleCount + 1, 0) {
  const auto all = cells();
  for (const auto& cell : all) {
    for (ParticleIndex p : cell) {
      if (p >= 0) {
        ++offsets[static_cast<std::size_t>(p) + 1];
      }
    }
  }
  for (std::size_t i = 1; i < offsets.size(); ++i) {
    offsets[i] += offsets[i - 1];
  }
  cellsOfParticle.resize(static_cast<std::size_t>(offsets.back()));
  std::vector<std::int32_t> fill(offsets.begin(), offsets.end() - 1);
  for (std::size_t c = 0; c < all.size(); ++c) {
    for (ParticleIndex p : all[c]) {
      if (p >= 0) {
        cellsOfParticle[static_cast<std::size_t>(fill[static_cast<std::size_t>(p)]++)] =
            static_cast<std::int32_t>(c);
      }
    }
  }
}

std::size_t ExplicitCells::memoryBytes() const {
  return cells().size_bytes() +
         (offsets.capacity() + cellsOfParticle.capacity()) * sizeof(std::int32_t);
}

LatticeDecomposition::LatticeDecomposition(const BondGraph& graph, int dimension,
                                           const ExplicitCells* explicitCells)
    : m_graph(graph),
      m_dimension(dimension),
      m_explicit(explicitCells),
      m_head(graph.particleCount(), -1),
      m_processed(graph.particleCount()),
      m_seenState(graph.bondCount()) {}

void LatticeDecomposition::enumerateCandidates(ParticleIndex v, std::vector<Candidate>& out) const {
  if (m_explicit != nullptr) {
    const CellType type = m_dimension == 2 ? CellType::kTriangle : CellType::kTetrahedron;
    for (std::int32_t c : m_explicit->of(v)) {
      const auto& nodes = m_explicit->cells()[static_cast<std::size_t>(c)];
      out.push_back({type, {nodes[0], nodes[1], nodes[2], nodes[3], -1, -1}});
    }
    return;
  }
  NeighbourGraph local;
  if (!buildNeighbourGraph(m_graph, v, local)) {
    return;
  }
  const std::size_t n = local.nodes.size();
  const auto& adj = local.adjacent;
  if (m_dimension == 2) {
    for (std::size_t a = 0; a < n; ++a) {
      for (std::uint64_t bits = adj[a] & above(a); bits != 0; bits &= bits - 1) {
        const auto b = static_cast<std::size_t>(std::countr_zero(bits));
        Candidate c{CellType::kTriangle, {v, local.nodes[a], local.nodes[b], -1, -1, -1}};
        std::sort(c.nodes.begin(), c.nodes.begin() + 3);
        out.push_back(c);
      }
    }
    return;
  }
  // Tetrahedra: v plus a triangle of its neighbour graph.
  for (std::size_t a = 0; a < n; ++a) {
    for (std::uint64_t bBits = adj[a] & above(a); bBits != 0; bBits &= bBits - 1) {
      const auto b = static_cast<std::size_t>(std::countr_zero(bBits));
      for (std::uint64_t cBits = adj[a] & adj[b] & above(b); cBits != 0; cBits &= cBits - 1) {
        const auto c = static_cast<std::size_t>(std::countr_zero(cBits));
        Candidate t{CellType::kTetrahedron,
                    {v, local.nodes[a], local.nodes[b], local.nodes[c], -1, -1}};
        std::sort(t.nodes.begin(), t.nodes.begin() + 4);
        out.push_back(t);
      }
    }
  }
  // Octahedra: v, a chordless 4-cycle a-b-c-d of its neighbours, and a
  // particle w bonded to all four but not to v.
  for (std::size_t a = 0; a < n; ++a) {
    for (std::uint64_t bBits = adj[a] & above(a); bBits != 0; bBits &= bBits - 1) {
      const auto b = static_cast<std::size_t>(std::countr_zero(bBits));
      for (std::uint64_t dBits = adj[a] & above(b) & ~adj[b]; dBits != 0; dBits &= dBits - 1) {
        const auto d = static_cast<std::size_t>(std::countr_zero(dBits));
        for (std::uint64_t cBits = adj[b] & adj[d] & above(a) & ~adj[a]; cBits != 0;
             cBits &= cBits - 1) {
          const auto c = static_cast<std::size_t>(std::countr_zero(cBits));
          const ParticleIndex pa = local.nodes[a];
          const ParticleIndex pb = local.nodes[b];
          const ParticleIndex pc = local.nodes[c];
          const ParticleIndex pd = local.nodes[d];
          for (BondIndex bond : m_graph.bondsOf(pa)) {
            const ParticleIndex w = m_graph.otherEnd(bond, pa);
            if (w == v || m_graph.bonded(v, w) || !m_graph.bonded(w, pb) ||
                !m_graph.bonded(w, pc) || !m_graph.bonded(w, pd)) {
              continue;
            }
            out.push_back({CellType::kPyramid, {pa, pb, pc, pd, v, w}});
          }
        }
      }
    }
  }
}

bool LatticeDecomposition::hasCell(const LatticeCell& probe) const {
  bool found = false;
  forEachCellOwnedBy(probe.lowestNode(), [&](CellIndex c) {
    const LatticeCell& cell = m_cells[static_cast<std::size_t>(c)];
    found = found || (cell.type == probe.type && cell.nodes == probe.nodes);
  });
  return found;
}

void LatticeDecomposition::appendCell(LatticeCell cell, std::span<const std::uint8_t> bondState) {
  const CellShape& shape = shapeOf(cell.type);
  cell.brokenMask = 0;
  for (int e = 0; e < shape.edgeCount; ++e) {
    const auto& edge = shape.edges[static_cast<std::size_t>(e)];
    const ParticleIndex a = cell.nodes[edge[0]];
    const ParticleIndex b = cell.nodes[edge[1]];
    const auto bonds = m_graph.bondsOf(a);
    const auto slot = std::find_if(bonds.begin(), bonds.end(),
                                   [&](BondIndex bond) { return m_graph.otherEnd(bond, a) == b; });
    if (slot - bonds.begin() > 255) {
      // A byte holds the slot: a triangulation's hull can fan hundreds of
      // edges from one particle; such a cell is left out and counted.
      ++m_skippedCells;
      return;
    }
    cell.edgeSlots[static_cast<std::size_t>(e)] = static_cast<std::uint8_t>(slot - bonds.begin());
    if (bondState[static_cast<std::size_t>(*slot)] != 0) {
      cell.brokenMask = static_cast<std::uint8_t>(cell.brokenMask | (1u << e));
    }
  }
  // Grow by a quarter, not double: the cells are most of the memory.
  if (m_cells.size() == m_cells.capacity()) {
    m_cells.reserve(m_cells.size() + m_cells.size() / 4 + 1024);
    m_next.reserve(m_cells.capacity());
  }
  const auto index = static_cast<CellIndex>(m_cells.size());
  const auto owner = static_cast<std::size_t>(cell.lowestNode());
  m_cells.push_back(cell);
  m_next.push_back(m_head[owner]);
  m_head[owner] = index;
}

void LatticeDecomposition::insertCandidate(const Candidate& candidate,
                                           std::span<const std::uint8_t> bondState) {
  LatticeCell cell;
  cell.type = candidate.type;
  if (candidate.type != CellType::kPyramid) {
    const int count = candidate.type == CellType::kTriangle ? 3 : 4;
    std::copy_n(candidate.nodes.begin(), count, cell.nodes.begin());
    if (!hasCell(cell)) {
      appendCell(cell, bondState);
    }
    return;
  }
  // Octahedron: cycle a b c d, axis v w. Split along the diagonal through the
  // lowest of the six particles, so the split does not depend on which
  // particle found the octahedron.
  const auto& n = candidate.nodes;
  std::array<std::array<ParticleIndex, 2>, 3> diagonals{{{n[0], n[2]}, {n[1], n[3]}, {n[4], n[5]}}};
  const ParticleIndex lowest = *std::min_element(n.begin(), n.end());
  int axis = 0;
  for (int k = 0; k < 3; ++k) {
    const auto& diagonal = diagonals[static_cast<std::size_t>(k)];
    if (diagonal[0] == lowest || diagonal[1] == lowest) {
      axis = k;
    }
  }
  const auto& apexes = diagonals[static_cast<std::size_t>(axis)];
  const auto& first = diagonals[static_cast<std::size_t>((axis + 1) % 3)];
  const auto& second = diagonals[static_cast<std::size_t>((axis + 2) % 3)];
  // Base cycle alternates between the two remaining diagonals; start at the
  // lowest base particle and go towards the lower of its two neighbours.
  std::array<ParticleIndex, 4> base{first[0], second[0], first[1], second[1]};
  const auto start =
      static_cast<std::size_t>(std::min_element(base.begin(), base.end()) - base.begin());
  std::array<ParticleIndex, 4> rotated{};
  for (std::size_t k = 0; k < 4; ++k) {
    rotated[k] = base[(start + k) % 4];
  }
  if (rotated[3] < rotated[1]) {
    std::swap(rotated[1], rotated[3]);
  }
  const ParticleIndex apexA = std::min(apexes[0], apexes[1]);
  const ParticleIndex apexB = std::max(apexes[0], apexes[1]);
  LatticeCell a;
  a.type = CellType::kPyramid;
  std::copy(rotated.begin(), rotated.end(), a.nodes.begin());
  a.nodes[4] = apexA;
  if (hasCell(a)) {
    return;
  }
  LatticeCell b = a;
  b.nodes[4] = apexB;
  a.partnerOffset = 1;
  b.partnerOffset = -1;
  appendCell(a, bondState);
  appendCell(b, bondState);
}

void LatticeDecomposition::addCellsAround(std::span<const ParticleIndex> particles,
                                          std::span<const std::uint8_t> bondState) {
  std::vector<ParticleIndex> todo;
  for (ParticleIndex p : particles) {
    if (!m_processed.test(static_cast<std::size_t>(p))) {
      m_processed.set(static_cast<std::size_t>(p), true);
      todo.push_back(p);
    }
  }
  std::sort(todo.begin(), todo.end());
  // Enumeration only reads the graph: run it on all cores, then insert in
  // particle order so the cell list is the same for any thread count.
  std::vector<std::vector<Candidate>> candidates(todo.size());
  tbb::parallel_for(std::size_t{0}, todo.size(),
                    [&](std::size_t k) { enumerateCandidates(todo[k], candidates[k]); });
  for (std::size_t k = 0; k < todo.size(); ++k) {
    if (m_graph.bondsOf(todo[k]).size() > kMaxDegree) {
      ++m_skipped;
    }
    for (const Candidate& candidate : candidates[k]) {
      insertCandidate(candidate, bondState);
    }
  }
}

void LatticeDecomposition::buildGlobal(std::span<const std::uint8_t> bondState) {
  m_firstNewCell = static_cast<CellIndex>(m_cells.size());
  std::vector<ParticleIndex> all(m_graph.particleCount());
  for (std::size_t i = 0; i < all.size(); ++i) {
    all[i] = static_cast<ParticleIndex>(i);
  }
  addCellsAround(all, bondState);
  for (std::size_t b = 0; b < bondState.size(); ++b) {
    m_seenState.set(b, bondState[b] != 0);
  }
}

// Cells containing bond (i, j) are owned by their lowest particle, which is
// i, j, or bonded to one of them (in an octahedron every particle is bonded
// to all but its opposite), and is not above min(i, j).
template <typename Visit>
void LatticeDecomposition::forEachCellWithBond(BondIndex b, Visit&& visit) const {
  const dem::Bond& bond = m_graph.bond(b);
  const ParticleIndex low = std::min(bond.first, bond.second);
  auto visitOwner = [&](ParticleIndex owner) {
    if (owner > low) {
      return;
    }
    forEachCellOwnedBy(owner, [&](CellIndex c) {
      const LatticeCell& cell = m_cells[static_cast<std::size_t>(c)];
      const int a = cell.localNode(bond.first);
      const int z = a >= 0 ? cell.localNode(bond.second) : -1;
      if (z >= 0) {
        const int edge = localEdge(cell.type, a, z);
        if (edge >= 0) {
          visit(c, edge);
        }
      }
    });
  };
  // Owners can be reached from both ends; visit each owner once.
  thread_local std::vector<ParticleIndex> owners;
  owners.clear();
  for (ParticleIndex end : {bond.first, bond.second}) {
    owners.push_back(end);
    for (BondIndex n : m_graph.bondsOf(end)) {
      owners.push_back(m_graph.otherEnd(n, end));
    }
  }
  std::sort(owners.begin(), owners.end());
  owners.erase(std::unique(owners.begin(), owners.end()), owners.end());
  for (ParticleIndex owner : owners) {
    visitOwner(owner);
  }
}

void LatticeDecomposition::setBrokenBit(BondIndex b, bool broken) {
  forEachCellWithBond(b, [&](CellIndex c, int edge) {
    LatticeCell& cell = m_cells[static_cast<std::size_t>(c)];
    const auto bit = static_cast<std::uint8_t>(1u << edge);
    cell.brokenMask =
        static_cast<std::uint8_t>(broken ? cell.brokenMask | bit : cell.brokenMask & ~bit);
  });
}

const std::vector<BondIndex>& LatticeDecomposition::update(
    std::span<const std::uint8_t> bondState) {
  m_changed.clear();
  std::vector<ParticleIndex> ends;
  // 64 bonds at a time against the seen bits: most words have not changed.
  for (std::size_t word = 0; word * 64 < bondState.size(); ++word) {
    const std::size_t first = word * 64;
    const std::size_t count = std::min<std::size_t>(64, bondState.size() - first);
    std::uint64_t now = 0;
    for (std::size_t k = 0; k < count; ++k) {
      now |= static_cast<std::uint64_t>(bondState[first + k] != 0) << k;
    }
    for (std::uint64_t diff = now ^ m_seenState.word(word); diff != 0; diff &= diff - 1) {
      const std::size_t b = first + static_cast<std::size_t>(std::countr_zero(diff));
      m_changed.push_back(static_cast<BondIndex>(b));
      if (bondState[b] != 0) {
        ends.push_back(m_graph.bond(static_cast<BondIndex>(b)).first);
        ends.push_back(m_graph.bond(static_cast<BondIndex>(b)).second);
      }
    }
  }
  m_firstNewCell = static_cast<CellIndex>(m_cells.size());
  addCellsAround(ends, bondState);  // new cells get their masks from bondState
  for (BondIndex b : m_changed) {
    const bool broken = bondState[static_cast<std::size_t>(b)] != 0;
    setBrokenBit(b, broken);
    m_seenState.set(static_cast<std::size_t>(b), broken);
  }
  return m_changed;
}

void LatticeDecomposition::cellsOfBond(BondIndex b, std::vector<CellIndex>& out) const {
  out.clear();
  forEachCellWithBond(b, [&](CellIndex c, int) { out.push_back(c); });
  std::sort(out.begin(), out.end());
}

std::size_t LatticeDecomposition::memoryBytes() const {
  return m_cells.capacity() * sizeof(LatticeCell) + m_head.capacity() * sizeof(CellIndex) +
         m_next.capacity() * sizeof(CellIndex) + m_processed.bytes() + m_seenState.bytes() +
         m_changed.capacity() * sizeof(BondIndex);
}

}  // namespace crackvis::cracks
