// Voro++'s global Voronoi diagram, the reference the local methods are
// measured against (tests compare cells face by face; `crackvis bench
// methods` times it). Voro++ is only linked here.
#pragma once

#include <functional>
#include <span>
#include <vector>

#include <crackvis/cracks/extractor.hpp>

namespace crackvis::cracks {

struct ReferenceFace {
  int neighbour;  // particle index, or a wall: -1 x-, -2 x+, -3 y-, -4 y+, -5 z-, -6 z+
  double area;
  std::vector<Vec3> vertices;
};

struct ReferenceCell {
  int particle;
  double volume;
  std::vector<ReferenceFace> faces;
};

struct GlobalVoronoiSummary {
  std::size_t cells = 0;
  std::size_t faces = 0;
  double volume = 0.0;
};

// Computes the Voronoi cell of every particle inside `box` (particles must lie
// inside it) with neighbours, face areas and face vertices, as a
// visualization filter needs them; calls `visit` for each when given. With
// unequal radii, the power (radical) diagram (Voro++'s container_poly).
GlobalVoronoiSummary globalVoronoi(std::span<const Vec3> positions, const Box& box,
                                   const std::function<void(const ReferenceCell&)>& visit = {},
                                   std::span<const double> radius = {});

}  // namespace crackvis::cracks
