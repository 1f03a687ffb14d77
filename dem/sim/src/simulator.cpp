#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <crackvis/dem/neighbour_grid.hpp>
#include <crackvis/sim/simulator.hpp>

namespace crackvis::sim {
namespace {

using dem::Vec3;

// Grain sizes: large enough that scheduling overhead is small against the
// ~10 ns per element of work, small enough to balance two to sixteen cores.
constexpr std::size_t kParticleGrain = 1024;
constexpr std::size_t kPairGrain = 4096;
constexpr std::uint8_t kIntact = static_cast<std::uint8_t>(dem::BondState::kIntact);
constexpr std::uint8_t kBroken = static_cast<std::uint8_t>(dem::BondState::kBroken);
// The Verlet skin of the contact list, as a fraction of the smallest radius.
constexpr double kSkinFraction = 0.25;

template <typename Body>
void parallelFor(std::size_t count, std::size_t grain, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        body(k);
                      }
                    });
}

Vec3 scaled(double s, Vec3 a) {
  return s * a;
}

// Components of `prescribed` along the axes in `mask`, of `free` elsewhere.
Vec3 mixAxes(std::uint8_t mask, Vec3 prescribed, Vec3 free) {
  return {(mask & kClampX) != 0 ? prescribed.x : free.x,
          (mask & kClampY) != 0 ? prescribed.y : free.y,
          (mask & kClampZ) != 0 ? prescribed.z : free.z};
}

}  // namespace

double sphereMass(double radius, double density) {
  return density * 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
}

double bondTimeScale(const dem::Lattice& lattice, const Material& material) {
  double minRadius = lattice.radius.empty() ? 0.0 : lattice.radius.front();
  for (double r : lattice.radius) {
    minRadius = std::min(minRadius, r);
  }
  return std::sqrt(sphereMass(minRadius, material.density) / material.bondStiffness);
}

