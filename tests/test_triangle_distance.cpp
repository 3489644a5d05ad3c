// Distance between closed triangles: analytic cases, dense-sampling bounds, symmetry, and
// consistency with the exact intersection test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "kdet_fcl/detail/triangle_distance.h"
#include "kdet_fcl/detail/triangle_intersection.h"

namespace {

using kdet_fcl::Vec3;
using kdet_fcl::detail::triangleDistanceSquared;
using kdet_fcl::detail::trianglesIntersect;
using kdet_fcl::detail::tri_dist::pointTriangleDistanceSquared;
using kdet_fcl::detail::tri_dist::segmentSegmentDistanceSquared;
using V = Vec3<double>;

struct Tri {
  V v[3];
};

double dist2(const Tri& P, const Tri& Q) {
  return triangleDistanceSquared(P.v[0], P.v[1], P.v[2], Q.v[0], Q.v[1], Q.v[2]);
}

const int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
Tri permuted(const Tri& T, int p) { return {{T.v[kPerm[p][0]], T.v[kPerm[p][1]], T.v[kPerm[p][2]]}}; }

/// Checks d^2(P, Q) against an analytic value (relative tolerance), for both argument orders and
/// all vertex orders.
void expectDist2(const Tri& P, const Tri& Q, double expected) {
  for (int a = 0; a < 6; ++a) {
    for (int b = 0; b < 6; ++b) {
      const Tri Pp = permuted(P, a), Qp = permuted(Q, b);
      const double tol = 1e-12 * std::max(1.0, expected);
      ASSERT_NEAR(dist2(Pp, Qp), expected, tol) << "perm " << a << "," << b;
      ASSERT_NEAR(dist2(Qp, Pp), expected, tol) << "swapped perm " << a << "," << b;
    }
  }
}

/// Dense barycentric samples of a closed triangle (n subdivisions per edge); works for degenerate
/// triangles too, since it samples the convex hull of the three points.
void samples(const Tri& T, int n, std::vector<V>& out) {
  out.clear();
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double a = double(i) / n, b = double(j) / n, c = 1 - a - b;
      out.push_back(T.v[0] * a + T.v[1] * b + T.v[2] * c);
    }
}

double maxEdge(const Tri& T) {
  double m = 0;
  for (int i = 0; i < 3; ++i) {
    const V d = T.v[(i + 1) % 3] - T.v[i];
    m = std::max(m, std::sqrt(kdet_fcl::dot(d, d)));
  }
  return m;
}

const Tri P0{{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}};

TEST(TriangleDistance, IntersectingIsExactlyZero) {
  EXPECT_EQ(dist2(P0, Tri{{{0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0.5}}}), 0.0);  // crossing
  EXPECT_EQ(dist2(P0, Tri{{{0, 0, 0}, {-1, 0, 1}, {0, -1, 1}}}), 0.0);           // shared vertex
  EXPECT_EQ(dist2(P0, Tri{{{1, 1, 0}, {3, 1, 0}, {1, 3, 0}}}), 0.0);             // coplanar touch
  EXPECT_EQ(dist2(P0, Tri{{{0.5, 0.5, 0}, {0.5, 0.5, 0}, {0.5, 0.5, 0}}}), 0.0);  // point on face
}

TEST(TriangleDistance, ParallelAndFaceCases) {
  for (double h : {1.0, 0.25, 1e-6, 3e3}) {
    expectDist2(P0, Tri{{{0, 0, h}, {2, 0, h}, {0, 2, h}}}, h * h);             // parallel copy
    expectDist2(P0, Tri{{{0.5, 0.5, h}, {0, 0, h + 1}, {1, 0, h + 1}}}, h * h);  // vertex over face
    expectDist2(P0, Tri{{{-1, 0.5, h}, {3, 0.5, h}, {1, 0.5, h + 2}}}, h * h);   // edge over face
    // Parallel, laterally offset beyond the hypotenuse: in-plane gap g = 1/sqrt(2) from (1,1).
    expectDist2(P0, Tri{{{1.5, 1.5, h}, {3, 1.5, h}, {1.5, 3, h}}}, h * h + 0.5);
  }
}

