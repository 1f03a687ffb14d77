// The second moment sum(w v v^T) of weighted vectors, and its principal
// axis: the mean direction of axial data (normals whose sign means nothing)
// or the direction of largest spread of offsets.
#pragma once

#include <cmath>

#include <crackvis/cracks/crack_components.hpp>

namespace crackvis::analysis {

class AxialTensor {
 public:
  void add(dem::Vec3 v, double weight) {
    const double c[3] = {v.x, v.y, v.z};
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) {
        m_sum[p][q] += weight * c[p] * c[q];
      }
    }
  }
  // Raises the z-z entry by `amount`: a 2D set's z then is no smallest axis.
  void addZ(double amount) { m_sum[2][2] += amount; }
  double trace() const { return m_sum[0][0] + m_sum[1][1] + m_sum[2][2]; }
  // v^T T v: the weighted second moment along a unit vector.
  double along(dem::Vec3 v) const {
    const double c[3] = {v.x, v.y, v.z};
    double sum = 0.0;
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) {
        sum += c[p] * m_sum[p][q] * c[q];
      }
    }
    return sum;
  }
  // The unit eigenvector of the smallest eigenvalue.
  dem::Vec3 smallestAxis() const { return cracks::smallestEigenvector(m_sum); }
  // The unit eigenvector of the largest eigenvalue; zero for an empty sum.
  dem::Vec3 principalAxis() const {
    const double trace = this->trace();
    if (!(trace > 0.0)) {
      return {};
    }
    cracks::Matrix3 shifted{};
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) {
        shifted[p][q] = (p == q ? trace : 0.0) - m_sum[p][q];
      }
    }
    return cracks::smallestEigenvector(shifted);
  }

 private:
  cracks::Matrix3 m_sum{};
};

}  // namespace crackvis::analysis
