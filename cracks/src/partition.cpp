#include <algorithm>
#include <cmath>
#include <numeric>

#include <crackvis/cracks/partition.hpp>
#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::cracks {
namespace {

int longestAxis(const dem::Bounds& box) {
  const Vec3 size = box.hi - box.lo;
  if (size.x >= size.y && size.x >= size.z) {
    return 0;
  }
  return size.y >= size.z ? 1 : 2;
}

double along(const Vec3& p, int axis) {
  return axis == 0 ? p.x : (axis == 1 ? p.y : p.z);
}

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

double longestBond(std::span<const Vec3> reference, std::span<const dem::Bond> bonds) {
  double longest = 0.0;
  for (const dem::Bond& bond : bonds) {
    const Vec3 d = reference[static_cast<std::size_t>(bond.second)] -
                   reference[static_cast<std::size_t>(bond.first)];
    longest = std::max(longest, std::sqrt(dem::dot(d, d)));
  }
  return longest;
}

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
  const int axis = longestAxis(dem::boundingBox(reference));
  // Equal counts per slab: the particles in order along the axis (index
  // breaks ties, so every piece draws the same lines).
  std::vector<dem::ParticleIndex> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](dem::ParticleIndex a, dem::ParticleIndex b) {
    const double ca = along(reference[static_cast<std::size_t>(a)], axis);
    const double cb = along(reference[static_cast<std::size_t>(b)], axis);
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
    const double lo = along(reference[static_cast<std::size_t>(order[first])], axis) - ghostWidth;
    const double hi =
        along(reference[static_cast<std::size_t>(order[last - 1])], axis) + ghostWidth;
    for (std::size_t i = 0; i < n; ++i) {
      const double c = along(reference[i], axis);
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
