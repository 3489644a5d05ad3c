#pragma once
/// \file
/// Axis-aligned boxes: the cheap filter in front of the exact triangle test.

#include "kdet_fcl/detail/host_device.h"
#include "kdet_fcl/vec3.h"

namespace kdet_fcl {
namespace detail {

/// A closed axis-aligned box [lo, hi].
template <class S>
struct Aabb {
  Vec3<S> lo, hi;
};

template <class S>
KDET_HD_INLINE S minOf3(S a, S b, S c) {
  S m = a < b ? a : b;
  return m < c ? m : c;
}
template <class S>
KDET_HD_INLINE S maxOf3(S a, S b, S c) {
  S m = a > b ? a : b;
  return m > c ? m : c;
}

/// The tight box of a triangle (min/max are exact, so two triangles that share a point always
/// have overlapping boxes).
template <class T, class S>
KDET_HD_INLINE Aabb<T> triangleBox(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c) {
  return {{T(minOf3(a.x, b.x, c.x)), T(minOf3(a.y, b.y, c.y)), T(minOf3(a.z, b.z, c.z))},
          {T(maxOf3(a.x, b.x, c.x)), T(maxOf3(a.y, b.y, c.y)), T(maxOf3(a.z, b.z, c.z))}};
}

/// Closed overlap: boxes that only touch overlap (touching triangles must reach the exact test).
template <class S, class T>
KDET_HD_INLINE bool boxesOverlap(const Aabb<S>& p, const Aabb<T>& q) {
  return p.lo.x <= q.hi.x && q.lo.x <= p.hi.x && p.lo.y <= q.hi.y && q.lo.y <= p.hi.y &&
         p.lo.z <= q.hi.z && q.lo.z <= p.hi.z;
}

/// The box grown by r on every side.
KDET_HD_INLINE Aabb<double> inflate(const Aabb<double>& b, double r) {
  return {{b.lo.x - r, b.lo.y - r, b.lo.z - r}, {b.hi.x + r, b.hi.y + r, b.hi.z + r}};
}

/// The intersection of two boxes (may be empty: lo > hi on some axis).
KDET_HD_INLINE Aabb<double> intersectBoxes(const Aabb<double>& p, const Aabb<double>& q) {
  return {{p.lo.x > q.lo.x ? p.lo.x : q.lo.x, p.lo.y > q.lo.y ? p.lo.y : q.lo.y,
           p.lo.z > q.lo.z ? p.lo.z : q.lo.z},
          {p.hi.x < q.hi.x ? p.hi.x : q.hi.x, p.hi.y < q.hi.y ? p.hi.y : q.hi.y,
           p.hi.z < q.hi.z ? p.hi.z : q.hi.z}};
}

KDET_HD_INLINE bool isEmpty(const Aabb<double>& b) {
  return !(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z);
}

}  // namespace detail
}  // namespace kdet_fcl
