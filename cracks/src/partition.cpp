#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <numeric>
#include <utility>

#include <fmt/format.h>

#include <crackvis/cracks/extractor.hpp>
#include <crackvis/cracks/partition.hpp>
#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::cracks {
namespace {

using dem::axisCoordinate;

// Calls visit(k, ids, count) for each primitive in VTK order: vertices,
// lines, polygons, volume cells.
template <typename Visit>
void forEachPrimitive(const CrackMesh& mesh, Visit&& visit) {
  std::size_t k = 0;
  for (const std::int32_t& v : mesh.vertices) {
    visit(k++, &v, std::size_t{1});
  }
  for (const PrimitiveList* list : {&mesh.lines, &mesh.polygons, &mesh.volumeCells}) {
    for (std::size_t i = 0; i < list->size(); ++i) {
      const auto first = static_cast<std::size_t>(list->offsets[i]);
      visit(k++, list->connectivity.data() + first,
            static_cast<std::size_t>(list->offsets[i + 1]) - first);
    }
  }
}

double smallerEnd(std::span<const dem::Bond> bonds, double id) {
  if (id < 0.0 || id >= static_cast<double>(bonds.size())) {
    return -1.0;
  }
  const dem::Bond& bond = bonds[static_cast<std::size_t>(id)];
  return std::min(bond.first, bond.second);
}

// The smallest non-negative of a and b (-1 when neither is).
double smallestKnown(double a, double b) {
  if (a < 0.0) {
    return b;
  }
  return b < 0.0 ? a : std::min(a, b);
}

void compact(AttributeArray& array, const std::vector<char>& keep) {
  const auto width = static_cast<std::size_t>(array.components);
  std::size_t kept = 0;
  for (std::size_t k = 0; k < keep.size() && (k + 1) * width <= array.values.size(); ++k) {
    if (keep[k] != 0) {
      std::copy_n(array.values.begin() + static_cast<std::ptrdiff_t>(k * width), width,
                  array.values.begin() + static_cast<std::ptrdiff_t>(kept * width));
      ++kept;
    }
  }
  array.values.resize(kept * width);
}

PrimitiveList keptOf(const PrimitiveList& list, const std::vector<char>& keep, std::size_t base,
                     const std::vector<std::int32_t>& newPoint) {
  PrimitiveList out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (keep[base + i] == 0) {
      continue;
    }
    for (auto v = list.offsets[i]; v < list.offsets[i + 1]; ++v) {
      out.connectivity.push_back(
          newPoint[static_cast<std::size_t>(list.connectivity[static_cast<std::size_t>(v)])]);
    }
    out.offsets.push_back(static_cast<std::int32_t>(out.connectivity.size()));
  }
  return out;
}

}  // namespace

namespace {

// Adds the nodes of every cell touching `held` (peeled cells too), then
// those nodes' bonded neighbours (partitionPiece).
void holdCellNeighbourhood(const Triangulation& triangulation, std::span<const dem::Bond> bonds,
                           std::vector<std::uint8_t>& held) {
  const std::vector<std::uint8_t> zone = held;
  auto inZone = [&](dem::ParticleIndex i) {
    return i >= 0 && zone[static_cast<std::size_t>(i)] != 0;
  };
  // The peeled cells too: their edges are the triangulation's.
  for (const auto* cells : {&triangulation.cells, &triangulation.peeled}) {
    for (const auto& cell : *cells) {
      if (std::any_of(cell.begin(), cell.end(), inZone)) {
        for (dem::ParticleIndex i : cell) {
          if (i >= 0) {
            held[static_cast<std::size_t>(i)] = 1;
          }
        }
      }
    }
  }
  const std::vector<std::uint8_t> withCells = held;
  for (const dem::Bond& bond : bonds) {
    const auto a = static_cast<std::size_t>(bond.first);
    const auto c = static_cast<std::size_t>(bond.second);
    if (withCells[a] != 0 && zone[a] == 0) {
      held[c] = 1;
    }
    if (withCells[c] != 0 && zone[c] == 0) {
      held[a] = 1;
    }
  }
}

}  // namespace

