// Exact orientation predicates vs. an exact rational (GMP) referee.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <random>

#include "kdet_fcl/detail/exact_predicates.h"
#include "near_coplanar_points.h"

namespace {

using kdet_fcl::Vec3;
using kdet_fcl::detail::orient2dSign;
using kdet_fcl::detail::orient3dFilterSign;
using kdet_fcl::detail::orient3dSign;
using kdet_fcl::detail::orientPlane;
using kdet_fcl::detail::exact::orient2dSignExact;
using kdet_fcl::detail::exact::orient3dSignExact;
using kdet_fcl::detail::exact::isFloatValue;
using kdet_fcl::detail::exact::orient3dSignShort;
using kdet_fcl::detail::exact::kSignUnknown;
using kdet_fcl::detail::exact::sumSign;
using V = Vec3<double>;

/// Exact rational from a double (mpq_set_d is exact).
mpq_class Q(double v) { return mpq_class(v); }

/// The sign of an exact rational as -1, 0, +1.
int refSign(const mpq_class& v) {
  const int s = mpq_sgn(v.get_mpq_t());
  return s > 0 ? 1 : (s < 0 ? -1 : 0);
}

/// Exact sign of det[b-a; c-a; d-a] in rational arithmetic.
int refOrient3d(const V& a, const V& b, const V& c, const V& d) {
  const mpq_class ux = Q(b.x) - Q(a.x), uy = Q(b.y) - Q(a.y), uz = Q(b.z) - Q(a.z);
  const mpq_class vx = Q(c.x) - Q(a.x), vy = Q(c.y) - Q(a.y), vz = Q(c.z) - Q(a.z);
  const mpq_class wx = Q(d.x) - Q(a.x), wy = Q(d.y) - Q(a.y), wz = Q(d.z) - Q(a.z);
  const mpq_class det =
      ux * (vy * wz - vz * wy) + uy * (vz * wx - vx * wz) + uz * (vx * wy - vy * wx);
  return refSign(det);
}

/// Exact sign of (bx-ax)(cy-ay) - (by-ay)(cx-ax).
int refOrient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  const mpq_class det = (Q(bx) - Q(ax)) * (Q(cy) - Q(ay)) - (Q(by) - Q(ay)) * (Q(cx) - Q(ax));
  return refSign(det);
}

/// Counts of referee outcomes, so each test can assert that it really exercised all signs.
struct Tally {
  int pos = 0, neg = 0, zero = 0;
  void add(int s) { (s > 0 ? pos : (s < 0 ? neg : zero))++; }
};

/// Checks the filtered and the always-exact predicate against the referee for one 3D case and the
/// 2D predicate on the xy, yz and zx projections of (a, b, c) and of (a, b, d).
void checkCase(const V& a, const V& b, const V& c, const V& d, Tally* t3 = nullptr,
               Tally* t2 = nullptr) {
  const int r3 = refOrient3d(a, b, c, d);
  if (t3) t3->add(r3);
  ASSERT_EQ(orient3dSign(a, b, c, d), r3) << "a=" << a.x << "," << a.y << "," << a.z;
  ASSERT_EQ(orient3dSignExact(a, b, c, d), r3);
  // The short sums, where they decide.
  const int s3 = orient3dSignShort(a, b, c, d);
  if (s3 != kSignUnknown) ASSERT_EQ(s3, r3);
  // The filter alone (the GPU plane filter's test) may abstain (0) but never proves a wrong sign.
  const int f3 = orient3dFilterSign(a, b, c, d);
  if (f3 != 0) ASSERT_EQ(f3, r3);
  // The plane of (a, b, c) prepared once (the triangle test's form, and the GPU plane filter's):
  // the same exact sign, and a filter that never proves a wrong one.
  const auto plane = orientPlane(a, b, c);
  ASSERT_EQ(orient3dSign(plane, a, b, c, d), r3);
  const int fp = orient3dFilterSign(plane, d);
  if (fp != 0) ASSERT_EQ(fp, r3);
  // Permutation parity: swapping two rows flips the sign; a cyclic shift of (a,b,c,d) of an
  // orientation of 4 points flips it too (odd permutation of 4 elements).
  ASSERT_EQ(orient3dSign(b, a, c, d), -r3);
  ASSERT_EQ(orient3dSign(b, c, d, a), -r3);
  const V pts[4] = {a, b, c, d};
  for (int k = 0; k < 3; ++k) {
    const int i = k, j = (k + 1) % 3;
    for (int last = 2; last <= 3; ++last) {
      const double ax = pts[0][i], ay = pts[0][j], bx = pts[1][i], by = pts[1][j],
                   cx = pts[last][i], cy = pts[last][j];
      const int r2 = refOrient2d(ax, ay, bx, by, cx, cy);
      if (t2) t2->add(r2);
      ASSERT_EQ(orient2dSign(ax, ay, bx, by, cx, cy), r2);
      ASSERT_EQ(orient2dSignExact(ax, ay, bx, by, cx, cy), r2);
      ASSERT_EQ(orient2dSign(bx, by, ax, ay, cx, cy), -r2);
    }
  }
}

