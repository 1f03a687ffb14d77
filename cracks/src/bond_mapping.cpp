#include <algorithm>

#include <fmt/format.h>

#include "surface_primitives.hpp"
#include <crackvis/cracks/bond_mapping.hpp>

namespace crackvis::cracks {

BondMapping mapBrokenBonds(const CrackMesh& mesh, std::span<const std::uint8_t> bondState,
                           const CrackExtractor& extractor) {
  BondMapping mapping;
  const std::size_t m = bondState.size();
  std::vector<char> mapped(m, 0);
  auto mark = [&](double id) {
    if (id >= 0.0 && id < static_cast<double>(m)) {
      mapped[static_cast<std::size_t>(id)] = 1;
    }
  };
  const std::vector<Primitive> primitives = surfacePrimitives(mesh);
  const std::size_t base = mesh.vertices.size() + (mesh.dimension == 2 ? 0 : mesh.lines.size());
  if (const AttributeArray* ids = mesh.findCellData("bond_id")) {
    for (const Primitive& primitive : primitives) {
      mark(ids->values[base + primitive.index]);
    }
  } else if (const AttributeArray* pointIds = mesh.findPointData("bond_id")) {
    for (const Primitive& primitive : primitives) {
      for (std::size_t k = 0; k < primitive.count; ++k) {
        mark(pointIds->values[static_cast<std::size_t>(primitive.ids[k])]);
      }
    }
  } else if (const LatticeDecomposition* cells = extractor.decomposition()) {
    std::vector<CellIndex> found;
    for (std::size_t b = 0; b < m; ++b) {
      if (bondState[b] != 0) {
        cells->cellsOfBond(static_cast<dem::BondIndex>(b), found);
        mapped[b] = found.empty() ? 0 : 1;
      }
    }
  }
  for (std::size_t b = 0; b < m; ++b) {
    if (bondState[b] != 0) {
      ++mapping.broken;
      mapping.mapped += mapped[b] != 0 ? 1 : 0;
    }
  }
  return mapping;
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