Result<Simulator> Simulator::create(SimulationSetup setup) {
  CRACKVIS_RETURN_IF_ERROR(dem::validateLattice(setup.lattice));
  const std::size_t n = setup.lattice.particleCount();
  const std::size_t m = setup.lattice.bondCount();
  if (setup.positions.size() != n) {
    return invalidArgument(fmt::format("{} positions for {} particles", setup.positions.size(), n));
  }
  if (!setup.velocities.empty() && setup.velocities.size() != n) {
    return invalidArgument(
        fmt::format("{} velocities for {} particles", setup.velocities.size(), n));
  }
  if (!setup.bondState.empty() && setup.bondState.size() != m) {
    return invalidArgument(fmt::format("{} bond states for {} bonds", setup.bondState.size(), m));
  }
  if (!setup.clamped.empty() &&
      (setup.clamped.size() != n || setup.prescribedVelocity.size() != n)) {
    return invalidArgument("clamped and prescribedVelocity need one entry per particle");
  }
  if (!(setup.timeStep > 0.0) || !std::isfinite(setup.timeStep)) {
    return invalidArgument(fmt::format("time step must be positive, got {}", setup.timeStep));
  }
  const Material& material = setup.material;
  if (!(material.density > 0.0) || !(material.bondStiffness > 0.0) ||
      !(material.bondDamping >= 0.0) || !(material.contact.effectiveModulus > 0.0) ||
      !(material.contact.restitution > 0.0 && material.contact.restitution <= 1.0) ||
      !(material.contact.friction >= 0.0) || !(material.contact.tangentialDamping >= 0.0)) {
    return invalidArgument(
        "material: density, stiffness and contact modulus must be > 0, damping and friction "
        ">= 0, restitution in (0, 1]");
  }

  Simulator sim;
  sim.m_lattice = std::move(setup.lattice);
  sim.m_material = material;
  sim.m_dt = setup.timeStep;
  sim.m_positions = std::move(setup.positions);
  sim.m_velocities = setup.velocities.empty() ? std::vector<Vec3>(n) : std::move(setup.velocities);
  sim.m_angularVelocities.assign(n, Vec3{});
  sim.m_forces.assign(n, Vec3{});
  sim.m_torques.assign(n, Vec3{});
  sim.m_clamped = setup.clamped.empty() ? std::vector<std::uint8_t>(n, 0) : setup.clamped;
  sim.m_prescribedVelocity =
      setup.prescribedVelocity.empty() ? std::vector<Vec3>(n) : setup.prescribedVelocity;
  if (!(setup.clampRampTime >= 0.0) || !std::isfinite(setup.clampRampTime)) {
    return invalidArgument(
        fmt::format("clamp ramp time must be >= 0, got {}", setup.clampRampTime));
  }
  sim.m_clampRampTime = setup.clampRampTime;
  sim.m_mass.resize(n);
  sim.m_inverseMass.resize(n);
  sim.m_inverseInertia.resize(n);
  double minRadius = sim.m_lattice.radius.empty() ? 0.0 : sim.m_lattice.radius.front();
  for (std::size_t p = 0; p < n; ++p) {
    const double r = sim.m_lattice.radius[p];
    minRadius = std::min(minRadius, r);
    sim.m_mass[p] = sphereMass(r, material.density);
    sim.m_inverseMass[p] = 1.0 / sim.m_mass[p];
    sim.m_inverseInertia[p] = 1.0 / (0.4 * sim.m_mass[p] * r * r);
    if (sim.m_clamped[p] > kClampAll) {
      return invalidArgument(fmt::format("particle {} has clamp mask {}, expected 0..7", p,
                                         static_cast<int>(sim.m_clamped[p])));
    }
    sim.m_velocities[p] = mixAxes(
        sim.m_clamped[p], sim.rampFactor(0.0) * sim.m_prescribedVelocity[p], sim.m_velocities[p]);
  }

  sim.m_bondState =
      setup.bondState.empty() ? std::vector<std::uint8_t>(m, kIntact) : std::move(setup.bondState);
  sim.m_restLength.resize(m);
  sim.m_bondDashpot.resize(m);
  for (std::size_t b = 0; b < m; ++b) {
    const dem::Bond bond = sim.m_lattice.bonds[b];
    const auto i = static_cast<std::size_t>(bond.first);
    const auto j = static_cast<std::size_t>(bond.second);
    if (sim.m_bondState[b] > kBroken) {
      return invalidArgument(fmt::format("bond {} has state {}, expected 0 or 1", b,
                                         static_cast<int>(sim.m_bondState[b])));
    }
    sim.m_restLength[b] = dem::norm(sim.m_positions[j] - sim.m_positions[i]);
    if (!(sim.m_restLength[b] > 0.0)) {
      return invalidArgument(
          fmt::format("bond {} joins particles {} and {} at the same place", b, i, j));
    }
    const double reducedMass = sim.m_mass[i] * sim.m_mass[j] / (sim.m_mass[i] + sim.m_mass[j]);
    sim.m_bondDashpot[b] =
        2.0 * material.bondDamping * std::sqrt(reducedMass * material.bondStiffness);
  }
  sim.m_bondNormalForce.assign(m, 0.0);
  sim.m_bondForce.assign(m, Vec3{});
  sim.m_bondTorqueAxis.assign(m, Vec3{});
  sim.buildBondAdjacency();
  sim.m_skin = kSkinFraction * minRadius;
  sim.rebuildContacts();
  sim.computeForces();
  sim.gatherForces(false);
  return sim;
}

void Simulator::buildBondAdjacency() {
  const std::size_t n = m_positions.size();
  m_bondStart.assign(n + 1, 0);
  for (const dem::Bond& bond : m_lattice.bonds) {
    ++m_bondStart[static_cast<std::size_t>(bond.first) + 1];
    ++m_bondStart[static_cast<std::size_t>(bond.second) + 1];
  }
  for (std::size_t p = 0; p < n; ++p) {
    m_bondStart[p + 1] += m_bondStart[p];
  }
  m_bondRefs.resize(static_cast<std::size_t>(m_bondStart[n]));
  std::vector<std::int32_t> fill(m_bondStart.begin(), m_bondStart.end() - 1);
  // Bond order within a particle's list is ascending: the gather order.
  for (std::size_t b = 0; b < m_lattice.bonds.size(); ++b) {
    const dem::Bond bond = m_lattice.bonds[b];
    const auto ref = static_cast<std::int32_t>(2 * b);
    m_bondRefs[static_cast<std::size_t>(fill[static_cast<std::size_t>(bond.first)]++)] = ref;
    m_bondRefs[static_cast<std::size_t>(fill[static_cast<std::size_t>(bond.second)]++)] = ref + 1;
  }
}