Piece partitionPiece(std::span<const Vec3> reference, std::span<const dem::Bond> bonds, int piece,
                     int pieces, double ghostWidth, const Triangulation* triangulation) {
  const std::size_t n = reference.size();
  const int axis = dem::sliceAxis(reference);
  // Equal counts per slab: the particles in order along the axis (index
  // breaks ties, so every piece draws the same lines).
  std::vector<dem::ParticleIndex> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](dem::ParticleIndex a, dem::ParticleIndex b) {
    const double ca = axisCoordinate(reference[static_cast<std::size_t>(a)], axis);
    const double cb = axisCoordinate(reference[static_cast<std::size_t>(b)], axis);
    return ca < cb || (ca == cb && a < b);
  });
  const std::size_t first = n * static_cast<std::size_t>(piece) / static_cast<std::size_t>(pieces);
  const std::size_t last =
      n * static_cast<std::size_t>(piece + 1) / static_cast<std::size_t>(pieces);
  std::vector<std::uint8_t> owned(n, 0);
  std::vector<std::uint8_t> held(n, 0);
  for (std::size_t k = first; k < last; ++k) {
    owned[static_cast<std::size_t>(order[k])] = 1;
  }
  if (first < last) {
    const double lo =
        axisCoordinate(reference[static_cast<std::size_t>(order[first])], axis) - ghostWidth;
    const double hi =
        axisCoordinate(reference[static_cast<std::size_t>(order[last - 1])], axis) + ghostWidth;
    for (std::size_t i = 0; i < n; ++i) {
      const double c = axisCoordinate(reference[i], axis);
      held[i] = owned[i] != 0 || (c >= lo && c <= hi) ? 1 : 0;
    }
    if (triangulation != nullptr) {
      holdCellNeighbourhood(*triangulation, bonds, held);
    }
  }
  Piece result;
  std::vector<dem::ParticleIndex> local(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    if (held[i] != 0) {
      local[i] = static_cast<dem::ParticleIndex>(result.particles.size());
      result.particles.push_back(static_cast<dem::ParticleIndex>(i));
      result.owned.push_back(owned[i]);
    }
  }
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const auto a = static_cast<std::size_t>(bonds[b].first);
    const auto c = static_cast<std::size_t>(bonds[b].second);
    if (held[a] != 0 && held[c] != 0) {
      result.bonds.push_back(static_cast<dem::BondIndex>(b));
      result.localBonds.push_back({local[a], local[c]});
      result.bondOwned.push_back(owned[std::min(a, c)]);
    }
  }
  return result;
}

namespace {

// The first position k in [lo, hi) of /index/coordinate for which
// before(coordinate[k]) is false (hi when there is none): a binary search
// that reads one coordinate per probe.
template <typename Before>
Result<std::int64_t> searchIndex(const dem::DemFileReader& reader, std::int64_t lo, std::int64_t hi,
                                 Before before) {
  while (lo < hi) {
    const std::int64_t middle = lo + (hi - lo) / 2;
    auto value = reader.readIndexCoordinate(middle);
    if (!value) {
      return value.status();
    }
    if (before(*value)) {
      lo = middle + 1;
    } else {
      hi = middle;
    }
  }
  return lo;
}

// The particles of order positions [held0, held1), ascending, with those
// at positions [owned0, owned1) owned.
Status heldParticles(const dem::DemFileReader& reader, std::int64_t held0, std::int64_t held1,
                     std::int64_t owned0, std::int64_t owned1, Piece& part) {
  auto order = reader.readIndexOrder(held0, held1);
  if (!order) {
    return order.status();
  }
  std::vector<std::pair<dem::ParticleIndex, std::uint8_t>> held;
  held.reserve(order->size());
  for (std::size_t k = 0; k < order->size(); ++k) {
    const auto at = held0 + static_cast<std::int64_t>(k);
    held.emplace_back((*order)[k], at >= owned0 && at < owned1 ? 1 : 0);
  }
  std::sort(held.begin(), held.end());
  for (std::size_t k = 0; k < held.size(); ++k) {
    if (k > 0 && held[k].first == held[k - 1].first) {
      return failedPrecondition(fmt::format("{}: {} names particle {} twice", reader.info().path,
                                            dem::kIndexOrderPath, held[k].first));
    }
    part.particles.push_back(held[k].first);
    part.owned.push_back(held[k].second);
  }
  return Status::ok();
}

// The bonds whose first end is a held particle, from /index/bond_start.
Result<std::vector<dem::BondIndex>> bondsFromHeld(const dem::DemFileReader& reader,
                                                  const std::vector<dem::ParticleIndex>& held,
                                                  std::vector<dem::ParticleIndex>& firstEnds) {
  std::vector<std::int32_t> rows;
  rows.reserve(2 * held.size());
  for (dem::ParticleIndex i : held) {
    if (rows.empty() || rows.back() < i) {
      rows.push_back(i);
    }
    rows.push_back(i + 1);
  }
  auto starts = reader.readBondStarts(rows);
  if (!starts) {
    return starts.status();
  }
  std::vector<dem::BondIndex> bonds;
  std::size_t row = 0;
  for (dem::ParticleIndex i : held) {
    while (rows[row] < i) {
      ++row;
    }
    const std::int64_t begin = (*starts)[row];
    const std::int64_t end = (*starts)[row + 1];
    if (end < begin || (!bonds.empty() && begin < std::int64_t{bonds.back()} + 1)) {
      return failedPrecondition(fmt::format("{}: {} is not ascending at particle {}",
                                            reader.info().path, dem::kIndexBondStartPath, i));
    }
    for (std::int64_t b = begin; b < end; ++b) {
      bonds.push_back(static_cast<dem::BondIndex>(b));
      firstEnds.push_back(i);
    }
  }
  return bonds;
}

// Keeps, of the candidate bonds, those whose other end the piece holds too.
Status keepHeldBonds(const dem::DemFileReader& reader,
                     const std::vector<dem::BondIndex>& candidates,
                     const std::vector<dem::ParticleIndex>& firstEnds, Piece& part) {
  auto pairs = reader.readBondRows(candidates);
  if (!pairs) {
    return pairs.status();
  }
  auto local = [&](dem::ParticleIndex i) -> std::int32_t {
    const auto at = std::lower_bound(part.particles.begin(), part.particles.end(), i);
    return at != part.particles.end() && *at == i
               ? static_cast<std::int32_t>(at - part.particles.begin())
               : -1;
  };
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const dem::Bond& pair = (*pairs)[k];
    if (pair.first != firstEnds[k]) {
      return failedPrecondition(fmt::format(
          "{}: {} puts bond {} at particle {}, but its first end is {}", reader.info().path,
          dem::kIndexBondStartPath, candidates[k], firstEnds[k], pair.first));
    }
    const std::int32_t a = local(pair.first);
    const std::int32_t c = local(pair.second);
    if (c >= 0) {
      part.bonds.push_back(candidates[k]);
      part.localBonds.push_back({a, c});
      part.bondOwned.push_back(
          part.owned[static_cast<std::size_t>(pair.first < pair.second ? a : c)]);
    }
  }
  return Status::ok();
}

