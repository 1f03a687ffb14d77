#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <memory>
#include <thread>
#include <type_traits>

#include <voro++/voro++.hh>

#include <crackvis/cracks_voro/voro_reference.hpp>

namespace crackvis::cracks {

namespace {

template <typename Container, typename Loop>
GlobalVoronoiSummary computeAll(Container& container,
                                const std::function<void(const ReferenceCell&)>& visit);

}  // namespace

namespace {

// Voro++'s blocks along each side for `count` particles in `box`: about 5
// particles per block is its sweet spot.
std::array<int, 3> blockCounts(const Box& box, std::size_t count) {
  const Vec3 size = box.hi - box.lo;
  const double volume = std::max(size.x * size.y * size.z, 1e-300);
  const double side = std::cbrt(volume * 5.0 / std::max<double>(1.0, static_cast<double>(count)));
  auto along = [&](double extent) { return std::max(1, static_cast<int>(extent / side)); };
  return {along(size.x), along(size.y), along(size.z)};
}

bool unequalRadii(std::span<const double> radius) {
  return !radius.empty() && *std::max_element(radius.begin(), radius.end()) >
                                *std::min_element(radius.begin(), radius.end());
}

}  // namespace

GlobalVoronoiSummary globalVoronoi(std::span<const Vec3> positions, const Box& box,
                                   const std::function<void(const ReferenceCell&)>& visit,
                                   std::span<const double> radius) {
  const std::array<int, 3> n = blockCounts(box, positions.size());
  const bool poly = unequalRadii(radius);
  if (poly) {
    // Radical (power) planes, as local Voronoi uses for unequal radii.
    voro::container_poly container(box.lo.x, box.hi.x, box.lo.y, box.hi.y, box.lo.z, box.hi.z, n[0],
                                   n[1], n[2], false, false, false, 8);
    for (std::size_t i = 0; i < positions.size(); ++i) {
      container.put(static_cast<int>(i), positions[i].x, positions[i].y, positions[i].z, radius[i]);
    }
    return computeAll<voro::container_poly, voro::c_loop_all>(container, visit);
  }
  voro::container container(box.lo.x, box.hi.x, box.lo.y, box.hi.y, box.lo.z, box.hi.z, n[0], n[1],
                            n[2], false, false, false, 8);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    container.put(static_cast<int>(i), positions[i].x, positions[i].y, positions[i].z);
  }
  return computeAll<voro::container, voro::c_loop_all>(container, visit);
}

namespace {

template <typename Container, typename Loop>
GlobalVoronoiSummary computeAll(Container& container,
                                const std::function<void(const ReferenceCell&)>& visit) {
  GlobalVoronoiSummary summary;
  Loop loop(container);
  voro::voronoicell_neighbor cell;
  std::vector<int> neighbours;
  std::vector<double> areas;
  std::vector<int> faceVertices;
  std::vector<double> vertices;
  ReferenceCell reference;
  if (loop.start()) {
    do {
      if (!container.compute_cell(cell, loop)) {
        continue;
      }
      double x = 0.0;
      double y = 0.0;
      double z = 0.0;
      loop.pos(x, y, z);
      cell.neighbors(neighbours);
      cell.face_areas(areas);
      cell.face_vertices(faceVertices);
      cell.vertices(x, y, z, vertices);
      ++summary.cells;
      summary.faces += neighbours.size();
      const double cellVolume = cell.volume();
      summary.volume += cellVolume;
      if (!visit) {
        continue;
      }
      reference.particle = loop.pid();
      reference.volume = cellVolume;
      reference.faces.clear();
      std::size_t cursor = 0;
      for (std::size_t f = 0; f < neighbours.size(); ++f) {
        ReferenceFace face{neighbours[f], areas[f], {}};
        const auto count = static_cast<std::size_t>(faceVertices[cursor++]);
        for (std::size_t k = 0; k < count; ++k) {
          const auto v = static_cast<std::size_t>(faceVertices[cursor++]);
          face.vertices.push_back({vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]});
        }
        reference.faces.push_back(std::move(face));
      }
      visit(reference);
    } while (loop.inc());
  }
  return summary;
}

}  // namespace

