// Crack extraction on packings whose bonds span no lattice (random and
// polydisperse packings, what Yade, ESyS-Particle and LAMMPS users run).
//
// Space is divided by the Delaunay (equal radii) or regular (unequal radii)
// triangulation of the reference configuration, made once. Its edges that
// are no bond become "virtual bonds" appended after the file's M bonds, so
// the four methods run unchanged on the extended graph with the
// triangulation's cells; local Voronoi then clips each cell by every
// triangulation neighbour, which makes it the (power) Voronoi cell.
//
// The rule for a never-bonded neighbour pair (i, j): it counts as bonded
// through every common bonded neighbour k (paths i-k-j of two bonds) or, if
// it has none, through every path i-k-l-j of three bonds, and breaks when the
// last such path has a broken bond. Material that holds together around the
// pair keeps it closed; a crack that cuts every path between i and j opens it
// with the real bonds around it. A pair with no such path (at the specimen's
// surface, or across a void) breaks when the intact bonds no longer join ends
// that the intact packing joined (a through crack separates them): at the
// surface and in a void it stays closed, a particle with no bond (a rattler)
// never opens, and a through crack leaves no hole. A bonded pair
// that is no triangulation neighbour keeps its bond, but no cell holds it,
// so it makes no face of its own (cell methods) or none that exists (local
// Voronoi reports it inconsistent); a bonded edge of peeled hull slivers
// alone is held by no cell either.
#include <algorithm>
#include <map>
#include <numeric>
#include <optional>

#include <fmt/format.h>

#include "methods.hpp"
#include <crackvis/cracks/partition.hpp>
#include <crackvis/cracks/surface_primitives.hpp>
#include <crackvis/cracks/triangulation.hpp>

namespace crackvis::cracks {
namespace {

class TriangulatedExtractor final : public CrackExtractor {
 public:
  TriangulatedExtractor(Method method, const BondGraph& graph, int dimension,
                        const ExtractOptions& options)
      : m_method(method), m_graph(graph), m_dimension(dimension), m_options(options) {
    if (!m_options.domain && m_options.domainMargin == 0.0) {
      m_options.domainMargin = 1.0;
    }
  }

  Method method() const override { return m_method; }
  Decomposition decompositionKind() const override { return Decomposition::kTriangulation; }
  const LatticeDecomposition* decomposition() const override {
    return m_inner ? m_inner->decomposition() : nullptr;
  }
  std::size_t inconsistentBondCount() const override { return m_inconsistent; }
  std::size_t memoryBytes() const override {
    std::size_t bytes =
        m_bonds.capacity() * sizeof(dem::Bond) + m_cells.memoryBytes() +
        m_supportStart.capacity() * sizeof(std::int32_t) +
        m_support.capacity() * sizeof(m_support[0]) + m_state.capacity() +
        m_force.capacity() * sizeof(float) + m_breakStep.capacity() * sizeof(std::int32_t) +
        m_piece.capacity() * sizeof(std::int32_t) + m_joined.capacity() + m_marked.capacity();
    if (m_extended) {
      bytes += m_extended->memoryBytes();
    }
    return m_inner ? bytes + m_inner->memoryBytes() : bytes;
  }

  Status extract(const StepInput& step, CrackMesh& out) override {
    CRACKVIS_RETURN_IF_ERROR(checkStepInput(m_graph, step));
    if (!m_inner) {
      CRACKVIS_RETURN_IF_ERROR(build(step));
    }
    extendStep(step);
    StepInput extended = step;
    extended.bondState = m_state;
    extended.bondForce = step.bondForce.empty() ? std::span<const float>{} : m_force;
    extended.breakStep = step.breakStep.empty() ? std::span<const std::int32_t>{} : m_breakStep;
    CRACKVIS_RETURN_IF_ERROR(m_inner->extract(extended, out));
    dropVirtualInconsistencies(out);
    if (m_options.ownerParticles) {
      appendOwnerParticles(out, m_bonds);  // virtual bonds still have their ids here
    }
    hideVirtualBondIds(out);
    return Status::ok();
  }