// The piece's rows of the time-independent arrays and of the first step.
Status readPieceRows(const dem::DemFileReader& reader, IndexedPiece& piece) {
  const Piece& part = piece.part;
  auto lattice = reader.readLatticeRows(part.particles, part.bonds);
  if (!lattice) {
    return lattice.status();
  }
  piece.lattice = std::move(*lattice);
  piece.lattice.bonds = part.localBonds;
  auto breakSteps = reader.readBreakStepRows(part.bonds);
  if (!breakSteps) {
    return breakSteps.status();
  }
  piece.breakSteps = std::move(*breakSteps);
  auto first = reader.readStepRows(0, part.particles, {});
  if (!first) {
    return first.status();
  }
  piece.reference = std::move(first->positions);
  return Status::ok();
}

}  // namespace

namespace {

// A rank's slab in the order: positions [first, last) own, [held0, held1)
// lie within the ghost width of the slab (partitionPiece's held zone).
struct SlabRange {
  std::int64_t first = 0;
  std::int64_t last = 0;
  std::int64_t held0 = 0;
  std::int64_t held1 = 0;
  double from = 0.0;  // the zone's coordinates along the axis
  double to = 0.0;
};

Result<SlabRange> findSlab(const dem::DemFileReader& reader, std::int64_t first, std::int64_t last,
                           double width) {
  const auto n = static_cast<std::int64_t>(reader.info().particleCount);
  auto lo = reader.readIndexCoordinate(first);
  auto hi = reader.readIndexCoordinate(last - 1);
  if (!lo || !hi) {
    return !lo ? lo.status() : hi.status();
  }
  SlabRange slab{first, last, 0, 0, *lo - width, *hi + width};
  auto held0 = searchIndex(reader, 0, first, [&](double c) { return c < slab.from; });
  auto held1 = searchIndex(reader, last, n, [&](double c) { return c <= slab.to; });
  if (!held0 || !held1) {
    return !held0 ? held0.status() : held1.status();
  }
  slab.held0 = *held0;
  slab.held1 = *held1;
  return slab;
}

bool contains(const std::vector<dem::ParticleIndex>& sorted, dem::ParticleIndex i) {
  return std::binary_search(sorted.begin(), sorted.end(), i);
}

// The order's particles at positions [first, last), ascending.
Result<std::vector<dem::ParticleIndex>> sortedOrder(const dem::DemFileReader& reader,
                                                    std::int64_t first, std::int64_t last) {
  auto order = reader.readIndexOrder(first, last);
  if (!order) {
    return order.status();
  }
  std::sort(order->begin(), order->end());
  return std::move(*order);
}

using CellList = std::vector<std::array<dem::ParticleIndex, 4>>;

// The whole set's cells that touch the zone (sorted, whole-set indices):
// the cells of the triangulation of every particle within `margin` of the
// zone whose reach stays inside it, and the stored wide cells; less the
// hull's slivers the whole set peels, which come apart, for their edges.
struct ZoneCells {
  CellList kept;
  CellList peeled;
};

// Nullopt when the zone's particles cannot be triangulated alone.
Result<std::optional<ZoneCells>> zoneCells(const dem::DemFileReader& reader,
                                           const dem::SpatialIndexInfo& index,
                                           const dem::WideCells& wide, const SlabRange& slab,
                                           const std::vector<dem::ParticleIndex>& zone) {
  using Cells = CellList;
  const auto n = static_cast<std::int64_t>(reader.info().particleCount);
  // A cell of reach r touching the zone lies, with every particle that
  // could unmake it, within 2 r of the zone; half as much again for the
  // rounding of the centre.
  const double margin = 2.5 * wide.reach;
  auto near0 = searchIndex(reader, 0, slab.held0, [&](double c) { return c < slab.from - margin; });
  auto near1 = searchIndex(reader, slab.held1, n, [&](double c) { return c <= slab.to + margin; });
  if (!near0 || !near1) {
    return !near0 ? near0.status() : near1.status();
  }
  auto near = sortedOrder(reader, *near0, *near1);
  if (!near) {
    return near.status();
  }
  auto positions = reader.readStepRows(0, *near, {});
  auto rows = reader.readLatticeRows(*near, {});
  if (!positions || !rows) {
    return !positions ? positions.status() : rows.status();
  }
  // The slab's hull is not the set's: its cells are not peeled here, the
  // set's peeled cells are taken out below.
  auto local = triangulate(positions->positions, rows->radius, reader.info().dimension,
                           {.weighted = wide.weighted, .peelHull = false});
  if (!local) {
    return std::optional<ZoneCells>{};
  }
  const std::vector<double> reach =
      cellReach(*local, positions->positions, rows->radius, index.largestRadius);
  // Zone membership by local index (both lists ascending).
  std::vector<std::uint8_t> inZone(near->size(), 0);
  auto z = zone.begin();
  for (std::size_t k = 0; k < near->size(); ++k) {
    while (z != zone.end() && *z < (*near)[k]) {
      ++z;
    }
    inZone[k] = z != zone.end() && *z == (*near)[k] ? 1 : 0;
  }
  Cells cells;
  for (std::size_t c = 0; c < local->cells.size(); ++c) {
    const std::array<dem::ParticleIndex, 4>& cell = local->cells[c];
    // The writer stored the cells of reach above wide.reach, computed from
    // the same numbers; the slack keeps a cell at the threshold found even
    // if another build rounds its reach otherwise (the margin allows it).
    if (reach[c] <= wide.reach * (1.0 + 1e-9) &&
        std::any_of(cell.begin(), cell.end(), [&](dem::ParticleIndex i) {
          return i >= 0 && inZone[static_cast<std::size_t>(i)] != 0;
        })) {
      std::array<dem::ParticleIndex, 4> global{};
      std::transform(cell.begin(), cell.end(), global.begin(), [&](dem::ParticleIndex i) {
        return i < 0 ? -1 : (*near)[static_cast<std::size_t>(i)];
      });
      cells.push_back(global);
    }
  }
  // The local cells come sorted (near is ascending, so the mapping keeps
  // their order): the wide cells are merged in.
  const auto localCount = static_cast<std::ptrdiff_t>(cells.size());
  for (const auto& cell : wide.cells) {
    if (std::any_of(cell.begin(), cell.end(),
                    [&](dem::ParticleIndex i) { return i >= 0 && contains(zone, i); })) {
      cells.push_back(cell);
    }
  }
  std::sort(cells.begin() + localCount, cells.end());
  std::inplace_merge(cells.begin(), cells.begin() + localCount, cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  // The hull's slivers the whole set's triangulation peels (the slab's
  // triangulation, with a hull of its own, was not peeled).
  ZoneCells out;
  out.kept.reserve(cells.size());
  std::set_difference(cells.begin(), cells.end(), wide.peeled.begin(), wide.peeled.end(),
                      std::back_inserter(out.kept));
  std::copy_if(wide.peeled.begin(), wide.peeled.end(), std::back_inserter(out.peeled),
               [&](const std::array<dem::ParticleIndex, 4>& cell) {
                 return std::any_of(cell.begin(), cell.end(), [&](dem::ParticleIndex i) {
                   return i >= 0 && contains(zone, i);
                 });
               });
  return std::optional<ZoneCells>{std::move(out)};
}

// Union-find over every particle without path compression, by size, so
// that the links it makes stay the forest's (BreakForest).
struct ForestBuilder {
  std::vector<std::int32_t> parent;
  std::vector<std::int32_t> size;
  std::vector<std::int32_t> holdsBefore;

  explicit ForestBuilder(std::size_t n) : parent(n, -1), size(n, 1), holdsBefore(n, 0) {}

  std::int32_t root(std::int32_t x) const {
    while (parent[static_cast<std::size_t>(x)] >= 0) {
      x = parent[static_cast<std::size_t>(x)];
    }
    return x;
  }
  void join(std::int32_t a, std::int32_t b, std::int32_t until) {
    a = root(a);
    b = root(b);
    if (a == b) {
      return;
    }
    if (size[static_cast<std::size_t>(a)] < size[static_cast<std::size_t>(b)]) {
      std::swap(a, b);
    }
    parent[static_cast<std::size_t>(b)] = a;
    holdsBefore[static_cast<std::size_t>(b)] = until;
    size[static_cast<std::size_t>(a)] += size[static_cast<std::size_t>(b)];
  }
};

// One pass over every bond, in spans: the forest of the whole set (bonds
// that never break first, then the others by falling break step), and the
// bonded neighbours of the particles `far` marks (none when it is empty).
struct BondPass {
  ForestBuilder forest;
  std::vector<dem::ParticleIndex> neighbours;  // of the far particles, unsorted
};

Result<BondPass> passOverBonds(const dem::DemFileReader& reader,
                               const std::vector<std::uint8_t>& far) {
  constexpr std::int64_t kSpan = std::int64_t{1} << 20;
  const auto m = static_cast<std::int64_t>(reader.info().bondCount);
  BondPass pass{ForestBuilder(static_cast<std::size_t>(reader.info().particleCount)), {}};
  struct Broken {
    std::int32_t step;
    dem::Bond bond;
  };
  std::vector<Broken> broken;
  std::vector<dem::BondIndex> rows;
  for (std::int64_t begin = 0; begin < m; begin += kSpan) {
    rows.resize(static_cast<std::size_t>(std::min(kSpan, m - begin)));
    std::iota(rows.begin(), rows.end(), static_cast<dem::BondIndex>(begin));
    auto pairs = reader.readBondRows(rows);
    auto steps = reader.readBreakStepRows(rows);
    if (!pairs || !steps) {
      return !pairs ? pairs.status() : steps.status();
    }
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const dem::Bond bond = (*pairs)[k];
      const std::int32_t step = (*steps)[k];
      if (step < 0) {
        pass.forest.join(bond.first, bond.second, std::numeric_limits<std::int32_t>::max());
      } else {
        broken.push_back({step, bond});
      }
      if (!far.empty() && far[static_cast<std::size_t>(bond.first)] != 0) {
        pass.neighbours.push_back(bond.second);
      }
      if (!far.empty() && far[static_cast<std::size_t>(bond.second)] != 0) {
        pass.neighbours.push_back(bond.first);
      }
    }
  }
  // Latest break first; ties by the bond's ends, so the forest does not
  // depend on the sort.
  std::sort(broken.begin(), broken.end(), [](const Broken& a, const Broken& b) {
    return a.step != b.step ? a.step > b.step
                            : (a.bond.first != b.bond.first ? a.bond.first < b.bond.first
                                                            : a.bond.second < b.bond.second);
  });
  for (const Broken& b : broken) {
    pass.forest.join(b.bond.first, b.bond.second, b.step);
  }
  return pass;
}

// The forest kept along the paths from the piece's particles to their roots.
BreakForest keepPaths(const ForestBuilder& whole, const std::vector<dem::ParticleIndex>& held) {
  BreakForest forest;
  std::vector<std::int32_t> slotOf(whole.parent.size(), -1);
  // The node's slot, and whether it is new.
  auto slot = [&](std::int32_t x) {
    std::int32_t& at = slotOf[static_cast<std::size_t>(x)];
    const bool added = at < 0;
    if (added) {
      at = static_cast<std::int32_t>(forest.parent.size());
      forest.parent.push_back(-1);
      forest.holdsBefore.push_back(whole.holdsBefore[static_cast<std::size_t>(x)]);
    }
    return std::pair{at, added};
  };
  for (dem::ParticleIndex i : held) {
    auto [node, added] = slot(i);
    forest.particleSlot.push_back(node);
    std::int32_t x = i;
    while (added && whole.parent[static_cast<std::size_t>(x)] >= 0) {
      x = whole.parent[static_cast<std::size_t>(x)];
      auto [up, upAdded] = slot(x);
      forest.parent[static_cast<std::size_t>(node)] = up;
      node = up;
      added = upAdded;
    }
  }
  return forest;
}

// The cells in piece indices, and the edges of them and of the peeled cells
// (sorted, each once: gathered per first end, since a particle has few).
Triangulation pieceTriangulation(const ZoneCells& cells,
                                 const std::vector<dem::ParticleIndex>& held,
                                 std::size_t particleCount, int dimension, bool weighted) {
  Triangulation out;
  out.dimension = dimension;
  out.weighted = weighted;
  std::vector<dem::ParticleIndex> localOf(particleCount, -1);
  for (std::size_t k = 0; k < held.size(); ++k) {
    localOf[static_cast<std::size_t>(held[k])] = static_cast<dem::ParticleIndex>(k);
  }
  const auto nodes = static_cast<std::size_t>(dimension == 3 ? 4 : 3);
  auto toLocal = [&](const std::array<dem::ParticleIndex, 4>& cell) {
    std::array<dem::ParticleIndex, 4> mapped{};
    std::transform(cell.begin(), cell.end(), mapped.begin(), [&](dem::ParticleIndex i) {
      return i < 0 ? -1 : localOf[static_cast<std::size_t>(i)];
    });
    return mapped;  // ascending still: the mapping keeps order
  };
  out.cells.reserve(cells.kept.size());
  std::transform(cells.kept.begin(), cells.kept.end(), std::back_inserter(out.cells), toLocal);
  CellList peeled;
  std::transform(cells.peeled.begin(), cells.peeled.end(), std::back_inserter(peeled), toLocal);
  // Six edges a tetrahedron: counted in 64 bits, past 2^31 at 5e7 particles.
  std::vector<std::int64_t> start(held.size() + 1, 0);
  for (const CellList* list : {&out.cells, &peeled}) {
    for (const auto& cell : *list) {
      for (std::size_t a = 0; a + 1 < nodes; ++a) {
        start[static_cast<std::size_t>(cell[a]) + 1] += static_cast<std::int64_t>(nodes - 1 - a);
      }
    }
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<dem::ParticleIndex> other(static_cast<std::size_t>(start.back()));
  std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
  for (const CellList* list : {&out.cells, &peeled}) {
    for (const auto& cell : *list) {
      for (std::size_t a = 0; a + 1 < nodes; ++a) {
        for (std::size_t b = a + 1; b < nodes; ++b) {
          other[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell[a])]++)] = cell[b];
        }
      }
    }
  }
  // Each particle's partners once, counted first: the edges are reserved
  // exactly, as a rank holds them for as long as it shows the piece.
  std::vector<std::int64_t> uniqueEnd(held.size());
  std::size_t edgeCount = 0;
  for (std::size_t a = 0; a < held.size(); ++a) {
    const auto first = other.begin() + start[a];
    const auto last = other.begin() + start[a + 1];
    std::sort(first, last);
    uniqueEnd[a] = std::unique(first, last) - other.begin();
    edgeCount += static_cast<std::size_t>(uniqueEnd[a] - start[a]);
  }
  out.edges.reserve(edgeCount);
  for (std::size_t a = 0; a < held.size(); ++a) {
    const auto first = other.begin() + start[a];
    const auto unique = other.begin() + uniqueEnd[a];
    for (auto b = first; b != unique; ++b) {
      out.edges.push_back({static_cast<dem::ParticleIndex>(a), *b});
    }
  }
  return out;
}

