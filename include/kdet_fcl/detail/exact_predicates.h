#pragma once
/// \file
/// Exact orientation predicates (orient2d / orient3d) for double coordinates, usable on the host
/// and on the device.
///
/// Each predicate first evaluates the determinant in plain double arithmetic together with a
/// conservative bound on its rounding error (a "floating-point filter"). When the computed value is
/// farther from zero than the bound, its sign is certainly right and is returned. Otherwise the
/// determinant is recomputed exactly as a floating-point expansion (a sum of non-overlapping
/// doubles, in the spirit of Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast
/// Robust Geometric Predicates", 1997) and the sign of that expansion is returned. For orient3d
/// a shorter exact evaluation comes first (orient3dSignShort: a fixed array of products split
/// exactly, summed by error-free passes); the expansion decides what it leaves.
///
/// Validity range (where the returned sign is the exact sign of the determinant of the given
/// doubles): every coordinate is either 0 or of magnitude in [2^-247, 2^330] (about [4.4e-75,
/// 2.2e99]). More precisely it suffices that every coordinate is an integer multiple of 2^-300 and
/// of magnitude at most 2^330: then every partial product of the exact evaluation is a multiple of
/// 2^-900 (no underflow can lose bits) and at most 2^993 (no overflow). Every float, converted to
/// double, is inside this range. Outside the range (and for inf/NaN) the functions still terminate,
/// never read or write out of bounds, and return some value in {-1, 0, +1}, but the sign may be
/// wrong.
///
/// Everything here is branch-light, loop-bounded, recursion-free and allocation-free so the same
/// code runs in CUDA kernels. The exact part uses only additions, subtractions and explicit fma
/// calls, so it gives bit-identical answers whether or not the compiler contracts a*b+c (the
/// filter's bound has slack for contraction too, see orient3dSign()).

#include <cmath>

#include "kdet_fcl/detail/host_device.h"
#include "kdet_fcl/vec3.h"

/// The exact fallbacks are large (a 192-component expansion, unrolled loops) and rarely run.
/// Under nvcc, KDET_HD_INLINE means __forceinline__, and force-inlining them at every predicate
/// call site multiplies device compile time (minutes for one kernel) and register pressure, so they
/// are kept out of line on the device. On the host `inline` keeps them ODR-safe in a header.
#if defined(__CUDACC__)
#define KDET_FCL_HD_NOINLINE __host__ __device__ __noinline__
#else
#define KDET_FCL_HD_NOINLINE inline
#endif