 private:
  Status build(const StepInput& step) {
    const std::span<const Vec3> reference =
        step.referencePositions.empty() ? step.positions : step.referencePositions;
    if (reference.size() != m_graph.particleCount()) {
      return invalidArgument(fmt::format("{} reference positions for N = {} particles",
                                         reference.size(), m_graph.particleCount()));
    }
    // A given triangulation is used where it is, not copied: its caller
    // keeps it (ExtractOptions::triangulation), and its cells are shared.
    const std::shared_ptr<const Triangulation>& given = m_options.triangulation;
    Triangulation made;
    if (given) {
      CRACKVIS_RETURN_IF_ERROR(checkGiven(*given));
    } else {
      auto triangulated = triangulate(reference, step.radius, m_dimension);
      if (!triangulated) {
        return triangulated.status();
      }
      made = std::move(*triangulated);
    }
    const Triangulation& triangulation = given ? *given : made;
    m_bonds.assign(m_graph.bonds().begin(), m_graph.bonds().end());
    m_supportStart.assign(1, 0);
    for (const dem::Bond& edge : triangulation.edges) {
      if (!m_graph.bonded(edge.first, edge.second)) {
        m_bonds.push_back(edge);
        addSupport(edge);
      }
    }
    made.edges = {};  // read: a triangulation made here keeps only its cells
    if (!step.intactComponents.empty()) {
      usePieces(step.intactComponents);
    } else {
      markPieces({});
    }
    m_joined.assign(m_supportStart.size() - 1, 0);
    for (std::size_t v = 0; v + 1 < m_supportStart.size(); ++v) {
      const dem::Bond& pair = m_bonds[m_graph.bondCount() + v];
      const bool unheld = m_supportStart[v] == m_supportStart[v + 1];
      m_joined[v] = unheld && m_piece[static_cast<std::size_t>(pair.first)] ==
                                  m_piece[static_cast<std::size_t>(pair.second)];
      m_joinedCount += m_joined[v];
    }
    m_extended.emplace(m_graph.particleCount(), m_bonds);
    m_cells = given ? ExplicitCells(m_graph.particleCount(),
                                    std::shared_ptr<const ExplicitCells::CellList>(
                                        given, &given->cells))  // aliasing: kept alive by it
                    : ExplicitCells(m_graph.particleCount(), std::move(made.cells));
    m_inner = makeInner();
    return Status::ok();
  }

  // A triangulation the caller gives (ExtractOptions::triangulation),
  // checked against the particles.
  Status checkGiven(const Triangulation& triangulation) const {
    const auto n = static_cast<dem::ParticleIndex>(m_graph.particleCount());
    auto outside = [n](dem::ParticleIndex i) { return i < -1 || i >= n; };
    for (const auto& cell : triangulation.cells) {
      if (std::any_of(cell.begin(), cell.end(), outside)) {
        return invalidArgument(
            fmt::format("a given triangulation cell names a particle beyond N = {}", n));
      }
    }
    for (const dem::Bond& edge : triangulation.edges) {
      if (edge.first < 0 || edge.second < 0 || outside(edge.first) || outside(edge.second)) {
        return invalidArgument(
            fmt::format("a given triangulation edge names a particle beyond N = {}", n));
      }
    }
    return Status::ok();
  }

  // The two-bond paths i-k-j between the ends of a never-bonded edge (both
  // bond lists are sorted by their other end, so one merge finds the k), or
  // the three-bond paths i-k-l-j when there is none.
  void addSupport(const dem::Bond& edge) {
    const std::size_t before = m_support.size();
    const auto first = m_graph.bondsOf(edge.first);
    const auto second = m_graph.bondsOf(edge.second);
    auto a = first.begin();
    auto b = second.begin();
    while (a != first.end() && b != second.end()) {
      const dem::ParticleIndex ka = m_graph.otherEnd(*a, edge.first);
      const dem::ParticleIndex kb = m_graph.otherEnd(*b, edge.second);
      if (ka < kb) {
        ++a;
      } else if (kb < ka) {
        ++b;
      } else {
        m_support.push_back({*a, *b, -1});
        ++a;
        ++b;
      }
    }
    if (m_support.size() == before) {
      for (dem::BondIndex ik : first) {
        const dem::ParticleIndex k = m_graph.otherEnd(ik, edge.first);
        for (dem::BondIndex lj : second) {
          const dem::ParticleIndex l = m_graph.otherEnd(lj, edge.second);
          const dem::BondIndex kl = k == l ? -1 : m_graph.bondBetween(k, l);
          if (k != edge.second && l != edge.first && kl >= 0) {
            m_support.push_back({ik, kl, lj});
          }
        }
      }
    }
    m_supportStart.push_back(static_cast<std::int32_t>(m_support.size()));
  }