// A triangulated packing's held particles (partitionPiece's: the zone, the
// nodes of the cells touching it, peeled or not, and those nodes' bonded
// neighbours), with the cells and the forest. False when the slab cannot be
// triangulated alone.
Result<bool> holdTriangulatedPiece(const dem::DemFileReader& reader, const SlabRange& slab,
                                   IndexedPiece& result) {
  auto wide = reader.readWideCells(result.index);  // the index info is read already
  if (!wide) {
    return wide.status();
  }
  auto zoneOrder = reader.readIndexOrder(slab.held0, slab.held1);
  if (!zoneOrder) {
    return zoneOrder.status();
  }
  std::vector<dem::ParticleIndex> zone = *zoneOrder;
  std::sort(zone.begin(), zone.end());
  auto cells = zoneCells(reader, result.index, **wide, slab, zone);
  if (!cells) {
    return cells.status();
  }
  if (!*cells) {
    return false;
  }
  const auto n = static_cast<std::size_t>(reader.info().particleCount);
  // 1: in the zone; 2: a node of a cell, outside the zone (far).
  std::vector<std::uint8_t> mark(n, 0);
  for (dem::ParticleIndex i : zone) {
    mark[static_cast<std::size_t>(i)] = 1;
  }
  std::vector<dem::ParticleIndex> held = zone;
  for (const CellList* list : {&(*cells)->kept, &(*cells)->peeled}) {
    for (const auto& cell : *list) {
      for (dem::ParticleIndex i : cell) {
        if (i >= 0 && mark[static_cast<std::size_t>(i)] == 0) {
          mark[static_cast<std::size_t>(i)] = 2;
          held.push_back(i);
        }
      }
    }
  }
  for (std::uint8_t& m : mark) {
    m = m == 2 ? 1 : 0;
  }
  auto pass = passOverBonds(reader, mark);
  if (!pass) {
    return pass.status();
  }
  held.insert(held.end(), pass->neighbours.begin(), pass->neighbours.end());
  std::sort(held.begin(), held.end());
  held.erase(std::unique(held.begin(), held.end()), held.end());
  const std::vector<dem::ParticleIndex> owned(zoneOrder->begin() + (slab.first - slab.held0),
                                              zoneOrder->begin() + (slab.last - slab.held0));
  std::vector<dem::ParticleIndex> ownedSorted = owned;
  std::sort(ownedSorted.begin(), ownedSorted.end());
  for (dem::ParticleIndex i : held) {
    result.part.particles.push_back(i);
    result.part.owned.push_back(contains(ownedSorted, i) ? 1 : 0);
  }
  PieceTriangulation triangulated;
  triangulated.triangulation =
      pieceTriangulation(**cells, held, n, reader.info().dimension, (*wide)->weighted);
  triangulated.forest = keepPaths(pass->forest, held);
  result.triangulated = std::move(triangulated);
  return true;
}

}  // namespace

