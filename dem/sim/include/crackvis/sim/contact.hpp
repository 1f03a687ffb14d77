// The contact law between two spheres that touch without an intact bond:
// Hertz normal force with nonlinear viscous damping (Tsuji et al. 1992, in the
// form of Zhu et al. 2008) and Coulomb friction regularized by a viscous law
// below sliding. A pure function, so it can be checked against the analytic
// Hertz solution on its own.
#pragma once

#include <crackvis/dem/model.hpp>

namespace crackvis::sim {

struct ContactParameters {
  double effectiveModulus = 1.0;   // E* = E / (2 (1 - nu^2)) for equal materials, Pa
  double restitution = 0.5;        // e in (0, 1]; 1 means no normal damping
  double friction = 0.5;           // Coulomb coefficient mu
  double tangentialDamping = 1.0;  // c_t / sqrt(m* S_n): stiffness of the sticking regime
};

// One sphere as the contact law sees it.
struct ContactBody {
  dem::Vec3 position;
  dem::Vec3 velocity;
  dem::Vec3 angularVelocity;
  double radius = 1.0;
  double mass = 1.0;
};

struct ContactForce {
  dem::Vec3 force;           // on the first body; the second gets -force
  dem::Vec3 torqueAxis;      // n x force: the torque on body k is radius_k * torqueAxis
  double normalForce = 0.0;  // repulsive magnitude, >= 0 (0 when not touching)
  double overlap = 0.0;      // r_i + r_j - |x_j - x_i|, > 0 when touching
};

// Returns zero force when the spheres do not overlap. The normal force is
//   F_n = 4/3 E* sqrt(R*) delta^(3/2) - gamma v_n,  clamped at >= 0,
//   gamma = -2 sqrt(5/6) beta sqrt(S_n m*),  S_n = 2 E* sqrt(R* delta),
//   beta = ln e / sqrt(ln^2 e + pi^2),
// with v_n the separation speed along n = (x_j - x_i) / |x_j - x_i|; the
// tangential force opposes the relative sliding velocity v_t of the contact
// point, |F_t| = min(mu F_n, c_t |v_t|), c_t = tangentialDamping sqrt(m* S_n).
ContactForce hertzContact(const ContactBody& first, const ContactBody& second,
                          const ContactParameters& parameters);

// The elastic force 4/3 E* sqrt(R*) delta^(3/2) alone, for tests and docs.
double hertzElasticForce(double overlap, double effectiveRadius, double effectiveModulus);

}  // namespace crackvis::sim