  std::unique_ptr<CrackExtractor> makeInner() const {
    switch (m_method) {
      case Method::kCellAttribute:
        return makeCellAttribute(*m_extended, m_dimension, m_options, &m_cells);
      case Method::kCellCut:
        return makeCellCut(*m_extended, m_dimension, m_options, &m_cells);
      case Method::kLocalVoronoi:
        return makeLocalVoronoi(*m_extended, m_dimension, m_options);
      case Method::kCellCentre:
        return makeCellCentre(*m_extended, m_dimension, m_options, &m_cells);
    }
    return nullptr;
  }

  // The step's arrays over the extended bonds: a virtual bond is broken when
  // every path that held it has a broken bond, since the step the last of
  // them broke (a path breaks with its first bond); it carries no force.
  void extendStep(const StepInput& step) {
    const std::size_t m = m_graph.bondCount();
    const std::size_t virtualCount = m_bonds.size() - m;
    m_state.assign(step.bondState.begin(), step.bondState.end());
    m_state.resize(m_bonds.size(), 0);
    if (!step.breakStep.empty()) {
      m_breakStep.assign(step.breakStep.begin(), step.breakStep.end());
      m_breakStep.resize(m_bonds.size(), -1);
    }
    if (!step.bondForce.empty()) {
      m_force.assign(step.bondForce.begin(), step.bondForce.end());
      m_force.resize(m_bonds.size(), 0.0f);
    }
    if (m_joinedCount > 0 && !step.components.empty()) {
      usePieces(step.components);
    } else if (m_joinedCount > 0) {
      markPieces(step.bondState);
    }
    for (std::size_t v = 0; v < virtualCount; ++v) {
      const auto first = static_cast<std::size_t>(m_supportStart[v]);
      const auto last = static_cast<std::size_t>(m_supportStart[v + 1]);
      if (first == last) {
        if (m_joined[v] != 0) {
          extendUnheld(step, m + v);
        }
        continue;
      }
      bool broken = true;
      std::int32_t brokeAt = -1;
      for (std::size_t s = first; s < last && broken; ++s) {
        std::int32_t pathBrokeAt = -1;
        broken = false;
        for (dem::BondIndex bond : m_support[s]) {
          if (bond >= 0 && step.bondState[static_cast<std::size_t>(bond)] != 0) {
            broken = true;
            if (!step.breakStep.empty()) {
              const std::int32_t at = step.breakStep[static_cast<std::size_t>(bond)];
              pathBrokeAt =
                  pathBrokeAt < 0 ? at : (at < 0 ? pathBrokeAt : std::min(pathBrokeAt, at));
            }
          }
        }
        brokeAt = std::max(brokeAt, pathBrokeAt);
      }
      m_state[m + v] = broken ? 1 : 0;
      if (!step.breakStep.empty()) {
        m_breakStep[m + v] = broken ? brokeAt : -1;
      }
    }
  }

  // The whole set's components, given for a piece of it (StepInput).
  void usePieces(std::span<const std::int32_t> components) {
    m_piece.assign(components.begin(), components.end());
    m_marked.clear();  // markPieces marks afresh
  }

  // The piece (connected by intact bonds) of each particle; with no state,
  // of the intact packing. A state equal to the last one marked is not
  // marked again.
  void markPieces(std::span<const std::uint8_t> bondState) {
    const std::size_t m = m_graph.bondCount();
    if (!bondState.empty() && m_marked.size() == m &&
        std::equal(m_marked.begin(), m_marked.end(), bondState.begin())) {
      return;
    }
    m_marked.assign(bondState.begin(), bondState.end());
    m_piece = connectedComponents(m_graph.particleCount(), m_graph.bonds(), bondState);
  }

