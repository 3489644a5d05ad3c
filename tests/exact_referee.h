#pragma once
// An exact-arithmetic referee for closed triangle-triangle intersection and for whole pair sets,
// written independently of the library's predicate (detail/triangle_intersection.h): it shares no
// code and no case analysis with it. Used by tests/test_extremes.cpp and the fuzz targets.
//
// Method. The six points (double coordinates; every float is a double) are scaled by one common
// power of two into integers (GMP mpz: exact, and faster than rationals), which preserves every
// sign below. Two compact convex sets P and Q are disjoint iff some axis a strictly separates
// them: max_P a.p < min_Q a.q or the converse. For two non-degenerate triangles the 17 classic
// axes suffice: both normals, the 9 edge-edge cross products and the 6 in-plane edge normals
// (n x e, needed when the triangles are coplanar). For degenerate triangles (segments, points)
// the referee uses a larger set derived from the Minkowski difference D = P - Q, whose facets
// and edges are spanned by the edge directions E of P and Q: the facet normals e_i x e_j, the
// in-plane edge normals (e_i x e_j) x e_k for a planar D, the directions e themselves and the
// perpendiculars (e x w) x e for a segment D (w = q - p ranges over vertex differences), and w
// itself for a point D. Whatever the dimension of D, one of these separates when 0 is not in D.
// Extra axes are harmless: any strict separation proves disjointness.

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "kdet_fcl/query.h"
#include "kdet_fcl/triangle_mesh.h"
#include "kdet_fcl/vec3.h"