V offsetScale(const V& p, double offset, double scale) {
  return {offset + p.x * scale, offset + p.y * scale, offset + p.z * scale};
}

/// Whether P == offset + p * scale holds exactly (componentwise, in rationals).
bool exactlyOffsetScaled(const V& p, const V& P, double offset, double scale) {
  for (int k = 0; k < 3; ++k)
    if (Q(P[k]) != Q(offset) + Q(p[k]) * Q(scale)) return false;
  return true;
}

/// Offsets and scales the test families run at: far from the origin and tiny.
const double kOffsets[] = {0.0, 1e3, 1e5, 1e7, -3.5e7};
const double kScales[] = {1.0, 1e-6, 0x1p-20, 1e3};

TEST(Predicates, RandomPointsMatchReferee) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Tally t3, t2;
  for (double off : kOffsets) {
    for (double sc : kScales) {
      for (int it = 0; it < 400; ++it) {
        auto rp = [&] { return offsetScale(V{U(rng), U(rng), U(rng)}, off, sc); };
        checkCase(rp(), rp(), rp(), rp(), &t3, &t2);
        if (HasFatalFailure()) return;
      }
    }
  }
  EXPECT_GT(t3.pos, 1000);
  EXPECT_GT(t3.neg, 1000);
  EXPECT_GT(t2.pos, 1000);
  EXPECT_GT(t2.neg, 1000);
}

TEST(Predicates, ExactlyCoplanarAndCollinearAreZero) {
  // d = a + s(b-a) + t(c-a) with small integers: exactly representable, exactly coplanar, also
  // after adding a large integer offset or multiplying by a power of two. Collinear 2D triples are
  // built the same way with t = 0.
  std::mt19937_64 rng(777);
  std::uniform_int_distribution<int> I(-50, 50), S(-4, 4);
  const double offsets[] = {0.0, 1e3, 1e5, 1e7, -1e7};
  const double scales[] = {1.0, 0x1p-30, 0x1p40, 0x1p-200, 0x1p250};
  Tally t3, t2;
  int cases = 0;
  for (double off : offsets) {
    for (double sc : scales) {
      for (int it = 0; it < 300; ++it) {
        const V a{double(I(rng)), double(I(rng)), double(I(rng))};
        const V b{double(I(rng)), double(I(rng)), double(I(rng))};
        const V c{double(I(rng)), double(I(rng)), double(I(rng))};
        const double s = S(rng), t = S(rng);
        const V d = a + (b - a) * s + (c - a) * t;
        const V A = offsetScale(a, off, sc), B = offsetScale(b, off, sc),
                C = offsetScale(c, off, sc), D = offsetScale(d, off, sc);
        // Skip the combinations where offset + scale * integer is not representable (e.g. 1e7 with
        // 2^-30 steps); everything else is an exact construction.
        if (!exactlyOffsetScaled(a, A, off, sc) || !exactlyOffsetScaled(b, B, off, sc) ||
            !exactlyOffsetScaled(c, C, off, sc) || !exactlyOffsetScaled(d, D, off, sc)) {
          continue;
        }
        ASSERT_EQ(refOrient3d(A, B, C, D), 0);  // the construction is exact
        checkCase(A, B, C, D, &t3, &t2);
        if (HasFatalFailure()) return;
        // Collinear: c' = a + s(b-a).
        const V e = a + (b - a) * s;
        const V E = offsetScale(e, off, sc);
        if (!exactlyOffsetScaled(e, E, off, sc)) continue;
        for (int k = 0; k < 3; ++k) {
          const int j = (k + 1) % 3;
          ASSERT_EQ(refOrient2d(A[k], A[j], B[k], B[j], E[k], E[j]), 0);
          ASSERT_EQ(orient2dSign(A[k], A[j], B[k], B[j], E[k], E[j]), 0);
          ASSERT_EQ(orient2dSignExact(A[k], A[j], B[k], B[j], E[k], E[j]), 0);
        }
        ASSERT_EQ(orient3dSign(A, B, E, C), 0);  // collinear triple: any fourth point is coplanar
        ++cases;
      }
    }
  }
  EXPECT_GT(cases, 3000);
  EXPECT_GT(t3.zero, 3000);
}