  // A virtual bond no short path holds, between particles the intact packing
  // joins, is broken while its ends lie in different pieces, since the latest
  // break among its ends' bonds (when the step has break steps).
  void extendUnheld(const StepInput& step, std::size_t v) {
    const dem::Bond& pair = m_bonds[v];
    const bool broken = m_piece[static_cast<std::size_t>(pair.first)] !=
                        m_piece[static_cast<std::size_t>(pair.second)];
    m_state[v] = broken ? 1 : 0;
    if (step.breakStep.empty()) {
      return;
    }
    std::int32_t brokeAt = -1;
    for (dem::ParticleIndex end : {pair.first, pair.second}) {
      for (dem::BondIndex b : m_graph.bondsOf(end)) {
        if (broken && step.bondState[static_cast<std::size_t>(b)] != 0) {
          brokeAt = std::max(brokeAt, step.breakStep[static_cast<std::size_t>(b)]);
        }
      }
    }
    m_breakStep[v] = brokeAt;
  }

  // A virtual bond whose face local Voronoi cannot make (a pair at the
  // specimen's surface whose face lies outside the domain) is no bond of the
  // file gone missing: its inconsistency mark is dropped, and only the file's
  // bonds count as inconsistent.
  void dropVirtualInconsistencies(CrackMesh& out) {
    m_inconsistent = 0;
    const AttributeArray* flag = out.findCellData("inconsistent");
    const AttributeArray* ids = out.findCellData("bond_id");
    if (flag == nullptr || ids == nullptr) {
      return;
    }
    const auto m = static_cast<double>(m_graph.bondCount());
    const std::size_t base = out.vertices.size();
    std::vector<char> keep(out.primitiveCount(), 1);
    PrimitiveList lines;
    for (std::size_t k = 0; k < out.lines.size(); ++k) {
      const bool flagged = flag->values[base + k] != 0.0;
      const bool virtualBond = ids->values[base + k] >= m;
      keep[base + k] = flagged && virtualBond ? 0 : 1;
      if (keep[base + k] != 0) {
        m_inconsistent += flagged ? 1 : 0;
        lines.addRange(out.lines.connectivity.begin() + out.lines.offsets[k],
                       out.lines.connectivity.begin() + out.lines.offsets[k + 1]);
      }
    }
    out.lines = std::move(lines);
    for (AttributeArray& array : out.cellData) {
      std::size_t kept = 0;
      const auto width = static_cast<std::size_t>(array.components);
      for (std::size_t p = 0; p < keep.size(); ++p) {
        if (keep[p] != 0) {
          std::copy_n(array.values.begin() + static_cast<std::ptrdiff_t>(p * width), width,
                      array.values.begin() + static_cast<std::ptrdiff_t>(kept * width));
          ++kept;
        }
      }
      array.values.resize(kept * width);
    }
  }

  // A virtual bond is no bond of the file: its faces get bond_id -1.
  void hideVirtualBondIds(CrackMesh& out) const {
    const auto m = static_cast<double>(m_graph.bondCount());
    for (auto* arrays : {&out.cellData, &out.pointData}) {
      for (AttributeArray& array : *arrays) {
        if (array.name == "bond_id" || array.name == "first_broken_bond") {
          for (double& id : array.values) {
            id = id >= m ? -1.0 : id;
          }
        }
      }
    }
  }

