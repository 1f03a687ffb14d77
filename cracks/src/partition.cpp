#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include <fmt/format.h>

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

// Adds the nodes of every cell touching `held`, then those nodes' bonded
// neighbours (partitionPiece).
void holdCellNeighbourhood(const Triangulation& triangulation, std::span<const dem::Bond> bonds,
                           std::vector<std::uint8_t>& held) {
  const std::vector<std::uint8_t> zone = held;
  auto inZone = [&](dem::ParticleIndex i) {
    return i >= 0 && zone[static_cast<std::size_t>(i)] != 0;
  };
  for (const auto& cell : triangulation.cells) {
    if (std::any_of(cell.begin(), cell.end(), inZone)) {
      for (dem::ParticleIndex i : cell) {
        if (i >= 0) {
          held[static_cast<std::size_t>(i)] = 1;
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

Result<std::optional<IndexedPiece>> readIndexedPiece(const dem::DemFileReader& reader, int piece,
                                                     int pieces, double ghostBonds) {
  auto index = reader.readSpatialIndexInfo();
  if (!index) {
    return index.status();
  }
  if (!*index || !(*index)->hasBondStart ||
      (*index)->decomposition != dem::CellDecomposition::kLattice) {
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
  const double width = ghostBonds * result.index.longestBond;
  auto lo = reader.readIndexCoordinate(first);
  auto hi = reader.readIndexCoordinate(last - 1);
  if (!lo || !hi) {
    return !lo ? lo.status() : hi.status();
  }
  const double from = *lo - width;
  const double to = *hi + width;
  auto held0 = searchIndex(reader, 0, first, [&](double c) { return c < from; });
  auto held1 = searchIndex(reader, last, n, [&](double c) { return c <= to; });
  if (!held0 || !held1) {
    return !held0 ? held0.status() : held1.status();
  }
  CRACKVIS_RETURN_IF_ERROR(heldParticles(reader, *held0, *held1, first, last, result.part));
  std::vector<dem::ParticleIndex> firstEnds;
  auto candidates = bondsFromHeld(reader, result.part.particles, firstEnds);
  if (!candidates) {
    return candidates.status();
  }
  CRACKVIS_RETURN_IF_ERROR(keepHeldBonds(reader, *candidates, firstEnds, result.part));
  CRACKVIS_RETURN_IF_ERROR(readPieceRows(reader, result));
  return std::optional<IndexedPiece>{std::move(result)};
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