namespace {

// One slab of the box: its container's extent (the slab and its halo) and
// the Voro++ wall ids of its inner walls (INT_MIN where the slab's side is
// the box's own wall).
struct Slab {
  Box container;
  int axis = 0;
  int lowerInnerWall = INT_MIN;
  int upperInnerWall = INT_MIN;
};

double along(Vec3 v, int axis) {
  return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

void setAlong(Vec3& v, int axis, double value) {
  (axis == 0 ? v.x : axis == 1 ? v.y : v.z) = value;
}

template <typename Container>
void putParticle(Container& container, voro::particle_order* owned, int id, Vec3 p,
                 std::span<const double> radius) {
  if constexpr (std::is_same_v<Container, voro::container_poly>) {
    const double r = radius[static_cast<std::size_t>(id)];
    owned != nullptr ? container.put(*owned, id, p.x, p.y, p.z, r)
                     : container.put(id, p.x, p.y, p.z, r);
  } else {
    owned != nullptr ? container.put(*owned, id, p.x, p.y, p.z) : container.put(id, p.x, p.y, p.z);
  }
}

// Neighbours and face areas of the cells of the particles a slab owns.
template <typename Container>
LeanVoronoiSummary leanSlab(std::span<const Vec3> positions, std::span<const double> radius,
                            const Box& box, const Slab& slab, int slabIndex, int slabCount) {
  const double lo = along(box.lo, slab.axis);
  const double width = (along(box.hi, slab.axis) - lo) / slabCount;
  const double from = along(slab.container.lo, slab.axis);
  const double to = along(slab.container.hi, slab.axis);
  std::size_t count = 0;
  for (const Vec3& p : positions) {
    count += along(p, slab.axis) >= from && along(p, slab.axis) <= to ? 1 : 0;
  }
  const std::array<int, 3> n = blockCounts(slab.container, count);
  const Box& b = slab.container;
  auto container = std::make_unique<Container>(b.lo.x, b.hi.x, b.lo.y, b.hi.y, b.lo.z, b.hi.z, n[0],
                                               n[1], n[2], false, false, false, 8);
  voro::particle_order owned;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const double c = along(positions[i], slab.axis);
    if (c < from || c > to) {
      continue;
    }
    const int owner = std::min(slabCount - 1, static_cast<int>((c - lo) / width));
    putParticle(*container, owner == slabIndex ? &owned : nullptr, static_cast<int>(i),
                positions[i], radius);
  }
  LeanVoronoiSummary summary;
  summary.containers = 1;
  voro::c_loop_order loop(*container, owned);
  voro::voronoicell_neighbor cell;
  std::vector<int> neighbours;
  std::vector<double> areas;
  if (loop.start()) {
    do {
      if (!container->compute_cell(cell, loop)) {
        continue;
      }
      cell.neighbors(neighbours);
      cell.face_areas(areas);
      ++summary.cells;
      summary.faces += neighbours.size();
      for (std::size_t f = 0; f < neighbours.size(); ++f) {
        summary.faceArea += areas[f];
        if (neighbours[f] == slab.lowerInnerWall || neighbours[f] == slab.upperInnerWall) {
          ++summary.haloWallFaces;
        }
      }
    } while (loop.inc());
  }
  return summary;
}

// The slabs along the box's longest side, each grown by a halo of three
// mean particle spacings (a cell's faces come from particles within about
// twice its radius; `haloWallFaces` reports where that was not enough).
std::vector<Slab> makeSlabs(const Box& box, std::size_t count, int slabCount) {
  const Vec3 size = box.hi - box.lo;
  const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
  const double volume = std::max(size.x * size.y * size.z, 1e-300);
  const double spacing = std::cbrt(volume / std::max<double>(1.0, static_cast<double>(count)));
  const double halo = 3.0 * spacing;
  const double lo = along(box.lo, axis);
  const double width = along(size, axis) / slabCount;
  std::vector<Slab> slabs(static_cast<std::size_t>(slabCount));
  for (int k = 0; k < slabCount; ++k) {
    Slab& slab = slabs[static_cast<std::size_t>(k)];
    slab.axis = axis;
    slab.container = box;
    if (k > 0) {
      setAlong(slab.container.lo, axis, lo + k * width - halo);
      slab.lowerInnerWall = -(2 * axis + 1);
    }
    if (k + 1 < slabCount) {
      setAlong(slab.container.hi, axis, lo + (k + 1) * width + halo);
      slab.upperInnerWall = -(2 * axis + 2);
    }
    setAlong(slab.container.lo, axis, std::max(along(slab.container.lo, axis), lo));
    setAlong(slab.container.hi, axis,
             std::min(along(slab.container.hi, axis), along(box.hi, axis)));
  }
  return slabs;
}

}  // namespace

LeanVoronoiSummary leanVoronoi(std::span<const Vec3> positions, const Box& box,
                               std::span<const double> radius, int slabs) {
  slabs = std::max(1, slabs);
  const std::vector<Slab> parts = makeSlabs(box, positions.size(), slabs);
  const bool poly = unequalRadii(radius);
  std::vector<LeanVoronoiSummary> results(parts.size());
  auto run = [&](int k) {
    results[static_cast<std::size_t>(k)] =
        poly ? leanSlab<voro::container_poly>(positions, radius, box,
                                              parts[static_cast<std::size_t>(k)], k, slabs)
             : leanSlab<voro::container>(positions, radius, box, parts[static_cast<std::size_t>(k)],
                                         k, slabs);
  };
  std::vector<std::thread> threads;
  for (int k = 1; k < slabs; ++k) {
    threads.emplace_back(run, k);
  }
  run(0);
  for (std::thread& thread : threads) {
    thread.join();
  }
  LeanVoronoiSummary total;
  for (const LeanVoronoiSummary& part : results) {
    total.cells += part.cells;
    total.faces += part.faces;
    total.faceArea += part.faceArea;
    total.containers += part.containers;
    total.haloWallFaces += part.haloWallFaces;
  }
  return total;
}

}  // namespace crackvis::cracks
