// Cell cut method (dissertation 2.1.2): in every cell of the local
// decomposition that a crack cuts, the primitives of the case table through
// the midpoints of its broken bonds. One point per broken bond, shared by all
// cells around it, so the surface is one connected mesh.
//
// Incremental: the decomposition only grows around newly broken bonds, and a
// broken bond keeps its point index from the step it broke on; per step only
// the midpoints move and the primitives are re-emitted from the cached masks.
#include <tbb/parallel_for.h>

#include "methods.hpp"
#include <crackvis/cracks/cut_cases.hpp>

namespace crackvis::cracks {
namespace {

class CellCutExtractor final : public CrackExtractor {
 public:
  CellCutExtractor(const BondGraph& graph, int dimension, const ExplicitCells* cells)
      : m_decomposition(graph, dimension, cells), m_pointOfBond(graph.bondCount(), -1) {}

  Method method() const override { return Method::kCellCut; }
  const LatticeDecomposition* decomposition() const override { return &m_decomposition; }

  std::size_t memoryBytes() const override {
    return m_decomposition.memoryBytes() + m_pointOfBond.capacity() * sizeof(std::int32_t) +
           m_pointBonds.capacity() * sizeof(dem::BondIndex) +
           m_orientation.capacity() * sizeof(Orientation);
  }

  Status extract(const StepInput& step, CrackMesh& out) override {
    CRACKVIS_RETURN_IF_ERROR(checkStepInput(m_decomposition.graph(), step));
    updatePoints(m_decomposition.update(step.bondState), step.bondState);
    out.clear();
    out.dimension = m_decomposition.dimension();
    computeMidpoints(step, out.points);
    std::vector<std::int32_t> tags;
    const auto& cells = m_decomposition.cells();
    m_orientation.resize(cells.size());
    fillInBlocks(cells.size(), m_blocks, out, tags,
                 [&](std::size_t first, std::size_t last, PrimitiveBlock& block) {
                   for (std::size_t c = first; c < last; ++c) {
                     if (cells[c].brokenMask != 0) {
                       emitCell(cells[c], static_cast<std::int32_t>(c), out.points, step.positions,
                                m_orientation[c], block);
                     }
                   }
                 });
    AttributeArray cellIndex{"cell_index", AttributeType::kInt32, 1, {tags.begin(), tags.end()}};
    out.cellData.push_back(std::move(cellIndex));
    appendBondAttributes(step, m_pointBonds, out.pointData);
    return Status::ok();
  }

 private:
  // New broken bonds get the next point index; a bond that is intact again
  // (the viewer stepped back in time) makes the numbering start over.
  void updatePoints(const std::vector<dem::BondIndex>& changed,
                    std::span<const std::uint8_t> state) {
    bool healed = false;
    for (dem::BondIndex b : changed) {
      healed = healed || state[static_cast<std::size_t>(b)] == 0;
    }
    if (healed) {
      std::fill(m_pointOfBond.begin(), m_pointOfBond.end(), -1);
      m_pointBonds.clear();
      for (std::size_t b = 0; b < state.size(); ++b) {
        if (state[b] != 0) {
          addPoint(static_cast<dem::BondIndex>(b));
        }
      }
      return;
    }
    for (dem::BondIndex b : changed) {
      addPoint(b);
    }
  }

  void addPoint(dem::BondIndex b) {
    m_pointOfBond[static_cast<std::size_t>(b)] = static_cast<std::int32_t>(m_pointBonds.size());
    m_pointBonds.push_back(b);
  }

  void computeMidpoints(const StepInput& step, std::vector<Vec3>& points) const {
    points.resize(m_pointBonds.size());
    const BondGraph& graph = m_decomposition.graph();
    tbb::parallel_for(std::size_t{0}, m_pointBonds.size(), [&](std::size_t k) {
      const dem::Bond& bond = graph.bond(m_pointBonds[k]);
      points[k] = 0.5 * (step.positions[static_cast<std::size_t>(bond.first)] +
                         step.positions[static_cast<std::size_t>(bond.second)]);
    });
  }