TEST(TriangleDistance, FarFromOriginKeepsAccuracy) {
  // Triangles around (1e7, 1e7, 1e7): the error must scale with their size, not with 1e7 (an
  // evaluation at absolute coordinates would be off by ~1e-9 in the distance here).
  const double o = 1e7;
  for (double h : {1e-6, 1e-4, 0.5}) {
    const double hz = (o + h) - o;  // the separation that is actually representable
    const Tri A{{{o, o, o}, {o + 2, o, o}, {o, o + 2, o}}};
    const Tri B{{{o + 0.5, o + 0.5, o + h}, {o, o, o + h + 1}, {o + 1, o, o + h + 1}}};
    const Tri C{{{o - 1, o + 0.5, o + h}, {o + 3, o + 0.5, o + h}, {o + 1, o + 0.5, o + h + 2}}};
    EXPECT_NEAR(dist2(A, B), hz * hz, 1e-9 * hz * hz) << h;  // vertex over face
    EXPECT_NEAR(dist2(B, A), hz * hz, 1e-9 * hz * hz) << h;
    EXPECT_NEAR(dist2(A, C), hz * hz, 1e-9 * hz * hz) << h;  // edge over face
    EXPECT_NEAR(dist2(C, A), hz * hz, 1e-9 * hz * hz) << h;
  }
}