void Simulator::rebuildContacts() {
  m_positionsAtRebuild = m_positions;
  double maxRadius = 0.0;
  for (double r : m_lattice.radius) {
    maxRadius = std::max(maxRadius, r);
  }
  const double cutoff = 2.0 * maxRadius + m_skin;
  const dem::NeighbourGrid grid(m_positions, cutoff);
  std::vector<dem::Bond> near = grid.pairsWithin(cutoff);
  m_contactPairs.clear();
  for (const dem::Bond& pair : near) {
    const auto i = static_cast<std::size_t>(pair.first);
    const double reach =
        m_lattice.radius[i] + m_lattice.radius[static_cast<std::size_t>(pair.second)] + m_skin;
    const Vec3 delta = m_positions[static_cast<std::size_t>(pair.second)] - m_positions[i];
    if (dem::dot(delta, delta) >= reach * reach) {
      continue;
    }
    // Pairs with a bond (intact or broken) are handled by the bond loop.
    bool bonded = false;
    for (auto k = m_bondStart[i]; k < m_bondStart[i + 1]; ++k) {
      const dem::Bond bond = m_lattice.bonds[static_cast<std::size_t>(m_bondRefs[k] >> 1)];
      if (bond.first + bond.second - pair.first == pair.second) {
        bonded = true;
        break;
      }
    }
    if (!bonded) {
      m_contactPairs.push_back(pair);
    }
  }
  const std::size_t n = m_positions.size();
  m_contactStart.assign(n + 1, 0);
  for (const dem::Bond& pair : m_contactPairs) {
    ++m_contactStart[static_cast<std::size_t>(pair.first) + 1];
    ++m_contactStart[static_cast<std::size_t>(pair.second) + 1];
  }
  for (std::size_t p = 0; p < n; ++p) {
    m_contactStart[p + 1] += m_contactStart[p];
  }
  m_contactRefs.resize(static_cast<std::size_t>(m_contactStart[n]));
  std::vector<std::int32_t> fill(m_contactStart.begin(), m_contactStart.end() - 1);
  for (std::size_t c = 0; c < m_contactPairs.size(); ++c) {
    const auto ref = static_cast<std::int32_t>(2 * c);
    m_contactRefs[static_cast<std::size_t>(
        fill[static_cast<std::size_t>(m_contactPairs[c].first)]++)] = ref;
    m_contactRefs[static_cast<std::size_t>(
        fill[static_cast<std::size_t>(m_contactPairs[c].second)]++)] = ref + 1;
  }
  m_contactForce.assign(m_contactPairs.size(), Vec3{});
  m_contactTorqueAxis.assign(m_contactPairs.size(), Vec3{});
}

void Simulator::rebuildContactsIfNeeded() {
  // max is exact and order-independent, so this reduction is deterministic.
  const double maxSquared = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, m_positions.size(), kParticleGrain), 0.0,
      [&](const tbb::blocked_range<std::size_t>& range, double current) {
        for (std::size_t p = range.begin(); p != range.end(); ++p) {
          const Vec3 moved = m_positions[p] - m_positionsAtRebuild[p];
          current = std::max(current, dem::dot(moved, moved));
        }
        return current;
      },
      [](double a, double b) { return std::max(a, b); });
  const double half = 0.5 * m_skin;
  if (maxSquared > half * half) {
    rebuildContacts();
  }
}

