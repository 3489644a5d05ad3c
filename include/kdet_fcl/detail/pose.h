#pragma once
/// \file
/// The one way a query maps the first mesh into the second mesh's frame. Every backend and the
/// brute-force reference use it, so they decide pairs on bit-identical coordinates.

#include <cmath>

#include "kdet_fcl/detail/host_device.h"
#include "kdet_fcl/vec3.h"

namespace kdet_fcl {
namespace detail {

/// The relative pose of mesh A in mesh B's frame, evaluated in double:
/// a_to_b = pose_b^-1 * pose_a (with R^-1 = R^T), and its inverse b_to_a.
struct RelativePose {
  Transform<double> a_to_b;
  Transform<double> b_to_a;
  bool identity = true;          ///< a_to_b is exactly the identity: no mapping needed
  double orthonormal_defect = 0; ///< max |(R^T R - I)_ij| of a_to_b.R
};

template <class S>
inline Transform<double> toDouble(const Transform<S>& t) {
  Transform<double> d;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d.R[i][j] = double(t.R[i][j]);
  d.t = {double(t.t.x), double(t.t.y), double(t.t.z)};
  return d;
}

/// R^T and -R^T t (the inverse of a rigid transform).
inline Transform<double> rigidInverse(const Transform<double>& t) {
  Transform<double> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.R[i][j] = t.R[j][i];
  for (int i = 0; i < 3; ++i)
    r.t[i] = -(r.R[i][0] * t.t.x + r.R[i][1] * t.t.y + r.R[i][2] * t.t.z);
  return r;
}

template <class S>
inline RelativePose relativePose(const Transform<S>& pose_a, const Transform<S>& pose_b) {
  RelativePose rp;
  const Transform<double> a = toDouble(pose_a);
  const Transform<double> b_inv = rigidInverse(toDouble(pose_b));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      rp.a_to_b.R[i][j] = b_inv.R[i][0] * a.R[0][j] + b_inv.R[i][1] * a.R[1][j] +
                          b_inv.R[i][2] * a.R[2][j];
    rp.a_to_b.t[i] = b_inv.R[i][0] * a.t.x + b_inv.R[i][1] * a.t.y + b_inv.R[i][2] * a.t.z +
                     b_inv.t[i];
  }
  rp.b_to_a = rigidInverse(rp.a_to_b);
  rp.identity = rp.a_to_b.isIdentity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += rp.a_to_b.R[k][i] * rp.a_to_b.R[k][j];
      rp.orthonormal_defect = std::fmax(rp.orthonormal_defect, std::fabs(s - (i == j ? 1.0 : 0.0)));
    }
  return rp;
}

/// A point of mesh A in B's frame: mapped in double, rounded once to S.
template <class S>
KDET_HD_INLINE Vec3<S> mapPoint(const Transform<double>& t, const Vec3<S>& p) {
  const Vec3<double> q = t.apply(Vec3<double>{double(p.x), double(p.y), double(p.z)});
  return {S(q.x), S(q.y), S(q.z)};
}

}  // namespace detail
}  // namespace kdet_fcl
