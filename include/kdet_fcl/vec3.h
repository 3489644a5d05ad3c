#pragma once
/// \file
/// A minimal 3-vector and rigid transform, usable on the host and on the device.

#include <cmath>

#include "kdet_fcl/detail/host_device.h"

namespace kdet_fcl {

/// A point or direction in 3D. Plain aggregate so meshes can be copied to the device as bytes.
template <class S>
struct Vec3 {
  S x, y, z;

  KDET_HD_INLINE S operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  KDET_HD_INLINE S& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  KDET_HD_INLINE Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  KDET_HD_INLINE Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  KDET_HD_INLINE Vec3 operator*(S s) const { return {x * s, y * s, z * s}; }
  KDET_HD_INLINE bool operator==(const Vec3& o) const { return x == o.x && y == o.y && z == o.z; }
  KDET_HD_INLINE bool operator!=(const Vec3& o) const { return !(*this == o); }
};

template <class S>
KDET_HD_INLINE S dot(const Vec3<S>& a, const Vec3<S>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

template <class S>
KDET_HD_INLINE Vec3<S> cross(const Vec3<S>& a, const Vec3<S>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

template <class S>
KDET_HD_INLINE S squaredNorm(const Vec3<S>& a) {
  return dot(a, a);
}

/// A rigid pose: p_world = R * p_local + t. R is row-major.
/// setPose() in HashedMesh rejects non-finite entries and R that is not orthonormal within
/// HashedMesh::orthonormalTolerance().
template <class S>
struct Transform {
  S R[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3<S> t = {0, 0, 0};

  /// The identity pose.
  static Transform identity() { return Transform(); }

  /// R * p + t, evaluated in a fixed order (the CPU and the GPU must round identically).
  KDET_HD_INLINE Vec3<S> apply(const Vec3<S>& p) const {
    return {R[0][0] * p.x + R[0][1] * p.y + R[0][2] * p.z + t.x,
            R[1][0] * p.x + R[1][1] * p.y + R[1][2] * p.z + t.y,
            R[2][0] * p.x + R[2][1] * p.y + R[2][2] * p.z + t.z};
  }

  /// Whether R is exactly the identity and t exactly zero.
  KDET_HD_INLINE bool isIdentity() const {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (R[i][j] != S(i == j ? 1 : 0)) return false;
    return t.x == 0 && t.y == 0 && t.z == 0;
  }
};

/// A rotation about a unit axis by `angle` radians, plus a translation (handy for tests/scenes).
template <class S>
Transform<S> makeTransform(const Vec3<S>& axis, S angle, const Vec3<S>& translation) {
  Transform<S> T;
  const double n = std::sqrt(double(axis.x) * axis.x + double(axis.y) * axis.y +
                             double(axis.z) * axis.z);
  const double x = n > 0 ? axis.x / n : 1, y = n > 0 ? axis.y / n : 0, z = n > 0 ? axis.z / n : 0;
  const double c = std::cos(double(angle)), s = std::sin(double(angle)), C = 1 - c;
  const double m[3][3] = {{x * x * C + c, x * y * C - z * s, x * z * C + y * s},
                          {y * x * C + z * s, y * y * C + c, y * z * C - x * s},
                          {z * x * C - y * s, z * y * C + x * s, z * z * C + c}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) T.R[i][j] = S(m[i][j]);
  T.t = translation;
  return T;
}

}  // namespace kdet_fcl