namespace kdet_referee {

using P3 = kdet_fcl::Vec3<double>;
using Tri = std::array<P3, 3>;

struct ZV {
  mpz_class x, y, z;
};
inline ZV sub(const ZV& a, const ZV& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline ZV crossZ(const ZV& a, const ZV& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline mpz_class dotZ(const ZV& a, const ZV& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline bool isZero(const ZV& a) { return sgn(a.x) == 0 && sgn(a.y) == 0 && sgn(a.z) == 0; }

/// The six points as integers under one common positive power-of-two scale (exact).
inline void toIntegers(const Tri& P, const Tri& Q, ZV out[6]) {
  std::int64_t m[18];
  int e[18];
  int emin = INT_MAX;
  for (int i = 0; i < 18; ++i) {
    const P3& p = (i < 9 ? P[i / 3] : Q[(i - 9) / 3]);
    const double v = p[i % 3];
    if (v == 0) {
      m[i] = 0;
      e[i] = 0;
      continue;
    }
    int E = 0;
    const double f = std::frexp(v, &E);  // v = f * 2^E, |f| in [0.5, 1): f * 2^53 is an integer
    m[i] = static_cast<std::int64_t>(std::ldexp(f, 53));
    e[i] = E - 53;
    emin = std::min(emin, e[i]);
  }
  if (emin == INT_MAX) emin = 0;
  mpz_class c[18];
  for (int i = 0; i < 18; ++i) {
    c[i] = static_cast<long>(m[i]);
    if (m[i] != 0) mpz_mul_2exp(c[i].get_mpz_t(), c[i].get_mpz_t(), mp_bitcnt_t(e[i] - emin));
  }
  for (int k = 0; k < 6; ++k) out[k] = {c[3 * k], c[3 * k + 1], c[3 * k + 2]};
}

/// Whether `a` strictly separates the point sets p[0..np) and q[0..nq).
inline bool separates(const ZV& a, const ZV* p, const ZV* q) {
  if (isZero(a)) return false;
  mpz_class pmin = dotZ(a, p[0]), pmax = pmin, qmin = dotZ(a, q[0]), qmax = qmin;
  for (int i = 1; i < 3; ++i) {
    const mpz_class dp = dotZ(a, p[i]), dq = dotZ(a, q[i]);
    if (dp < pmin) pmin = dp;
    if (dp > pmax) pmax = dp;
    if (dq < qmin) qmin = dq;
    if (dq > qmax) qmax = dq;
  }
  return pmax < qmin || qmax < pmin;
}

/// Whether one axis of the general set (see the file comment) strictly separates p and q.
inline bool separatedByGeneralAxes(const ZV* p, const ZV* q) {
  std::vector<ZV> E;  // edge directions of both
  for (int i = 0; i < 3; ++i) {
    const ZV a = sub(p[(i + 1) % 3], p[i]), b = sub(q[(i + 1) % 3], q[i]);
    if (!isZero(a)) E.push_back(a);
    if (!isZero(b)) E.push_back(b);
  }
  std::vector<ZV> W;  // vertex differences: the points whose hull is D
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) W.push_back(sub(q[j], p[i]));
  for (const ZV& w : W)
    if (separates(w, p, q)) return true;
  for (const ZV& e : E) {
    if (separates(e, p, q)) return true;
    for (const ZV& w : W)
      if (separates(crossZ(crossZ(e, w), e), p, q)) return true;
  }
  for (std::size_t i = 0; i < E.size(); ++i)
    for (std::size_t j = i + 1; j < E.size(); ++j) {
      const ZV c = crossZ(E[i], E[j]);
      if (isZero(c)) continue;
      if (separates(c, p, q)) return true;
      for (const ZV& e : E)
        if (separates(crossZ(c, e), p, q)) return true;
    }
  return false;
}

/// Exact closed intersection of two triangles, degenerate ones included (see the file comment).
inline bool trianglesMeet(const Tri& P, const Tri& Q) {
  // Exact box rejection first (comparisons of doubles are exact): cheap and always sound.
  for (int k = 0; k < 3; ++k) {
    const double plo = std::min({P[0][k], P[1][k], P[2][k]}), phi = std::max({P[0][k], P[1][k], P[2][k]});
    const double qlo = std::min({Q[0][k], Q[1][k], Q[2][k]}), qhi = std::max({Q[0][k], Q[1][k], Q[2][k]});
    if (phi < qlo || qhi < plo) return false;
  }
  ZV z[6];
  toIntegers(P, Q, z);
  const ZV* p = z;
  const ZV* q = z + 3;
  const ZV ep[3] = {sub(p[1], p[0]), sub(p[2], p[1]), sub(p[0], p[2])};
  const ZV eq[3] = {sub(q[1], q[0]), sub(q[2], q[1]), sub(q[0], q[2])};
  const ZV np = crossZ(ep[0], ep[1]), nq = crossZ(eq[0], eq[1]);
  if (!isZero(np) && !isZero(nq)) {
    // The 17 axes of two proper triangles.
    if (separates(np, p, q) || separates(nq, p, q)) return false;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (separates(crossZ(ep[i], eq[j]), p, q)) return false;
    for (int i = 0; i < 3; ++i)
      if (separates(crossZ(np, ep[i]), p, q) || separates(crossZ(nq, eq[i]), p, q)) return false;
    return true;
  }
  // At least one is a segment or a point: the general axis set of the Minkowski difference.
  return !separatedByGeneralAxes(p, q);
}

/// The general axis set on any pair (the tests cross-check it against the 17-axis path).
inline bool trianglesMeetGeneral(const Tri& P, const Tri& Q) {
  ZV z[6];
  toIntegers(P, Q, z);
  return !separatedByGeneralAxes(z, z + 3);
}

// ------------------------------------------------------------------ pair sets

struct Box {
  double lo[3], hi[3];
};

template <class S>
Tri triangleOf(const std::vector<kdet_fcl::Vec3<S>>& v, const kdet_fcl::Triangle& t) {
  Tri r;
  for (int k = 0; k < 3; ++k) r[k] = {double(v[t[k]].x), double(v[t[k]].y), double(v[t[k]].z)};
  return r;
}

inline Box boxOf(const Tri& t) {
  Box b;
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = std::min({t[0][k], t[1][k], t[2][k]});
    b.hi[k] = std::max({t[0][k], t[1][k], t[2][k]});
  }
  return b;
}

inline bool boxesMeet(const Box& a, const Box& b) {
  for (int k = 0; k < 3; ++k)
    if (a.hi[k] < b.lo[k] || b.hi[k] < a.lo[k]) return false;
  return true;
}

/// Calls fn(i, j) for every (i in A, j in B) whose closed boxes overlap: sweep along x over the
/// boxes sorted by their lower x bound (an independent broad phase, no hashing).
template <class Fn>
void forEachBoxOverlap(const std::vector<Box>& A, const std::vector<Box>& B, Fn&& fn) {
  struct Ev {
    double lo;
    std::uint32_t id;
    bool fromA;
  };
  std::vector<Ev> ev;
  ev.reserve(A.size() + B.size());
  for (std::size_t i = 0; i < A.size(); ++i) ev.push_back({A[i].lo[0], std::uint32_t(i), true});
  for (std::size_t j = 0; j < B.size(); ++j) ev.push_back({B[j].lo[0], std::uint32_t(j), false});
  std::sort(ev.begin(), ev.end(), [](const Ev& a, const Ev& b) {
    return a.lo != b.lo ? a.lo < b.lo : (a.fromA != b.fromA ? a.fromA : a.id < b.id);
  });
  std::vector<std::uint32_t> activeA, activeB;
  for (const Ev& e : ev) {
    const Box& me = e.fromA ? A[e.id] : B[e.id];
    auto& other = e.fromA ? activeB : activeA;
    const auto& otherBoxes = e.fromA ? B : A;
    // Drop boxes that end before this one starts (they cannot meet anything later either).
    other.erase(std::remove_if(other.begin(), other.end(),
                               [&](std::uint32_t k) { return otherBoxes[k].hi[0] < me.lo[0]; }),
                other.end());
    for (std::uint32_t k : other)
      if (boxesMeet(me, otherBoxes[k])) e.fromA ? fn(e.id, k) : fn(k, e.id);
    (e.fromA ? activeA : activeB).push_back(e.id);
  }
}

/// Every intersecting (i of A, j of B), sorted; A's vertices already in B's frame.
template <class S>
std::vector<kdet_fcl::TrianglePair> meshPairs(const std::vector<kdet_fcl::Vec3<S>>& va,
                                              const std::vector<kdet_fcl::Triangle>& ta,
                                              const std::vector<kdet_fcl::Vec3<S>>& vb,
                                              const std::vector<kdet_fcl::Triangle>& tb) {
  std::vector<Tri> A, B;
  std::vector<Box> BA, BB;
  for (const auto& t : ta) A.push_back(triangleOf(va, t)), BA.push_back(boxOf(A.back()));
  for (const auto& t : tb) B.push_back(triangleOf(vb, t)), BB.push_back(boxOf(B.back()));
  std::vector<kdet_fcl::TrianglePair> out;
  forEachBoxOverlap(BA, BB, [&](std::uint32_t i, std::uint32_t j) {
    if (trianglesMeet(A[i], B[j])) out.push_back({i, j});
  });
  std::sort(out.begin(), out.end());
  return out;
}

/// Every intersecting (i < j) of one mesh that share no vertex (neither an index nor equal
/// coordinates: the library's documented self-collision rule), sorted.
template <class S>
std::vector<kdet_fcl::TrianglePair> selfPairs(const kdet_fcl::TriangleMesh<S>& m) {
  std::vector<Tri> T;
  std::vector<Box> BX;
  for (const auto& t : m.triangles) T.push_back(triangleOf(m.vertices, t)), BX.push_back(boxOf(T.back()));
  std::vector<kdet_fcl::TrianglePair> out;
  forEachBoxOverlap(BX, BX, [&](std::uint32_t i, std::uint32_t j) {
    if (i >= j) return;  // each unordered pair is seen twice (and (i, i) once)
    const auto& a = m.triangles[i];
    const auto& b = m.triangles[j];
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q)
        if (a[p] == b[q] || T[i][p] == T[j][q]) return;
    if (trianglesMeet(T[i], T[j])) out.push_back({i, j});
  });
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace kdet_referee