Result<std::optional<IndexedPiece>> readIndexedPiece(const dem::DemFileReader& reader, int piece,
                                                     int pieces, double ghostBonds) {
  auto index = reader.readSpatialIndexInfo();
  if (!index) {
    return index.status();
  }
  const bool lattice = *index && (*index)->decomposition == dem::CellDecomposition::kLattice;
  const bool triangulated = *index &&
                            (*index)->decomposition == dem::CellDecomposition::kTriangulation &&
                            (*index)->hasWideCells && (*index)->hasPeeledCells;
  if (!*index || !(*index)->hasBondStart || (!lattice && !triangulated)) {
    return std::optional<IndexedPiece>{};
  }
  IndexedPiece result;
  result.index = **index;
  result.lattice.dimension = reader.info().dimension;
  const auto n = static_cast<std::int64_t>(reader.info().particleCount);
  const std::int64_t first = n * piece / pieces;
  const std::int64_t last = n * (piece + 1) / pieces;
  if (first >= last) {
    return std::optional<IndexedPiece>{std::move(result)};
  }
  // partitionPiece's slab: order [first, last), and every particle whose
  // coordinate lies within the ghost width of it, a range of the order.
  auto slab = findSlab(reader, first, last, ghostBonds * result.index.longestBond);
  if (!slab) {
    return slab.status();
  }
  if (triangulated) {
    auto held = holdTriangulatedPiece(reader, *slab, result);
    if (!held) {
      return held.status();
    }
    if (!*held) {
      return std::optional<IndexedPiece>{};
    }
  } else {
    CRACKVIS_RETURN_IF_ERROR(
        heldParticles(reader, slab->held0, slab->held1, first, last, result.part));
  }
  std::vector<dem::ParticleIndex> firstEnds;
  auto candidates = bondsFromHeld(reader, result.part.particles, firstEnds);
  if (!candidates) {
    return candidates.status();
  }
  CRACKVIS_RETURN_IF_ERROR(keepHeldBonds(reader, *candidates, firstEnds, result.part));
  CRACKVIS_RETURN_IF_ERROR(readPieceRows(reader, result));
  return std::optional<IndexedPiece>{std::move(result)};
}