namespace kdet_fcl {
namespace detail {

/// The bounds of the validity range above: 2^-247 and 2^330. A mesh whose largest coordinate
/// magnitude lies outside [kExactMinMagnitude, kExactMaxMagnitude] (and is not 0) is refused by
/// TriangleMesh::validateForQueries() and by HashedMesh's vertex updates (src/coordinate_range.h):
/// at such scales the diameters' squares overflow or underflow, so the hierarchy's levels no
/// longer bound the cells a triangle covers (a query would enumerate up to 2^38 cells per axis),
/// and the predicates' signs are no longer exact.
constexpr double kExactMinMagnitude = 0x1p-247;
constexpr double kExactMaxMagnitude = 0x1p330;

/// Converts a point to double coordinates. Exact for float and double inputs (every float is a
/// double), which is what lets the exact predicates decide float geometry exactly.
template <class S>
KDET_HD_INLINE Vec3<double> toDouble(const Vec3<S>& p) {
  return {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)};
}

namespace exact {

/// Unit roundoff of double precision (half an ulp of 1), u = 2^-53.
constexpr double kUnitRoundoff = 1.1102230246251565404e-16;

/// Below this permanent the filter is not trusted: gradual underflow of the products could add
/// absolute errors that the relative error bound does not cover, so the exact path decides.
constexpr double kFilterMinPermanent = 1e-250;

/// Absolute value without <cmath> overload questions on the device.
KDET_HD_INLINE double absd(double a) { return a < 0 ? -a : a; }

/// The orient3d filter's verdict from a computed triple-product expansion and its permanent (the
/// same sum with every product taken in absolute value): +1 or -1 where the sign is proven, 0
/// where the exact path must decide. The bound and its validity range are argued at
/// orient3dFilterSign(); every orient3d filter shares them through this function.
KDET_HD_INLINE int orient3dFilterVerdict(double det, double permanent) {
  const double bound = 10.0 * kUnitRoundoff * permanent;
  if (permanent >= kFilterMinPermanent && permanent <= 1e308) {
    if (det > bound) return 1;
    if (-det > bound) return -1;
  }
  return 0;
}

/// Fused multiply-add a*b+c with a single rounding; exactness of twoProduct() depends on it, so it
/// must be a real fma (CUDA's fma and C++'s std::fma both are, never a contracted expression).
KDET_HD_INLINE double fmad(double a, double b, double c) {
#if defined(__CUDA_ARCH__)
  return ::fma(a, b, c);
#else
  return std::fma(a, b, c);
#endif
}

/// Knuth's TwoSum: s + e == a + b exactly, with s = fl(a + b) (valid for any finite a, b whose sum
/// does not overflow). Branch-free, so it does not need |a| >= |b|.
KDET_HD_INLINE void twoSum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bv = s - a;   // the part of b that made it into s
  const double av = s - bv;  // the part of a that made it into s
  e = (a - av) + (b - bv);
}

/// TwoDiff: s + e == a - b exactly, with s = fl(a - b).
KDET_HD_INLINE void twoDiff(double a, double b, double& s, double& e) { twoSum(a, -b, s, e); }

/// TwoProduct via fma: p + e == a * b exactly, with p = fl(a * b), as long as the product neither
/// overflows nor underflows (guaranteed inside the documented validity range).
KDET_HD_INLINE void twoProduct(double a, double b, double& p, double& e) {
  p = a * b;
  e = fmad(a, b, -p);
}

/// A non-overlapping expansion with a fixed capacity N, components stored in increasing order of
/// magnitude, zeros eliminated. Its value is the exact sum of the components.
template <int N>
struct Expansion {
  double c[N];
  int n = 0;

  /// Adds the double b exactly (Shewchuk's Grow-Expansion with zero elimination). The result stays
  /// non-overlapping and sorted and grows by at most one component; when the capacity would be
  /// exceeded (impossible for the callers below, which size N for their worst case) the new
  /// component is folded into the most significant one instead of writing past the end, so the
  /// function can never write out of bounds.
  KDET_HD_INLINE void add(double b) {
    if (b == 0) return;
    double q = b;
    int out = 0;
    for (int i = 0; i < n; ++i) {
      double s, e;
      twoSum(q, c[i], s, e);
      q = s;
      if (e != 0) c[out++] = e;  // out <= i, so this never overtakes the read position
    }
    if (q != 0) {
      if (out < N) {
        c[out++] = q;
      } else {
        c[N - 1] += q;  // unreachable for correctly sized N; keeps memory safety unconditional
      }
    }
    n = out;
  }

  /// Adds the exact product a*b (two components).
  KDET_HD_INLINE void addProduct(double a, double b) {
    if (a == 0 || b == 0) return;
    double p, e;
    twoProduct(a, b, p, e);
    add(e);
    add(p);
  }

  /// Adds the exact product sign*a*b*d (four components): a*b = p + e exactly, then p*d and e*d
  /// are each split exactly again.
  KDET_HD_INLINE void addTripleProduct(double a, double b, double d, double sign) {
    if (a == 0 || b == 0 || d == 0) return;
    double p, e;
    twoProduct(a, b, p, e);
    double p1, e1;
    twoProduct(p, d, p1, e1);
    add(sign * e1);
    add(sign * p1);
    if (e != 0) {
      double p2, e2;
      twoProduct(e, d, p2, e2);
      add(sign * e2);
      add(sign * p2);
    }
  }

