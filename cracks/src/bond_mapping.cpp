#include <algorithm>
#include <numeric>
#include <unordered_set>

#include <fmt/format.h>

#include <crackvis/cracks/bond_mapping.hpp>
#include <crackvis/cracks/crack_components.hpp>
#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::cracks {

namespace {

// Calls visit(primitive index among surfaceCount, bond) for each bond a
// surface primitive carries (cell data bond_id, or the point data bond_id of
// its points). False when the mesh carries no bond ids.
template <typename Visit>
bool forEachPrimitiveBond(const CrackMesh& mesh, const std::vector<Primitive>& primitives,
                          std::size_t bondCount, Visit&& visit) {
  const std::size_t base = mesh.vertices.size() + (mesh.dimension == 2 ? 0 : mesh.lines.size());
  auto valid = [&](double id) { return id >= 0.0 && id < static_cast<double>(bondCount); };
  if (const AttributeArray* ids = mesh.findCellData("bond_id")) {
    for (const Primitive& primitive : primitives) {
      const double id = ids->values[base + primitive.index];
      if (valid(id)) {
        visit(primitive, static_cast<std::size_t>(id));
      }
    }
    return true;
  }
  if (const AttributeArray* pointIds = mesh.findPointData("bond_id")) {
    for (const Primitive& primitive : primitives) {
      for (std::size_t k = 0; k < primitive.count; ++k) {
        const double id = pointIds->values[static_cast<std::size_t>(primitive.ids[k])];
        if (valid(id)) {
          visit(primitive, static_cast<std::size_t>(id));
        }
      }
    }
    return true;
  }
  return false;
}

// Which bonds a mesh maps to surface elements (see the header).
std::vector<char> mappedMask(const CrackMesh& mesh, std::span<const std::uint8_t> bondState,
                             const CrackExtractor& extractor) {
  const std::size_t m = bondState.size();
  std::vector<char> mapped(m, 0);
  const std::vector<Primitive> primitives = surfacePrimitives(mesh);
  const bool carried = forEachPrimitiveBond(
      mesh, primitives, m, [&](const Primitive&, std::size_t b) { mapped[b] = 1; });
  if (!carried) {
    if (const LatticeDecomposition* cells = extractor.decomposition()) {
      std::vector<CellIndex> found;
      for (std::size_t b = 0; b < m; ++b) {
        if (bondState[b] != 0) {
          cells->cellsOfBond(static_cast<dem::BondIndex>(b), found);
          mapped[b] = found.empty() ? 0 : 1;
        }
      }
    }
  }
  return mapped;
}

}  // namespace

BondMapping mapBrokenBonds(const CrackMesh& mesh, std::span<const std::uint8_t> bondState,
                           const CrackExtractor& extractor) {
  const std::vector<char> mapped = mappedMask(mesh, bondState, extractor);
  BondMapping mapping;
  for (std::size_t b = 0; b < bondState.size(); ++b) {
    if (bondState[b] != 0) {
      ++mapping.broken;
      mapping.mapped += mapped[b] != 0 ? 1 : 0;
    }
  }
  return mapping;
}

std::vector<std::uint8_t> separatingBonds(const BondGraph& graph,
                                          std::span<const std::uint8_t> bondState) {
  const std::size_t n = graph.particleCount();
  std::vector<std::int32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t b = 0; b < bondState.size(); ++b) {
    if (bondState[b] == 0) {
      const dem::Bond& bond = graph.bond(static_cast<dem::BondIndex>(b));
      parent[static_cast<std::size_t>(findRoot(parent, bond.first))] =
          findRoot(parent, bond.second);
    }
  }
  std::vector<std::size_t> size(n, 0);
  for (std::size_t p = 0; p < n; ++p) {
    ++size[static_cast<std::size_t>(findRoot(parent, static_cast<std::int32_t>(p)))];
  }
  std::int32_t first = -1;
  std::int32_t second = -1;
  for (std::size_t p = 0; p < n; ++p) {
    const auto root = static_cast<std::int32_t>(p);
    if (findRoot(parent, root) != root) {
      continue;
    }
    if (first < 0 || size[p] > size[static_cast<std::size_t>(first)]) {
      second = first;
      first = root;
    } else if (second < 0 || size[p] > size[static_cast<std::size_t>(second)]) {
      second = root;
    }
  }
  std::vector<std::uint8_t> separating(bondState.size(), 0);
  for (std::size_t b = 0; b < bondState.size() && second >= 0; ++b) {
    if (bondState[b] != 0) {
      const dem::Bond& bond = graph.bond(static_cast<dem::BondIndex>(b));
      const std::int32_t a = findRoot(parent, bond.first);
      const std::int32_t c = findRoot(parent, bond.second);
      separating[b] = (a == first && c == second) || (a == second && c == first) ? 1 : 0;
    }
  }
  return separating;
}

