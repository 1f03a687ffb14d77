// Regular lattices of monodisperse spheres with bonds between nearest
// neighbours: the starting configurations of lattice DEM runs.
//
// Sites are counted per axis ("sites"):
//  - fcc: face-centred cubic in its cubic orientation; site planes a/2 = d/sqrt(2)
//    apart along x, y and z, sites where the plane indices sum to an even
//    number. A block of n x n x n cubic unit cells has 2n+1 planes per axis.
//  - hcp: hexagonal close packing, ABAB stacking of triangular layers; sites
//    per row (x, d apart), rows per layer (y, d*sqrt(3)/2 apart), layers (z,
//    d*sqrt(2/3) apart).
//  - triangular (2D): sites per row (x) and rows (y), z = 0.
// d = 2r is the bond length. Spheres touch the block's lower faces (x, y, z >= r).
// Bonds join every pair at distance d before jitter; the jitter then moves each
// coordinate by a uniform amount in [-jitter*r, jitter*r) from a seeded
// generator that gives the same numbers on every platform.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::dem {

enum class LatticeKind { kFcc, kHcp, kTriangular };

std::string_view toString(LatticeKind kind);
Result<LatticeKind> parseLatticeKind(std::string_view name);
inline int dimensionOf(LatticeKind kind) {
  return kind == LatticeKind::kTriangular ? 2 : 3;
}

struct BlockSpec {
  LatticeKind kind = LatticeKind::kFcc;
  std::array<int, 3> sites{5, 5, 5};  // per axis; the third is ignored in 2D
  double radius = 1e-3;               // m
  double strength = 1.0;              // R_n of every bond, N
  double jitter = 0.0;                // fraction of the radius, in [0, 0.5)
  std::uint64_t seed = 1;
};

struct LatticeBlock {
  Lattice lattice;
  std::vector<Vec3> positions;  // initial positions (step 0)
  Vec3 extent;                  // size of the box the spheres fill, before jitter
};

// The spacing of site planes along each axis for spheres of radius r.
std::array<double, 3> siteSpacing(LatticeKind kind, double radius);

// FCC sites per axis for n x n x n cubic unit cells.
inline std::array<int, 3> fccUnitCells(int nx, int ny, int nz) {
  return {2 * nx + 1, 2 * ny + 1, 2 * nz + 1};
}

// The most sites per axis whose spheres fit inside a box of the given size.
std::array<int, 3> sitesForBox(LatticeKind kind, Vec3 box, double radius);

Result<LatticeBlock> generateBlock(const BlockSpec& spec);

// Pairs of particles closer than tolerance * (r_i + r_j), sorted: the
// nearest-neighbour bonds of a touching packing.
std::vector<Bond> nearestNeighbourBonds(const std::vector<Vec3>& positions, double radius,
                                        double tolerance = 1.01);

// Bonds per particle.
std::vector<int> coordination(const Lattice& lattice);

}  // namespace crackvis::dem