TEST(TriangleDistance, TranslationByLargeOffsetKeepsDistance) {
  // Random close pairs with coordinates on a 2^-20 grid, translated exactly by 2^23 (~8.4e6): the
  // distance must match the one at the origin to a small relative error, although at absolute
  // coordinates every rounding would be ~1e-9, far above these distances.
  std::mt19937_64 rng(12);
  std::uniform_int_distribution<int> G(-(1 << 20), 1 << 20);
  const double off = 0x1p23;
  int checked = 0;
  for (int it = 0; it < 3000; ++it) {
    Tri A, B;
    for (V& v : A.v) v = {G(rng) * 0x1p-20, G(rng) * 0x1p-20, G(rng) * 0x1p-20};
    for (V& v : B.v) v = {G(rng) * 0x1p-20, G(rng) * 0x1p-20, G(rng) * 0x1p-20};
    // Pull B to within ~1e-4 of A's centroid region by moving its first vertex next to A's edge.
    B.v[0] = A.v[0] * 0.5 + A.v[1] * 0.5 + V{0x1p-14, -0x1p-15, 0x1p-13};
    const double d0 = dist2(A, B);
    if (d0 == 0) continue;
    Tri As = A, Bs = B;
    for (V& v : As.v) v = v + V{off, off, off};
    for (V& v : Bs.v) v = v + V{off, off, off};
    ASSERT_NEAR(dist2(As, Bs), d0, 1e-6 * d0) << "case " << it;
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(TriangleDistance, EdgeEdgeCases) {
  // P lies in z <= 0 touching z = 0 only along the x-axis edge; Q lies in z >= h touching z = h
  // only along its y-axis edge: the distance is h, between edge interiors.
  const Tri P{{{-1, 0, 0}, {1, 0, 0}, {0, -1, -1}}};
  for (double h : {1.0, 1e-3, 7.0}) {
    expectDist2(P, Tri{{{0, -1, h}, {0, 1, h}, {0, 0, h + 1}}}, h * h);
    // Shift Q along x by 3: closest points are P's endpoint (1,0,0) and Q's edge point (3,0,h).
    expectDist2(P, Tri{{{3, -1, h}, {3, 1, h}, {3, 0, h + 1}}}, 4 + h * h);
  }
}

TEST(TriangleDistance, DegenerateTriangles) {
  const Tri pt{{{1, 2, 3}, {1, 2, 3}, {1, 2, 3}}};
  const Tri pt2{{{4, 6, 3}, {4, 6, 3}, {4, 6, 3}}};
  expectDist2(pt, pt2, 25.0);                                             // point-point
  expectDist2(pt, pt, 0.0);
  expectDist2(P0, Tri{{{0.5, 0.5, 2}, {0.5, 0.5, 2}, {0.5, 0.5, 2}}}, 4.0);  // point over face
  expectDist2(P0, Tri{{{3, 3, 0}, {3, 3, 0}, {3, 3, 0}}}, 8.0);           // point beside hypotenuse
  expectDist2(P0, Tri{{{-3, -4, 0}, {-3, -4, 0}, {-3, -4, 0}}}, 25.0);     // point near vertex
  const Tri seg{{{0, 0, 0}, {2, 0, 0}, {1, 0, 0}}};
  expectDist2(seg, Tri{{{0, 1, 0}, {2, 1, 0}, {1, 1, 0}}}, 1.0);    // parallel, overlapping
  expectDist2(seg, Tri{{{3, 1, 0}, {5, 1, 0}, {4, 1, 0}}}, 2.0);    // parallel, disjoint
  expectDist2(seg, Tri{{{5, 0, 0}, {7, 0, 0}, {6, 0, 0}}}, 9.0);    // collinear gap
  expectDist2(seg, Tri{{{1, -1, 2}, {1, 1, 2}, {1, 0, 2}}}, 4.0);   // skew, perpendicular
  expectDist2(seg, Tri{{{1, 0, 2}, {1, 0, 2}, {1, 0, 2}}}, 4.0);    // point over segment
  expectDist2(seg, P0, 0.0);                                        // segment on an edge
  expectDist2(Tri{{{0.5, 0.5, 1}, {0.5, 0.5, 3}, {0.5, 0.5, 2}}}, P0, 1.0);  // segment above face
  // Nearly degenerate (sliver) triangle: the plane is poorly defined, edges decide.
  const Tri sliver{{{0, 0, 0}, {2, 0, 0}, {1, 1e-13, 0}}};
  expectDist2(sliver, Tri{{{1, 0, 5}, {1, 0, 5}, {1, 0, 5}}}, 25.0);
}

TEST(TriangleDistance, FloatInput) {
  const Vec3<float> a{0, 0, 0}, b{2, 0, 0}, c{0, 2, 0};
  const Vec3<float> d{0.5f, 0.5f, 1.5f}, e{0, 0, 3}, f{1, 0, 3};
  EXPECT_NEAR(triangleDistanceSquared(a, b, c, d, e, f), 2.25, 1e-12);
  EXPECT_EQ(triangleDistanceSquared(a, b, c, a, e, f), 0.0);
}

/// Random (also degenerate) triangles vs dense sampling: the computed distance is at most the
/// sampled minimum and at least the sampled minimum minus the sampling resolution.
TEST(TriangleDistance, MatchesDenseSampling) {
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::uniform_int_distribution<int> M(0, 5);
  const int n = 40;
  std::vector<V> sp, sq;
  int positive = 0;
  for (int it = 0; it < 300; ++it) {
    Tri T[2];
    for (Tri& t : T) {
      for (V& v : t.v) v = {U(rng), U(rng), U(rng)};
      const int m = M(rng);
      if (m == 0) t.v[2] = t.v[0] * 0.25 + t.v[1] * 0.75;  // (nearly) collinear
      if (m == 1) t.v[1] = t.v[2] = t.v[0];                 // point
    }
    T[1].v[0] = T[1].v[0] + V{U(rng), U(rng), U(rng)} * (it % 2 ? 1.5 : 0.3);
    T[1].v[1] = T[1].v[1] + V{1.0, 0.0, 0.0} * (it % 3 ? 1.0 : 0.0);
    const double d = std::sqrt(dist2(T[0], T[1]));
    samples(T[0], n, sp);
    samples(T[1], n, sq);
    double best = INFINITY;
    for (const V& p : sp)
      for (const V& q : sq) {
        const V w = p - q;
        best = std::min(best, kdet_fcl::dot(w, w));
      }
    best = std::sqrt(best);
    // Each closed triangle lies within maxEdge/n of its samples.
    const double res = (maxEdge(T[0]) + maxEdge(T[1])) / n;
    ASSERT_LE(d, best + 1e-12) << "case " << it;
    ASSERT_GE(d, best - res - 1e-12) << "case " << it;
    positive += d > 0;
  }
  EXPECT_GT(positive, 100);
}

/// Segment-segment and point-triangle pieces against sampling, including parallel and zero-length
/// segments.
TEST(TriangleDistance, PiecesMatchSampling) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int it = 0; it < 2000; ++it) {
    V p0{U(rng), U(rng), U(rng)}, p1{U(rng), U(rng), U(rng)}, q0{U(rng), U(rng), U(rng)},
        q1{U(rng), U(rng), U(rng)};
    if (it % 4 == 1) q1 = q0 + (p1 - p0) * U(rng);  // parallel
    if (it % 4 == 2) p1 = p0;                        // zero length
    if (it % 8 == 3) q0 = q1 = p0 + V{0, 0, 0.5};    // both points
    const double d = std::sqrt(segmentSegmentDistanceSquared(p0, p1, q0, q1));
    double best = INFINITY;
    const int n = 400;
    for (int i = 0; i <= n; ++i) {
      const V a = p0 + (p1 - p0) * (double(i) / n);
      // Exact closest point of segment q to a (clamped projection), so only p is sampled.
      const V e = q1 - q0;
      const double ee = kdet_fcl::dot(e, e);
      double t = ee > 0 ? kdet_fcl::dot(a - q0, e) / ee : 0;
      t = std::min(1.0, std::max(0.0, t));
      const V w = a - (q0 + e * t);
      best = std::min(best, std::sqrt(kdet_fcl::dot(w, w)));
    }
    const V dp = p1 - p0;
    const double res = std::sqrt(kdet_fcl::dot(dp, dp)) / n;
    ASSERT_LE(d, best + 1e-12) << it;
    ASSERT_GE(d, best - res - 1e-12) << it;
    ASSERT_NEAR(segmentSegmentDistanceSquared(q0, q1, p0, p1), d * d, 1e-12);
  }
  // Point-triangle: a point straight above the interior, and beside it.
  const V a{0, 0, 0}, b{2, 0, 0}, c{0, 2, 0};
  EXPECT_NEAR(pointTriangleDistanceSquared(V{0.5, 0.5, -3}, a, b, c), 9.0, 1e-12);
  EXPECT_NEAR(pointTriangleDistanceSquared(V{-1, -1, 1}, a, b, c), 3.0, 1e-12);
  EXPECT_NEAR(pointTriangleDistanceSquared(V{1, 1, 0}, a, b, c), 0.0, 1e-12);
  EXPECT_NEAR(pointTriangleDistanceSquared(V{5, 5, 0}, a, a, a), 50.0, 1e-12);
}

