// Cell attribute method (dissertation 2.1.1): the cells of the decomposition
// with the number of their broken bonds as a cell attribute (eq. 2.2).
#include <algorithm>
#include <cmath>

#include "methods.hpp"

namespace crackvis::cracks {
namespace {

// The bond quantities the other methods carry per face, per cell here, so
// that a cell attribute view can be coloured by them too:
// first_broken_bond, the lowest index of the cell's broken bonds (not
// bond_id: a cell stands for several bonds, and bond_id means one);
// break_step, when the cell first cracked (the earliest break); bond_force,
// the largest magnitude on the cell's bonds (the load around the crack). The
// state is broken_bonds itself.
// The nodes of a volume cell in the order VTK counts its volume positive:
// a tetrahedron's first three points turn counter-clockwise seen from the
// fourth, a pyramid's base does so seen from its apex. The decomposition
// keeps a tetrahedron's nodes by particle index, so about half of them came
// out inside out (ParaView's Integrate Variables summed a negative volume).
// The current positions decide: the picture is of this step.
std::array<dem::ParticleIndex, kMaxCellNodes> vtkOrder(const LatticeCell& cell,
                                                       std::span<const dem::Vec3> positions) {
  std::array<dem::ParticleIndex, kMaxCellNodes> nodes = cell.nodes;
  auto at = [&](int k) { return positions[static_cast<std::size_t>(nodes[k])]; };
  if (cell.type == CellType::kTetrahedron) {
    if (dem::dot(at(1) - at(0), cross(at(2) - at(0), at(3) - at(0))) < 0.0) {
      std::swap(nodes[1], nodes[2]);
    }
  } else if (cell.type == CellType::kPyramid) {
    const dem::Vec3 normal = cross(at(2) - at(0), at(3) - at(1));
    if (dem::dot(normal, at(4) - at(0)) < 0.0) {
      std::swap(nodes[1], nodes[3]);  // the base cycle the other way round
    }
  }
  return nodes;
}

class CellBondValues {
 public:
  explicit CellBondValues(const StepInput& step)
      : m_hasBreakStep(!step.breakStep.empty()), m_hasForce(!step.bondForce.empty()) {}

  void add(const LatticeCell& cell, const LatticeDecomposition& cells, const StepInput& step) {
    double lowestId = -1.0;
    double earliest = -1.0;
    double load = 0.0;
    for (int e = 0; e < cell.edgeCount(); ++e) {
      const auto b = static_cast<std::size_t>(cells.bondOf(cell, e));
      if (b >= step.bondState.size()) {
        continue;  // a triangulation's edge that was never a bond
      }
      if (m_hasForce) {
        load = std::max(load, std::abs(static_cast<double>(step.bondForce[b])));
      }
      if ((cell.brokenMask & (1U << e)) == 0) {
        continue;
      }
      if (lowestId < 0.0 || static_cast<double>(b) < lowestId) {
        lowestId = static_cast<double>(b);
      }
      if (m_hasBreakStep && (earliest < 0.0 || step.breakStep[b] < earliest)) {
        earliest = step.breakStep[b];
      }
    }
    m_id.values.push_back(lowestId);
    if (m_hasBreakStep) {
      m_breakStep.values.push_back(earliest);
    }
    if (m_hasForce) {
      m_force.values.push_back(load);
    }
  }

  void moveTo(std::vector<AttributeArray>& arrays) {
    arrays.push_back(std::move(m_id));
    if (m_hasBreakStep) {
      arrays.push_back(std::move(m_breakStep));
    }
    if (m_hasForce) {
      arrays.push_back(std::move(m_force));
    }
  }

 private:
  bool m_hasBreakStep;
  bool m_hasForce;
  AttributeArray m_id{"first_broken_bond", AttributeType::kInt32, 1, {}};
  AttributeArray m_breakStep{"break_step", AttributeType::kInt32, 1, {}};
  AttributeArray m_force{"bond_force", AttributeType::kFloat32, 1, {}};
};

class CellAttributeExtractor final : public CrackExtractor {
 public:
  CellAttributeExtractor(const BondGraph& graph, int dimension, const ExtractOptions& options,
                         const ExplicitCells* cells)
      : m_decomposition(graph, dimension, cells),
        m_options(options),
        m_pointOf(graph.particleCount(), -1) {}

  Method method() const override { return Method::kCellAttribute; }
  const LatticeDecomposition* decomposition() const override { return &m_decomposition; }

  std::size_t memoryBytes() const override {
    return m_decomposition.memoryBytes() + m_pointOf.capacity() * sizeof(std::int32_t);
  }

  Status extract(const StepInput& step, CrackMesh& out) override {
    CRACKVIS_RETURN_IF_ERROR(checkStepInput(m_decomposition.graph(), step));
    if (m_options.globalDecomposition && m_decomposition.cellCount() == 0) {
      m_decomposition.buildGlobal(step.bondState);
    }
    m_decomposition.update(step.bondState);
    out.clear();
    out.dimension = m_decomposition.dimension();
    AttributeArray broken{"broken_bonds", AttributeType::kInt32, 1, {}};
    CellBondValues bondValues(step);
    std::vector<dem::ParticleIndex> used;
    for (const LatticeCell& cell : m_decomposition.cells()) {
      if (cell.brokenCount() < m_options.minBrokenBonds) {
        continue;
      }
      std::array<std::int32_t, kMaxCellNodes> ids{};
      const int count = cell.nodeCount();
      const std::array<dem::ParticleIndex, kMaxCellNodes> nodes = vtkOrder(cell, step.positions);
      for (int k = 0; k < count; ++k) {
        const auto particle = static_cast<std::size_t>(nodes[static_cast<std::size_t>(k)]);
        if (m_pointOf[particle] < 0) {
          m_pointOf[particle] = static_cast<std::int32_t>(used.size());
          used.push_back(static_cast<dem::ParticleIndex>(particle));
        }
        ids[static_cast<std::size_t>(k)] = m_pointOf[particle];
      }
      if (cell.type == CellType::kTriangle) {
        out.polygons.addRange(ids.begin(), ids.begin() + 3);
      } else {
        out.volumeCells.addRange(ids.begin(), ids.begin() + count);
        out.volumeCellTypes.push_back(static_cast<std::uint8_t>(vtkCellTypeOf(cell.type)));
      }
      broken.values.push_back(cell.brokenCount());
      bondValues.add(cell, m_decomposition, step);
    }
    out.points.reserve(used.size());
    AttributeArray particleId{"particle_id", AttributeType::kInt32, 1, {}};
    for (dem::ParticleIndex p : used) {
      out.points.push_back(step.positions[static_cast<std::size_t>(p)]);
      particleId.values.push_back(p);
      m_pointOf[static_cast<std::size_t>(p)] = -1;
    }
    out.cellData.push_back(std::move(broken));
    bondValues.moveTo(out.cellData);
    out.pointData.push_back(std::move(particleId));
    return Status::ok();
  }

 private:
  LatticeDecomposition m_decomposition;
  ExtractOptions m_options;
  std::vector<std::int32_t> m_pointOf;  // particle -> output point during one step, else -1
};

}  // namespace

std::unique_ptr<CrackExtractor> makeCellAttribute(const BondGraph& graph, int dimension,
                                                  const ExtractOptions& options,
                                                  const ExplicitCells* cells) {
  return std::make_unique<CellAttributeExtractor>(graph, dimension, options, cells);
}

}  // namespace crackvis::cracks
