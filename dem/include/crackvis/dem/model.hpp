// The DEM data model: particles, the fixed lattice of bonds between them, and
// the per-step state (positions, which bonds are broken).
//
// Arrays are flat (structure of arrays) and indexed by particle or bond index,
// so a step maps 1:1 onto the HDF5 datasets of docs/data-format.md and onto
// the hot loops of the crack extraction. 2D data sets keep three coordinates
// with z = 0, so every consumer handles one layout.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/vocabulary/names.hpp>
#include <crackvis/vocabulary/vec3.hpp>

namespace crackvis::dem {

using ParticleIndex = std::int32_t;
using BondIndex = std::int32_t;

// An axis-aligned box.
struct Bounds {
  Vec3 lo;
  Vec3 hi;
};
// The smallest box holding the points; a zero box at the origin when empty.
Bounds boundingBox(std::span<const Vec3> points);

// A bond (spring) of the lattice between two particles; first < second in
// files written by crackvis, but readers accept either order.
struct Bond {
  ParticleIndex first = 0;
  ParticleIndex second = 0;

  friend bool operator==(const Bond&, const Bond&) = default;
};
static_assert(sizeof(Bond) == 2 * sizeof(std::int32_t), "Bond must map onto int32[M,2] rows");

// Values of a bond_state array.
enum class BondState : std::uint8_t { kIntact = 0, kBroken = 1 };

// Bits of a bond's flags (crackvis-dem v1.1 /bonds/flags).
enum BondFlag : std::uint8_t {
  // Cut or absent at the start (a notch, a pre-existing joint): broken from
  // the first step on, but not by load.
  kBondCutAtStart = 1,
};

// What an extra array belongs to.
enum class ExtraOwner { kParticles, kBonds };

// A named quantity a source code wrote beside the layout's own arrays
// (damage, forces, coordination...): crackvis-dem v1.1 `extra/NAME`, carried
// along so a view can colour by it. Values are row-major [count, components].
struct ExtraArray {
  std::string name;
  ExtraOwner owner = ExtraOwner::kParticles;
  int components = 1;  // 1 (scalar) or 3 (vector)
  std::vector<double> values;

  std::size_t rows() const { return components > 0 ? values.size() / components : 0; }
};

// The per-bond extra array in which `crackvis import` keeps the mode the
// code itself recorded for each bond's break (Yade JCFpm's crack file):
// 1 tension, 2 shear, 0 none recorded (or not broken by that step).
inline constexpr std::string_view kBreakModeArray = "break_mode";

// A named per-step scalar (load, displacement, energy...): v1.1.
struct StepScalar {
  std::string name;
  double value = 0.0;

  friend bool operator==(const StepScalar&, const StepScalar&) = default;
};

// The time-independent part of a data set: what every step shares. The
// arrays marked optional are empty when a file does not hold them.
struct Lattice {
  int dimension = 3;             // 2 or 3
  std::vector<double> radius;    // [N] particle radii, m
  std::vector<Bond> bonds;       // [M] the fixed lattice topology
  std::vector<double> strength;  // [M] tensile strength R_n of each bond, N; optional (v1.1)
  std::vector<std::int64_t> particleId;     // [N] the source code's particle ids; optional
  std::vector<std::int32_t> particleGroup;  // [N] group label (clamp, material...); optional
  std::vector<std::uint8_t> bondFlags;      // [M] BondFlag bits; optional
  std::vector<ExtraArray> extras;           // constant extra arrays

  std::size_t particleCount() const { return radius.size(); }
  std::size_t bondCount() const { return bonds.size(); }
  // Whether bond b was cut at the start (a notch) rather than broken by load.
  bool cutAtStart(std::size_t b) const {
    return !bondFlags.empty() && (bondFlags[b] & kBondCutAtStart) != 0;
  }
};

// The state of the lattice at one saved time step.
struct StepState {
  double time = 0.0;                             // simulated time, s
  std::vector<Vec3> positions;                   // [N] particle centres, m
  std::vector<std::uint8_t> bondState;           // [M] BondState values
  std::vector<std::array<float, 3>> velocities;  // [N] optional, m/s
  std::vector<float> bondForce;                  // [M] optional normal force, N
  std::vector<StepScalar> scalars;               // named scalars of this step (v1.1)
  std::vector<ExtraArray> extras;                // per-step extra arrays (v1.1)

  std::size_t brokenBondCount() const;
};

// Checks extra arrays against N and M: valid unique names, 1 or 3
// components, the right number of rows, finite values.
Status validateExtras(std::span<const ExtraArray> extras, std::size_t particleCount,
                      std::size_t bondCount);

// The largest coordinate or radius a data set may hold, m: far beyond any
// specimen, and small enough that differences and bounding boxes of
// positions stay finite.
inline constexpr double kMaxCoordinate = 1e15;

// Checks what a lattice must satisfy whatever its source: dimension 2 or 3,
// positive finite radii (up to kMaxCoordinate), strengths (when present) of
// length M that are not NaN or negative, bond ends in range, no self-bond, no
// duplicate bond, optional per-particle and per-bond arrays of the right
// length, particle ids unique, extras valid. The message names the first
// offending bond or particle.
Status validateLattice(const Lattice& lattice);
// The same without the strengths (a view reads no strengths): the one check
// of radii and bonds that `crackvis info`, `extract` and the render server's
// step sources share. kCheckedAlready skips the bond ends' range, for a list
// that checkBondEnds passed as it arrived.
enum class BondEnds { kCheck, kCheckedAlready };
Status validateTopology(const Lattice& lattice, BondEnds ends = BondEnds::kCheck);

// Every bond joins two of `particles` particles (indices 0..N-1); `first` is
// the index of bonds[0] in the whole list, for a list checked in pieces.
// INVALID_ARGUMENT "bond B joins particles I and J: index out of range
// (N = n particles)". The one range check of a bond list, local or remote.
Status checkBondEnds(std::span<const Bond> bonds, std::int64_t particles, std::size_t first = 0);

// Checks a step against its lattice: array lengths agree with N and M,
// positions finite and within kMaxCoordinate, z = 0 in 2D, bond states 0
// or 1.
Status validateStep(const Lattice& lattice, const StepState& step);
// The same, for readers that know only the dimension, N and M.
Status validateStep(int dimension, std::size_t particleCount, std::size_t bondCount,
                    const StepState& step);
// Bond states 0 or 1 (the last part of validateStep).
Status validateBondStates(std::span<const std::uint8_t> bondState);

}  // namespace crackvis::dem
