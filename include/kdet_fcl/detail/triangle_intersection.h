#pragma once
/// \file
/// The exact closed triangle-triangle intersection test, usable on the host and on the device.
///
/// trianglesIntersect() answers whether two CLOSED triangles share at least one point, decided
/// exactly on the given float/double coordinates: every decision is the sign of an exact
/// orientation predicate (exact_predicates.h) or an exact coordinate comparison, so touching at a
/// vertex, along an edge, and coplanar overlap are all reported as intersections (FCL's
/// semantics), and the CPU and the GPU always agree. Degenerate triangles are valid input: three
/// collinear points form the segment between the two extreme points, three equal points a point.
///
/// The answer is exact inside the validity range of the predicates (coordinates zero or of
/// magnitude in [2^-247, 2^330]; every float qualifies).
///
/// Device code note: most helpers are KDET_HD_INLINE (__forceinline__ under nvcc). The few that
/// are called at many sites with large bodies (segmentTriangleSigns, segmentsIntersectProj,
/// pointInTriangleProj, segmentSegment) are KDET_FCL_HD_NOINLINE (plain `inline` on the host,
/// __noinline__ on the device): force-inlining them made one trianglesIntersect call use 255
/// registers with spills on sm_90; out of line it needs under 100 and compiles in about a second.

#include "kdet_fcl/detail/exact_predicates.h"
#include "kdet_fcl/detail/host_device.h"
#include "kdet_fcl/predicate.h"
#include "kdet_fcl/vec3.h"