  /// The sign of the exact value: for a non-overlapping expansion the most significant nonzero
  /// component dominates the sum of all the others. NaN components (outside the validity range)
  /// give 0.
  KDET_HD_INLINE int sign() const {
    if (n == 0) return 0;
    const double top = c[n - 1];
    return top > 0 ? 1 : (top < 0 ? -1 : 0);
  }
};

/// The exact sign of (bx-ax)*(cy-ay) - (by-ay)*(cx-ax), always by the exact expansion path.
/// Exposed for tests and as a reference; prefer orient2dSign(), which filters first.
KDET_FCL_HD_NOINLINE int orient2dSignExact(double ax, double ay, double bx, double by, double cx,
                                     double cy) {
  // Each difference is an exact 2-term expansion (head h, tail t).
  double uxh, uxt, uyh, uyt, vxh, vxt, vyh, vyt;
  twoDiff(bx, ax, uxh, uxt);
  twoDiff(by, ay, uyh, uyt);
  twoDiff(cx, ax, vxh, vxt);
  twoDiff(cy, ay, vyh, vyt);
  const double ux[2] = {uxh, uxt}, uy[2] = {uyh, uyt}, vx[2] = {vxh, vxt}, vy[2] = {vyh, vyt};
  // Worst case: 2 products * 4 head/tail combinations * 2 components = 16 terms, and
  // Grow-Expansion adds at most one component per term.
  Expansion<16> acc;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      acc.addProduct(ux[i], vy[j]);
      acc.addProduct(-uy[i], vx[j]);
    }
  }
  return acc.sign();
}

/// The exact sign of det[b-a; c-a; d-a], always by the exact expansion path.
/// Exposed for tests and as a reference; prefer orient3dSign(), which filters first.
KDET_FCL_HD_NOINLINE int orient3dSignExact(const Vec3<double>& a, const Vec3<double>& b,
                                     const Vec3<double>& c, const Vec3<double>& d) {
  // Rows u = b-a, v = c-a, w = d-a; each entry an exact 2-term expansion m[row][col][head/tail].
  double m[3][3][2];
  const Vec3<double>* rows[3] = {&b, &c, &d};
  for (int r = 0; r < 3; ++r) {
    twoDiff(rows[r]->x, a.x, m[r][0][0], m[r][0][1]);
    twoDiff(rows[r]->y, a.y, m[r][1][0], m[r][1][1]);
    twoDiff(rows[r]->z, a.z, m[r][2][0], m[r][2][1]);
  }
  // Leibniz expansion: det = sum over the 6 permutations s of sgn(s) * m0[s0] m1[s1] m2[s2].
  const int perm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {1, 0, 2}, {2, 1, 0}};
  const double psign[6] = {1, 1, 1, -1, -1, -1};
  // Worst case: 6 permutations * 8 head/tail combinations * 4 components = 192 terms, and
  // Grow-Expansion adds at most one component per term. Heads are added last so that, when the
  // tails are zero (the common case), the expansion stays short.
  Expansion<192> acc;
  for (int combo = 7; combo >= 0; --combo) {
    const int i = (combo >> 2) & 1, j = (combo >> 1) & 1, k = combo & 1;
    for (int s = 0; s < 6; ++s) {
      acc.addTripleProduct(m[0][perm[s][0]][i], m[1][perm[s][1]][j], m[2][perm[s][2]][k],
                           psign[s]);
    }
  }
  return acc.sign();
}

/// The answer of sumSign and orient3dSignShort where they cannot tell the sign (only the
/// expansion can).
constexpr int kSignUnknown = 2;

