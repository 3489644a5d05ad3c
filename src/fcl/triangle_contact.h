#pragma once
/// \file
/// Contact values for one intersecting triangle pair (the FCL adapter's enable_contact output):
/// a point of the intersection, a unit normal and a local penetration depth, all finite for every
/// input, degenerate and coplanar pairs included. Plain double arithmetic with a relative
/// tolerance: this is reporting, not deciding (the decision is trianglesIntersect's).

#include <cmath>

#include "kdet_fcl/vec3.h"

namespace kdet_fcl {
namespace detail {

/// Contact values of a triangle pair, in the frame of the input coordinates.
struct TriangleContact {
  Vec3<double> pos;     ///< a point on (within rounding of) both triangles
  Vec3<double> normal;  ///< unit; see triangleContact()
  double depth = 0;     ///< >= 0; see triangleContact()
};

namespace tri_contact {

inline double norm(const Vec3<double>& v) { return std::sqrt(dot(v, v)); }

/// Appends to `sum`/`count` the end points of the part of segment [a, b] that lies on the closed
/// triangle T (within `tol`, a length), if any. T must be non-degenerate with unit normal u.
inline void clipSegment(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double> T[3],
                        const Vec3<double>& u, double tol, Vec3<double>& sum, int& count) {
  const double da = dot(u, a - T[0]), db = dot(u, b - T[0]);
  double lo = 0, hi = 1;
  if (std::fabs(da) <= tol && std::fabs(db) <= tol) {
    // In T's plane: clip by the three edge half-planes below.
  } else if ((da > tol && db > tol) || (da < -tol && db < -tol) || da == db) {
    return;
  } else {
    double t = da / (da - db);
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    lo = hi = t;
  }
  for (int k = 0; k < 3; ++k) {
    const Vec3<double> e0 = T[k], e1 = T[(k + 1) % 3];
    Vec3<double> m = cross(u, e1 - e0);  // points into T (T is counter-clockwise about u)
    const double mn = norm(m);
    if (!(mn > 0)) return;
    m = m * (1.0 / mn);
    const double ga = dot(m, a - e0), gb = dot(m, b - e0);  // g(t) = ga + t (gb - ga) >= -tol
    const double slope = gb - ga;
    if (slope == 0) {
      if (ga < -tol) return;
      continue;
    }
    const double t = (-tol - ga) / slope;
    if (slope > 0) {
      if (t > lo) lo = t;
    } else if (t < hi) {
      hi = t;
    }
    if (lo > hi) return;
  }
  sum = sum + (a + (b - a) * lo) + (a + (b - a) * hi);
  count += 2;
}

/// Closest points of segment [p0, p1] and segment [q0, q1] (either may be a point).
inline void closestSegmentSegment(const Vec3<double>& p0, const Vec3<double>& p1,
                                  const Vec3<double>& q0, const Vec3<double>& q1,
                                  Vec3<double>& cp, Vec3<double>& cq) {
  const Vec3<double> d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
  double s = 0, t = 0;
  auto clamp01 = [](double x) { return x < 0 ? 0.0 : (x > 1 ? 1.0 : x); };
  if (a <= 0 && e <= 0) {
    s = t = 0;
  } else if (a <= 0) {
    t = clamp01(f / e);
  } else {
    const double c = dot(d1, r);
    if (e <= 0) {
      s = clamp01(-c / a);
    } else {
      const double b = dot(d1, d2), den = a * e - b * b;
      s = den > 0 ? clamp01((b * f - c * e) / den) : 0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = clamp01(-c / a);
      } else if (t > 1) {
        t = 1;
        s = clamp01((b - c) / a);
      }
    }
  }
  cp = p0 + d1 * s;
  cq = q0 + d2 * t;
}

/// Closest point of the (non-degenerate, unit normal u) triangle T to p, if p projects inside T.
inline bool projectsInside(const Vec3<double>& p, const Vec3<double> T[3], const Vec3<double>& u,
                           Vec3<double>& q) {
  for (int k = 0; k < 3; ++k)
    if (dot(cross(T[(k + 1) % 3] - T[k], p - T[k]), u) < 0) return false;
  q = p - u * dot(u, p - T[0]);
  return true;
}

/// Unit normal of T, or false when T is degenerate relative to the length scale L.
inline bool unitNormal(const Vec3<double> T[3], double L, Vec3<double>& u) {
  const Vec3<double> n = cross(T[1] - T[0], T[2] - T[0]);
  const double nn = norm(n);
  if (!(nn > 1e-12 * L * L) || !std::isfinite(nn)) return false;
  u = n * (1.0 / nn);
  return true;
}

}  // namespace tri_contact

/// Contact values of the triangles P (of the first object) and Q (of the second), meant for pairs
/// that intersect (touching included):
///  - pos: the mean of the end points of the edge-against-triangle clips (the vertices of the
///    intersection segment or, for coplanar pairs, of the overlap polygon), so a point of the
///    intersection; when rounding leaves no clip (touching pairs, degenerate triangles), the
///    midpoint of the closest points of the two triangles.
///  - normal: -(unit normal of Q by its winding), i.e. from the first object into the second for
///    outward-wound (counter-clockwise seen from outside) meshes; if Q is degenerate, P's unit
///    normal; if both are, the unit direction between their centroids; else (0, 0, 1).
///  - depth: how far the deepest vertex of P lies behind Q's plane along `normal` (for the P-normal
///    fallback: the deepest vertex of Q behind P's plane), clamped at 0; 0 for the other fallbacks.
///    A local per-pair measure like FCL's, not the objects' penetration depth.
inline TriangleContact triangleContact(const Vec3<double> P0[3], const Vec3<double> Q0[3]) {
  using namespace tri_contact;
  // Relative to P's first vertex, so far-from-origin meshes lose nothing to the absolute position.
  const Vec3<double> o = P0[0];
  const Vec3<double> P[3] = {P0[0] - o, P0[1] - o, P0[2] - o};
  const Vec3<double> Q[3] = {Q0[0] - o, Q0[1] - o, Q0[2] - o};
  double L = 0;
  for (int k = 0; k < 3; ++k) {
    L = std::fmax(L, norm(P[k] - P[(k + 1) % 3]));
    L = std::fmax(L, norm(Q[k] - Q[(k + 1) % 3]));
    L = std::fmax(L, norm(Q[k]));
  }
  const double tol = 1e-9 * L;

  Vec3<double> up{0, 0, 1}, uq{0, 0, 1};
  const bool p_ok = L > 0 && unitNormal(P, L, up);
  const bool q_ok = L > 0 && unitNormal(Q, L, uq);

  TriangleContact c;
  Vec3<double> sum{0, 0, 0};
  int count = 0;
  if (q_ok)
    for (int k = 0; k < 3; ++k) clipSegment(P[k], P[(k + 1) % 3], Q, uq, tol, sum, count);
  if (p_ok)
    for (int k = 0; k < 3; ++k) clipSegment(Q[k], Q[(k + 1) % 3], P, up, tol, sum, count);
  if (count > 0) {
    c.pos = sum * (1.0 / count);
  } else {
    // Closest points: vertex against triangle interior, and edge against edge.
    double best = INFINITY;
    Vec3<double> bp = P[0], bq = Q[0];
    auto consider = [&](const Vec3<double>& a, const Vec3<double>& b) {
      const double d = dot(a - b, a - b);
      if (d < best) best = d, bp = a, bq = b;
    };
    Vec3<double> x;
    for (int k = 0; k < 3; ++k) {
      if (q_ok && projectsInside(P[k], Q, uq, x)) consider(P[k], x);
      if (p_ok && projectsInside(Q[k], P, up, x)) consider(x, Q[k]);
      for (int l = 0; l < 3; ++l) {
        Vec3<double> cp, cq;
        closestSegmentSegment(P[k], P[(k + 1) % 3], Q[l], Q[(l + 1) % 3], cp, cq);
        consider(cp, cq);
      }
    }
    c.pos = (bp + bq) * 0.5;
  }

  if (q_ok) {
    c.normal = uq * -1.0;
    for (int k = 0; k < 3; ++k) c.depth = std::fmax(c.depth, dot(P[k] - Q[0], c.normal));
  } else if (p_ok) {
    c.normal = up;
    for (int k = 0; k < 3; ++k) c.depth = std::fmax(c.depth, dot(P[0] - Q[k], c.normal));
  } else {
    const Vec3<double> d = (Q[0] + Q[1] + Q[2] - P[0] - P[1] - P[2]) * (1.0 / 3);
    const double dn = norm(d);
    c.normal = (dn > 0 && std::isfinite(dn)) ? d * (1.0 / dn) : Vec3<double>{0, 0, 1};
  }
  c.pos = c.pos + o;
  if (!std::isfinite(c.pos.x) || !std::isfinite(c.pos.y) || !std::isfinite(c.pos.z)) c.pos = P0[0];
  if (!std::isfinite(c.depth)) c.depth = 0;
  return c;
}

}  // namespace detail
}  // namespace kdet_fcl