Result<BreakForest> readBreakForest(const dem::DemFileReader& reader,
                                    const std::vector<dem::ParticleIndex>& particles) {
  auto pass = passOverBonds(reader, {});
  if (!pass) {
    return pass.status();
  }
  return keepPaths(pass->forest, particles);
}

std::vector<std::int32_t> componentsAt(const BreakForest& forest, int step) {
  std::vector<std::int32_t> labels;
  labels.reserve(forest.particleSlot.size());
  for (std::int32_t node : forest.particleSlot) {
    while (forest.parent[static_cast<std::size_t>(node)] >= 0 &&
           step < forest.holdsBefore[static_cast<std::size_t>(node)]) {
      node = forest.parent[static_cast<std::size_t>(node)];
    }
    labels.push_back(node);
  }
  return labels;
}

Result<dem::WideCells> wideCellsOf(std::span<const Vec3> first, const dem::Lattice& lattice) {
  auto triangulation = triangulate(first, lattice.radius, lattice.dimension);
  if (!triangulation) {
    return triangulation.status();
  }
  const double largest = lattice.radius.empty()
                             ? 0.0
                             : *std::max_element(lattice.radius.begin(), lattice.radius.end());
  dem::WideCells wide;
  wide.weighted = triangulation->weighted;
  wide.reach = kWideCellReach * dem::longestBond(first, lattice.bonds);
  if (!(wide.reach > 0.0)) {
    wide.reach = 4.0 * largest;  // no bonds: the particles' size sets the scale
  }
  // The wide cells of the unpeeled triangulation, the peeled ones too: a
  // reader that knows no peeled cells (before 2026-11-30) then cuts its
  // pieces as it cuts its whole set, and one that does takes them out.
  auto addWide = [&](const Triangulation& cells) {
    const std::vector<double> reach = cellReach(cells, first, lattice.radius, largest);
    for (std::size_t c = 0; c < reach.size(); ++c) {
      if (!(reach[c] <= wide.reach)) {
        wide.cells.push_back(cells.cells[c]);
      }
    }
  };
  addWide(*triangulation);
  Triangulation peeled;
  peeled.dimension = triangulation->dimension;
  peeled.weighted = triangulation->weighted;
  peeled.cells = std::move(triangulation->peeled);
  addWide(peeled);
  std::sort(wide.cells.begin(), wide.cells.end());
  wide.peeled = std::move(peeled.cells);
  return wide;
}