  std::int32_t pointOf(const LatticeCell& cell, std::uint8_t edge) const {
    return m_pointOfBond[static_cast<std::size_t>(m_decomposition.bondOf(cell, edge))];
  }

  // Which polygons of a cell's case are reversed, decided with the positions
  // of the step the case first appeared in: lattice cells do not turn inside
  // out, so the orientation holds until the case changes.
  struct Orientation {
    std::uint8_t mask = 0;  // the case it was computed for (0: not yet)
    std::uint8_t reversed = 0;
  };

  void emitCell(const LatticeCell& cell, std::int32_t index, const std::vector<Vec3>& points,
                std::span<const Vec3> positions, Orientation& orientation,
                PrimitiveBlock& block) const {
    const CutCase& cut = cutCase(cell.type, cell.brokenMask);
    const bool known = orientation.mask == cell.brokenMask;
    if (!known) {
      orientation.mask = cell.brokenMask;
      orientation.reversed = 0;
    }
    for (std::uint8_t edge : cut.points) {
      block.vertices.push_back(pointOf(cell, edge));
      block.vertexTags.push_back(index);
    }
    for (const auto& line : cut.lines) {
      block.lines.add({pointOf(cell, line[0]), pointOf(cell, line[1])});
      block.lineTags.push_back(index);
    }
    for (std::size_t p = 0; p < cut.polygons.size(); ++p) {
      const CutPolygon& polygon = cut.polygons[p];
      std::array<std::int32_t, kMaxCellEdges> ids{};
      const std::size_t count = polygon.edges.size();
      for (std::size_t k = 0; k < count; ++k) {
        ids[k] = pointOf(cell, polygon.edges[k]);
      }
      if (count == 2) {  // 2D: the enclosure is a segment
        block.lines.addRange(ids.begin(), ids.begin() + 2);
        block.lineTags.push_back(index);
        continue;
      }
      const auto bit = static_cast<std::uint8_t>(1u << p);
      if (!known &&
          pointsTowards(cell, polygon.insideNodes, points, positions, ids.data(), count)) {
        orientation.reversed = static_cast<std::uint8_t>(orientation.reversed | bit);
      }
      if (orientation.reversed & bit) {
        std::reverse(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(count));
      }
      block.polygons.addRange(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(count));
      block.polygonTags.push_back(index);
    }
  }

  // Whether the polygon's normal points towards the enclosed particles (it
  // should point away from them, to the rest of the cell).
  static bool pointsTowards(const LatticeCell& cell, std::uint8_t insideNodes,
                            const std::vector<Vec3>& points, std::span<const Vec3> positions,
                            const std::int32_t* ids, std::size_t count) {
    Vec3 inside{};
    int insideCount = 0;
    for (int k = 0; k < cell.nodeCount(); ++k) {
      if ((insideNodes >> k) & 1u) {
        inside =
            inside + positions[static_cast<std::size_t>(cell.nodes[static_cast<std::size_t>(k)])];
        ++insideCount;
      }
    }
    Vec3 centre{};
    for (std::size_t k = 0; k < count; ++k) {
      centre = centre + points[static_cast<std::size_t>(ids[k])];
    }
    const Vec3 towardsInside =
        (1.0 / insideCount) * inside - (1.0 / static_cast<double>(count)) * centre;
    return dem::dot(polygonNormal(points, ids, count), towardsInside) > 0.0;
  }

  LatticeDecomposition m_decomposition;
  std::vector<PrimitiveBlock> m_blocks;      // per-step scratch, kept for its buffers
  std::vector<std::int32_t> m_pointOfBond;   // [M] point index of a broken bond, else -1
  std::vector<dem::BondIndex> m_pointBonds;  // point index -> bond, in order of breaking
  std::vector<Orientation> m_orientation;    // [cells]
};

}  // namespace

std::unique_ptr<CrackExtractor> makeCellCut(const BondGraph& graph, int dimension,
                                            const ExtractOptions&, const ExplicitCells* cells) {
  return std::make_unique<CellCutExtractor>(graph, dimension, cells);
}

}  // namespace crackvis::cracks