/// Exactness-consistency: on small-integer triangles, distance 0 iff the exact test says they
/// intersect (a non-intersecting pair of such triangles is far from touching), and the distance is
/// symmetric.
TEST(TriangleDistance, ZeroIffIntersectingAndSymmetric) {
  std::mt19937_64 rng(10);
  std::uniform_int_distribution<int> I(-2, 2);
  int hits = 0, misses = 0;
  for (int it = 0; it < 20000; ++it) {
    Tri T[2];
    for (Tri& t : T)
      for (V& v : t.v) v = {double(I(rng)), double(I(rng)), double(I(rng))};
    const double d = dist2(T[0], T[1]);
    const bool isect = trianglesIntersect(T[0].v[0], T[0].v[1], T[0].v[2], T[1].v[0], T[1].v[1],
                                          T[1].v[2]);
    ASSERT_EQ(d == 0.0, isect) << "case " << it;
    if (d > 0) {
      ASSERT_FALSE(isect);
      // A positive distance between integer triangles is at least 1/sqrt(3*4*...) -- certainly not
      // below 1e-3 here; rounding noise would be ~1e-16.
      ASSERT_GT(d, 1e-3);
    }
    ASSERT_NEAR(dist2(T[1], T[0]), d, 1e-12 * std::max(1.0, d));
    (isect ? hits : misses)++;
  }
  EXPECT_GT(hits, 2000);
  EXPECT_GT(misses, 2000);
}

}  // namespace
