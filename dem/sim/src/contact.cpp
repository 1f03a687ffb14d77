#include <algorithm>
#include <cmath>
#include <numbers>

#include <crackvis/sim/contact.hpp>

namespace crackvis::sim {
namespace {

using dem::Vec3;

Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// beta of the damping term; 0 for a perfectly elastic contact (e = 1).
double dampingBeta(double restitution) {
  if (restitution >= 1.0) {
    return 0.0;
  }
  const double logE = std::log(restitution);
  return logE / std::sqrt(logE * logE + std::numbers::pi * std::numbers::pi);
}

}  // namespace

double hertzElasticForce(double overlap, double effectiveRadius, double effectiveModulus) {
  if (overlap <= 0.0) {
    return 0.0;
  }
  return 4.0 / 3.0 * effectiveModulus * std::sqrt(effectiveRadius) * overlap * std::sqrt(overlap);
}

ContactForce hertzContact(const ContactBody& first, const ContactBody& second,
                          const ContactParameters& parameters) {
  ContactForce result;
  const Vec3 delta = second.position - first.position;
  const double distance = dem::norm(delta);
  const double overlap = first.radius + second.radius - distance;
  if (overlap <= 0.0 || distance <= 0.0) {
    return result;
  }
  result.overlap = overlap;
  const Vec3 n = (1.0 / distance) * delta;
  const double effectiveRadius = first.radius * second.radius / (first.radius + second.radius);
  const double effectiveMass = first.mass * second.mass / (first.mass + second.mass);
  const double stiffness = 2.0 * parameters.effectiveModulus * std::sqrt(effectiveRadius * overlap);
  const double massStiffness = std::sqrt(effectiveMass * stiffness);
  const double gamma =
      -2.0 * std::sqrt(5.0 / 6.0) * dampingBeta(parameters.restitution) * massStiffness;

  // Velocity of the second body's surface point relative to the first's.
  const Vec3 contactVelocity =
      (second.velocity + cross(second.angularVelocity, -second.radius * n)) -
      (first.velocity + cross(first.angularVelocity, first.radius * n));
  const double separationSpeed = dem::dot(second.velocity - first.velocity, n);
  const double elastic = hertzElasticForce(overlap, effectiveRadius, parameters.effectiveModulus);
  // Damping may not turn a separating contact into an attracting one.
  const double normal = std::max(0.0, elastic - gamma * separationSpeed);
  result.normalForce = normal;

  Vec3 force = -normal * n;
  const Vec3 slip = contactVelocity - dem::dot(contactVelocity, n) * n;
  const double slipSpeed = dem::norm(slip);
  if (slipSpeed > 0.0) {
    const double sticking = parameters.tangentialDamping * massStiffness * slipSpeed;
    const double tangential = std::min(parameters.friction * normal, sticking);
    force = force + (tangential / slipSpeed) * slip;
  }
  result.force = force;
  result.torqueAxis = cross(n, force);
  return result;
}

}  // namespace crackvis::sim
