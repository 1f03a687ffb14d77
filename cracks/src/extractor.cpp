#include <fmt/format.h>

#include "methods.hpp"
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/partition.hpp>

namespace crackvis::cracks {

namespace {

// Adds each primitive's owner particle to what a lattice method outputs.
class OwnerMarking final : public CrackExtractor {
 public:
  OwnerMarking(std::unique_ptr<CrackExtractor> inner, const BondGraph& graph)
      : m_inner(std::move(inner)), m_graph(graph) {}
  Method method() const override { return m_inner->method(); }
  Status extract(const StepInput& step, CrackMesh& out) override {
    CRACKVIS_RETURN_IF_ERROR(m_inner->extract(step, out));
    appendOwnerParticles(out, m_graph.bonds());
    return Status::ok();
  }
  std::size_t memoryBytes() const override { return m_inner->memoryBytes(); }
  const LatticeDecomposition* decomposition() const override { return m_inner->decomposition(); }
  std::size_t inconsistentBondCount() const override { return m_inner->inconsistentBondCount(); }
  Decomposition decompositionKind() const override { return m_inner->decompositionKind(); }

 private:
  std::unique_ptr<CrackExtractor> m_inner;
  const BondGraph& m_graph;
};

std::unique_ptr<CrackExtractor> makeLatticeExtractor(Method method, const BondGraph& graph,
                                                     int dimension, const ExtractOptions& options) {
  switch (method) {
    case Method::kCellAttribute:
      return makeCellAttribute(graph, dimension, options);
    case Method::kCellCut:
      return makeCellCut(graph, dimension, options);
    case Method::kLocalVoronoi:
      return makeLocalVoronoi(graph, dimension, options);
    case Method::kCellCentre:
      return makeCellCentre(graph, dimension, options);
  }
  return nullptr;
}

}  // namespace

std::unique_ptr<CrackExtractor> makeExtractor(Method method, const BondGraph& graph, int dimension,
                                              const ExtractOptions& options) {
  Decomposition kind = options.decomposition;
  if (kind == Decomposition::kAuto) {
    kind =
        isLatticeGraph(graph, dimension) ? Decomposition::kLattice : Decomposition::kTriangulation;
  }
  if (kind == Decomposition::kTriangulation) {
    return makeTriangulated(method, graph, dimension, options);
  }
  auto extractor = makeLatticeExtractor(method, graph, dimension, options);
  if (options.ownerParticles) {
    return std::make_unique<OwnerMarking>(std::move(extractor), graph);
  }
  return extractor;
}

dem::CellDecomposition decompositionOf(const dem::Lattice& lattice) {
  const BondGraph graph(lattice.particleCount(), lattice.bonds);
  return isLatticeGraph(graph, lattice.dimension) ? dem::CellDecomposition::kLattice
                                                  : dem::CellDecomposition::kTriangulation;
}

Decomposition settledByFile(Decomposition chosen, dem::CellDecomposition recorded) {
  if (chosen != Decomposition::kAuto) {
    return chosen;
  }
  switch (recorded) {
    case dem::CellDecomposition::kLattice:
      return Decomposition::kLattice;
    case dem::CellDecomposition::kTriangulation:
      return Decomposition::kTriangulation;
    case dem::CellDecomposition::kUnknown:
      break;
  }
  return Decomposition::kAuto;
}

Status checkStepInput(const BondGraph& graph, const StepInput& step) {
  const std::size_t n = graph.particleCount();
  const std::size_t m = graph.bondCount();
  if (step.positions.size() != n || step.radius.size() != n) {
    return invalidArgument(fmt::format("{} positions and {} radii for N = {} particles",
                                       step.positions.size(), step.radius.size(), n));
  }
  if (step.bondState.size() != m) {
    return invalidArgument(
        fmt::format("{} bond states for M = {} bonds", step.bondState.size(), m));
  }
  if ((!step.components.empty() && step.components.size() != n) ||
      (!step.intactComponents.empty() && step.intactComponents.size() != n)) {
    return invalidArgument(fmt::format("component arrays do not have N = {} values", n));
  }
  if ((!step.bondForce.empty() && step.bondForce.size() != m) ||
      (!step.breakStep.empty() && step.breakStep.size() != m)) {
    return invalidArgument(
        fmt::format("bond force or break step arrays do not have M = {} values", m));
  }
  return Status::ok();
}

void appendBondAttributes(const StepInput& step, std::span<const dem::BondIndex> bonds,
                          std::vector<AttributeArray>& arrays) {
  AttributeArray id{"bond_id", AttributeType::kInt32, 1, {}};
  AttributeArray state{"bond_state", AttributeType::kInt32, 1, {}};
  id.values.reserve(bonds.size());
  state.values.reserve(bonds.size());
  for (dem::BondIndex b : bonds) {
    id.values.push_back(b);
    state.values.push_back(step.bondState[static_cast<std::size_t>(b)]);
  }
  arrays.push_back(std::move(id));
  arrays.push_back(std::move(state));
  if (!step.breakStep.empty()) {
    AttributeArray breakStep{"break_step", AttributeType::kInt32, 1, {}};
    breakStep.values.reserve(bonds.size());
    for (dem::BondIndex b : bonds) {
      breakStep.values.push_back(step.breakStep[static_cast<std::size_t>(b)]);
    }
    arrays.push_back(std::move(breakStep));
  }
  if (!step.bondForce.empty()) {
    AttributeArray force{"bond_force", AttributeType::kFloat32, 1, {}};
    force.values.reserve(bonds.size());
    for (dem::BondIndex b : bonds) {
      force.values.push_back(step.bondForce[static_cast<std::size_t>(b)]);
    }
    arrays.push_back(std::move(force));
  }
}

}  // namespace crackvis::cracks
