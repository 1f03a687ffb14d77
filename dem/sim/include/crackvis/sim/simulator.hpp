// The explicit lattice DEM solver of the dissertation's chapter 1.3.
//
// Bonded neighbours interact by linear normal springs, F = k_n (|x_j - x_i| - L0)
// along the bond (tension positive), with an optional dashpot in parallel; a
// bond breaks for good in the step in which its elastic tensile force exceeds
// its strength R_n. Broken bonds, and pairs that touch without ever having been
// bonded, interact by the Hertz contact law of contact.hpp. Translation and
// rotation are integrated with velocity Verlet; clamped particles move at a
// prescribed constant velocity and do not rotate.
//
// Determinism: bond and contact forces are computed per pair into arrays, and
// each particle then gathers the forces of its pairs in a fixed (CSR) order,
// so no sum depends on scheduling. Results are bit-identical for any number of
// TBB threads.
#pragma once

#include <cstdint>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/dem/model.hpp>
#include <crackvis/sim/contact.hpp>

namespace crackvis::sim {

inline constexpr std::uint8_t kClampX = 1;
inline constexpr std::uint8_t kClampY = 2;
inline constexpr std::uint8_t kClampZ = 4;
inline constexpr std::uint8_t kClampAll = kClampX | kClampY | kClampZ;

struct Material {
  double density = 2500.0;       // of the sphere material, kg/m^3
  double bondStiffness = 1.0e8;  // k_n, N/m
  double bondDamping = 0.0;      // critical damping ratio zeta of the bond dashpot
  ContactParameters contact;
};

// Everything a run starts from. Bond rest lengths are the initial distances,
// so the initial configuration is stress-free.
struct SimulationSetup {
  dem::Lattice lattice;                 // dimension, radii, bonds, strengths R_n
  std::vector<dem::Vec3> positions;     // [N] initial
  std::vector<dem::Vec3> velocities;    // [N] initial; empty means at rest
  std::vector<std::uint8_t> bondState;  // [M] initial (defects broken); empty means intact
  // [N] bit mask of the axes (kClampX | kClampY | kClampZ) along which a
  // particle moves at its prescribedVelocity; the other axes are integrated.
  // Clamped particles (any bit) do not rotate. Empty: none clamped.
  std::vector<std::uint8_t> clamped;
  std::vector<dem::Vec3> prescribedVelocity;  // [N] used along clamped axes
  // The prescribed velocities rise smoothly from 0, (1 - cos(pi t / T)) / 2,
  // over this time T (0: from the first step), so that starting the grips
  // does not send a shock wave through the specimen.
  double clampRampTime = 0.0;  // s
  Material material;
  double timeStep = 1e-7;  // s
};

// sqrt(m_min / k_n): the time scale of the stiffest bond on the lightest
// particle. Velocity Verlet on a close-packed lattice of such springs is
// stable below about 0.5 of it (12 neighbours); presets use a fraction of it.
double bondTimeScale(const dem::Lattice& lattice, const Material& material);

// Mass of a sphere of radius r.
double sphereMass(double radius, double density);

class Simulator {
 public:
  // Validates the setup (array lengths, positive time step, no overlapping
  // bonded pair at zero length) and computes the initial forces.
  static Result<Simulator> create(SimulationSetup setup);

  // Advances `steps` time steps.
  void advance(std::int64_t steps);

  std::int64_t stepIndex() const { return m_step; }
  double time() const { return static_cast<double>(m_step) * m_dt; }
  double timeStep() const { return m_dt; }
  std::size_t particleCount() const { return m_positions.size(); }
  std::size_t bondCount() const { return m_bondState.size(); }

  const dem::Lattice& lattice() const { return m_lattice; }
  const std::vector<dem::Vec3>& positions() const { return m_positions; }
  const std::vector<dem::Vec3>& velocities() const { return m_velocities; }
  const std::vector<dem::Vec3>& angularVelocities() const { return m_angularVelocities; }
  const std::vector<std::uint8_t>& bondState() const { return m_bondState; }
  // Elastic normal force k_n (L - L0) of intact bonds (tension positive), the
  // Hertz normal force of touching broken bonds as a negative (compressive)
  // value, and 0 for separated broken bonds.
  const std::vector<double>& bondNormalForce() const { return m_bondNormalForce; }
  std::size_t brokenBondCount() const;
  // Non-bonded pairs currently tracked for contact (within radius sum + skin).
  std::size_t contactCandidateCount() const { return m_contactPairs.size(); }

  // Translational plus rotational kinetic energy, fully clamped particles excluded, J.
  double kineticEnergy() const;
  // Elastic energy of intact bonds and Hertz contacts, J.
  double potentialEnergy() const;

  // The state as a file step; velocities and bond forces are optional.
  dem::StepState snapshot(bool withVelocities, bool withBondForce) const;

 private:
  Simulator() = default;
  void buildBondAdjacency();
  void rebuildContactsIfNeeded();
  void rebuildContacts();
  void computeBondForces();
  void computeContactForces();
  void computeForces();
  void gatherForces(bool kick);
  void drift();
  double rampFactor(double time) const;

  dem::Lattice m_lattice;
  Material m_material;
  double m_dt = 0.0;
  std::int64_t m_step = 0;

  // Particles (structure of arrays).
  std::vector<dem::Vec3> m_positions;
  std::vector<dem::Vec3> m_velocities;
  std::vector<dem::Vec3> m_angularVelocities;
  std::vector<dem::Vec3> m_forces;
  std::vector<dem::Vec3> m_torques;
  std::vector<double> m_inverseMass;
  std::vector<double> m_inverseInertia;
  std::vector<double> m_mass;
  std::vector<std::uint8_t> m_clamped;
  std::vector<dem::Vec3> m_prescribedVelocity;
  double m_clampRampTime = 0.0;

  // Bonds.
  std::vector<double> m_restLength;
  std::vector<double> m_bondDashpot;  // c = 2 zeta sqrt(m* k_n)
  std::vector<std::uint8_t> m_bondState;
  std::vector<double> m_bondNormalForce;
  std::vector<dem::Vec3> m_bondForce;       // on the first particle
  std::vector<dem::Vec3> m_bondTorqueAxis;  // n x force (contacts of broken bonds)
  // CSR: the bonds of particle p are m_bondRefs[m_bondStart[p] .. m_bondStart[p+1]),
  // each 2 * bond + (1 if p is the bond's second particle).
  std::vector<std::int32_t> m_bondStart;
  std::vector<std::int32_t> m_bondRefs;

  // Contacts between pairs without a bond (Verlet list with a skin).
  double m_skin = 0.0;
  std::vector<dem::Vec3> m_positionsAtRebuild;
  std::vector<dem::Bond> m_contactPairs;
  std::vector<dem::Vec3> m_contactForce;
  std::vector<dem::Vec3> m_contactTorqueAxis;
  std::vector<std::int32_t> m_contactStart;
  std::vector<std::int32_t> m_contactRefs;
};

}  // namespace crackvis::sim