/// The exact sign of t[0] + ... + t[N-1] (doubles in any order, overlapping or not) where at most
/// kPasses error-free passes prove it, else kSignUnknown; t is overwritten by terms of the same
/// exact sum. A pass (VecSum of Ogita, Rump and Oishi, "Accurate sum and dot product", 2005) runs
/// TwoSum up the array: t[i] becomes the rounded sum of t[i] and t[i-1], t[i-1] its rounding
/// error. The exact sum never changes, and t[N-1] tends to it. The sign is proven when the rest
/// are all zero (the sum is t[N-1], zero included), or when |t[N-1]| exceeds twice the rest's
/// magnitudes summed in floating point. That computed sum of N-1 non-negative terms is at least
/// (1 - (N-2)u) times the exact one, so twice it bounds the rest for any N below 2^50. Fixed-size
/// and unrolled, so that on the device the terms stay in registers. A term that overflows, or a
/// non-finite one, leaves the sign undecided.
template <int N, int kPasses>
KDET_HD_INLINE int sumSign(double (&t)[N]) {
  for (int pass = 0; pass < kPasses; ++pass) {
    KDET_UNROLL
    for (int i = 1; i < N; ++i) twoSum(t[i], t[i - 1], t[i], t[i - 1]);
    double rest = 0;
    KDET_UNROLL
    for (int i = 0; i < N - 1; ++i) rest += absd(t[i]);
    const double top = t[N - 1];
    if (rest == 0) return top > 0 ? 1 : (top < 0 ? -1 : 0);
    if (absd(top) > 2 * rest) return top > 0 ? 1 : -1;
  }
  return kSignUnknown;
}

/// t[at], t[at + 1]: sign * x * y * z split exactly into two doubles, for x, y and z floats (their
/// product x * y has at most 48 bits, exact in double; TwoProduct splits the rest).
template <int N>
KDET_HD_INLINE void floatTripleTerms(double (&t)[N], int at, double x, double y, double z,
                                     double sign) {
  double h, l;
  twoProduct(x * y, z, h, l);
  t[at] = sign * l;
  t[at + 1] = sign * h;
}

/// t[at .. at + 3]: sign * x * y * z split exactly into four doubles (y * z = p + e, then x * p
/// and x * e each by TwoProduct).
template <int N>
KDET_HD_INLINE void tripleTerms(double (&t)[N], int at, double x, double y, double z,
                                double sign) {
  double p, e, h1, l1, h2, l2;
  twoProduct(y, z, p, e);
  twoProduct(x, p, h1, l1);
  twoProduct(x, e, h2, l2);
  t[at] = sign * l2;
  t[at + 1] = sign * l1;
  t[at + 2] = sign * h2;
  t[at + 3] = sign * h1;
}

/// Whether the double x is a float's value (finite; the range test first, as converting a
/// double beyond float's range is undefined).
KDET_HD_INLINE bool isFloatValue(double x) {
  return absd(x) <= 3.4028234663852886e38 && static_cast<double>(static_cast<float>(x)) == x;
}