TEST(Predicates, AxisAlignedPlanesAreZeroAndOneUlpOffIsNot) {
  // Points of an axis-aligned plane (one coordinate shared by all four, or by the three of an
  // orient2d): the exact zero without an expansion (sameCoordinate). Then the shared coordinate
  // of the last point moved by one ulp, where the shortcut must not fire and the sign is the
  // referee's; random doubles and floats at scales from tiny to large, against the referee.
  std::mt19937_64 rng(8080);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::uniform_int_distribution<int> K(0, 2);
  Tally zero3, moved3, moved2;
  for (double sc : {1.0, 1e-30, 1e30, 0x1p-200, 0x1p250}) {
    for (int it = 0; it < 400; ++it) {
      const bool floats = it % 2 == 1 && sc < 1e35 && sc > 1e-35;  // inside float's range
      auto coord = [&] {
        const double x = U(rng) * sc;
        return floats ? double(float(x)) : x;  // floats, converted exactly, or doubles
      };
      V p[4];
      for (V& q : p) q = {coord(), coord(), coord()};
      const int k = K(rng);
      const double shared = coord();
      for (V& q : p) q[k] = shared;
      const int r = refOrient3d(p[0], p[1], p[2], p[3]);
      ASSERT_EQ(r, 0);
      zero3.add(orient3dSign(p[0], p[1], p[2], p[3]));
      checkCase(p[0], p[1], p[2], p[3]);  // every orient2d projection too, one of them collinear
      if (HasFatalFailure()) return;
      // One ulp off the plane: not the shortcut's case any more.
      V d = p[3];
      d[k] = std::nextafter(d[k], (it & 4) ? INFINITY : -INFINITY);
      const int rd = refOrient3d(p[0], p[1], p[2], d);
      moved3.add(rd);
      ASSERT_EQ(orient3dSign(p[0], p[1], p[2], d), rd) << "it " << it << " sc " << sc;
      ASSERT_EQ(orient3dSign(orientPlane(p[0], p[1], p[2]), p[0], p[1], p[2], d), rd);
      // orient2d: three points on a line x = c (or y = c), then the third moved by one ulp.
      const int j = (k + 1) % 3;
      const double cx = std::nextafter(p[2][k], (it & 8) ? INFINITY : -INFINITY);
      ASSERT_EQ(orient2dSign(p[0][k], p[0][j], p[1][k], p[1][j], p[2][k], p[2][j]), 0);
      ASSERT_EQ(orient2dSign(p[0][j], p[0][k], p[1][j], p[1][k], p[2][j], p[2][k]), 0);
      const int r2 = refOrient2d(p[0][k], p[0][j], p[1][k], p[1][j], cx, p[2][j]);
      moved2.add(r2);
      ASSERT_EQ(orient2dSign(p[0][k], p[0][j], p[1][k], p[1][j], cx, p[2][j]), r2);
    }
  }
  EXPECT_EQ(zero3.zero, 2000);
  EXPECT_GT(moved3.pos, 500);
  EXPECT_GT(moved3.neg, 500);
  EXPECT_GT(moved2.pos + moved2.neg, 1500);
}