namespace {

// Cells carry no bonds: a bond of the main crack is in a component when it is
// an edge of one of the component's cells (their corners' particle_id).
double cellShareInLargest(const CrackMesh& mesh, const CrackComponents& components,
                          std::span<const std::uint8_t> separating,
                          const CrackExtractor& extractor) {
  const AttributeArray* particle = mesh.findPointData("particle_id");
  const LatticeDecomposition* decomposition = extractor.decomposition();
  if (particle == nullptr || decomposition == nullptr) {
    return 0.0;
  }
  auto key = [](double a, double b) {
    const auto lo = static_cast<std::uint64_t>(std::min(a, b));
    const auto hi = static_cast<std::uint64_t>(std::max(a, b));
    return lo << 32 | hi;
  };
  std::unordered_set<std::uint64_t> anyCell;
  std::unordered_set<std::uint64_t> largest;
  const PrimitiveList& cells = mesh.dimension == 2 ? mesh.polygons : mesh.volumeCells;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    for (auto i = cells.offsets[k]; i < cells.offsets[k + 1]; ++i) {
      for (auto j = i + 1; j < cells.offsets[k + 1]; ++j) {
        const std::uint64_t edge = key(
            particle
                ->values[static_cast<std::size_t>(cells.connectivity[static_cast<std::size_t>(i)])],
            particle->values[static_cast<std::size_t>(
                cells.connectivity[static_cast<std::size_t>(j)])]);
        anyCell.insert(edge);
        if (components.ofPrimitive[k] == 0) {
          largest.insert(edge);
        }
      }
    }
  }
  std::size_t held = 0;
  std::size_t inLargest = 0;
  const BondGraph& graph = decomposition->graph();
  for (std::size_t b = 0; b < separating.size() && b < graph.bondCount(); ++b) {
    if (separating[b] != 0) {
      const dem::Bond& bond = graph.bond(static_cast<dem::BondIndex>(b));
      const std::uint64_t edge = key(bond.first, bond.second);
      held += anyCell.count(edge);
      inLargest += largest.count(edge);
    }
  }
  return held > 0 ? static_cast<double>(inLargest) / static_cast<double>(held) : 0.0;
}

}  // namespace

MainCrack measureMainCrack(const CrackMesh& mesh, std::span<const std::uint8_t> separating,
                           const CrackExtractor& extractor) {
  MainCrack main;
  main.mapped = mapBrokenBonds(mesh, separating, extractor);
  const CrackComponents components = findComponents(mesh);
  if (mesh.holdsCells()) {
    main.largestShare = cellShareInLargest(mesh, components, separating, extractor);
    return main;
  }
  const std::vector<Primitive> primitives = surfacePrimitives(mesh);
  std::vector<char> counted(mesh.dimension == 2 ? mesh.lines.size() : mesh.polygons.size(), 0);
  double inLargest = 0.0;
  forEachPrimitiveBond(mesh, primitives, separating.size(),
                       [&](const Primitive& primitive, std::size_t b) {
                         if (separating[b] == 0 || counted[primitive.index] != 0) {
                           return;
                         }
                         counted[primitive.index] = 1;
                         const double area = measure(mesh, primitive);
                         main.area += area;
                         inLargest += components.ofPrimitive[primitive.index] == 0 ? area : 0.0;
                       });
  main.largestShare = main.area > 0.0 ? inLargest / main.area : 0.0;
  return main;
}

std::string diagnoseMapping(const BondMapping& mapping, const CrackExtractor& extractor,
                            const BondGraph& graph, int dimension, std::span<const double> radius,
                            const ExtractOptions& options) {
  if (mapping.fraction() >= kMappedWarning) {
    return {};
  }
  const bool lattice = extractor.decompositionKind() == Decomposition::kLattice;
  if (lattice && !isLatticeGraph(graph, dimension)) {
    return "the bonds span no lattice (a random packing?): use --decomposition auto or "
           "triangulation";
  }
  const auto [lo, hi] = std::minmax_element(radius.begin(), radius.end());
  if (lattice && lo != radius.end() && *hi - *lo > 1e-9 * *hi) {
    return "the radii are unequal and the cells are the lattice's: use --decomposition "
           "triangulation";
  }
  if (extractor.method() == Method::kLocalVoronoi && options.validate &&
      extractor.inconsistentBondCount() > 0) {
    return fmt::format(
        "validation refused the faces of {} bonds (a crack opened far beyond its reference "
        "geometry, or a packing whose neighbours are not all bonded; try --no-validation)",
        extractor.inconsistentBondCount());
  }
  if (extractor.method() == Method::kCellCut) {
    return "broken bonds that separate no particles of their cells (isolated breaks, scattered "
           "damage): cell cut draws them as lines, not faces";
  }
  return "broken bonds between particles that are no neighbours in the decomposition, or whose "
         "faces lie outside the domain";
}

}  // namespace crackvis::cracks
