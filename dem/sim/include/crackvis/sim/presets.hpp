// The benchmark problems of the dissertation's chapter 3.1 as ready-to-run
// simulation setups: uniaxial tension of a notched plate (2D) and of a notched
// cuboid (3D, defect sets A, B, C), with the calibrated material of
// docs/simulator.md.
//
//  - plate2d:  triangular lattice, 120 spheres per row x 39 rows, r = 1.58 mm
//              (4,680 particles, 13,723 bonds; the dissertation: 4,679 and
//              13,722); 3 pre-broken bonds at the middle of the lower long edge;
//              ends pulled apart at 0.05 m/s each; 1,284 saved steps.
//  - cuboid3d: FCC with x along [100]: 75 square layers of 25 x 25 spheres,
//              r = 2 mm (46,875 particles, 267,674 bonds, as the dissertation);
//              a rectangle of pre-broken bonds across the middle layer gap at
//              the bottom face (A 5 x 25 = 125, B 5 x 49 = 245, C 11 x 11 =
//              121 bonds); ends pulled apart at 0.025 m/s each; 200 saved steps.
//
// Scaling by S in (0, 1] multiplies the spheres per axis by S (rounded) and
// divides the radius by S: same geometry, about S^dim as many particles and
// 1/S fewer time steps. Stiffness, strength and mass follow the radius so the
// macroscopic material is the same at every scale.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include <crackvis/common/status.hpp>
#include <crackvis/sim/simulator.hpp>
#include <crackvis/sim/strength.hpp>

namespace crackvis::sim {

// The scale-free description of the material; presets derive the per-bond and
// per-particle values from it and the particle size.
struct MaterialModel {
  double youngsModulus = 30.0e9;   // E of the lattice along the pull axis, Pa
  double density = 2500.0;         // of the spheres, kg/m^3
  double poissonRatio = 0.2;       // of the sphere material, for the Hertz modulus
  double bondDamping = 0.05;       // zeta of the bond dashpots
  double restitution = 0.5;        // of contacts
  double friction = 0.5;           // mu of contacts
  StrengthDistribution strength;   // bond strain at break
  double timeStepFraction = 0.15;  // dt <= fraction * sqrt(m / k_n)
};

// The calibrated defaults per dimension (docs/simulator.md explains them).
MaterialModel defaultMaterial(int dimension);

struct PresetOptions {
  std::string name = "cuboid3d";  // plate2d | cuboid3d
  char defectSet = 'A';           // cuboid3d only: A, B or C
  double scale = 1.0;             // (0, 1]
  std::uint64_t seed = 1;         // of the bond strengths
  double duration = 0.0;          // simulated time of the last saved step; 0: preset's
  int savedSteps = 0;             // 0: the preset's; others stop earlier or later, same spacing
  MaterialModel material;         // presets start from defaultMaterial(dimension)
  bool customMaterial = false;    // true: use `material` instead of the default
};

struct Preset {
  std::string description;  // "cuboid3d set A, scale 1"
  SimulationSetup setup;
  std::int64_t stepsPerSave = 1;
  int savedSteps = 1;         // including step 0
  double pullVelocity = 0.0;  // of each clamped end, m/s
  std::size_t defectBonds = 0;
  dem::Vec3 defectCentre;  // mean midpoint of the pre-broken bonds
  dem::Vec3 extent;        // bounding box of the spheres
};

Result<Preset> makePreset(const PresetOptions& options);

// Uniaxial tension of any specimen (a generated random packing, an imported
// run's first step): a notch of bonds across the mid-plane x, from the bottom
// face (z in 3D, y in 2D) up to `notchDepth` of the height, over the whole
// width; grips of three mean radii at both x ends pulled apart at the
// benchmarks' strain rate (the cuboid's in 3D, the plate's in 2D) for their
// loading time; bond stiffness from the mean radius and each bond's strength
// from its rest length and a strain drawn from the material's distribution.
// `options` supplies seed, duration, saved steps (default 200) and material.
Result<Preset> makeTensionPreset(const dem::Lattice& specimen,
                                 const std::vector<dem::Vec3>& positions,
                                 const PresetOptions& options, double notchDepth = 0.1);

// "plate2d", "cuboid3d".
bool isPresetName(std::string_view name);

// Simulated time of a preset's last saved step (calibrated), s; 0 for an
// unknown name.
double presetDuration(std::string_view name);

}  // namespace crackvis::sim