void Simulator::computeBondForces() {
  const double stiffness = m_material.bondStiffness;
  const ContactParameters& contact = m_material.contact;
  parallelFor(m_lattice.bonds.size(), kPairGrain, [&](std::size_t b) {
    const dem::Bond bond = m_lattice.bonds[b];
    const auto i = static_cast<std::size_t>(bond.first);
    const auto j = static_cast<std::size_t>(bond.second);
    const Vec3 delta = m_positions[j] - m_positions[i];
    const double length = dem::norm(delta);
    if (m_bondState[b] == kIntact) {
      const double elastic = stiffness * (length - m_restLength[b]);
      if (elastic <= m_lattice.strength[b]) {
        const Vec3 n = scaled(1.0 / length, delta);
        const double rate = dem::dot(m_velocities[j] - m_velocities[i], n);
        m_bondForce[b] = scaled(elastic + m_bondDashpot[b] * rate, n);
        m_bondNormalForce[b] = elastic;
        return;
      }
      // Perfectly brittle: from this step on, only contact.
      m_bondState[b] = kBroken;
    }
    if (length >= m_lattice.radius[i] + m_lattice.radius[j]) {
      m_bondForce[b] = Vec3{};
      m_bondTorqueAxis[b] = Vec3{};
      m_bondNormalForce[b] = 0.0;
      return;
    }
    const ContactForce force = hertzContact(
        {m_positions[i], m_velocities[i], m_angularVelocities[i], m_lattice.radius[i], m_mass[i]},
        {m_positions[j], m_velocities[j], m_angularVelocities[j], m_lattice.radius[j], m_mass[j]},
        contact);
    m_bondForce[b] = force.force;
    m_bondTorqueAxis[b] = force.torqueAxis;
    m_bondNormalForce[b] = -force.normalForce;
  });
}

void Simulator::computeContactForces() {
  const ContactParameters& contact = m_material.contact;
  parallelFor(m_contactPairs.size(), kPairGrain, [&](std::size_t c) {
    const auto i = static_cast<std::size_t>(m_contactPairs[c].first);
    const auto j = static_cast<std::size_t>(m_contactPairs[c].second);
    const ContactForce force = hertzContact(
        {m_positions[i], m_velocities[i], m_angularVelocities[i], m_lattice.radius[i], m_mass[i]},
        {m_positions[j], m_velocities[j], m_angularVelocities[j], m_lattice.radius[j], m_mass[j]},
        contact);
    m_contactForce[c] = force.force;
    m_contactTorqueAxis[c] = force.torqueAxis;
  });
}

void Simulator::computeForces() {
  computeBondForces();
  computeContactForces();
}

double Simulator::rampFactor(double time) const {
  if (time >= m_clampRampTime) {
    return 1.0;
  }
  return 0.5 * (1.0 - std::cos(std::numbers::pi * time / m_clampRampTime));
}

void Simulator::gatherForces(bool kick) {
  const double halfStep = 0.5 * m_dt;
  // The kick ends the step: grips move at their speed of the new time.
  const double ramp = rampFactor(static_cast<double>(m_step + 1) * m_dt);
  parallelFor(m_positions.size(), kParticleGrain, [&](std::size_t p) {
    Vec3 force{};
    Vec3 torque{};
    const double radius = m_lattice.radius[p];
    for (auto k = m_bondStart[p]; k < m_bondStart[p + 1]; ++k) {
      const auto ref = m_bondRefs[static_cast<std::size_t>(k)];
      const auto b = static_cast<std::size_t>(ref >> 1);
      force = force + scaled((ref & 1) != 0 ? -1.0 : 1.0, m_bondForce[b]);
      if (m_bondState[b] != kIntact) {
        torque = torque + scaled(radius, m_bondTorqueAxis[b]);
      }
    }
    for (auto k = m_contactStart[p]; k < m_contactStart[p + 1]; ++k) {
      const auto ref = m_contactRefs[static_cast<std::size_t>(k)];
      const auto c = static_cast<std::size_t>(ref >> 1);
      force = force + scaled((ref & 1) != 0 ? -1.0 : 1.0, m_contactForce[c]);
      torque = torque + scaled(radius, m_contactTorqueAxis[c]);
    }
    m_forces[p] = force;
    m_torques[p] = torque;
    if (kick) {
      const std::uint8_t clamp = m_clamped[p];
      m_velocities[p] = mixAxes(clamp, ramp * m_prescribedVelocity[p],
                                m_velocities[p] + scaled(halfStep * m_inverseMass[p], force));
      if (clamp == 0) {
        m_angularVelocities[p] =
            m_angularVelocities[p] + scaled(halfStep * m_inverseInertia[p], torque);
      }
    }
  });
}

