#pragma once
/// \file
/// Squared Euclidean distance between two closed triangles, evaluated in double precision (not
/// exact), usable on the host and on the device. The k-free analysis of the kDet paper uses it to
/// ask whether another triangle comes within distance d/4 of a given one.
///
/// Intersection is decided exactly first (trianglesIntersect), so touching or overlapping triangles
/// get exactly 0. Otherwise the minimum is attained at a vertex of one triangle against the other
/// triangle, or between two edges, so it is the minimum of 6 point-triangle and 9 segment-segment
/// distances. Every sub-routine evaluates the distance between two actual points of the two sets
/// (or a clamped projection), so the error of the distance is an absolute one of a few ulps of the
/// triangles' extent (coordinates are first taken relative to p0, plus one rounding of each
/// coordinate difference), also for degenerate (segment- or point-like) triangles. It is not a
/// relative error: two triangles 1e-15 apart may come out as 0 or 1e-14 apart; only intersection
/// (distance exactly 0) is decided exactly. Host and device results may differ in the last bits
/// when nvcc contracts into fma (--fmad=true, its default).

#include "kdet_fcl/detail/host_device.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "kdet_fcl/vec3.h"

namespace kdet_fcl {
namespace detail {
namespace tri_dist {

/// min of two doubles (no <algorithm> on the device).
KDET_HD_INLINE double minD(double a, double b) { return b < a ? b : a; }

/// Clamps t to [0, 1].
KDET_HD_INLINE double clamp01(double t) { return t < 0 ? 0 : (t > 1 ? 1 : t); }

/// Squared distance from p to the closed segment [a, b]; a zero-length segment is the point a.
KDET_HD_INLINE double pointSegmentDistanceSquared(const Vec3<double>& p, const Vec3<double>& a,
                                                  const Vec3<double>& b) {
  const Vec3<double> ab = b - a;
  const double len2 = dot(ab, ab);
  double t = 0;
  if (len2 > 0) t = clamp01(dot(p - a, ab) / len2);
  // Evaluate the distance to the actual closest point; at the endpoints use the endpoint itself so
  // that a vertex-to-vertex distance carries no rounding from a + t * ab.
  const Vec3<double> c = t <= 0 ? a : (t >= 1 ? b : a + ab * t);
  const Vec3<double> d = p - c;
  return dot(d, d);
}

/// Squared distance from p to the closed triangle (a, b, c). If the triangle is (nearly) degenerate
/// its edges are used instead: the triangle is then (within rounding) the union of its edges.
KDET_HD_INLINE double pointTriangleDistanceSquared(const Vec3<double>& p, const Vec3<double>& a,
                                                   const Vec3<double>& b, const Vec3<double>& c) {
  const double edges = minD(pointSegmentDistanceSquared(p, a, b),
                            minD(pointSegmentDistanceSquared(p, b, c),
                                 pointSegmentDistanceSquared(p, c, a)));
  const Vec3<double> e0 = b - a, e1 = c - a;
  const Vec3<double> n = cross(e0, e1);
  const double nn = dot(n, n);
  // |n|^2 = |e0|^2 |e1|^2 sin^2(angle); below a relative 1e-24 (angle ~1e-12) the plane is not
  // well determined by the rounded normal, and the edge distances are then the answer anyway.
  if (!(nn > 1e-24 * dot(e0, e0) * dot(e1, e1))) return edges;
  // The projection of p onto the plane is inside iff p lies on the inner side of the three edge
  // planes (each spanned by an edge and n).
  const bool inside = dot(cross(b - a, p - a), n) >= 0 && dot(cross(c - b, p - b), n) >= 0 &&
                      dot(cross(a - c, p - c), n) >= 0;
  if (!inside) return edges;
  const double h = dot(p - a, n);
  // Inside, the plane distance is the answer; min() guards against rounding in the inside test.
  return minD(h * h / nn, edges);
}

/// Squared distance between the closed segments [p0, p1] and [q0, q1]; zero-length and parallel
/// segments are handled. The minimum is either attained with an endpoint of one segment (the four
/// point-segment distances) or at an interior pair where the connecting vector is perpendicular
/// to both (only for non-parallel segments; solved from the 2x2 normal equations).
KDET_HD_INLINE double segmentSegmentDistanceSquared(const Vec3<double>& p0, const Vec3<double>& p1,
                                                    const Vec3<double>& q0,
                                                    const Vec3<double>& q1) {
  double best = minD(minD(pointSegmentDistanceSquared(p0, q0, q1),
                          pointSegmentDistanceSquared(p1, q0, q1)),
                     minD(pointSegmentDistanceSquared(q0, p0, p1),
                          pointSegmentDistanceSquared(q1, p0, p1)));
  const Vec3<double> d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = dot(d1, d1), e = dot(d2, d2);
  if (a > 0 && e > 0) {
    const double b = dot(d1, d2), c = dot(d1, r), f = dot(d2, r);
    const double denom = a * e - b * b;  // = |d1 x d2|^2 >= 0 in exact arithmetic
    // Skip (nearly) parallel pairs: for them an endpoint attains the minimum, and the solution of
    // the normal equations would be dominated by rounding.
    if (denom > 1e-24 * a * e) {
      const double s = (b * f - c * e) / denom;
      const double t = (a * f - b * c) / denom;
      if (s > 0 && s < 1 && t > 0 && t < 1) {
        const Vec3<double> x = p0 + d1 * s, y = q0 + d2 * t;
        const Vec3<double> d = x - y;
        best = minD(best, dot(d, d));
      }
    }
  }
  return best;
}

}  // namespace tri_dist

/// Squared Euclidean distance between the closed triangles (p0, p1, p2) and (q0, q1, q2), in
/// double precision: exactly 0 when they intersect (decided exactly by trianglesIntersect),
/// otherwise the minimum over the 6 vertex-triangle and 9 edge-edge distances. Degenerate
/// triangles (segments, points) are handled.
template <class S>
KDET_HD_INLINE double triangleDistanceSquared(const Vec3<S>& p0, const Vec3<S>& p1,
                                              const Vec3<S>& p2, const Vec3<S>& q0,
                                              const Vec3<S>& q1, const Vec3<S>& q2) {
  if (trianglesIntersect(p0, p1, p2, q0, q1, q2)) return 0.0;
  // Work relative to p0: for meshes far from the origin (say at 1e7) the rounding error of every
  // product then scales with the triangles' size and separation instead of with |p0|, and the one
  // rounding per coordinate spent here is the only error tied to the absolute position.
  const Vec3<double> o = toDouble(p0);
  const Vec3<double> P[3] = {Vec3<double>{0, 0, 0}, toDouble(p1) - o, toDouble(p2) - o};
  const Vec3<double> Q[3] = {toDouble(q0) - o, toDouble(q1) - o, toDouble(q2) - o};
  double best = tri_dist::pointTriangleDistanceSquared(P[0], Q[0], Q[1], Q[2]);
  for (int i = 1; i < 3; ++i)
    best = tri_dist::minD(best, tri_dist::pointTriangleDistanceSquared(P[i], Q[0], Q[1], Q[2]));
  for (int i = 0; i < 3; ++i)
    best = tri_dist::minD(best, tri_dist::pointTriangleDistanceSquared(Q[i], P[0], P[1], P[2]));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      best = tri_dist::minD(best, tri_dist::segmentSegmentDistanceSquared(
                                      P[i], P[(i + 1) % 3], Q[j], Q[(j + 1) % 3]));
    }
  }
  return best;
}

}  // namespace detail
}  // namespace kdet_fcl