void describeCells(dem::DemMetadata& metadata, const dem::Lattice& lattice) {
  metadata.decomposition = decompositionOf(lattice);
  if (metadata.decomposition == dem::CellDecomposition::kTriangulation) {
    metadata.wideCells = wideCellsOf;
  }
}

std::vector<std::int32_t> connectedComponents(std::size_t particleCount,
                                              std::span<const dem::Bond> bonds,
                                              std::span<const std::uint8_t> bondState) {
  std::vector<std::int32_t> parent(particleCount);
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    if (bondState.empty() || bondState[b] == 0) {
      const std::int32_t a = findRoot(parent, bonds[b].first);
      const std::int32_t c = findRoot(parent, bonds[b].second);
      parent[static_cast<std::size_t>(std::max(a, c))] = std::min(a, c);
    }
  }
  for (std::size_t i = 0; i < particleCount; ++i) {
    parent[i] = findRoot(parent, static_cast<std::int32_t>(i));
  }
  return parent;
}

void appendOwnerParticles(CrackMesh& mesh, std::span<const dem::Bond> bonds) {
  const AttributeArray* cellBond = mesh.findCellData("bond_id");
  const AttributeArray* pointBond = mesh.findPointData("bond_id");
  const AttributeArray* pointParticle = mesh.findPointData("particle_id");
  AttributeArray owner{"owner_particle", AttributeType::kInt32, 1, {}};
  owner.values.assign(mesh.primitiveCount(), -1.0);
  forEachPrimitive(mesh, [&](std::size_t k, const std::int32_t* ids, std::size_t count) {
    double smallest = -1.0;
    if (cellBond != nullptr) {
      smallest = smallerEnd(bonds, cellBond->values[k]);
    }
    // Otherwise the smallest end over all the bonds of its points, or the
    // smallest of its points' particles.
    for (std::size_t v = 0; v < count && cellBond == nullptr && pointBond != nullptr; ++v) {
      smallest = smallestKnown(
          smallest, smallerEnd(bonds, pointBond->values[static_cast<std::size_t>(ids[v])]));
    }
    for (std::size_t v = 0;
         v < count && cellBond == nullptr && pointBond == nullptr && pointParticle != nullptr;
         ++v) {
      smallest = smallestKnown(smallest, pointParticle->values[static_cast<std::size_t>(ids[v])]);
    }
    owner.values[k] = smallest;
  });
  mesh.cellData.push_back(std::move(owner));
}