  Method m_method;
  const BondGraph& m_graph;
  int m_dimension;
  ExtractOptions m_options;
  std::vector<dem::Bond> m_bonds;  // the graph's M bonds, then the virtual ones
  std::optional<BondGraph> m_extended;
  ExplicitCells m_cells;
  std::vector<std::int32_t> m_supportStart;              // [virtual + 1]
  std::vector<std::array<dem::BondIndex, 3>> m_support;  // paths of 2 (third -1) or 3 bonds
  std::unique_ptr<CrackExtractor> m_inner;
  std::vector<std::uint8_t> m_state;
  std::vector<float> m_force;
  std::vector<std::int32_t> m_breakStep;
  // Virtual bonds no path of 2 or 3 bonds holds whose ends the intact
  // packing joins (1 each, over the virtual bonds), and how many.
  std::vector<std::uint8_t> m_joined;
  std::size_t m_joinedCount = 0;
  std::vector<std::int32_t> m_piece;   // markPieces: the root of each particle's piece
  std::vector<std::uint8_t> m_marked;  // the bond state m_piece is of
  std::size_t m_inconsistent = 0;
};

}  // namespace

std::unique_ptr<CrackExtractor> makeTriangulated(Method method, const BondGraph& graph,
                                                 int dimension, const ExtractOptions& options) {
  return std::make_unique<TriangulatedExtractor>(method, graph, dimension, options);
}

bool isLatticeGraph(const BondGraph& graph, int dimension) {
  const std::size_t n = graph.particleCount();
  if (n == 0 || graph.bondCount() == 0) {
    return true;
  }
  constexpr std::size_t kSample = 256;
  const std::size_t stride = std::max<std::size_t>(1, n / kSample);
  std::vector<dem::ParticleIndex> sample;
  for (std::size_t i = 0; i < n; i += stride) {
    sample.push_back(static_cast<dem::ParticleIndex>(i));
  }
  const std::vector<std::uint8_t> intact(graph.bondCount(), 0);
  LatticeDecomposition cells(graph, dimension);
  cells.addCellsAround(sample, intact);
  std::size_t bonds = 0;
  std::size_t covered = 0;
  std::vector<CellIndex> found;
  for (dem::ParticleIndex p : sample) {
    for (dem::BondIndex b : graph.bondsOf(p)) {
      cells.cellsOfBond(b, found);
      ++bonds;
      covered += found.empty() ? 0 : 1;
    }
  }
  if (bonds > 0 && static_cast<double>(covered) < 0.98 * static_cast<double>(bonds)) {
    return false;
  }
  // Covered is not enough: a densely bonded random packing (Yade's bonds at
  // 1.5 x the radius sum) has nearly every bond in some bonded tetrahedron,
  // but those tetrahedra overlap. Cells that tile share each face with at
  // most one other cell; count how many faces at the sample have more.
  std::map<std::array<dem::ParticleIndex, 4>, int> faceUses;
  std::vector<CellIndex> around;
  for (dem::ParticleIndex p : sample) {
    around.clear();
    for (dem::BondIndex b : graph.bondsOf(p)) {
      cells.cellsOfBond(b, found);
      around.insert(around.end(), found.begin(), found.end());
    }
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    for (CellIndex c : around) {
      const LatticeCell& cell = cells.cell(c);
      const CellShape& shape = shapeOf(cell.type);
      for (int f = 0; f < shape.faceCount; ++f) {
        std::array<dem::ParticleIndex, 4> face{-1, -1, -1, -1};
        bool atSample = false;
        for (int k = 0; k < shape.faceSizes[static_cast<std::size_t>(f)]; ++k) {
          const auto node = static_cast<std::size_t>(
              shape.faces[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)]);
          face[static_cast<std::size_t>(k)] = cell.nodes[node];
          atSample = atSample || cell.nodes[node] == p;
        }
        if (atSample) {
          std::sort(face.begin(), face.end());
          ++faceUses[face];
        }
      }
    }
  }
  // Each face is counted once per sampled particle on it and cell using it;
  // a tiling's face has at most two cells, whatever the multiplicity.
  std::size_t overlapping = 0;
  for (const auto& [face, uses] : faceUses) {
    const auto onSample = static_cast<int>(std::count_if(face.begin(), face.end(), [&](auto node) {
      return node >= 0 && std::binary_search(sample.begin(), sample.end(), node);
    }));
    overlapping += uses > 2 * std::max(1, onSample) ? 1 : 0;
  }
  return static_cast<double>(overlapping) <= 0.01 * static_cast<double>(faceUses.size());
}

}  // namespace crackvis::cracks
