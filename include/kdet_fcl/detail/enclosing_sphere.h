#pragma once
/// \file
/// Diameter of a triangle's minimum enclosing sphere: the size that orders triangles in kDet.

#include <cmath>

#include "kdet_fcl/detail/host_device.h"
#include "kdet_fcl/vec3.h"

namespace kdet_fcl {
namespace detail {

/// The diameter d of the smallest sphere containing triangle (a, b, c), evaluated in double.
/// - Right or obtuse triangles (and degenerate ones: collinear points, repeated vertices): the
///   longest edge, since the sphere on the longest edge as diameter contains the third vertex.
///   Using the circumcircle there would be wrong and unbounded for slivers.
/// - Acute triangles: the circumdiameter |ab||bc||ca| / |(b-a)x(c-a)|, clamped to
///   [L, 2L/sqrt(3)] (L = longest edge; an acute triangle's circumdiameter lies in that range) so
///   that rounding can never make it smaller than the triangle or blow it up.
/// The result only orders triangles and picks levels; any deterministic value with
/// box extent <= d (up to rounding) is correct.
template <class S>
KDET_HD_INLINE double enclosingDiameter(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c) {
  const Vec3<double> A{double(a.x), double(a.y), double(a.z)};
  const Vec3<double> B{double(b.x), double(b.y), double(b.z)};
  const Vec3<double> C{double(c.x), double(c.y), double(c.z)};
  const Vec3<double> ab = B - A, bc = C - B, ca = A - C;
  const double lab = squaredNorm(ab), lbc = squaredNorm(bc), lca = squaredNorm(ca);
  // Angle at A is >= 90 degrees iff (B-A).(C-A) <= 0; then the opposite edge bc is longest.
  if (dot(ab, ca) >= 0) return ::sqrt(lbc);  // (B-A).(A-C) >= 0  <=>  (B-A).(C-A) <= 0
  if (dot(bc, ab) >= 0) return ::sqrt(lca);  // angle at B
  if (dot(ca, bc) >= 0) return ::sqrt(lab);  // angle at C
  const double longest = ::sqrt(lab > lbc ? (lab > lca ? lab : lca) : (lbc > lca ? lbc : lca));
  const double area2 = ::sqrt(squaredNorm(cross(ab, C - A)));
  double d = area2 > 0 ? ::sqrt(lab) * ::sqrt(lbc) * ::sqrt(lca) / area2 : longest;
  const double upper = longest * 1.1547005383792517;  // 2/sqrt(3), the equilateral case
  if (!(d >= longest)) d = longest;
  if (d > upper) d = upper;
  return d;
}

}  // namespace detail
}  // namespace kdet_fcl