TEST(Predicates, OneUlpPerturbationsMatchReferee) {
  // Exactly coplanar points with one coordinate moved by one ulp up or down: the true sign is
  // nonzero (usually) but far below what the double evaluation can resolve.
  std::mt19937_64 rng(4242);
  std::uniform_int_distribution<int> I(-1000, 1000), S(-3, 3), W(0, 11);
  Tally t3, t2;
  int cases = 0;
  for (double off : kOffsets) {
    for (double sc : {1.0, 0x1p-20, 0x1p10}) {
      for (int it = 0; it < 300; ++it) {
        const V a{double(I(rng)), double(I(rng)), double(I(rng))};
        const V b{double(I(rng)), double(I(rng)), double(I(rng))};
        const V c{double(I(rng)), double(I(rng)), double(I(rng))};
        const V d = a + (b - a) * double(S(rng)) + (c - a) * double(S(rng));
        V P[4] = {offsetScale(a, off, sc), offsetScale(b, off, sc), offsetScale(c, off, sc),
                  offsetScale(d, off, sc)};
        // Perturb a nonzero coordinate: nextafter(0) is subnormal, outside the validity range.
        int which = W(rng);
        for (int tries = 0; tries < 12 && P[which / 3][which % 3] == 0; ++tries)
          which = (which + 1) % 12;
        double& coord = P[which / 3][which % 3];  // non-const Vec3::operator[] is a reference
        coord = std::nextafter(coord, (it & 1) ? INFINITY : -INFINITY);
        checkCase(P[0], P[1], P[2], P[3], &t3, &t2);
        if (HasFatalFailure()) return;
        ++cases;
      }
    }
  }
  EXPECT_GT(cases, 4000);
  EXPECT_GT(t3.pos, 500);
  EXPECT_GT(t3.neg, 500);
}

