// The exact closed triangle-triangle test: hand-made cases, symmetry, and randomized cross-checks
// against two independent exact (GMP rational) referees.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "kdet_fcl/detail/triangle_intersection.h"

namespace {

using kdet_fcl::Vec3;
using kdet_fcl::detail::FilterVerdict;
using kdet_fcl::detail::trianglesFilterVerdict;
using kdet_fcl::detail::trianglesIntersect;
using V = Vec3<double>;

struct Tri {
  V v[3];
};

// ---------------------------------------------------------------- exact rational referees

struct QV {
  mpq_class x, y, z;
};
QV toQ(const V& p) { return {mpq_class(p.x), mpq_class(p.y), mpq_class(p.z)}; }
QV sub(const QV& a, const QV& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
QV crossQ(const QV& a, const QV& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
mpq_class dotQ(const QV& a, const QV& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
bool isZero(const QV& a) { return sgn(a.x) == 0 && sgn(a.y) == 0 && sgn(a.z) == 0; }

/// Referee 1 (proper triangles only): the 17-axis separating-axis test in exact rationals: the
/// two normals, the 9 edge-edge cross products and the 3 + 3 in-plane edge normals n x e. The
/// closed triangles are disjoint iff some axis strictly separates their projections.
bool satReferee(const Tri& P, const Tri& Q) {
  QV p[3], q[3];
  for (int i = 0; i < 3; ++i) p[i] = toQ(P.v[i]), q[i] = toQ(Q.v[i]);
  QV ep[3], eq[3];
  for (int i = 0; i < 3; ++i) ep[i] = sub(p[(i + 1) % 3], p[i]), eq[i] = sub(q[(i + 1) % 3], q[i]);
  const QV np = crossQ(ep[0], sub(p[2], p[0])), nq = crossQ(eq[0], sub(q[2], q[0]));
  EXPECT_FALSE(isZero(np));
  EXPECT_FALSE(isZero(nq));
  QV axes[17];
  int n = 0;
  axes[n++] = np;
  axes[n++] = nq;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) axes[n++] = crossQ(ep[i], eq[j]);
  for (int i = 0; i < 3; ++i) axes[n++] = crossQ(np, ep[i]);
  for (int j = 0; j < 3; ++j) axes[n++] = crossQ(nq, eq[j]);
  for (int k = 0; k < n; ++k) {
    if (isZero(axes[k])) continue;
    mpq_class pmin = dotQ(axes[k], p[0]), pmax = pmin, qmin = dotQ(axes[k], q[0]), qmax = qmin;
    for (int i = 1; i < 3; ++i) {
      const mpq_class a = dotQ(axes[k], p[i]), b = dotQ(axes[k], q[i]);
      if (a < pmin) pmin = a;
      if (a > pmax) pmax = a;
      if (b < qmin) qmin = b;
      if (b > qmax) qmax = b;
    }
    if (pmax < qmin || qmax < pmin) return false;
  }
  return true;
}

/// Referee 2 (any triangles, degenerate included): P and Q meet iff 0 is in the convex hull of the
/// 9 differences s = p_i - q_j. If not, the point x of the hull nearest 0 strictly separates, and
/// x is a positive multiple of a hull vertex s_i, of the component of s_i orthogonal to an edge
/// direction d = s_j - s_i, or of a (signed) triangle normal. Try all those candidates exactly.
bool minkowskiReferee(const Tri& P, const Tri& Q) {
  QV s[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s[3 * i + j] = sub(toQ(P.v[i]), toQ(Q.v[j]));
  auto separates = [&](const QV& a) {
    if (isZero(a)) return false;
    for (int k = 0; k < 9; ++k)
      if (sgn(dotQ(a, s[k])) <= 0) return false;
    return true;
  };
  for (int i = 0; i < 9; ++i) {
    if (separates(s[i])) return false;
    for (int j = i + 1; j < 9; ++j) {
      const QV d = sub(s[j], s[i]);
      const mpq_class dd = dotQ(d, d), ds = dotQ(d, s[i]);
      const QV perp{s[i].x * dd - d.x * ds, s[i].y * dd - d.y * ds, s[i].z * dd - d.z * ds};
      if (separates(perp)) return false;
      for (int k = j + 1; k < 9; ++k) {
        QV nrm = crossQ(d, sub(s[k], s[i]));
        if (separates(nrm)) return false;
        nrm = {-nrm.x, -nrm.y, -nrm.z};
        if (separates(nrm)) return false;
      }
    }
  }
  return true;
}

// ---------------------------------------------------------------- helpers

/// Tallies of trianglesFilterVerdict over every pair that test() checked.
struct VerdictTally {
  long decided = 0, undecided = 0;
};
VerdictTally g_verdicts;

/// trianglesIntersect(P, Q); where the floating-point filters alone decide the pair
/// (trianglesFilterVerdict, which the GPU's plane filter uses to skip the exact kernel), their
/// verdict must be that same answer, and so in every test of this file that calls test().
bool test(const Tri& P, const Tri& Q) {
  const bool r = trianglesIntersect(P.v[0], P.v[1], P.v[2], Q.v[0], Q.v[1], Q.v[2]);
  const FilterVerdict v = trianglesFilterVerdict(P.v[0], P.v[1], P.v[2], Q.v[0], Q.v[1], Q.v[2]);
  if (v == FilterVerdict::Undecided) {
    ++g_verdicts.undecided;
  } else {
    ++g_verdicts.decided;
    EXPECT_EQ(v == FilterVerdict::Intersect, r) << "the filters' verdict is not the exact answer";
  }
  return r;
}

const int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

Tri permuted(const Tri& T, int p) { return {{T.v[kPerm[p][0]], T.v[kPerm[p][1]], T.v[kPerm[p][2]]}}; }

/// Whether every coordinate of T survives a round trip through float.
bool floatExact(const Tri& T) {
  for (const V& v : T.v)
    for (int k = 0; k < 3; ++k)
      if (double(float(v[k])) != v[k]) return false;
  return true;
}

Vec3<float> toF(const V& v) { return {float(v.x), float(v.y), float(v.z)}; }

/// Whether T has no area (collinear or repeated vertices), in exact rationals: the SAT referee
/// takes proper triangles only.
bool degenerateTri(const Tri& T) {
  return isZero(crossQ(sub(toQ(T.v[1]), toQ(T.v[0])), sub(toQ(T.v[2]), toQ(T.v[0]))));
}

/// Checks the expected answer for (P, Q) and (Q, P), under all 6 x 6 vertex orders, and for float
/// coordinates when they are representable.
void expectAll(const Tri& P, const Tri& Q, bool expected) {
  for (int a = 0; a < 6; ++a) {
    for (int b = 0; b < 6; ++b) {
      const Tri Pp = permuted(P, a), Qp = permuted(Q, b);
      ASSERT_EQ(test(Pp, Qp), expected) << "perm " << a << "," << b;
      ASSERT_EQ(test(Qp, Pp), expected) << "swapped, perm " << a << "," << b;
    }
  }
  if (floatExact(P) && floatExact(Q)) {
    EXPECT_EQ(trianglesIntersect(toF(P.v[0]), toF(P.v[1]), toF(P.v[2]), toF(Q.v[0]), toF(Q.v[1]),
                                 toF(Q.v[2])),
              expected)
        << "float";
  }
  // The general referee must agree with the hand-made expectation, too.
  EXPECT_EQ(minkowskiReferee(P, Q), expected) << "referee disagrees with the hand-made case";
}

const double kUp1 = std::nextafter(1.0, 2.0);  // 1 + 2^-52: one ulp above the plane z = 1

// Base triangle in the plane z = 0 and a copy in z = 1 (so that 1-ulp offsets stay normal).
const Tri P0{{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}};
const Tri P1{{{0, 0, 1}, {2, 0, 1}, {0, 2, 1}}};

// ---------------------------------------------------------------- hand-made cases

TEST(TriangleIntersection, CrossingAndDisjoint) {
  expectAll(P0, Tri{{{0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0.5}}}, true);  // Q pierces P
  expectAll(P0, Tri{{{-1, 0.5, -1}, {3, 0.5, -1}, {1, 0.5, 2}}}, true);   // interlocked
  expectAll(P0, Tri{{{0, 0, 1}, {2, 0, 1}, {0, 2, 1}}}, false);            // parallel, above
  expectAll(P0, Tri{{{3, 3, -1}, {3, 3, 1}, {5, 0, 0}}}, false);           // crosses plane outside
  expectAll(P0, Tri{{{0.5, 0.5, 0.25}, {1, 0.5, 2}, {0.5, 1, 3}}}, false);  // above, steep
}

TEST(TriangleIntersection, TouchingAtVertexEdgeFace) {
  expectAll(P0, Tri{{{0, 0, 0}, {-1, 0, 1}, {0, -1, 1}}}, true);    // shared vertex only
  expectAll(P0, Tri{{{2, 0, 0}, {3, 0, -1}, {3, 1, 1}}}, true);     // vertex on vertex
  expectAll(P0, Tri{{{1, 0, 0}, {1, -1, 1}, {2, -1, 1}}}, true);    // vertex on edge interior
  expectAll(P0, Tri{{{1, 0, 0}, {1, -1, -1}, {2, -1, 1}}}, true);   // vertex on edge, Q below+above
  expectAll(P0, Tri{{{0.5, 0.5, 0}, {0, 0, 1}, {1, 0, 1}}}, true);  // vertex on face interior
  expectAll(P0, Tri{{{1, 1, -1}, {1, 1, 1}, {3, 3, 0}}}, true);     // edge through hypotenuse point
  expectAll(P0, Tri{{{0, -1, 0}, {0, -1, 1}, {-1, -1, 0}}}, false);  // near but off
  // Edge crossing an edge, non-coplanar (X shape touching at (1, 0, 0)).
  expectAll(P0, Tri{{{1, -1, 0}, {1, 1, 0}, {1, 0, 1}}}, true);
}

TEST(TriangleIntersection, SharedEdge) {
  expectAll(P0, Tri{{{0, 0, 0}, {2, 0, 0}, {0, -2, 0}}}, true);  // coplanar, other side
  expectAll(P0, Tri{{{0, 0, 0}, {2, 0, 0}, {0, 0, 2}}}, true);   // hinge
  expectAll(P0, Tri{{{0, 0, 0}, {2, 0, 0}, {1, 1, 0}}}, true);   // coplanar, same side (overlap)
}

TEST(TriangleIntersection, Coplanar) {
  expectAll(P0, Tri{{{0.5, 0.5, 0}, {3, 0.5, 0}, {0.5, 3, 0}}}, true);      // overlapping
  expectAll(P0, Tri{{{2, 2, 0}, {4, 2, 0}, {2, 4, 0}}}, false);             // disjoint
  expectAll(P0, Tri{{{0, 2, 0}, {2, 0, 0}, {2, 2, 0}}}, true);              // full shared edge
  expectAll(P0, Tri{{{1, 1, 0}, {3, -1, 0}, {3, 3, 0}}}, true);             // partial edge overlap
  expectAll(P0, Tri{{{0.25, 0.25, 0}, {1, 0.25, 0}, {0.25, 1, 0}}}, true);  // Q inside P
  expectAll(Tri{{{0.25, 0.25, 0}, {1, 0.25, 0}, {0.25, 1, 0}}}, P0, true);  // P inside Q
  expectAll(P0, Tri{{{-1, -1, 0}, {5, -1, 0}, {-1, 5, 0}}}, true);          // P inside Q
  expectAll(P0, Tri{{{-1, 0.5, 0}, {3, 0.5, 0}, {1, -3, 0}}}, true);        // star of David-like
  // Coplanar, 1 ulp apart: the vertex (1 + ulp, 1) is just beyond the hypotenuse x + y = 2.
  const double u = std::nextafter(1.0, 2.0);
  expectAll(P0, Tri{{{u, 1, 0}, {3, 1, 0}, {1, 3, 0}}}, false);
  expectAll(P0, Tri{{{1, 1, 0}, {3, 1, 0}, {1, 3, 0}}}, true);  // touching at (1, 1)
  // Coplanar in a tilted plane (x + y + z = 3) far from the coordinate planes.
  expectAll(Tri{{{3, 0, 0}, {0, 3, 0}, {0, 0, 3}}}, Tri{{{1, 1, 1}, {2, 1, 0}, {1, 2, 0}}}, true);
  expectAll(Tri{{{3, 0, 0}, {0, 3, 0}, {0, 0, 3}}}, Tri{{{4, -1, 0}, {5, -1, -1}, {4, 0, -1}}},
            false);
}

TEST(TriangleIntersection, OneUlpAboveThePlane) {
  // All of Q one ulp above P's plane z = 1: parallel, disjoint.
  expectAll(P1, Tri{{{0, 0, kUp1}, {2, 0, kUp1}, {0, 2, kUp1}}}, false);
  // Tilted, touching P exactly at a vertex / edge; then lifted by one ulp.
  expectAll(P1, Tri{{{0, 0, 1}, {2, 0, kUp1}, {0, 2, kUp1}}}, true);
  expectAll(P1, Tri{{{0, 0, kUp1}, {2, 0, kUp1}, {0, 2, 2}}}, false);
  expectAll(P1, Tri{{{0.5, 0.5, 1}, {0, 0, 2}, {1, 0, 2}}}, true);
  expectAll(P1, Tri{{{0.5, 0.5, kUp1}, {0, 0, 2}, {1, 0, 2}}}, false);
  expectAll(P1, Tri{{{1, 0, 1}, {1, -1, 2}, {2, -1, 2}}}, true);
  expectAll(P1, Tri{{{1, 0, kUp1}, {1, -1, 2}, {2, -1, 2}}}, false);
  // An edge of Q one ulp beside P's edge in the plane direction y.
  // (2^-54 rather than nextafter(0, -1): subnormals are outside the predicates' validity range.)
  expectAll(P1, Tri{{{0.5, -0x1p-54, 1}, {1.5, -0x1p-54, 1}, {1, -1, 1}}}, false);
  expectAll(P1, Tri{{{0.5, 0, 1}, {1.5, -0x1p-54, 1}, {1, -1, 1}}}, true);
}

TEST(TriangleIntersection, DegenerateSegmentVsTriangle) {
  // Collinear triangles are segments between their extreme points (middle vertex in any slot).
  expectAll(P0, Tri{{{0.5, 0.5, -1}, {0.5, 0.5, 1}, {0.5, 0.5, 0.25}}}, true);  // crossing
  expectAll(P1, Tri{{{0.5, 0.5, kUp1}, {0.5, 0.5, 3}, {0.5, 0.5, 2}}}, false);  // 1 ulp above
  expectAll(P1, Tri{{{0.5, 0.5, 1}, {0.5, 0.5, 3}, {0.5, 0.5, 2}}}, true);      // ends on face
  expectAll(P0, Tri{{{3, 3, -1}, {3, 3, 1}, {3, 3, 0}}}, false);                // crosses plane outside
  expectAll(P0, Tri{{{-1, 1, 0}, {3, 1, 0}, {1, 1, 0}}}, true);                 // in plane, crossing
  expectAll(P0, Tri{{{-1, 3, 0}, {3, 3, 0}, {1, 3, 0}}}, false);                // in plane, outside
  expectAll(P0, Tri{{{0.5, 0.5, 0}, {5, 5, 0}, {1, 1, 0}}}, true);              // in plane, from inside
  expectAll(P0, Tri{{{0.25, 0.25, 0}, {0.5, 0.5, 0}, {0.5, 0.5, 0}}}, true);    // in plane, inside
  expectAll(P0, Tri{{{-1, 3, 0}, {3, -1, 0}, {1, 1, 0}}}, true);  // in plane along hypotenuse
  expectAll(P0, Tri{{{1, 1, -1}, {1, 1, 1}, {1, 1, 0}}}, true);   // through an edge point
  expectAll(P0, Tri{{{0, 0, 0}, {0, 0, 0}, {-1, -1, -1}}}, true);  // duplicate vertex, ends on P
  expectAll(P0, Tri{{{-1, 0, 0}, {-3, 0, 0}, {-3, 0, 0}}}, false);  // collinear with an edge, off
}

TEST(TriangleIntersection, DegeneratePointVsTriangle) {
  expectAll(P0, Tri{{{0.5, 0.5, 0}, {0.5, 0.5, 0}, {0.5, 0.5, 0}}}, true);    // on the face
  expectAll(P0, Tri{{{1, 1, 0}, {1, 1, 0}, {1, 1, 0}}}, true);                // on an edge
  expectAll(P0, Tri{{{2, 0, 0}, {2, 0, 0}, {2, 0, 0}}}, true);                // at a vertex
  expectAll(P0, Tri{{{0.5, 0.5, 1}, {0.5, 0.5, 1}, {0.5, 0.5, 1}}}, false);   // off the plane
  expectAll(P0, Tri{{{3, 3, 0}, {3, 3, 0}, {3, 3, 0}}}, false);               // in plane, outside
  expectAll(P1, Tri{{{0.5, 0.5, kUp1}, {0.5, 0.5, kUp1}, {0.5, 0.5, kUp1}}}, false);  // 1 ulp
}

TEST(TriangleIntersection, DegenerateSegmentsAndPoints) {
  const Tri S{{{0, 0, 0}, {2, 0, 0}, {1, 0, 0}}};
  expectAll(S, Tri{{{1, -1, 0}, {1, 1, 0}, {1, 1, 0}}}, true);      // crossing
  expectAll(S, Tri{{{1, -1, 5}, {1, 1, -5}, {1, 0, 0}}}, true);     // crossing, other plane
  expectAll(S, Tri{{{1, 0, 0}, {3, 0, 0}, {2, 0, 0}}}, true);       // collinear overlapping
  expectAll(S, Tri{{{2, 0, 0}, {3, 0, 0}, {3, 0, 0}}}, true);       // collinear, touching end
  expectAll(S, Tri{{{2.5, 0, 0}, {3, 0, 0}, {3, 0, 0}}}, false);    // collinear disjoint
  expectAll(S, Tri{{{-1, 0, 0}, {4, 0, 0}, {0, 0, 0}}}, true);      // collinear containing
  expectAll(S, Tri{{{1, -1, 1}, {1, 1, 1}, {1, 0, 1}}}, false);     // skew
  // Skew, but crossing in the projection that drops x (so the coplanarity check matters).
  expectAll(Tri{{{0, 0, 0}, {2, 2, 0}, {1, 1, 0}}}, Tri{{{3, 0, 1}, {3, 2, -1}, {3, 1, 0}}}, false);
  expectAll(Tri{{{0, 0, 0}, {2, 2, 0}, {1, 1, 0}}}, Tri{{{1, 0, 1}, {1, 2, -1}, {1, 1, 0}}}, true);
  expectAll(S, Tri{{{3, -1, 0}, {3, 1, 0}, {3, 1, 0}}}, false);     // coplanar, apart
  expectAll(S, Tri{{{0, 1, 0}, {2, 1, 0}, {1, 1, 0}}}, false);      // parallel
  expectAll(S, Tri{{{2, 0, 0}, {3, 1, 0}, {4, 2, 0}}}, true);       // touching at an endpoint
  expectAll(S, Tri{{{1, 1, 1}, {3, 3, 3}, {2, 2, 2}}}, false);      // non-coplanar, near
  // Point vs segment and point vs point.
  expectAll(S, Tri{{{1.5, 0, 0}, {1.5, 0, 0}, {1.5, 0, 0}}}, true);
  expectAll(S, Tri{{{2, 0, 0}, {2, 0, 0}, {2, 0, 0}}}, true);
  expectAll(S, Tri{{{2.5, 0, 0}, {2.5, 0, 0}, {2.5, 0, 0}}}, false);
  expectAll(S, Tri{{{1, 1e-9, 0}, {1, 1e-9, 0}, {1, 1e-9, 0}}}, false);
  const Tri A{{{1, 2, 3}, {1, 2, 3}, {1, 2, 3}}};
  expectAll(A, A, true);
  expectAll(A, Tri{{{1, 2, kUp1 * 3}, {1, 2, kUp1 * 3}, {1, 2, kUp1 * 3}}}, false);
}

TEST(TriangleIntersection, FloatMatchesDoubleOfSameValues) {
  // S = float is decided on the exactly converted coordinates: same answer as double.
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> U(-1.f, 1.f);
  int hits = 0;
  for (int it = 0; it < 3000; ++it) {
    Vec3<float> f[6];
    for (auto& p : f) p = {U(rng), U(rng), U(rng)};
    if (it % 3 == 0) f[3] = f[0];  // share a vertex: an exactly touching case
    const bool r = trianglesIntersect(f[0], f[1], f[2], f[3], f[4], f[5]);
    const Tri P{{kdet_fcl::detail::toDouble(f[0]), kdet_fcl::detail::toDouble(f[1]),
                 kdet_fcl::detail::toDouble(f[2])}};
    const Tri Q{{kdet_fcl::detail::toDouble(f[3]), kdet_fcl::detail::toDouble(f[4]),
                 kdet_fcl::detail::toDouble(f[5])}};
    ASSERT_EQ(r, test(P, Q));
    ASSERT_EQ(r, satReferee(P, Q));
    hits += r;
  }
  EXPECT_GT(hits, 1000);
  EXPECT_LT(hits, 2900);
}

/// The normal form of the transversal test (tri_isect::loneVertex), on every sign pattern it can
/// get (not all zero, not all equal and non-zero): after the optional negation the chosen vertex
/// is on the non-negative side and the other two on the non-positive side, and the chosen vertex
/// is off the plane whenever another vertex is on it (so the triangle meets the plane in the
/// segment between its two edges at the chosen vertex).
TEST(TriangleIntersection, LoneVertexNormalFormOfEverySignPattern) {
  using kdet_fcl::detail::tri_isect::loneVertex;
  int patterns = 0, negated = 0, zero_lone = 0;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c) {
        const int s[3] = {a, b, c};
        if (a == b && b == c) continue;  // all zero (coplanar) or strictly one-sided
        int first = -1;
        bool negate = false;
        loneVertex(s, first, negate);
        ASSERT_TRUE(first >= 0 && first < 3);
        const int k = negate ? -1 : 1;
        const int lone = k * s[first], o1 = k * s[(first + 1) % 3], o2 = k * s[(first + 2) % 3];
        EXPECT_GE(lone, 0) << a << b << c;
        EXPECT_LE(o1, 0) << a << b << c;
        EXPECT_LE(o2, 0) << a << b << c;
        if (o1 == 0 || o2 == 0) EXPECT_NE(lone, 0) << a << b << c;
        ++patterns;
        negated += negate;
        zero_lone += lone == 0;
      }
  EXPECT_EQ(patterns, 24);
  EXPECT_GT(negated, 0);
  EXPECT_GT(zero_lone, 0);  // (0, -, -) and (0, +, +)
}

// ---------------------------------------------------------------- randomized cross-checks

/// Small-integer proper triangles: lots of shared vertices, touching and coplanar configurations.
TEST(TriangleIntersection, RandomSmallIntegersMatchSatReferee) {
  std::mt19937_64 rng(1);
  int hits = 0, cases = 0;
  for (int range : {1, 2, 3}) {
    std::uniform_int_distribution<int> I(-range, range);
    for (int it = 0; it < 6000; ++it) {
      Tri T[2];
      for (Tri& t : T)
        for (V& v : t.v) v = {double(I(rng)), double(I(rng)), double(I(rng))};
      if (it % 4 == 1) T[1].v[2].z = T[1].v[0].z = T[1].v[1].z = T[0].v[0].z;  // often coplanar
      if (degenerateTri(T[0]) || degenerateTri(T[1])) continue;
      const bool ref = satReferee(T[0], T[1]);
      ASSERT_EQ(test(T[0], T[1]), ref) << "case " << it;
      ASSERT_EQ(test(T[1], T[0]), ref);
      if (it % 50 == 0) {
        ASSERT_EQ(minkowskiReferee(T[0], T[1]), ref);  // the two referees agree
      }
      if (it % 20 == 0) {
        for (int a = 0; a < 6; ++a)
          for (int b = 0; b < 6; ++b) ASSERT_EQ(test(permuted(T[0], a), permuted(T[1], b)), ref);
      }
      hits += ref;
      ++cases;
    }
  }
  EXPECT_GT(cases, 10000);
  EXPECT_GT(hits, cases / 10);
  EXPECT_LT(hits, cases - cases / 10);
}

/// Coplanar proper pairs (the exact test's 2D branch, coplanarProper): both triangles on one
/// lattice of a plane, skew or axis-aligned, so that every point lies on it exactly; small
/// lattices give many shared vertices, touching edges and vertices on edges. The plane is placed
/// near the origin and far from it (offset 2^30, steps 2^-12: every coordinate still exact).
TEST(TriangleIntersection, RandomCoplanarPairsMatchSatReferee) {
  std::mt19937_64 rng(7);
  int hits = 0, cases = 0;
  const V planes[3][2] = {{{2, 1, -1}, {-1, 3, 2}},   // skew
                          {{1, 0, 0}, {0, 1, 0}},     // z = const
                          {{0, 1, 1}, {0, -1, 2}}};   // x = const, sheared
  for (const auto& E : planes)
    for (const double far : {0.0, 1.0}) {
      const V origin = far > 0 ? V{std::ldexp(1.0, 30), -std::ldexp(1.0, 29), 3.0}
                               : V{0.5, -1.25, 3.0};
      const double step = far > 0 ? std::ldexp(1.0, -12) : 1.0;
      for (int range : {1, 2, 4}) {
        std::uniform_int_distribution<int> I(-range, range);
        for (int it = 0; it < 1500; ++it) {
          Tri T[2];
          for (Tri& t : T)
            for (V& v : t.v) {
              const double u = step * I(rng), w = step * I(rng);
              v = {origin.x + u * E[0].x + w * E[1].x, origin.y + u * E[0].y + w * E[1].y,
                   origin.z + u * E[0].z + w * E[1].z};
            }
          if (degenerateTri(T[0]) || degenerateTri(T[1])) continue;
          // Coplanar by construction (the referee's arithmetic says so too).
          const QV n = crossQ(sub(toQ(T[0].v[1]), toQ(T[0].v[0])),
                              sub(toQ(T[0].v[2]), toQ(T[0].v[0])));
          for (const V& q : T[1].v) ASSERT_EQ(sgn(dotQ(n, sub(toQ(q), toQ(T[0].v[0])))), 0);
          const bool ref = satReferee(T[0], T[1]);
          ASSERT_EQ(test(T[0], T[1]), ref) << "case " << it;
          ASSERT_EQ(test(T[1], T[0]), ref) << "case " << it;
          if (it % 10 == 0) {
            ASSERT_EQ(minkowskiReferee(T[0], T[1]), ref);
            for (int a = 0; a < 6; ++a)
              for (int b = 0; b < 6; ++b)
                ASSERT_EQ(test(permuted(T[0], a), permuted(T[1], b)), ref);
          }
          hits += ref;
          ++cases;
        }
      }
    }
  EXPECT_GT(cases, 15000);
  EXPECT_GT(hits, cases / 10);
  EXPECT_LT(hits, cases - cases / 10);
}

/// Near-touching configurations: Q has a vertex (or its edge passes) exactly at a point of P
/// (vertex, edge point or interior point with dyadic barycentrics), optionally in P's plane, then one
/// coordinate is moved by one ulp; coordinates get large offsets and small or large scales.
TEST(TriangleIntersection, RandomNearTouchingMatchesSatReferee) {
  std::mt19937_64 rng(2);
  std::uniform_int_distribution<int> I(-20, 20), B(0, 4), W(0, 8), M(0, 3);
  const double offsets[] = {0.0, 1e3, 1e5, 1e7};
  const double scales[] = {1.0, 0x1p-20, 1e-6, 0x1p10};
  int hits = 0, cases = 0;
  for (double off : offsets) {
    for (double sc : scales) {
      for (int it = 0; it < 800; ++it) {
        Tri P, Q;
        for (V& v : P.v) v = {double(I(rng)), double(I(rng)), double(I(rng))};
        // Touch point X = P0 + a/4 (P1 - P0) + b/4 (P2 - P0) with a + b <= 4 (on P, dyadic).
        int a = B(rng), b = B(rng);
        if (a + b > 4) b = 4 - a;
        const V X = P.v[0] + (P.v[1] - P.v[0]) * (a / 4.0) + (P.v[2] - P.v[0]) * (b / 4.0);
        const int mode = M(rng);
        for (int k = 0; k < 3; ++k) {
          if (mode == 0) {  // Q coplanar with P, anchored at X
            const double s = I(rng) / 4.0, t = I(rng) / 4.0;
            Q.v[k] = X + (P.v[1] - P.v[0]) * s + (P.v[2] - P.v[0]) * t;
          } else {
            Q.v[k] = X + V{double(I(rng)), double(I(rng)), double(I(rng))};
          }
        }
        Q.v[0] = X;
        if (mode == 3) Q.v[1] = X + (X - Q.v[2]);  // edge of Q passes through X (X midpoint)
        for (Tri* T : {&P, &Q})
          for (V& v : T->v) v = {off + v.x * sc, off + v.y * sc, off + v.z * sc};
        // One-ulp move of a random coordinate of Q's touching vertex (or a random vertex).
        if (it % 3 != 0) {
          const int w = W(rng);
          double& c = Q.v[w < 6 ? 0 : w - 6][w % 3];  // mostly the touching vertex
          if (c != 0) c = std::nextafter(c, (it & 4) ? INFINITY : -INFINITY);
        }
        if (degenerateTri(P) || degenerateTri(Q)) continue;
        const bool ref = satReferee(P, Q);
        ASSERT_EQ(test(P, Q), ref) << "case " << it << " off " << off << " sc " << sc;
        ASSERT_EQ(test(Q, P), ref);
        if (it % 40 == 0) {
          for (int pa = 0; pa < 6; ++pa)
            for (int pb = 0; pb < 6; ++pb) ASSERT_EQ(test(permuted(P, pa), permuted(Q, pb)), ref);
        }
        hits += ref;
        ++cases;
      }
    }
  }
  EXPECT_GT(cases, 10000);
  EXPECT_GT(hits, cases / 5);
  EXPECT_LT(hits, cases - cases / 5);
}

/// Degenerate triangles (segments, points, repeated vertices) against anything, checked with the
/// general convex-hull referee.
TEST(TriangleIntersection, RandomDegenerateMatchesMinkowskiReferee) {
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int> K(-2, 2), M(0, 4);
  int hits = 0, cases = 0, degenerate = 0;
  for (int it = 0; it < 4000; ++it) {
    std::uniform_int_distribution<int> I(-1 - it % 2, 1 + it % 2);  // [-1,1] meets more often
    Tri T[2];
    for (Tri& t : T) {
      for (V& v : t.v) v = {double(I(rng)), double(I(rng)), double(I(rng))};
      switch (M(rng)) {
        case 0:  // collinear: v2 = v0 + k (v1 - v0)
          t.v[2] = t.v[0] + (t.v[1] - t.v[0]) * double(K(rng));
          break;
        case 1:  // collinear with a half step (dyadic, exact)
          t.v[2] = t.v[0] + (t.v[1] - t.v[0]) * (K(rng) / 2.0);
          break;
        case 2:  // a point
          t.v[1] = t.v[2] = t.v[0];
          break;
        case 3:  // repeated vertex
          t.v[1] = t.v[0];
          break;
        default:  // proper (probably)
          break;
      }
    }
    const bool ref = minkowskiReferee(T[0], T[1]);
    ASSERT_EQ(test(T[0], T[1]), ref) << "case " << it;
    ASSERT_EQ(test(T[1], T[0]), ref);
    for (int a = 0; a < 6; a += (it % 10 == 0 ? 1 : 5))
      for (int b = 0; b < 6; b += (it % 10 == 0 ? 1 : 5))
        ASSERT_EQ(test(permuted(T[0], a), permuted(T[1], b)), ref);
    for (const Tri& t : T) degenerate += degenerateTri(t);
    hits += ref;
    ++cases;
  }
  EXPECT_GT(degenerate, 3000);
  EXPECT_GT(hits, cases / 10);
  EXPECT_LT(hits, cases - cases / 10);
}

/// The filter verdict's vertices (tri_isect::transversalVertices, closed form) are the general
/// transversalOrder's, for every pattern of six non-zero signs where neither triangle lies
/// strictly on one side of the other's plane (6 mixed patterns per triangle): the vertices are
/// labelled by their indices, so each picked label must be transversalOrder's index.
TEST(TriangleIntersection, TransversalVerticesOfNonZeroSignsAreTransversalOrders) {
  namespace ti = kdet_fcl::detail::tri_isect;
  int patterns = 0;
  for (int m = 0; m < 64; ++m) {
    int sp[3], sq[3];
    for (int i = 0; i < 3; ++i) {
      sp[i] = ((m >> i) & 1) != 0 ? 1 : -1;
      sq[i] = ((m >> (3 + i)) & 1) != 0 ? 1 : -1;
    }
    if (ti::strictlyOneSide(sp) || ti::strictlyOneSide(sq)) continue;
    int x[6];
    ti::transversalOrder(sp, sq, x);
    int v[6];
    ti::transversalVertices(sp, sq, 0, 1, 2, 0, 1, 2, v[0], v[1], v[2], v[3], v[4], v[5]);
    for (int k = 0; k < 6; ++k) EXPECT_EQ(v[k], x[k]) << "signs " << m << ", vertex " << k;
    ++patterns;
  }
  EXPECT_EQ(patterns, 36);
}

/// The filters decide generic pairs: random triangles in general position (crossing and
/// disjoint, in float and double), each decided verdict checked against the exact test and the
/// SAT referee. Pairs that share a vertex are never decided (the GPU's exact kernel then drops
/// adjacent pairs). The hand-made, degenerate and near-touching pairs of the tests above have
/// their decided verdicts checked through test().
TEST(TriangleIntersection, FilterVerdictDecidesGenericPairsAndAbstainsOnSharedVertices) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  int decided = 0, crossing = 0, cases = 0, shared_undecided = 0;
  for (int it = 0; it < 4000; ++it) {
    Tri T[2];
    for (Tri& t : T)
      for (V& v : t.v) v = {U(rng), U(rng), U(rng)};
    if (it % 2 == 1)  // floats, converted exactly
      for (Tri& t : T)
        for (V& v : t.v) v = {double(float(v.x)), double(float(v.y)), double(float(v.z))};
    const bool ref = satReferee(T[0], T[1]);
    ASSERT_EQ(test(T[0], T[1]), ref) << "case " << it;
    const FilterVerdict v = trianglesFilterVerdict(T[0].v[0], T[0].v[1], T[0].v[2], T[1].v[0],
                                                   T[1].v[1], T[1].v[2]);
    if (v != FilterVerdict::Undecided) {
      ++decided;
      ASSERT_EQ(v == FilterVerdict::Intersect, ref) << "case " << it;
    }
    if (it % 2 == 1) {
      const Vec3<float> f[6] = {toF(T[0].v[0]), toF(T[0].v[1]), toF(T[0].v[2]),
                                toF(T[1].v[0]), toF(T[1].v[1]), toF(T[1].v[2])};
      EXPECT_EQ(trianglesFilterVerdict(f[0], f[1], f[2], f[3], f[4], f[5]), v) << "case " << it;
    }
    crossing += ref;
    ++cases;
    // The same pair with one vertex of Q moved onto one of P: never decided.
    Tri Q = T[1];
    Q.v[it % 3] = T[0].v[(it / 3) % 3];
    const FilterVerdict w =
        trianglesFilterVerdict(T[0].v[0], T[0].v[1], T[0].v[2], Q.v[0], Q.v[1], Q.v[2]);
    shared_undecided += w == FilterVerdict::Undecided;
    (void)test(T[0], Q);
  }
  EXPECT_GT(crossing, cases / 20);  // both answers occur
  EXPECT_LT(crossing, cases - cases / 20);
  EXPECT_GT(decided, cases - cases / 100);  // generic pairs: nearly all decided
  EXPECT_EQ(shared_undecided, cases);
  // Over every pair test() has checked so far in this program (the hand-made, degenerate and
  // near-touching cases above when the whole file runs), the filters decided some and left some.
  EXPECT_GT(g_verdicts.decided, 0);
  EXPECT_GT(g_verdicts.undecided, 0);
}

/// Edges that cross in an axis-aligned plane, as where a folded cloth lies over itself on the same
/// grid rows: each triangle has an edge in the plane y = 0 and its third vertex off it, on either
/// side, with small integer coordinates (many exact touchings). transversalFilterVerdict cannot
/// prove such an orientation, but knows it is exactly 0 (sameCoordinate): the filters decide these
/// pairs, and each decided verdict is the exact test's and the SAT referee's.
TEST(TriangleIntersection, FilterVerdictDecidesEdgesCrossingInAnAxisPlane) {
  namespace ti = kdet_fcl::detail::tri_isect;
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> I(-3, 3), Y(1, 2), B(0, 1);
  int cases = 0, hits = 0, by_zero[2] = {0, 0}, by_zero_hits = 0;
  for (int it = 0; it < 20000; ++it) {
    Tri T[2];
    for (Tri& t : T) {
      t.v[0] = {double(I(rng)), 0, double(I(rng))};
      t.v[1] = {double(I(rng)), 0, double(I(rng))};
      t.v[2] = {double(I(rng)), double(B(rng) ? Y(rng) : -Y(rng)), double(I(rng))};
    }
    if (degenerateTri(T[0]) || degenerateTri(T[1])) continue;
    const bool ref = satReferee(T[0], T[1]);
    ASSERT_EQ(test(T[0], T[1]), ref) << "case " << it;
    ASSERT_EQ(test(T[1], T[0]), ref) << "case " << it;
    ++cases;
    hits += ref;
    // Decided where the filter alone proved no sign of the last step: by an exact zero.
    int sp[3], sq[3];
    FilterVerdict v;
    const V* p = T[0].v;
    const V* q = T[1].v;
    if (!kdet_fcl::detail::planeFilterSigns(p[0], p[1], p[2], q[0], q[1], q[2], sp, sq, v))
      continue;
    V a, b, c, d, e, f;
    ti::transversalVertices(sp, sq, p[0], p[1], p[2], q[0], q[1], q[2], a, b, c, d, e, f);
    const int o1 = kdet_fcl::detail::orient3dFilterSign(b, d, a, e);
    const int o2 = kdet_fcl::detail::orient3dFilterSign(a, d, c, f);
    const bool zero = o1 == 0 || (o1 < 0 && o2 == 0);
    v = trianglesFilterVerdict(p[0], p[1], p[2], q[0], q[1], q[2]);
    if (zero && v != FilterVerdict::Undecided) {
      ++by_zero[o1 == 0 ? 0 : 1];
      by_zero_hits += v == FilterVerdict::Intersect;
      ASSERT_EQ(v == FilterVerdict::Intersect, ref) << "case " << it;
    }
  }
  EXPECT_GT(cases, 15000);
  EXPECT_GT(hits, cases / 10);
  // The pairs the exact zeros decide, by the first orientation and by the second (touching: all
  // intersect here).
  EXPECT_GT(by_zero[0], 100);
  EXPECT_GT(by_zero[1], 100);
  EXPECT_EQ(by_zero_hits, by_zero[0] + by_zero[1]);
}

}  // namespace