void keepOwned(CrackMesh& mesh, std::span<const std::uint8_t> owned) {
  const auto found =
      std::find_if(mesh.cellData.begin(), mesh.cellData.end(),
                   [](const AttributeArray& a) { return a.name == "owner_particle"; });
  if (found == mesh.cellData.end()) {
    return;
  }
  std::vector<char> keep(mesh.primitiveCount(), 1);
  for (std::size_t k = 0; k < keep.size(); ++k) {
    const double owner = found->values[k];
    keep[k] = owner < 0.0 || owned[static_cast<std::size_t>(owner)] != 0 ? 1 : 0;
  }
  mesh.cellData.erase(found);
  std::vector<char> used(mesh.points.size(), 0);
  forEachPrimitive(mesh, [&](std::size_t k, const std::int32_t* ids, std::size_t count) {
    for (std::size_t v = 0; v < count && keep[k] != 0; ++v) {
      used[static_cast<std::size_t>(ids[v])] = 1;
    }
  });
  std::vector<std::int32_t> newPoint(mesh.points.size(), -1);
  std::vector<Vec3> points;
  for (std::size_t p = 0; p < used.size(); ++p) {
    if (used[p] != 0) {
      newPoint[p] = static_cast<std::int32_t>(points.size());
      points.push_back(mesh.points[p]);
    }
  }
  std::vector<std::int32_t> vertices;
  for (std::size_t k = 0; k < mesh.vertices.size(); ++k) {
    if (keep[k] != 0) {
      vertices.push_back(newPoint[static_cast<std::size_t>(mesh.vertices[k])]);
    }
  }
  const std::size_t lineBase = mesh.vertices.size();
  const std::size_t polygonBase = lineBase + mesh.lines.size();
  const std::size_t volumeBase = polygonBase + mesh.polygons.size();
  std::vector<std::uint8_t> volumeTypes;
  for (std::size_t k = 0; k < mesh.volumeCellTypes.size(); ++k) {
    if (keep[volumeBase + k] != 0) {
      volumeTypes.push_back(mesh.volumeCellTypes[k]);
    }
  }
  mesh.vertices = std::move(vertices);
  mesh.lines = keptOf(mesh.lines, keep, lineBase, newPoint);
  mesh.polygons = keptOf(mesh.polygons, keep, polygonBase, newPoint);
  mesh.volumeCells = keptOf(mesh.volumeCells, keep, volumeBase, newPoint);
  mesh.volumeCellTypes = std::move(volumeTypes);
  for (AttributeArray& array : mesh.cellData) {
    compact(array, keep);
  }
  for (AttributeArray& array : mesh.pointData) {
    compact(array, used);
  }
  mesh.points = std::move(points);
}

}  // namespace crackvis::cracks