/// The exact sign of det[b-a; c-a; d-a] by short sums of exact products where they prove it, else
/// kSignUnknown (orient3dSignExact decides then). Two forms:
/// - every coordinate difference exact in double (no TwoDiff tail; always so for floats whose
///   exponents differ by less than 29): the determinant's six triple products of the differences,
///   each split exactly into four doubles (tripleTerms), summed by sumSign: 24 terms;
/// - else, every coordinate a float: the same determinant as the 4x4 determinant of the points
///   with a column of ones, det3(b, c, d) - det3(a, c, d) + det3(a, b, d) - det3(a, b, c) for
///   det3(p, q, r) = p . (q x r), with no difference taken: 24 triple products of floats, each two
///   doubles (floatTripleTerms): 48 terms.
/// On the device the expansion (a 192-component array in local memory, grown one term at a time
/// through long dependent chains) made a few pairs' exact tests the exact kernel's whole time;
/// these sums stay in registers. Out of line on the device, as the expansion is.
KDET_FCL_HD_NOINLINE int orient3dSignShort(const Vec3<double>& a, const Vec3<double>& b,
                                           const Vec3<double>& c, const Vec3<double>& d) {
  double ux, uy, uz, vx, vy, vz, wx, wy, wz, r[9];
  twoDiff(b.x, a.x, ux, r[0]);
  twoDiff(b.y, a.y, uy, r[1]);
  twoDiff(b.z, a.z, uz, r[2]);
  twoDiff(c.x, a.x, vx, r[3]);
  twoDiff(c.y, a.y, vy, r[4]);
  twoDiff(c.z, a.z, vz, r[5]);
  twoDiff(d.x, a.x, wx, r[6]);
  twoDiff(d.y, a.y, wy, r[7]);
  twoDiff(d.z, a.z, wz, r[8]);
  bool exact_differences = true;
  KDET_UNROLL
  for (int i = 0; i < 9; ++i) exact_differences = exact_differences && r[i] == 0;
  if (exact_differences) {
    double t[24];
    tripleTerms(t, 0, ux, vy, wz, 1);
    tripleTerms(t, 4, ux, vz, wy, -1);
    tripleTerms(t, 8, uy, vz, wx, 1);
    tripleTerms(t, 12, uy, vx, wz, -1);
    tripleTerms(t, 16, uz, vx, wy, 1);
    tripleTerms(t, 20, uz, vy, wx, -1);
    return sumSign<24, 3>(t);
  }
  const Vec3<double>* const p[4] = {&a, &b, &c, &d};
  bool floats = true;
  KDET_UNROLL
  for (int i = 0; i < 4; ++i)
    floats = floats && isFloatValue(p[i]->x) && isFloatValue(p[i]->y) && isFloatValue(p[i]->z);
  if (!floats) return kSignUnknown;
  double t[48];
  // det3(p, q, r) with the given sign, 12 terms from t[at].
  const auto det3 = [&t](int at, const Vec3<double>& P, const Vec3<double>& Q,
                         const Vec3<double>& R, double sign) {
    floatTripleTerms(t, at, P.x, Q.y, R.z, sign);
    floatTripleTerms(t, at + 2, P.x, Q.z, R.y, -sign);
    floatTripleTerms(t, at + 4, P.y, Q.z, R.x, sign);
    floatTripleTerms(t, at + 6, P.y, Q.x, R.z, -sign);
    floatTripleTerms(t, at + 8, P.z, Q.x, R.y, sign);
    floatTripleTerms(t, at + 10, P.z, Q.y, R.x, -sign);
  };
  det3(0, b, c, d, 1);
  det3(12, a, c, d, -1);
  det3(24, a, b, d, 1);
  det3(36, a, b, c, -1);
  return sumSign<48, 4>(t);
}

}  // namespace exact

/// The exact sign (-1, 0, +1) of (bx-ax)*(cy-ay) - (by-ay)*(cx-ax): +1 when a, b, c turn
/// counter-clockwise. Exact inside the validity range documented at the top of this file.
KDET_HD_INLINE int orient2dSign(double ax, double ay, double bx, double by, double cx, double cy) {
  const double l = (bx - ax) * (cy - ay);
  const double r = (by - ay) * (cx - ax);
  const double det = l - r;
  const double permanent = exact::absd(l) + exact::absd(r);
  // Error bound: each of the two products passes through at most 4 roundings (its two input
  // differences, the product, the subtraction), so |computed - exact| <= gamma_4 times the exact
  // permanent, and the computed permanent is within a factor (1 +- u)^4 of the exact one.
  // Shewchuk's sharper analysis gives (3u + 16u^2) * permanent; we use 6u, which also covers fma
  // contraction (fewer roundings) and the rounding of the bound itself. Inside the validity range
  // nothing underflows; the minimum-permanent test is extra safety outside it.
  // `permanent <= 1e308` is false for inf and NaN, so non-finite values fall through.
  const double bound = 6.0 * exact::kUnitRoundoff * permanent;
  if (permanent >= exact::kFilterMinPermanent && permanent <= 1e308) {
    if (det > bound) return 1;
    if (-det > bound) return -1;
  }
  // Three points equal in one coordinate: each product has a zero factor, the value is exactly 0
  // (as for the projections of a triangle in an axis-aligned plane), with no expansion.
  if ((ax == bx && bx == cx) || (ay == by && by == cy)) return 0;
  return exact::orient2dSignExact(ax, ay, bx, by, cx, cy);
}

