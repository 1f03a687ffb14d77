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

// What the lean baseline computed: every cell's neighbours and face areas.
struct LeanVoronoiSummary {
  std::size_t cells = 0;
  std::size_t faces = 0;
  double faceArea = 0.0;          // sum over all faces of all cells (a checksum)
  int containers = 0;             // Voro++ containers (slabs) used
  std::size_t haloWallFaces = 0;  // owned cells that reached a slab's inner wall: not exact
};

// The leanest honest global baseline for a crack filter: Voro++ computing
// each cell's neighbours and face areas only (no vertex lists), as a filter
// needs them to find the faces of broken bonds. With `slabs` > 1 the box is
// cut along its longest side into that many Voro++ containers, each run on
// its own thread with a halo of neighbouring particles; `haloWallFaces`
// counts cells the halo was too thin for (0: the diagram is exact).
LeanVoronoiSummary leanVoronoi(std::span<const Vec3> positions, const Box& box,
                               std::span<const double> radius = {}, int slabs = 1);

}  // namespace crackvis::cracks
