#include <algorithm>
#include <cmath>

#include <voro++/voro++.hh>

#include <crackvis/cracks/voro_reference.hpp>

namespace crackvis::cracks {

namespace {

template <typename Container, typename Loop>
GlobalVoronoiSummary computeAll(Container& container,
                                const std::function<void(const ReferenceCell&)>& visit);

}  // namespace

GlobalVoronoiSummary globalVoronoi(std::span<const Vec3> positions, const Box& box,
                                   const std::function<void(const ReferenceCell&)>& visit,
                                   std::span<const double> radius) {
  // About 5 particles per block is Voro++'s sweet spot.
  const Vec3 size = box.hi - box.lo;
  const double volume = std::max(size.x * size.y * size.z, 1e-300);
  const double blockSide =
      std::cbrt(volume * 5.0 / std::max<double>(1.0, static_cast<double>(positions.size())));
  auto blocks = [&](double extent) { return std::max(1, static_cast<int>(extent / blockSide)); };
  const bool poly = !radius.empty() && *std::max_element(radius.begin(), radius.end()) >
                                           *std::min_element(radius.begin(), radius.end());
  if (poly) {
    // Radical (power) planes, as local Voronoi uses for unequal radii.
    voro::container_poly container(box.lo.x, box.hi.x, box.lo.y, box.hi.y, box.lo.z, box.hi.z,
                                   blocks(size.x), blocks(size.y), blocks(size.z), false, false,
                                   false, 8);
    for (std::size_t i = 0; i < positions.size(); ++i) {
      container.put(static_cast<int>(i), positions[i].x, positions[i].y, positions[i].z, radius[i]);
    }
    return computeAll<voro::container_poly, voro::c_loop_all>(container, visit);
  }
  voro::container container(box.lo.x, box.hi.x, box.lo.y, box.hi.y, box.lo.z, box.hi.z,
                            blocks(size.x), blocks(size.y), blocks(size.z), false, false, false, 8);
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

}  // namespace crackvis::cracks