namespace kdet_fcl {
namespace detail {
namespace tri_isect {

/// The shape a closed triangle actually is once its degeneracies are resolved.
enum class Kind { Point, Segment, Proper };

/// A classified triangle. For Proper: v[0..2] are the vertices and `axis` is a coordinate (0, 1, 2)
/// whose projection (dropping that coordinate) keeps the triangle non-degenerate, hence maps its
/// plane one-to-one onto the coordinate plane. For Segment: v[0], v[1] are the endpoints (distinct).
/// For Point: v[0].
struct Shape {
  Kind kind;
  int axis;
  Vec3<double> v[3];
};

/// The coordinate of p kept first when dropping `axis` (cyclic order keeps orientations consistent
/// within one projection; consistency across projections is not needed).
KDET_HD_INLINE double projU(const Vec3<double>& p, int axis) {
  return axis == 0 ? p.y : (axis == 1 ? p.z : p.x);
}

/// The coordinate of p kept second when dropping `axis`.
KDET_HD_INLINE double projV(const Vec3<double>& p, int axis) {
  return axis == 0 ? p.z : (axis == 1 ? p.x : p.y);
}

/// Exact orientation of a, b, c projected by dropping coordinate `axis`. Its value is (up to sign
/// convention) the `axis` component of cross(b-a, c-a), so all three are zero iff a, b, c are
/// collinear.
template <class K>
KDET_HD_INLINE int orient2dProj(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c,
                                int axis) {
  return K::orient2d(projU(a, axis), projV(a, axis), projU(b, axis), projV(b, axis),
                      projU(c, axis), projV(c, axis));
}

/// Whether a, b, c are exactly collinear (all three coordinate projections have zero area). When
/// not, `axis` receives a coordinate whose projection keeps them non-collinear.
template <class K>
KDET_HD_INLINE bool collinear(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c,
                              int& axis) {
  for (int k = 0; k < 3; ++k) {
    if (orient2dProj<K>(a, b, c, k) != 0) {
      axis = k;
      return false;
    }
  }
  return true;
}

/// A coordinate along which a and b differ (a != b required; returns 0 otherwise). Along a line
/// through a and b, that coordinate is a strictly monotone function of the position, so comparisons
/// of it order points on the line exactly.
KDET_HD_INLINE int differingAxis(const Vec3<double>& a, const Vec3<double>& b) {
  if (a.x != b.x) return 0;
  if (a.y != b.y) return 1;
  if (a.z != b.z) return 2;
  return 0;
}

/// Whether value t lies in the closed interval spanned by a and b (in either order).
KDET_HD_INLINE bool between(double a, double b, double t) {
  return a <= b ? (a <= t && t <= b) : (b <= t && t <= a);
}

/// Resolves the degeneracies of the closed triangle (a, b, c).
template <class K>
KDET_HD_INLINE Shape classify(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c) {
  Shape s;
  s.axis = 0;
  s.v[0] = a;
  s.v[1] = b;
  s.v[2] = c;
  int axis = 0;
  if (!collinear<K>(a, b, c, axis)) {
    s.kind = Kind::Proper;
    s.axis = axis;
    return s;
  }
  if (a == b && b == c) {
    s.kind = Kind::Point;
    return s;
  }
  // Collinear and not all equal: find a coordinate in which the points are not all equal; along the
  // common line it orders them, so the extreme points are the endpoints of the segment.
  int k = differingAxis(a, b);
  if (a == b) k = differingAxis(a, c);
  const Vec3<double>* lo = &a;
  const Vec3<double>* hi = &a;
  const Vec3<double>* pts[3] = {&a, &b, &c};
  for (int i = 1; i < 3; ++i) {
    if ((*pts[i])[k] < (*lo)[k]) lo = pts[i];
    if ((*pts[i])[k] > (*hi)[k]) hi = pts[i];
  }
  s.kind = Kind::Segment;
  s.v[0] = *lo;
  s.v[1] = *hi;
  return s;
}

/// Whether p lies on the closed segment [s0, s1] (s0 != s1): exactly collinear and between the
/// endpoints along a coordinate in which they differ.
template <class K>
KDET_HD_INLINE bool pointOnSegment(const Vec3<double>& p, const Vec3<double>& s0,
                                   const Vec3<double>& s1) {
  int unused = 0;
  if (!collinear<K>(s0, s1, p, unused)) return false;
  const int k = differingAxis(s0, s1);
  return between(s0[k], s1[k], p[k]);
}

/// Closed 2D segment intersection in the projection dropping `axis`; both segments must project
/// to non-degenerate segments (true when they are non-degenerate and lie in a plane that projects
/// one-to-one). Uses the 3D coordinates only through exact projections and comparisons.
template <class K>
KDET_FCL_HD_NOINLINE bool segmentsIntersectProj(const Vec3<double>& p0, const Vec3<double>& p1,
                                          const Vec3<double>& q0, const Vec3<double>& q1,
                                          int axis) {
  const int d1 = orient2dProj<K>(p0, p1, q0, axis);
  const int d2 = orient2dProj<K>(p0, p1, q1, axis);
  if (d1 * d2 > 0) return false;  // q strictly on one side of line p
  const int d3 = orient2dProj<K>(q0, q1, p0, axis);
  const int d4 = orient2dProj<K>(q0, q1, p1, axis);
  if (d3 * d4 > 0) return false;  // p strictly on one side of line q
  if (d1 == 0 && d2 == 0) {
    // All four points on one line (d1 = d2 = 0 with q0 != q1 forces d3 = d4 = 0): the segments
    // meet iff their intervals along a coordinate that varies along the line overlap.
    const double pu0 = projU(p0, axis), pu1 = projU(p1, axis);
    const bool useU = pu0 != pu1;
    const double a0 = useU ? pu0 : projV(p0, axis), a1 = useU ? pu1 : projV(p1, axis);
    const double b0 = useU ? projU(q0, axis) : projV(q0, axis);
    const double b1 = useU ? projU(q1, axis) : projV(q1, axis);
    const double alo = a0 < a1 ? a0 : a1, ahi = a0 < a1 ? a1 : a0;
    const double blo = b0 < b1 ? b0 : b1, bhi = b0 < b1 ? b1 : b0;
    return alo <= bhi && blo <= ahi;
  }
  // The supporting lines are distinct and not parallel-disjoint, so they meet at one point X; each
  // segment reaches the other's line, which can only happen at X, so X lies on both.
  return true;
}

/// Whether p (in the plane of the proper triangle abc) lies in the closed triangle, decided in the
/// one-to-one projection dropping `axis`: no two edge orientations of strictly opposite sign.
template <class K>
KDET_FCL_HD_NOINLINE bool pointInTriangleProj(const Vec3<double>& p, const Vec3<double>& a,
                                        const Vec3<double>& b, const Vec3<double>& c, int axis) {
  const int s1 = orient2dProj<K>(a, b, p, axis);
  const int s2 = orient2dProj<K>(b, c, p, axis);
  const int s3 = orient2dProj<K>(c, a, p, axis);
  const bool hasPos = s1 > 0 || s2 > 0 || s3 > 0;
  const bool hasNeg = s1 < 0 || s2 < 0 || s3 < 0;
  return !(hasPos && hasNeg);
}

/// Point vs proper triangle: on the plane and inside in the one-to-one projection.
template <class K>
KDET_HD_INLINE bool pointTriangle(const Vec3<double>& p, const Shape& t) {
  if (K::orient3d(t.v[0], t.v[1], t.v[2], p) != 0) return false;
  return pointInTriangleProj<K>(p, t.v[0], t.v[1], t.v[2], t.axis);
}

/// Closed segment [p, q] (p != q) vs proper triangle t, with op = orient3d(t, p) and
/// oq = orient3d(t, q) already known (the caller often has them).
template <class K>
KDET_FCL_HD_NOINLINE bool segmentTriangleSigns(const Vec3<double>& p, const Vec3<double>& q,
                                         const Shape& t, int op, int oq) {
  if (op * oq > 0) return false;  // both endpoints strictly on one side of the plane
  const Vec3<double>& a = t.v[0];
  const Vec3<double>& b = t.v[1];
  const Vec3<double>& c = t.v[2];
  if (op == 0 && oq == 0) {
    // Coplanar: in the one-to-one projection, p inside or the segment meeting an edge. (If p is
    // outside, any point of the segment inside the triangle is reached by crossing its boundary.)
    if (pointInTriangleProj<K>(p, a, b, c, t.axis)) return true;
    return segmentsIntersectProj<K>(p, q, a, b, t.axis) || segmentsIntersectProj<K>(p, q, b, c, t.axis) ||
           segmentsIntersectProj<K>(p, q, c, a, t.axis);
  }
  // The line pq is transversal to the plane and meets it at one point X inside the closed segment.
  // X is in the closed triangle iff the line passes the three edges on a consistent side: the
  // signed volumes with the three edges are never of strictly opposite signs.
  const int s1 = K::orient3d(p, q, a, b);
  const int s2 = K::orient3d(p, q, b, c);
  const int s3 = K::orient3d(p, q, c, a);
  const bool hasPos = s1 > 0 || s2 > 0 || s3 > 0;
  const bool hasNeg = s1 < 0 || s2 < 0 || s3 < 0;
  return !(hasPos && hasNeg);
}

/// Closed segment [p, q] (p != q) vs proper triangle t.
template <class K>
KDET_HD_INLINE bool segmentTriangle(const Vec3<double>& p, const Vec3<double>& q, const Shape& t) {
  const int op = K::orient3d(t.v[0], t.v[1], t.v[2], p);
  const int oq = K::orient3d(t.v[0], t.v[1], t.v[2], q);
  return segmentTriangleSigns<K>(p, q, t, op, oq);
}

/// Closed segment vs closed segment, both non-degenerate.
template <class K>
KDET_FCL_HD_NOINLINE bool segmentSegment(const Vec3<double>& p0, const Vec3<double>& p1,
                                   const Vec3<double>& q0, const Vec3<double>& q1) {
  // Not coplanar: the segments cannot meet.
  if (K::orient3d(p0, p1, q0, q1) != 0) return false;
  // Coplanar: find a projection keeping (p0, p1, q0) or (p0, p1, q1) non-collinear; it maps the
  // common plane one-to-one, so the 2D test is exact for the 3D question.
  for (int k = 0; k < 3; ++k) {
    if (orient2dProj<K>(p0, p1, q0, k) != 0 || orient2dProj<K>(p0, p1, q1, k) != 0) {
      return segmentsIntersectProj<K>(p0, p1, q0, q1, k);
    }
  }
  // q0 and q1 both lie on the line p0p1: compare intervals along a coordinate varying on it.
  const int k = differingAxis(p0, p1);
  const double alo = p0[k] < p1[k] ? p0[k] : p1[k], ahi = p0[k] < p1[k] ? p1[k] : p0[k];
  const double blo = q0[k] < q1[k] ? q0[k] : q1[k], bhi = q0[k] < q1[k] ? q1[k] : q0[k];
  return alo <= bhi && blo <= ahi;
}

/// Two proper triangles in one plane (with exact signs: every orientation of either's vertices
/// against the other's plane zero), decided in the projection dropping P.axis. That projection
/// keeps P proper, so the common plane's normal has a non-zero component along the axis and the
/// projection maps the plane one-to-one: Q's projection is proper too, and every sign below is
/// the 3D configuration's. Two closed convex polygons are disjoint iff an edge line of one has
/// all vertices of the other strictly on its outer side: if they are disjoint, the origin lies
/// outside their Minkowski difference P - Q, a convex polygon, so strictly outside one of its
/// edges; that edge's outward normal n is the outward normal of an edge of P or of -Q, and
/// max over P of p.n < min over Q of q.n puts Q strictly beyond that edge of P (or P beyond the
/// edge of Q). The converse is plain. So at most 18 orient2d signs (each vertex of one against
/// each edge of the other), with a return at the first separating edge, where the edge-by-edge
/// tests of properProperSigns take up to 90 on a disjoint coplanar pair (segmentTriangleSigns'
/// coplanar branch, six times).
template <class K>
KDET_FCL_HD_NOINLINE bool coplanarProper(const Shape& P, const Shape& Q) {
  const int axis = P.axis;
  // The orientations of the projected triangles (non-zero: both are proper there); a vertex x is
  // strictly outside edge (a, b) of a triangle of orientation o iff orient2d(a, b, x) o < 0.
  const int op = orient2dProj<K>(P.v[0], P.v[1], P.v[2], axis);
  const int oq = orient2dProj<K>(Q.v[0], Q.v[1], Q.v[2], axis);
  for (int side = 0; side < 2; ++side) {
    const Shape& E = side == 0 ? P : Q;  // the edges'
    const Shape& X = side == 0 ? Q : P;  // the vertices'
    const int o = side == 0 ? op : oq;
    for (int i = 0; i < 3; ++i) {
      const Vec3<double>& a = E.v[i];
      const Vec3<double>& b = E.v[i == 2 ? 0 : i + 1];
      if (orient2dProj<K>(a, b, X.v[0], axis) * o < 0 &&
          orient2dProj<K>(a, b, X.v[1], axis) * o < 0 &&
          orient2dProj<K>(a, b, X.v[2], axis) * o < 0)
        return false;  // a separating edge
    }
  }
  return true;
}

/// Whether all three signs are equal and non-zero (three points strictly on one side of a plane).
KDET_HD_INLINE bool strictlyOneSide(const int s[3]) {
  return s[0] != 0 && s[0] == s[1] && s[1] == s[2];
}

/// Proper triangle vs proper triangle, given sp[i] = orient3d(Q, P.v[i]) and
/// sq[i] = orient3d(P, Q.v[i]), neither triple strictly one-sided.
template <class K>
KDET_HD_INLINE bool properProperSigns(const Shape& P, const Shape& Q, const int sp[3],
                                      const int sq[3]) {
  // The triangles meet iff some closed edge of one meets the other closed triangle. Non-coplanar:
  // both meet the line L of the two planes in closed intervals whose endpoints lie on their edges;
  // overlapping intervals contain an endpoint of one in the other. Coplanar: two convex polygons
  // that meet either have crossing edges or one contains a vertex (on an edge) of the other.
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (segmentTriangleSigns<K>(P.v[i], P.v[j], Q, sp[i], sp[j])) return true;
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (segmentTriangleSigns<K>(Q.v[i], Q.v[j], P, sq[i], sq[j])) return true;
  }
  return false;
}

/// Proper triangle vs proper triangle.
template <class K>
KDET_HD_INLINE bool properProper(const Shape& P, const Shape& Q) {
  // Signs of P's vertices against Q's plane, and of Q's vertices against P's plane.
  int sp[3], sq[3];
  K::orient3dSides(Q.v[0], Q.v[1], Q.v[2], P.v, sp);
  if (strictlyOneSide(sp)) return false;  // P strictly on one side
  K::orient3dSides(P.v[0], P.v[1], P.v[2], Q.v, sq);
  if (strictlyOneSide(sq)) return false;  // Q strictly on one side
  return properProperSigns<K>(P, Q, sp, sq);
}

/// For a triangle whose vertices have the orientations s[0..2] against the other triangle's plane
/// (not all zero, not all equal and non-zero): the vertex `first` that is alone on its side, and
/// whether the signs must be negated (the other plane reversed) so that it lies on the
/// non-negative side and the other two on the non-positive side. When another vertex is on the
/// plane, the lone vertex is a non-zero one; only a zero vertex with the other two strictly on
/// one side is the lone vertex itself. Then the triangle meets the plane in the closed segment
/// between its edges (first, first+1) and (first, first+2) (a point when the lone vertex is on it).
KDET_HD_INLINE void loneVertex(const int s[3], int& first, bool& negate) {
  int pos = 0, neg = 0;
  for (int i = 0; i < 3; ++i) {
    pos += s[i] > 0;
    neg += s[i] < 0;
  }
  first = 0;
  negate = false;
  for (int i = 0; i < 3; ++i)
    if (pos == 1 && s[i] > 0) {  // the others are <= 0
      first = i;
      return;
    }
  for (int i = 0; i < 3; ++i)
    if (neg == 1 && s[i] < 0) {  // the others are >= 0
      first = i;
      negate = true;
      return;
    }
  for (int i = 0; i < 3; ++i)
    if (s[i] == 0) {  // the other two share a sign
      first = i;
      negate = pos > 0;
      return;
    }
}

/// Two proper triangles in different planes, neither strictly on one side of the other's plane,
/// given sp[i] = orient3d(Q, P[i]) and sq[i] = orient3d(P, Q[i]) (not all zero: the planes
/// differ). Each triangle meets the line L common to both planes in a closed segment; they meet iff
/// the two segments overlap. With each triangle's lone vertex first and the planes oriented so that
/// it lies on the non-negative side of the other's (loneVertex), the overlap is two orientation
/// signs (Guigue and Devillers, "Fast and robust triangle-triangle overlap test using orientation
/// predicates", J. Graphics Tools 8(1), 2003): the segments overlap iff neither ends before the
/// other begins along L. Two more predicates instead of the up to eighteen of the edge-by-edge
/// tests of properProperSigns. transversalOrder picks the vertices a, b, c of P and d, e, f of Q
/// by their indices, x[0..5]: the triangles meet iff orient3d(b, d, a, e) <= 0 and
/// orient3d(a, d, c, f) <= 0.
KDET_HD_INLINE void transversalOrder(const int sp[3], const int sq[3], int x[6]) {
  int fp = 0, fq = 0;
  bool np = false, nq = false;
  loneVertex(sp, fp, np);
  // Q's vertices, their order reversed (its plane flipped) when P's signs must be negated.
  int q[3] = {0, 1, 2};
  if (np) q[1] = 2, q[2] = 1;
  const int s2[3] = {sq[q[0]], sq[q[1]], sq[q[2]]};
  loneVertex(s2, fq, nq);
  x[0] = fp;
  x[1] = (fp + (nq ? 2 : 1)) % 3;  // P reversed when Q's signs must be negated
  x[2] = (fp + (nq ? 1 : 2)) % 3;
  x[3] = q[fq];
  x[4] = q[(fq + 1) % 3];
  x[5] = q[(fq + 2) % 3];
}

/// The lone vertex of a triangle whose three orientation signs against the other's plane are all
/// non-zero and not all equal (loneVertex's `first` for such signs, in closed form): the one whose
/// sign differs from the other two's.
KDET_HD_INLINE int loneOfNonZero(const int s[3]) {
  return s[0] == s[1] ? 2 : (s[0] == s[2] ? 1 : 0);
}

/// Whether loneVertex negates such signs (all non-zero, not all equal): where the lone vertex is
/// negative, i.e. the other two, the majority, are positive; their sum has the majority's sign.
KDET_HD_INLINE bool negateOfNonZero(const int s[3]) { return s[0] + s[1] + s[2] > 0; }

/// The triangle (t0, t1, t2) from vertex `first` on: a = t_first, and (b, c) = (t_first+1,
/// t_first+2) (indices mod 3), swapped when `reverse`. By selection on named values, with no array
/// indexed: on the device the general transversalOrder's indexed arrays became long chains of
/// predicated moves (benchmarks/RESULTS-gpu.md, the plane filter's SASS).
template <class T>
KDET_HD_INLINE void fromVertex(const T& t0, const T& t1, const T& t2, int first, bool reverse,
                               T& a, T& b, T& c) {
  const bool f0 = first == 0, f1 = first == 1;
  a = f0 ? t0 : (f1 ? t1 : t2);
  const T n1 = f0 ? t1 : (f1 ? t2 : t0);
  const T n2 = f0 ? t2 : (f1 ? t0 : t1);
  b = reverse ? n2 : n1;
  c = reverse ? n1 : n2;
}

/// transversalOrder for six non-zero signs (neither triangle strictly on one side): the same
/// vertices a, b, c of P = (p0, p1, p2) and d, e, f of Q = (q0, q1, q2), picked by fromVertex.
/// With all signs non-zero, P's lone vertex comes first and is reversed when Q's signs are negated;
/// Q's order reversed when P's signs are negated (transversalOrder's q) leaves its lone vertex in
/// front and swaps the two after it.
template <class T>
KDET_HD_INLINE void transversalVertices(const int sp[3], const int sq[3], const T& p0,
                                        const T& p1, const T& p2, const T& q0, const T& q1,
                                        const T& q2, T& a, T& b, T& c, T& d, T& e, T& f) {
  fromVertex(p0, p1, p2, loneOfNonZero(sp), negateOfNonZero(sq), a, b, c);
  fromVertex(q0, q1, q2, loneOfNonZero(sq), negateOfNonZero(sp), d, e, f);
}

/// T[k] (k in 0..2) by selection rather than by indexing, so that on the device the array can
/// stay in registers.
template <class T>
KDET_HD_INLINE Vec3<double> pick(const T t[3], int k) {
  return toDouble(k == 0 ? t[0] : (k == 1 ? t[1] : t[2]));
}

/// The test of the comment above, with the orientation signs of kernel K.
template <class K>
KDET_HD_INLINE bool transversalProper(const Vec3<double> P[3], const Vec3<double> Q[3],
                                      const int sp[3], const int sq[3]) {
  int x[6];
  transversalOrder(sp, sq, x);
  const Vec3<double> a = pick(P, x[0]), d = pick(Q, x[3]);
  return K::orient3d(pick(P, x[1]), d, a, pick(Q, x[4])) <= 0 &&
         K::orient3d(a, d, pick(P, x[2]), pick(Q, x[5])) <= 0;
}

/// Any classified shape vs any other; A.kind <= B.kind in the order Point < Segment < Proper is
/// not required (the function orders them itself).
template <class K>
KDET_HD_INLINE bool shapesIntersect(const Shape& A0, const Shape& B0) {
  // Order so that A is the "smaller" kind; each pair is then handled once.
  const bool swap = static_cast<int>(A0.kind) > static_cast<int>(B0.kind);
  const Shape& A = swap ? B0 : A0;
  const Shape& B = swap ? A0 : B0;
  switch (A.kind) {
    case Kind::Point:
      if (B.kind == Kind::Point) return A.v[0] == B.v[0];
      if (B.kind == Kind::Segment) return pointOnSegment<K>(A.v[0], B.v[0], B.v[1]);
      return pointTriangle<K>(A.v[0], B);
    case Kind::Segment:
      if (B.kind == Kind::Segment) return segmentSegment<K>(A.v[0], A.v[1], B.v[0], B.v[1]);
      return segmentTriangle<K>(A.v[0], A.v[1], B);
    case Kind::Proper:
    default:
      return properProper<K>(A, B);
  }
}

}  // namespace tri_isect

/// Orientation signs decided exactly (the default: filtered, with an exact fallback).
struct ExactKernel {
  static constexpr bool kExactSigns = true;
  static KDET_HD_INLINE int orient3d(const Vec3<double>& a, const Vec3<double>& b,
                                     const Vec3<double>& c, const Vec3<double>& d) {
    return orient3dSign(a, b, c, d);
  }
  /// s[i] = orient3d(a, b, c, p[i]), the plane's filter products computed once.
  static KDET_HD_INLINE void orient3dSides(const Vec3<double>& a, const Vec3<double>& b,
                                           const Vec3<double>& c, const Vec3<double> p[3],
                                           int s[3]) {
    const OrientPlane plane = orientPlane(a, b, c);
    for (int i = 0; i < 3; ++i) s[i] = orient3dSign(plane, a, b, c, p[i]);
  }
  static KDET_HD_INLINE int orient2d(double ax, double ay, double bx, double by, double cx,
                                     double cy) {
    return orient2dSign(ax, ay, bx, by, cx, cy);
  }
};

/// Orientation signs in plain T arithmetic, with no filter and no fallback: the coordinates are
/// rounded to T and the determinants evaluated naively. Fast, and wrong near degeneracies: this is
/// the "float" and "double" end of the speed/accuracy trade (docs/numerics.md measures it).
template <class T>
struct PlainKernel {
  static constexpr bool kExactSigns = false;
  static KDET_HD_INLINE int sign(T v) { return v > T(0) ? 1 : (v < T(0) ? -1 : 0); }
  static KDET_HD_INLINE int orient3d(const Vec3<double>& a, const Vec3<double>& b,
                                     const Vec3<double>& c, const Vec3<double>& d) {
    const T ax = T(a.x), ay = T(a.y), az = T(a.z);
    const T bx = T(b.x) - ax, by = T(b.y) - ay, bz = T(b.z) - az;
    const T cx = T(c.x) - ax, cy = T(c.y) - ay, cz = T(c.z) - az;
    const T dx = T(d.x) - ax, dy = T(d.y) - ay, dz = T(d.z) - az;
    return sign((by * cz - bz * cy) * dx + (bz * cx - bx * cz) * dy + (bx * cy - by * cx) * dz);
  }
  /// s[i] = orient3d(a, b, c, p[i]) (the same evaluation, point by point).
  static KDET_HD_INLINE void orient3dSides(const Vec3<double>& a, const Vec3<double>& b,
                                           const Vec3<double>& c, const Vec3<double> p[3],
                                           int s[3]) {
    for (int i = 0; i < 3; ++i) s[i] = orient3d(a, b, c, p[i]);
  }
  static KDET_HD_INLINE int orient2d(double ax, double ay, double bx, double by, double cx,
                                     double cy) {
    return sign((T(bx) - T(ax)) * (T(cy) - T(ay)) - (T(by) - T(ay)) * (T(cx) - T(ax)));
  }
};

/// What the orientation filters alone tell about trianglesIntersect() (the exact test).
enum class FilterVerdict { Disjoint, Intersect, Undecided };

/// trianglesFilterVerdict's first steps: the filter's signs of each triangle's vertices against
/// the other's plane. Returns true, with sp and sq set, where the verdict is left to
/// transversalFilterVerdict (all six signs proven non-zero, neither triangle strictly on one
/// side); else false, with `verdict` Disjoint (one triangle provably strictly on one side) or
/// Undecided (a sign not proven). The GPU's plane filter runs the last step for the pairs
/// that need it together, in full warps (cuda_backend.cu).
template <class S>
KDET_HD_INLINE bool planeFilterSigns(const Vec3<S>& p0, const Vec3<S>& p1, const Vec3<S>& p2,
                                     const Vec3<S>& q0, const Vec3<S>& q1, const Vec3<S>& q2,
                                     int sp[3], int sq[3], FilterVerdict& verdict) {
  // The coordinates stay in S (converted exactly where used: fewer registers for float), and in
  // named values, never in an indexed array.
  verdict = FilterVerdict::Disjoint;
  const OrientPlane qp = orientPlane(toDouble(q0), toDouble(q1), toDouble(q2));
  sp[0] = orient3dFilterSign(qp, toDouble(p0));
  sp[1] = orient3dFilterSign(qp, toDouble(p1));
  sp[2] = orient3dFilterSign(qp, toDouble(p2));
  if (tri_isect::strictlyOneSide(sp)) return false;
  const OrientPlane pp = orientPlane(toDouble(p0), toDouble(p1), toDouble(p2));
  sq[0] = orient3dFilterSign(pp, toDouble(q0));
  sq[1] = orient3dFilterSign(pp, toDouble(q1));
  sq[2] = orient3dFilterSign(pp, toDouble(q2));
  if (tri_isect::strictlyOneSide(sq)) return false;
  verdict = FilterVerdict::Undecided;
  for (int i = 0; i < 3; ++i)
    if (sp[i] == 0 || sq[i] == 0) return false;
  return true;
}

/// trianglesFilterVerdict's last step, for the signs planeFilterSigns left to it (all six
/// non-zero): transversalProper's two orientations on transversalOrder's vertices, where both are
/// known (orient3dKnownSign: proven, or exactly 0 where the four points are equal in one
/// coordinate, as orient3dSign finds it): edges that cross in an axis-aligned plane, as where a
/// folded cloth lies over itself on the same grid rows (most of the procedural cloths' undecided
/// pairs, benchmarks/RESULTS-gpu.md).
template <class S>
KDET_HD_INLINE FilterVerdict transversalFilterVerdict(const int sp[3], const int sq[3],
                                                      const Vec3<S>& p0, const Vec3<S>& p1,
                                                      const Vec3<S>& p2, const Vec3<S>& q0,
                                                      const Vec3<S>& q1, const Vec3<S>& q2) {
  Vec3<S> a, b, c, d, e, f;
  tri_isect::transversalVertices(sp, sq, p0, p1, p2, q0, q1, q2, a, b, c, d, e, f);
  int o1 = 0, o2 = 0;
  if (!orient3dKnownSign(toDouble(b), toDouble(d), toDouble(a), toDouble(e), o1))
    return FilterVerdict::Undecided;
  if (o1 > 0) return FilterVerdict::Disjoint;
  if (!orient3dKnownSign(toDouble(a), toDouble(d), toDouble(c), toDouble(f), o2))
    return FilterVerdict::Undecided;
  return o2 > 0 ? FilterVerdict::Disjoint : FilterVerdict::Intersect;
}

/// The exact test's answer where its floating-point filters decide it, without any exact
/// (expansion) arithmetic: Disjoint when either triangle lies provably strictly on one side of the
/// other's plane; for two triangles whose six vertex signs are all proven non-zero (proper
/// triangles in different planes), the answer of transversalProper's two orientations where both
/// are known (orient3dKnownSign); Undecided otherwise. Every decided answer is
/// trianglesIntersect()'s: the filters' proven signs and those zeros are the exact signs
/// (orient3dFilterSign, orient3dSign), and the test takes the same steps on them. Triangles that
/// share a vertex (equal coordinates) always give Undecided, since that vertex's sign against the
/// other's plane is exactly zero and no filter proves a zero. The GPU uses it to take most
/// candidate pairs out of its exact kernel (cuda_backend.cu).
template <class S>
KDET_HD_INLINE FilterVerdict trianglesFilterVerdict(const Vec3<S>& p0, const Vec3<S>& p1,
                                                    const Vec3<S>& p2, const Vec3<S>& q0,
                                                    const Vec3<S>& q1, const Vec3<S>& q2) {
  int sp[3], sq[3];
  FilterVerdict verdict;
  if (!planeFilterSigns(p0, p1, p2, q0, q1, q2, sp, sq, verdict)) return verdict;
  return transversalFilterVerdict(sp, sq, p0, p1, p2, q0, q1, q2);
}

/// trianglesIntersect() with the orientation signs of kernel K (ExactKernel, PlainKernel<T>).
template <class K, class S>
KDET_HD_INLINE bool trianglesIntersectWith(const Vec3<S>& p0, const Vec3<S>& p1,
                                           const Vec3<S>& p2, const Vec3<S>& q0,
                                           const Vec3<S>& q1, const Vec3<S>& q2) {
  const Vec3<double> P[3] = {toDouble(p0), toDouble(p1), toDouble(p2)};
  const Vec3<double> Q[3] = {toDouble(q0), toDouble(q1), toDouble(q2)};
  // Fast rejection before any classification (most candidate pairs end here): all of one
  // triangle strictly on one side of the other's plane. A degenerate triangle has no plane: its
  // orientations are all zero, so it never rejects here and is handled below.
  int sp[3], sq[3];
  K::orient3dSides(Q[0], Q[1], Q[2], P, sp);
  if (tri_isect::strictlyOneSide(sp)) return false;
  K::orient3dSides(P[0], P[1], P[2], Q, sq);
  if (tri_isect::strictlyOneSide(sq)) return false;
  // A degenerate triangle's orientations are all exactly zero, and so are those of a triangle in
  // the other's plane: some non-zero sign on each side means two proper triangles in different
  // planes. (Exact signs only: a plain kernel's rounding can make a degenerate triangle look
  // proper, so those keep the classification below.)
  if (K::kExactSigns && (sp[0] != 0 || sp[1] != 0 || sp[2] != 0) &&
      (sq[0] != 0 || sq[1] != 0 || sq[2] != 0))
    return tri_isect::transversalProper<K>(P, Q, sp, sq);
  const tri_isect::Shape SP = tri_isect::classify<K>(P[0], P[1], P[2]);
  const tri_isect::Shape SQ = tri_isect::classify<K>(Q[0], Q[1], Q[2]);
  // Two proper triangles keep their vertices in order, so the signs above are theirs. With exact
  // signs, two proper triangles here lie in one plane (all six signs zero): the 2D test.
  if (SP.kind == tri_isect::Kind::Proper && SQ.kind == tri_isect::Kind::Proper) {
    if (K::kExactSigns && sp[0] == 0 && sp[1] == 0 && sp[2] == 0 && sq[0] == 0 && sq[1] == 0 &&
        sq[2] == 0)
      return tri_isect::coplanarProper<K>(SP, SQ);
    return tri_isect::properProperSigns<K>(SP, SQ, sp, sq);
  }
  return tri_isect::shapesIntersect<K>(SP, SQ);
}

/// Whether the closed triangles (p0, p1, p2) and (q0, q1, q2) share at least one point, decided
/// exactly on the given coordinates (S = float or double; converted to double without rounding).
/// Touching counts; degenerate triangles count as the segment or point they are. Exact inside the
/// validity range of exact_predicates.h.
template <class S>
KDET_HD_INLINE bool trianglesIntersect(const Vec3<S>& p0, const Vec3<S>& p1, const Vec3<S>& p2,
                                       const Vec3<S>& q0, const Vec3<S>& q1, const Vec3<S>& q2) {
  return trianglesIntersectWith<ExactKernel>(p0, p1, p2, q0, q1, q2);
}

/// trianglesIntersect() under the chosen Predicate.
template <class S>
KDET_HD_INLINE bool trianglesIntersect(Predicate pred, const Vec3<S>& p0, const Vec3<S>& p1,
                                       const Vec3<S>& p2, const Vec3<S>& q0, const Vec3<S>& q1,
                                       const Vec3<S>& q2) {
  switch (pred) {
    case Predicate::Double:
      return trianglesIntersectWith<PlainKernel<double>>(p0, p1, p2, q0, q1, q2);
    case Predicate::Float:
      return trianglesIntersectWith<PlainKernel<float>>(p0, p1, p2, q0, q1, q2);
    default:
      return trianglesIntersectWith<ExactKernel>(p0, p1, p2, q0, q1, q2);
  }
}

}  // namespace detail
}  // namespace kdet_fcl
