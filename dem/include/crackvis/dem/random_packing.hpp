// Dense random packings of spheres (3D) or disks (2D) in a box, bonded by an
// interaction-range rule: the specimens Yade, ESyS-Particle and LAMMPS users
// run, made reproducibly from a seed so crack methods can be tested on them.
//
// Radii are drawn uniformly from [radiusMin, radiusMax] (equal: monodisperse)
// until the spheres' volume reaches solidFraction of the box. Centres start
// uniformly at random; the radii are then grown from a loose start to their
// full size in stages, and after each growth overlaps are relaxed by moving
// every overlapping pair apart (Gauss-Seidel sweeps over the pairs in index
// order; walls keep spheres inside the box). This is the "inflate and relax"
// scheme of Lubachevsky-Stillinger-like generators without dynamics: it
// reaches solid fractions of about 0.6 (3D) and 0.8 (2D) with overlaps below
// `overlapTolerance` of the smallest radius, in seconds for 10^4 particles.
// It runs sequentially, so a seed gives the same packing on every machine.
//
// Bonds join every pair with |x_i - x_j| <= interactionRange * (r_i + r_j),
// the usual rule of bonded-particle models (Yade's JCFpm intRadius, ESyS's
// bonding tolerance).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::dem {

struct RandomPackingSpec {
  int dimension = 3;
  Vec3 box{0.02, 0.02, 0.02};   // m; z ignored in 2D
  double radiusMin = 5e-4;      // m
  double radiusMax = 5e-4;      // m (>= radiusMin; 2 x radiusMin for "1:2" polydisperse)
  double solidFraction = 0.55;  // volume (3D) or area (2D) of the spheres over the box's
  double interactionRange = 1.1;
  double strength = 1.0;  // R_n of every bond, N
  std::uint64_t seed = 1;
  // Largest overlap r_i + r_j - |x_i - x_j| left, as a fraction of radiusMin.
  double overlapTolerance = 0.01;
};

struct RandomPacking {
  Lattice lattice;
  std::vector<Vec3> positions;
  double solidFraction = 0.0;   // of the spheres actually placed
  double largestOverlap = 0.0;  // m, after relaxation
  int relaxationSweeps = 0;
};

// Progress in [0, 1], for a progress bar.
using PackingProgress = std::function<void(double)>;

Status validate(const RandomPackingSpec& spec);
Result<RandomPacking> generateRandomPacking(const RandomPackingSpec& spec,
                                            const PackingProgress& progress = {});

// Pairs with |x_i - x_j| <= range * (r_i + r_j), sorted by (i, j).
std::vector<Bond> interactionRangeBonds(const std::vector<Vec3>& positions,
                                        const std::vector<double>& radius, double range);

}  // namespace crackvis::dem
