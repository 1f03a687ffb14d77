// A point or vector in 3D, as every part of crackvis writes it: the data
// model, the crack methods and the pipeline descriptions' cameras and clip
// planes. Here, apart from the data model (crackvis/dem/model.hpp), so that
// the thin client can name a camera without building HDF5.
#pragma once

#include <cmath>

namespace crackvis::dem {

struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;

  friend bool operator==(const Vec3&, const Vec3&) = default;
};
static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must map onto float64[N,3] rows");

inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator*(double s, Vec3 a) {
  return {s * a.x, s * a.y, s * a.z};
}
inline double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline double norm(Vec3 a) {
  return std::sqrt(dot(a, a));
}
inline double component(Vec3 p, int axis) {
  return axis == 0 ? p.x : (axis == 1 ? p.y : p.z);
}

}  // namespace crackvis::dem