void Simulator::drift() {
  const double halfStep = 0.5 * m_dt;
  // Grips move at their mid-step speed: exact displacement for a linear ramp.
  const double ramp = rampFactor((static_cast<double>(m_step) + 0.5) * m_dt);
  parallelFor(m_positions.size(), kParticleGrain, [&](std::size_t p) {
    const std::uint8_t clamp = m_clamped[p];
    m_velocities[p] = mixAxes(clamp, ramp * m_prescribedVelocity[p],
                              m_velocities[p] + scaled(halfStep * m_inverseMass[p], m_forces[p]));
    if (clamp == 0) {
      m_angularVelocities[p] =
          m_angularVelocities[p] + scaled(halfStep * m_inverseInertia[p], m_torques[p]);
    }
    m_positions[p] = m_positions[p] + scaled(m_dt, m_velocities[p]);
  });
}

void Simulator::advance(std::int64_t steps) {
  for (std::int64_t s = 0; s < steps; ++s) {
    // Velocity Verlet: half kick and drift, forces at the new positions
    // (dashpots see the half-step velocities), second half kick.
    drift();
    rebuildContactsIfNeeded();
    computeForces();
    gatherForces(true);
    ++m_step;
  }
}

std::size_t Simulator::brokenBondCount() const {
  return static_cast<std::size_t>(std::count(m_bondState.begin(), m_bondState.end(), kBroken));
}

double Simulator::kineticEnergy() const {
  double energy = 0.0;
  for (std::size_t p = 0; p < m_positions.size(); ++p) {
    if (m_clamped[p] == kClampAll) {
      continue;
    }
    const double inertia = 1.0 / m_inverseInertia[p];
    energy += 0.5 * m_mass[p] * dem::dot(m_velocities[p], m_velocities[p]) +
              0.5 * inertia * dem::dot(m_angularVelocities[p], m_angularVelocities[p]);
  }
  return energy;
}

double Simulator::potentialEnergy() const {
  auto hertzEnergy = [&](std::size_t i, std::size_t j) {
    const double ri = m_lattice.radius[i];
    const double rj = m_lattice.radius[j];
    const double overlap = ri + rj - dem::norm(m_positions[j] - m_positions[i]);
    if (overlap <= 0.0) {
      return 0.0;
    }
    const double effectiveRadius = ri * rj / (ri + rj);
    return 8.0 / 15.0 * m_material.contact.effectiveModulus * std::sqrt(effectiveRadius) *
           std::pow(overlap, 2.5);
  };
  double energy = 0.0;
  for (std::size_t b = 0; b < m_bondState.size(); ++b) {
    const dem::Bond bond = m_lattice.bonds[b];
    const auto i = static_cast<std::size_t>(bond.first);
    const auto j = static_cast<std::size_t>(bond.second);
    if (m_bondState[b] == kIntact) {
      const double stretch = dem::norm(m_positions[j] - m_positions[i]) - m_restLength[b];
      energy += 0.5 * m_material.bondStiffness * stretch * stretch;
    } else {
      energy += hertzEnergy(i, j);
    }
  }
  for (const dem::Bond& pair : m_contactPairs) {
    energy +=
        hertzEnergy(static_cast<std::size_t>(pair.first), static_cast<std::size_t>(pair.second));
  }
  return energy;
}

dem::StepState Simulator::snapshot(bool withVelocities, bool withBondForce) const {
  dem::StepState step;
  step.time = time();
  step.positions = m_positions;
  step.bondState = m_bondState;
  if (withVelocities) {
    step.velocities.resize(m_velocities.size());
    for (std::size_t p = 0; p < m_velocities.size(); ++p) {
      const Vec3 v = m_velocities[p];
      step.velocities[p] = {static_cast<float>(v.x), static_cast<float>(v.y),
                            static_cast<float>(v.z)};
    }
  }
  if (withBondForce) {
    step.bondForce.resize(m_bondNormalForce.size());
    std::transform(m_bondNormalForce.begin(), m_bondNormalForce.end(), step.bondForce.begin(),
                   [](double f) { return static_cast<float>(f); });
  }
  return step;
}

}  // namespace crackvis::sim