/// The floating-point filter of orient3dSign() alone: +1 or -1 when it proves the sign of
/// det[b-a; c-a; d-a] (then that is the exact sign), 0 when it cannot (orient3dSign would fall
/// back to expansion arithmetic). For callers that only act on proven signs, such as the GPU's
/// plane filter, which drops a candidate pair only where the exact test would reject it.
KDET_HD_INLINE int orient3dFilterSign(const Vec3<double>& a, const Vec3<double>& b,
                                      const Vec3<double>& c, const Vec3<double>& d) {
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
  const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  const double wx = d.x - a.x, wy = d.y - a.y, wz = d.z - a.z;
  const double vywz = vy * wz, vzwy = vz * wy;
  const double vzwx = vz * wx, vxwz = vx * wz;
  const double vxwy = vx * wy, vywx = vy * wx;
  const double det = ux * (vywz - vzwy) + uy * (vzwx - vxwz) + uz * (vxwy - vywx);
  const double permanent = exact::absd(ux) * (exact::absd(vywz) + exact::absd(vzwy)) +
                           exact::absd(uy) * (exact::absd(vzwx) + exact::absd(vxwz)) +
                           exact::absd(uz) * (exact::absd(vxwy) + exact::absd(vywx));
  // Error bound: each of the six triple products passes through at most 8 roundings (3 input
  // differences, 2 products, 1 subtraction, 2 additions), so |computed - exact| <= gamma_8 times
  // the exact permanent, and the computed permanent is within (1 +- u)^8 of the exact one.
  // Shewchuk's sharper analysis gives (7u + 56u^2) * permanent; we use 10u, which also covers fma
  // contraction (fewer roundings) and the rounding of the bound. Inside the validity range no
  // product underflows; tiny permanents (possible underflow outside it) and non-finite values go to
  // the exact path anyway.
  return exact::orient3dFilterVerdict(det, permanent);
}

/// The plane of a triangle (a, b, c), prepared for the orientation of many points against it:
/// n = cross(b - a, c - a), and per component the sum of the absolute values of its two products
/// (the plane's share of orient3dFilterSign's permanent). Then the filter costs six products per
/// point instead of fifteen. The triangle test evaluates six points against two planes this way.
struct OrientPlane {
  double ax, ay, az;  // a
  double nx, ny, nz;  // cross(b - a, c - a)
  double mx, my, mz;  // |uy vz| + |uz vy|, |uz vx| + |ux vz|, |ux vy| + |uy vx| (u = b-a, v = c-a)
};

KDET_HD_INLINE OrientPlane orientPlane(const Vec3<double>& a, const Vec3<double>& b,
                                       const Vec3<double>& c) {
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
  const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  const double uyvz = uy * vz, uzvy = uz * vy;
  const double uzvx = uz * vx, uxvz = ux * vz;
  const double uxvy = ux * vy, uyvx = uy * vx;
  return {a.x,
          a.y,
          a.z,
          uyvz - uzvy,
          uzvx - uxvz,
          uxvy - uyvx,
          exact::absd(uyvz) + exact::absd(uzvy),
          exact::absd(uzvx) + exact::absd(uxvz),
          exact::absd(uxvy) + exact::absd(uyvx)};
}