TEST(Predicates, Orient2dOneUlpFromCollinearMatchesReferee) {
  // Exactly collinear 2D triples (integers, offsets, power-of-two scales) with one coordinate moved
  // by one ulp, and triples rounded onto a line.
  std::mt19937_64 rng(2024);
  std::uniform_int_distribution<int> I(-1000, 1000), S(-5, 5), W(0, 5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Tally t2;
  for (double off : kOffsets) {
    for (double sc : {1.0, 0x1p-20, 1e-6}) {
      for (int it = 0; it < 400; ++it) {
        const double ax = off + sc * I(rng), ay = off + sc * I(rng);
        const double bx = off + sc * I(rng), by = off + sc * I(rng);
        const double s = (it & 2) ? double(S(rng)) : U(rng);
        double p[6] = {ax, ay, bx, by, ax + s * (bx - ax), ay + s * (by - ay)};
        if (it & 1) {
          int which = W(rng);
          for (int tries = 0; tries < 6 && p[which] == 0; ++tries) which = (which + 1) % 6;
          p[which] = std::nextafter(p[which], (it & 4) ? INFINITY : -INFINITY);
        }
        const int r = refOrient2d(p[0], p[1], p[2], p[3], p[4], p[5]);
        t2.add(r);
        ASSERT_EQ(orient2dSign(p[0], p[1], p[2], p[3], p[4], p[5]), r);
        ASSERT_EQ(orient2dSignExact(p[0], p[1], p[2], p[3], p[4], p[5]), r);
        ASSERT_EQ(orient2dSign(p[2], p[3], p[4], p[5], p[0], p[1]), r);  // cyclic invariance
      }
    }
  }
  EXPECT_GT(t2.zero, 500);
  EXPECT_GT(t2.pos, 500);
  EXPECT_GT(t2.neg, 500);
}

TEST(Predicates, NearCoplanarRoundedConstructionsMatchReferee) {
  // d = a + s(b-a) + t(c-a) with real s, t, evaluated in double: within a few ulps of the plane,
  // often exactly on it, and with mixed magnitudes (1e-6 .. 1e7) the coordinate differences are
  // not exact, so the exact path has to handle nonzero tails.
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Tally t3, t2;
  for (double off : kOffsets) {
    for (double sc : kScales) {
      for (int it = 0; it < 250; ++it) {
        const V a = offsetScale(V{U(rng), U(rng), U(rng)}, off, sc);
        // Mixed magnitude: b near the origin when a is far away.
        const V b = (it % 3 == 0) ? V{U(rng) * 1e-6, U(rng) * 1e-3, U(rng)}
                                  : offsetScale(V{U(rng), U(rng), U(rng)}, off, sc);
        const V c = offsetScale(V{U(rng), U(rng), U(rng)}, off, sc);
        const double s = U(rng), t = U(rng);
        const V d{a.x + s * (b.x - a.x) + t * (c.x - a.x), a.y + s * (b.y - a.y) + t * (c.y - a.y),
                  a.z + s * (b.z - a.z) + t * (c.z - a.z)};
        checkCase(a, b, c, d, &t3, &t2);
        if (HasFatalFailure()) return;
        // 2D: a point rounded onto the line ab.
        const double px = a.x + s * (b.x - a.x), py = a.y + s * (b.y - a.y);
        ASSERT_EQ(orient2dSign(a.x, a.y, b.x, b.y, px, py), refOrient2d(a.x, a.y, b.x, b.y, px, py));
      }
    }
  }
  EXPECT_GT(t3.pos, 200);
  EXPECT_GT(t3.neg, 200);
}

TEST(Predicates, ExtremeScalesInsideValidityRange) {
  // Coordinates near the ends of the documented range: random 53-bit mantissas at 2^-240 and 2^300,
  // with near-coplanar fourth points; mixed-exponent differences give long expansions.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Tally t3;
  for (double sc : {0x1p-240, 0x1p300, 0x1p-100, 0x1p100}) {
    for (int it = 0; it < 500; ++it) {
      auto rp = [&] { return V{U(rng) * sc, U(rng) * sc * 0x1p-20, U(rng) * sc}; };
      const V a = rp(), b = rp(), c = rp();
      const double s = U(rng), t = U(rng);
      const V d{a.x + s * (b.x - a.x) + t * (c.x - a.x), a.y + s * (b.y - a.y) + t * (c.y - a.y),
                a.z + s * (b.z - a.z) + t * (c.z - a.z)};
      checkCase(a, b, c, d, &t3, nullptr);
      if (HasFatalFailure()) return;
    }
  }
  EXPECT_GT(t3.pos + t3.neg, 100);
}

TEST(Predicates, WorstCaseTailsExactPath) {
  // Every coordinate difference has a nonzero tail (1 + tiny vs. large values), so the exact path
  // builds the longest expansions; compare the always-exact function with the referee, including
  // exactly-zero determinants obtained by repeating a point.
  std::mt19937_64 rng(31337);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::uniform_int_distribution<int> E(-40, 40);
  Tally t3;
  for (int it = 0; it < 3000; ++it) {
    auto coord = [&] { return std::ldexp(U(rng), E(rng)); };
    const V a{coord(), coord(), coord()}, b{coord(), coord(), coord()},
        c{coord(), coord(), coord()};
    V d{coord(), coord(), coord()};
    if (it % 10 == 0) d = b;  // exactly degenerate
    const int r = refOrient3d(a, b, c, d);
    t3.add(r);
    ASSERT_EQ(orient3dSignExact(a, b, c, d), r);
    ASSERT_EQ(orient3dSign(a, b, c, d), r);
    ASSERT_EQ(orient2dSignExact(a.x, a.y, b.x, b.y, c.x, c.y),
              refOrient2d(a.x, a.y, b.x, b.y, c.x, c.y));
  }
  EXPECT_GT(t3.zero, 200);
  EXPECT_GT(t3.pos, 500);
  EXPECT_GT(t3.neg, 500);
}

TEST(Predicates, SignConventions) {
  const V a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  // cross(b-a, c-a) = +z: a point above is positive.
  EXPECT_EQ(orient3dSign(a, b, c, V{0, 0, 1}), 1);
  EXPECT_EQ(orient3dSign(a, b, c, V{0.3, 0.3, -1e-300}), -1);
  EXPECT_EQ(orient3dSign(a, b, c, V{5, -7, 0}), 0);
  EXPECT_EQ(orient2dSign(0, 0, 1, 0, 0, 1), 1);   // counter-clockwise
  EXPECT_EQ(orient2dSign(0, 0, 0, 1, 1, 0), -1);  // clockwise
  EXPECT_EQ(orient2dSign(0, 0, 1, 1, 3, 3), 0);
  // toDouble is exact for floats.
  const Vec3<float> f{0.1f, -3.25f, 1e-30f};
  const V fd = kdet_fcl::detail::toDouble(f);
  EXPECT_EQ(fd.x, double(0.1f));
  EXPECT_EQ(fd.y, -3.25);
  EXPECT_EQ(fd.z, double(1e-30f));
}

TEST(Predicates, NonFiniteInputTerminates) {
  // Outside the validity range the answer is unspecified, but the call must terminate and return
  // a value in {-1, 0, 1}.
  const double bad[] = {INFINITY, -INFINITY, NAN, 1e308, 1e-320};
  for (double v : bad) {
    const int s3 = orient3dSign(V{v, 0, 0}, V{1, v, 0}, V{0, 1, v}, V{v, v, 1});
    EXPECT_TRUE(s3 >= -1 && s3 <= 1);
    const int s2 = orient2dSign(v, 0, 1, v, 0, 1);
    EXPECT_TRUE(s2 >= -1 && s2 <= 1);
  }
}

TEST(Predicates, FilterProvesFarSignsAndAbstainsNearThePlane) {
  // orient3dFilterSign proves the sign of clearly non-coplanar points and abstains on points one
  // ulp from a plane (where orient3dSign needs its exact fallback); checkCase() checks that a
  // proven sign always equals the referee's.
  std::mt19937_64 rng(777);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  int proven = 0, abstained = 0, proven_plane = 0, abstained_plane = 0;
  for (int it = 0; it < 2000; ++it) {
    const V a{U(rng), U(rng), U(rng)}, b{U(rng), U(rng), U(rng)}, c{U(rng), U(rng), U(rng)};
    const V far{U(rng), U(rng), U(rng)};
    checkCase(a, b, c, far);
    if (HasFatalFailure()) return;
    proven += orient3dFilterSign(a, b, c, far) != 0;
    proven_plane += orient3dFilterSign(orientPlane(a, b, c), far) != 0;
    // A point on the plane up to rounding, then one ulp off: the filter cannot resolve it.
    V near = a + (b - a) * 0.25 + (c - a) * 0.5;
    near.z = std::nextafter(near.z, (it & 1) ? INFINITY : -INFINITY);
    checkCase(a, b, c, near);
    if (HasFatalFailure()) return;
    abstained += orient3dFilterSign(a, b, c, near) == 0;
    abstained_plane += orient3dFilterSign(orientPlane(a, b, c), near) == 0;
  }
  EXPECT_GT(proven, 1900);
  EXPECT_GT(abstained, 1500);
  EXPECT_GT(proven_plane, 1900);
  EXPECT_GT(abstained_plane, 1500);
}

/// Whether every coordinate difference from a is exact in double (orient3dSignShort's first form).
bool exactDifferences(const V& a, const V& b, const V& c, const V& d) {
  for (const V* p : {&b, &c, &d})
    for (int k = 0; k < 3; ++k)
      if (Q((*p)[k] - a[k]) != Q((*p)[k]) - Q(a[k])) return false;
  return true;
}

bool floatPoint(const V& p) {
  return isFloatValue(p.x) && isFloatValue(p.y) && isFloatValue(p.z);
}

/// orient3dSignShort's two forms on near-coplanar points (near_coplanar_points.h): the sign it
/// proves is the referee's, exact zeros included, and it proves them all (checkCase also checks
/// every other predicate). First form: coordinates on a grid of 2^-30 (every difference exact).
/// Second form: floats on the plane z = x + y whose magnitudes differ by up to 2^60, so that
/// differences are not exact in double. Points of neither kind (doubles with inexact
/// differences) are left to the expansion.
TEST(Predicates, ShortSumsDecideNearCoplanarPointsOfBothForms) {
  using kdet_test::ShortForm;
  Tally grid, floats;
  int grid_cases = 0, float_cases = 0, inexact_float_cases = 0, it = 0;
  for (const kdet_test::NearCoplanarCase& k : kdet_test::nearCoplanarCases(3000, 2026)) {
    const V& a = k.p[0];
    const V& b = k.p[1];
    const V& c = k.p[2];
    const V& d = k.p[3];
    const int r = refOrient3d(a, b, c, d);
    switch (k.form) {
      case ShortForm::ExactDifferences:
        ASSERT_TRUE(exactDifferences(a, b, c, d));
        grid.add(r);
        ASSERT_EQ(orient3dSignShort(a, b, c, d), r) << "grid case " << it;
        ++grid_cases;
        break;
      case ShortForm::Floats:
        for (const V& p : k.p) ASSERT_TRUE(floatPoint(p));
        floats.add(r);
        ASSERT_EQ(orient3dSignShort(a, b, c, d), r) << "float case " << it;
        ++float_cases;
        inexact_float_cases += !exactDifferences(a, b, c, d);
        break;
      case ShortForm::Neither:
        ASSERT_FALSE(exactDifferences(a, b, c, d));
        ASSERT_EQ(orient3dSignShort(a, b, c, d), kSignUnknown) << "case " << it;
        break;
    }
    checkCase(a, b, c, d);
    if (HasFatalFailure()) return;
    ++it;
  }
  EXPECT_GT(grid.zero, grid_cases / 5);
  EXPECT_GT(grid.pos + grid.neg, grid_cases / 5);
  EXPECT_GT(floats.zero, float_cases / 5);
  EXPECT_GT(floats.pos + floats.neg, float_cases / 5);
  EXPECT_GT(inexact_float_cases, float_cases / 5);  // the second form really ran
  // Neither form: 1 + 2^-40 against 1e-30 has no exact difference and is no float.
  const V a{1e-30, 0, 0}, b{1 + 0x1p-40, 1, 0}, c{0, 1e-30, 1}, d{1, 1, 1};
  EXPECT_FALSE(exactDifferences(a, b, c, d));
  EXPECT_EQ(orient3dSignShort(a, b, c, d), kSignUnknown);
  checkCase(a, b, c, d);
}

/// The exact sum of doubles in rationals.
int refSumSign(const double* t, int n) {
  mpq_class sum = 0;
  for (int i = 0; i < n; ++i) sum += Q(t[i]);
  return refSign(sum);
}

/// sumSign: where it proves a sign, that of the exact sum; what one pass leaves, a second
/// decides; non-finite terms and overflow leave it undecided.
TEST(Predicates, SumSignProvesTheExactSumsSignOrAbstains) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::uniform_int_distribution<int> E(-60, 60);
  Tally tally;
  int decided = 0;
  for (int it = 0; it < 4000; ++it) {
    // Eleven random terms, their negations and two residues far below them (every third case
    // opposite), in a shuffled order: sums that cancel to zero or to a tiny value.
    double t[24];
    for (int i = 0; i < 11; ++i) t[i] = std::ldexp(U(rng), E(rng));
    for (int i = 0; i < 11; ++i) t[11 + i] = -t[i];
    t[22] = std::ldexp(U(rng), E(rng) - 60);
    t[23] = it % 3 == 0 ? -t[22] : std::ldexp(U(rng), E(rng) - 60);
    std::shuffle(std::begin(t), std::end(t), rng);
    const int r = refSumSign(t, 24);
    tally.add(r);
    double w[24];
    std::copy(std::begin(t), std::end(t), w);
    const int s = sumSign<24, 6>(w);
    if (s != kSignUnknown) {
      ++decided;
      ASSERT_EQ(s, r) << "case " << it;
    }
    ASSERT_EQ(refSumSign(w, 24), r) << "the passes changed the exact sum";
  }
  EXPECT_GT(tally.zero, 1000);
  EXPECT_GT(tally.pos + tally.neg, 2000);
  EXPECT_GT(decided, 3900);
  // One pass leaves {2^-60, 0, 0} (sum 2^-60 under a zero top), a second proves it.
  double one[3] = {1, 0x1p-60, -1};
  EXPECT_EQ((sumSign<3, 1>(one)), kSignUnknown);
  double two[3] = {1, 0x1p-60, -1};
  EXPECT_EQ((sumSign<3, 2>(two)), 1);
  double zero[4] = {0x1p80, -3, 3, -0x1p80};
  EXPECT_EQ((sumSign<4, 2>(zero)), 0);
  double nan[3] = {1, NAN, 2};
  EXPECT_EQ((sumSign<3, 4>(nan)), kSignUnknown);
  double big[2] = {1.7e308, 1.7e308};
  EXPECT_EQ((sumSign<2, 4>(big)), kSignUnknown);
}

}  // namespace