/// orient3dFilterSign(a, b, c, d) for the prepared plane of (a, b, c): +1 or -1 only where that is
/// the exact sign of det[b-a; c-a; d-a], 0 where the filter cannot tell. The determinant is the
/// same scalar triple product expanded along d - a instead of b - a (w . (u x v) = u . (v x w)),
/// so the same error analysis holds term by term: each of the six triple products passes through
/// at most 8 roundings (3 input differences, 2 products, 1 subtraction, 2 additions), and the
/// bound 10u * permanent covers them, fma contraction and the bound's own rounding, as in
/// orient3dFilterSign. The proven signs of the two filters are therefore both exact; they may
/// abstain on different near-coplanar inputs, which only changes who falls back to the exact path.
KDET_HD_INLINE int orient3dFilterSign(const OrientPlane& p, const Vec3<double>& d) {
  const double wx = d.x - p.ax, wy = d.y - p.ay, wz = d.z - p.az;
  const double det = wx * p.nx + wy * p.ny + wz * p.nz;
  const double permanent =
      exact::absd(wx) * p.mx + exact::absd(wy) * p.my + exact::absd(wz) * p.mz;
  return exact::orient3dFilterVerdict(det, permanent);
}

/// Whether the four points are equal in one coordinate: then that column of det[b-a; c-a; d-a] is
/// zero and the determinant exactly 0. Checked where the filter cannot tell, before any expansion:
/// points of an axis-aligned plane (a cloth lying on a floor) are where exact zeros come from in
/// practice (every one of the cloth ball's undecided candidate pairs, benchmarks/RESULTS-gpu.md).
KDET_HD_INLINE bool sameCoordinate(const Vec3<double>& a, const Vec3<double>& b,
                                   const Vec3<double>& c, const Vec3<double>& d) {
  return (a.x == b.x && b.x == c.x && c.x == d.x) || (a.y == b.y && b.y == c.y && c.y == d.y) ||
         (a.z == b.z && b.z == c.z && c.z == d.z);
}

/// Whether the sign of det[b-a; c-a; d-a] is known without exact arithmetic, and then that sign
/// in `s`: proven by orient3dFilterSign, or the exact 0 of four points equal in one coordinate
/// (sameCoordinate). For callers that act on known signs only (the plane filter's last step,
/// trianglesFilterVerdict).
KDET_HD_INLINE bool orient3dKnownSign(const Vec3<double>& a, const Vec3<double>& b,
                                      const Vec3<double>& c, const Vec3<double>& d, int& s) {
  s = orient3dFilterSign(a, b, c, d);
  return s != 0 || sameCoordinate(a, b, c, d);
}

/// The exact sign of det[b-a; c-a; d-a] where a filter could not prove it: 0 for four points
/// equal in one coordinate, else by the short sums (exact::orient3dSignShort) or, where they leave
/// it, the expansion.
KDET_HD_INLINE int orient3dSignUnfiltered(const Vec3<double>& a, const Vec3<double>& b,
                                          const Vec3<double>& c, const Vec3<double>& d) {
  if (sameCoordinate(a, b, c, d)) return 0;
  const int s = exact::orient3dSignShort(a, b, c, d);
  return s != exact::kSignUnknown ? s : exact::orient3dSignExact(a, b, c, d);
}

/// The exact sign (-1, 0, +1) of det[b-a; c-a; d-a] (rows) = dot(cross(b-a, c-a), d-a): positive
/// when d lies on the side of the plane (a, b, c) that cross(b-a, c-a) points to. Exact inside the
/// validity range documented at the top of this file.
KDET_HD_INLINE int orient3dSign(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c,
                                const Vec3<double>& d) {
  const int s = orient3dFilterSign(a, b, c, d);
  return s != 0 ? s : orient3dSignUnfiltered(a, b, c, d);
}

/// orient3dSign(a, b, c, d) with the plane of (a, b, c) prepared by orientPlane(a, b, c): the same
/// exact sign, the filter's products shared between the points of one plane.
KDET_HD_INLINE int orient3dSign(const OrientPlane& plane, const Vec3<double>& a,
                                const Vec3<double>& b, const Vec3<double>& c,
                                const Vec3<double>& d) {
  const int s = orient3dFilterSign(plane, d);
  return s != 0 ? s : orient3dSignUnfiltered(a, b, c, d);
}

}  // namespace detail
}  // namespace kdet_fcl
