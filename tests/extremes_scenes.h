#pragma once
// The scene table of the numerical-extremes suite (issue 6), shared by tests/test_extremes.cpp
// (kDet's queries in every precision mode against the exact referee) and
// tests/test_fcl_extremes.cpp (FCL's own collide and kdet_fcl::collide on the same scenes).
// Every scene is built in float or double; sceneTable<S>() lists them all.

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/kdet_fcl.h"
#include "test_util.h"

namespace kdet_extremes {

using namespace kdet_fcl;

// ------------------------------------------------------------------ scenes

template <class S>
struct Scene {
  std::string name;
  TriangleMesh<S> a, b;
  Transform<S> pose_a, pose_b;
  /// Pairs the exact referee must find between a and b (a sanity check that the scene really is
  /// the intended construction); -1: not known by construction, only > 0 required when
  /// `nonempty` is set.
  long expected_pairs = -1;
  bool nonempty = false;
  int min_height = 0;  ///< required HierarchyStats::height of a (size-ratio scenes)
  bool run_self = true;  ///< also run intersectSelf on the merged mesh (identity poses only)
  bool pair_query = true;  ///< run intersectMeshes(a, b) and (b, a)
  /// Generic position (random coordinates, no constructed contacts or near-degeneracies): the
  /// Double predicate must give the exact answer here.
  bool generic = false;
};

using V3 = Vec3<double>;

/// Appends triangle (p, q, r) given in double, rounded to S.
template <class S>
void add(TriangleMesh<S>& m, const V3& p, const V3& q, const V3& r) {
  m.addTriangle({S(p.x), S(p.y), S(p.z)}, {S(q.x), S(q.y), S(q.z)}, {S(r.x), S(r.y), S(r.z)});
}

template <class S>
TriangleMesh<S> transformed(const TriangleMesh<double>& m, double scale, const V3& offset) {
  TriangleMesh<S> r;
  r.triangles = m.triangles;
  for (const V3& v : m.vertices)
    r.vertices.push_back({S(offset.x + scale * v.x), S(offset.y + scale * v.y),
                          S(offset.z + scale * v.z)});
  return r;
}

template <class S>
TriangleMesh<S> merged(const TriangleMesh<S>& a, const TriangleMesh<S>& b) {
  TriangleMesh<S> m = a;
  const auto off = std::uint32_t(a.vertices.size());
  m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const Triangle& t : b.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  return m;
}

/// The small reference scene, in double, around the origin within [-2, 2]^3: a 6x6-quad sheet at
/// z = 1/2 (A) against a sphere of radius 1 plus hand-placed triangles that touch the sheet at a
/// vertex, along an edge, overlap it coplanarly, or stay one grid step away (B). Coordinates of
/// the hand-placed parts are small dyadic numbers, exact in float.
struct BaseScene {
  TriangleMesh<double> a, b;
};

inline BaseScene baseScene() {
  BaseScene s;
  const int n = 6;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) s.a.vertices.push_back({-1.5 + 0.5 * i, -1.5 + 0.5 * j, 0.5});
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const auto v = [&](int a, int b) { return std::uint32_t(a * (n + 1) + b); };
      s.a.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      s.a.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  s.b = makeSphere<double>({0, 0, 0}, 1.0, 12, 6);
  // Touching the sheet at exactly one grid vertex, from above.
  s.b.addTriangle({1.0, 1.0, 0.5}, {1.25, 1.0, 1.0}, {1.0, 1.25, 1.0});
  // A hinge along the grid edge from (-1.5, -1.5) to (-1, -1.5), standing up.
  s.b.addTriangle({-1.5, -1.5, 0.5}, {-1.0, -1.5, 0.5}, {-1.25, -1.5, 1.25});
  // Coplanar overlap inside one quad, and a coplanar triangle touching a grid vertex only.
  s.b.addTriangle({1.125, -1.375, 0.5}, {1.375, -1.375, 0.5}, {1.25, -1.125, 0.5});
  s.b.addTriangle({1.5, 1.5, 0.5}, {1.75, 1.5, 0.5}, {1.75, 1.75, 0.5});
  // Parallel to the sheet one grid step above: no contact.
  s.b.addTriangle({-1.25, 1.0, 1.0}, {-1.0, 1.0, 1.0}, {-1.0, 1.25, 1.0});
  return s;
}

/// The scale ladder (docs/numerics.md section 1): the base scene with its sphere's coordinates
/// rounded to multiples of 2^-20 (the hand-placed parts already are), scaled by 2^k. Its largest
/// coordinate magnitude is 1.75 and every coordinate is a multiple of 2^-20, so for k in
/// [kLadderLow<S>, kLadderHigh<S>] the scaling is exact in S and, in double, keeps every
/// coordinate a multiple of 2^-300 of magnitude at most 2^330: the predicates are exact on every
/// rung, and the pair sets cannot depend on k. The double rungs' ends put the largest magnitude at
/// 1.75 * 2^-247 and 1.75 * 2^329, next to the ends of the range a mesh may have
/// (TriangleMesh::validateForQueries: [2^-247, 2^330]).
template <class S>
constexpr int kLadderLow = std::is_same<S, float>::value ? -129 : -247;
template <class S>
constexpr int kLadderHigh = std::is_same<S, float>::value ? 126 : 329;

/// The ladder's rungs: every 8th k from kLadderLow and both ends.
template <class S>
std::vector<int> ladderRungs() {
  std::vector<int> k;
  for (int e = kLadderLow<S>; e < kLadderHigh<S>; e += 8) k.push_back(e);
  k.push_back(kLadderHigh<S>);
  return k;
}

inline BaseScene ladderBase() {
  BaseScene s = baseScene();
  for (V3& v : s.b.vertices)
    for (int a = 0; a < 3; ++a) v[a] = std::ldexp(std::round(std::ldexp(v[a], 20)), -20);
  return s;
}

/// Rung k of the ladder: {a, b} of the base scene times 2^k, in S.
template <class S>
std::pair<TriangleMesh<S>, TriangleMesh<S>> ladderRung(int k) {
  const BaseScene s = ladderBase();
  const double f = std::ldexp(1.0, k);
  return {transformed<S>(s.a, f, {0, 0, 0}), transformed<S>(s.b, f, {0, 0, 0})};
}

/// A 3x3 rotation given exactly (entries 0, +-1) plus a translation.
template <class S>
Transform<S> exactPose(const int R[3][3], const V3& t) {
  Transform<S> T;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) T.R[i][j] = S(R[i][j]);
  T.t = {S(t.x), S(t.y), S(t.z)};
  return T;
}
constexpr int kRz90[3][3] = {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}};
constexpr int kRx180[3][3] = {{1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
constexpr int kRy180[3][3] = {{-1, 0, 0}, {0, 1, 0}, {0, 0, -1}};
constexpr int kRz180[3][3] = {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}};

/// Far from the origin: the base scene translated by `off` (baked into the coordinates).
template <class S>
Scene<S> farBaked(double off) {
  const BaseScene base = baseScene();
  Scene<S> s;
  s.name = "far_baked_" + std::to_string(int(std::log10(off)));
  s.a = transformed<S>(base.a, 1.0, {off, off, off});
  s.b = transformed<S>(base.b, 1.0, {off, off, off});
  return s;
}

/// Far from the origin through the poses: A's local copy is turned by -90 degrees about z and its
/// pose turns it back (exact matrix) and translates by `off`; B's pose translates by `off` plus a
/// small shift that its local coordinates undo.
template <class S>
Scene<S> farPosed(double off) {
  const BaseScene base = baseScene();
  Scene<S> s;
  s.name = "far_posed_" + std::to_string(int(std::log10(off)));
  TriangleMesh<double> a = base.a;
  for (V3& v : a.vertices) v = {v.y, -v.x, v.z};  // R_z(-90)
  s.a = transformed<S>(a, 1.0, {0, 0, 0});
  s.b = transformed<S>(base.b, 1.0, {-0.125, 0.25, -0.375});
  s.pose_a = exactPose<S>(kRz90, {off, off, off});
  s.pose_b = exactPose<S>(kRz90, {off, off, off});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s.pose_b.R[i][j] = S(i == j ? 1 : 0);
  s.pose_b.t = {S(off + 0.125), S(off - 0.25), S(off + 0.375)};
  return s;
}

/// Far from the origin under random rotations of both meshes (rounding in every mapped point).
template <class S>
Scene<S> farRandomPose(double off, std::uint64_t seed) {
  const BaseScene base = baseScene();
  Scene<S> s;
  s.name = "far_random_pose_" + std::to_string(int(std::log10(off))) + "_s" + std::to_string(seed);
  s.a = transformed<S>(base.a, 1.0, {0, 0, 0});
  s.b = transformed<S>(base.b, 1.0, {0, 0, 0});
  std::mt19937_64 rng(seed);
  s.pose_a = kdet_test::randomPose<S>(rng, off, off + 1);
  s.pose_b = s.pose_a;  // the same pose: the scene is as designed up to rounding of the mapping
  return s;
}

template <class S>
Scene<S> scaled(double scale, double off, const std::string& name) {
  const BaseScene base = baseScene();
  Scene<S> s;
  s.name = name;
  s.a = transformed<S>(base.a, scale, {off, off, off});
  s.b = transformed<S>(base.b, scale, {off, off, off});
  s.nonempty = true;
  return s;
}

/// One mesh with triangle sizes from 1 to ~2e7 (hierarchy height >= 24): a huge triangle in the
/// plane z = 0 and vertical triangles of sizes 10^k, k = 0..6, crossing it, touching it at a
/// vertex or an edge, or floating just above it; B is a copy turned by 180 degrees about x.
template <class S>
Scene<S> sizeRatio() {
  Scene<S> s;
  s.name = "size_ratio_1e7";
  add(s.a, {-1e7, -1e7, 0}, {1e7, -1e7, 0}, {0, 1e7, 0});
  long crossings = 0;
  for (int k = 0; k <= 6; ++k) {
    const double h = std::pow(10.0, k);
    for (int r = 0; r < 4; ++r) {
      const double x = -5e6 + 1.5e6 * k, y = -4e6 + 2e6 * r;
      if (r == 0) add(s.a, {x, y, -h / 2}, {x + h, y, h / 2}, {x, y, h / 2});  // crosses
      if (r == 1) add(s.a, {x, y, 0}, {x + h, y, h}, {x, y, h});              // touches at a vertex
      if (r == 2) add(s.a, {x, y, 0}, {x + h, y, 0}, {x, y, h});              // touches along an edge
      if (r == 3) add(s.a, {x, y, h / 4}, {x + h, y, h}, {x, y, h});          // above
      crossings += r < 3;
    }
  }
  (void)crossings;
  s.b = s.a;
  s.pose_b = exactPose<S>(kRx180, {0, 0, 0});
  s.nonempty = true;
  s.min_height = 24;
  s.run_self = false;
  return s;
}

/// Self collisions of the size-ratio mesh: every small triangle that crosses or touches the huge
/// one is a pair (they share no vertex), nothing else is.
template <class S>
Scene<S> sizeRatioSelf() {
  Scene<S> s = sizeRatio<S>();
  s.name = "size_ratio_1e7_self";
  s.b = TriangleMesh<S>{};
  s.pose_b = Transform<S>{};
  s.run_self = true;
  s.pair_query = false;
  return s;
}

/// Slivers (aspect ratio up to 1e6) and needles (two vertices 1e-12 apart) in a star in the
/// plane z = 1, against vertical slivers that cross them, touch them with their tip, or miss by
/// one ulp. (The plane is z = 1, not z = 0: one ulp above 0 is a subnormal number, outside the
/// predicates' validity range; see BelowThePredicateRange.)
template <class S>
Scene<S> slivers() {
  Scene<S> s;
  s.name = "slivers_needles";
  for (int k = 0; k < 12; ++k) {
    const double ang = k * 0.5235987755982988, c = std::cos(ang), sn = std::sin(ang);
    const double w = std::pow(10.0, -(k % 7));  // width 1 .. 1e-6: aspect up to 1e6
    add(s.a, {0.01 * c, 0.01 * sn, 1}, {1.0 * c, 1.0 * sn, 1}, {0.5 * c - w * sn, 0.5 * sn + w * c, 1});
  }
  // Needles: a long edge and a vanishing one.
  add(s.a, {2, 0, 1}, {3, 0, 1}, {3, 1e-12, 1});
  add(s.a, {2, 1, 1}, {3, 1, 1 + 1e-12}, {3, 1, 1});
  const double up = double(std::nextafter(S(1), S(2)));
  for (int k = 0; k < 12; ++k) {
    const double ang = k * 0.5235987755982988, c = std::cos(ang), sn = std::sin(ang);
    const double x = double(S(0.75 * c)), y = double(S(0.75 * sn));
    if (k % 3 == 0) add(s.b, {x, y, 0.5}, {x, y, 1.5}, {x + 1e-6, y, 1.5});
    if (k % 3 == 1) add(s.b, {x, y, 1}, {x, y, 1.5}, {x + 1e-6, y, 1.5});
    if (k % 3 == 2) add(s.b, {x, y, up}, {x, y, 1.5}, {x + 1e-6, y, 1.5});
  }
  add(s.b, {2.5, -0.5, 1}, {2.5, 0.5, 1}, {2.5, 0.5, 2});    // crosses the first needle
  add(s.b, {2.5, 1, 0}, {2.5, 1, 2}, {2.5000001, 1, 2});     // meets the second needle
  s.nonempty = true;
  return s;
}

/// Degenerate triangles: zero area (collinear), repeated vertices, points, against a proper
/// triangle and each other, with exact contacts (on the face, on an edge, at a vertex) and
/// near misses.
template <class S>
Scene<S> degenerate() {
  Scene<S> s;
  s.name = "degenerate";
  add(s.a, {0, 0, 0}, {4, 0, 0}, {0, 4, 0});        // proper
  add(s.a, {5, 5, 5}, {6, 6, 6}, {7, 7, 7});        // collinear
  add(s.a, {9, 9, 9}, {9, 9, 9}, {9, 9, 9});        // point
  add(s.a, {-1, -1, 1}, {-1, -1, 1}, {-2, -1, 1});  // repeated vertex: a segment
  // B:
  add(s.b, {1, 1, 0}, {1, 1, 0}, {1, 1, 0});              // point on the face
  add(s.b, {2, 0, 0}, {2, 0, 0}, {2, 0, 0});              // point on an edge
  add(s.b, {4, 0, 0}, {4, 0, 0}, {4, 0, 0});              // point at a vertex
  add(s.b, {1, 1, 1}, {1, 1, 1}, {1, 1, 1});              // point above
  add(s.b, {1, 1, -1}, {1, 1, 1}, {1, 1, 0.5});           // collinear segment through the face
  add(s.b, {-1, 2, 0}, {1, 2, 0}, {0, 2, 0});             // in-plane segment crossing an edge
  add(s.b, {0, 5, 0}, {0, 4, 0}, {0, 4.5, 0});            // in-plane segment touching a vertex
  add(s.b, {0, 4.5, 0}, {0, 5, 0}, {0, 4.75, 0});         // in-plane segment missing
  add(s.b, {6, 6, 6}, {8, 8, 8}, {7, 7, 7});              // collinear overlap with A's segment
  add(s.b, {7, 7, 7}, {8, 8, 8}, {7.5, 7.5, 7.5});        // collinear touching at an end
  add(s.b, {5, 7, 6}, {7, 5, 6}, {6, 6, 6});              // crossing segment
  add(s.b, {9, 9, 9}, {9, 9, 9}, {9, 9, 9});              // the same point
  add(s.b, {8, 8, 8}, {10, 10, 10}, {8, 10, 9});          // proper, through the point
  add(s.b, {-1, -1, 1}, {-1, -1, 1}, {-1, -1, 1});        // point at a segment end
  add(s.b, {-1.5, -1, 1}, {-1.5, -1, 1}, {-1.5, -1, 1});  // point inside a segment
  s.nonempty = true;
  return s;
}

/// Coincident duplicates (separate vertex indices, equal coordinates), coplanar overlapping and
/// coplanar touching pairs, in-plane misses by one ulp, and 3D vertex / edge contacts.
template <class S>
Scene<S> coplanarAndTouching() {
  Scene<S> s;
  s.name = "coplanar_touching_duplicates";
  const S gap = std::nextafter(S(1), S(2));  // one ulp beyond 1
  add(s.a, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  add(s.a, {3, 0, 0}, {4, 0, 0}, {3, 1, 0});
  add(s.a, {6, 0, 0}, {7, 0, 0}, {6, 1, 0});
  add(s.a, {9, 0, 0}, {10, 0, 0}, {9, 1, 0});
  add(s.a, {12, 0, 0}, {13, 0, 0}, {12, 1, 0});
  add(s.b, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});                           // duplicate
  add(s.b, {3.25, 0.25, 0}, {4.25, 0.25, 0}, {3.25, 1.25, 0});         // coplanar overlap
  add(s.b, {7, 0, 0}, {8, 0, 0}, {7, 1, 0});                           // coplanar, touching at a vertex
  add(s.b, {9.5, 0.5, 0}, {10.5, 0.5, 0}, {9.5, 1.5, 0});              // coplanar, sharing a point of an edge
  add(s.b, {12 + double(gap), 0, 0}, {14, 0, 0}, {14, 1, 0});          // coplanar, one ulp apart
  add(s.b, {0, 0, 0}, {-1, 0, 1}, {0, -1, 1});                         // 3D, at a vertex
  add(s.b, {3, 0, 0}, {4, 0, 0}, {3.5, -0.5, 1});                      // 3D, along an edge (hinge)
  add(s.b, {6.25, 0.25, 0}, {6.25, 0.25, 1}, {6.5, 0.25, 1});          // 3D, vertex on the face
  s.nonempty = true;
  return s;
}

/// Nearly parallel triangles at distances just above and below rounding: B lies in z = 1 (and in
/// the tilted plane x + y + z = 1); A's triangles are parallel one ulp above or below, exactly
/// in the plane, or tilted so that one vertex is one ulp below and two one ulp above.
template <class S>
Scene<S> nearParallel() {
  Scene<S> s;
  s.name = "near_parallel";
  const double one = 1, up = double(std::nextafter(S(1), S(2))), dn = double(std::nextafter(S(1), S(0)));
  add(s.b, {0, 0, one}, {8, 0, one}, {0, 8, one});
  add(s.a, {1, 1, up}, {2, 1, up}, {1, 2, up});  // one ulp above: no
  add(s.a, {1, 3, dn}, {2, 3, dn}, {1, 4, dn});  // one ulp below: no
  add(s.a, {3, 1, one}, {4, 1, one}, {3, 2, one});  // coplanar: yes
  add(s.a, {3, 3, dn}, {4, 3, up}, {3, 4, up});  // crosses by one ulp: yes
  add(s.a, {5, 1, one}, {6, 1, up}, {5, 2, up});  // touches at one vertex: yes
  add(s.a, {8, 0, up}, {9, 0, up}, {8, 1, one});  // touches B's corner? no: (8,1) is outside B
  // Tilted plane x + y + z = 1 (not axis-aligned: the offsets are not representable exactly).
  add(s.b, {1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  const S third = S(1) / S(3);
  const double t = double(third), tz = double(S(1) - third - third);
  const double tzu = double(std::nextafter(S(tz), S(2))), tzd = double(std::nextafter(S(tz), S(-2)));
  add(s.a, {t, t, tzu}, {t + 0.5, t, tzu}, {t, t + 0.25, tzu});
  add(s.a, {t, t, tzd}, {t - 0.5, t, tzd}, {t, t - 0.25, tzd});
  add(s.a, {t, t, tz}, {t + 0.25, t + 0.25, tz}, {t, t, 2});
  s.nonempty = true;
  return s;
}

/// A fan of `n` triangles around one vertex (indexed, or a soup whose centres are separate
/// vertices with equal coordinates), slightly wavy, against two triangles cutting through it.
template <class S>
Scene<S> fan(int n, bool soup) {
  Scene<S> s;
  s.name = std::string(soup ? "fan_soup_" : "fan_") + std::to_string(n);
  const double pi = 3.141592653589793;
  if (!soup) {
    s.a.vertices.push_back({S(0), S(0), S(0)});
    for (int k = 0; k < n; ++k)
      s.a.vertices.push_back({S(std::cos(2 * pi * k / n)), S(std::sin(2 * pi * k / n)),
                              S(k % 2 ? 0.01 : -0.01)});
    for (int k = 0; k < n; ++k)
      s.a.triangles.push_back({0, std::uint32_t(1 + k), std::uint32_t(1 + (k + 1) % n)});
  } else {
    for (int k = 0; k < n; ++k)
      add(s.a, {0, 0, 0}, {std::cos(2 * pi * k / n), std::sin(2 * pi * k / n), k % 2 ? 0.01 : -0.01},
          {std::cos(2 * pi * (k + 1) / n), std::sin(2 * pi * (k + 1) / n), (k + 1) % 2 ? 0.01 : -0.01});
  }
  add(s.b, {-2, 0.001, -1}, {2, 0.001, -1}, {0, 0.001, 1});  // cuts the fan near the centre
  add(s.b, {0.5, -2, -1}, {0.5, 2, -1}, {0.5, 0, 1});
  s.nonempty = true;
  return s;
}

/// A crumpled cloth: an (n x n)-quad grid whose vertices are scattered at random in a unit cube,
/// so every triangle overlaps every other one in one cell; B is a second crumpled cloth.
template <class S>
Scene<S> crumpled(int n, std::uint64_t seed) {
  Scene<S> s;
  s.name = "crumpled_cloth_" + std::to_string(n);
  s.generic = true;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (TriangleMesh<S>* m : {&s.a, &s.b}) {
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) m->vertices.push_back({S(u(rng)), S(u(rng)), S(u(rng))});
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const auto v = [&](int a, int b) { return std::uint32_t(a * (n + 1) + b); };
        m->triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
        m->triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
      }
  }
  s.nonempty = true;
  return s;
}

/// Meshes of 0, 1 and 2 triangles.
template <class S>
std::vector<Scene<S>> tinyMeshes() {
  TriangleMesh<S> m[3];
  add(m[1], {0, 0, 0}, {2, 0, 0}, {0, 2, 0});
  m[2] = m[1];
  add(m[2], {0.5, 0.5, -1}, {0.5, 0.5, 1}, {0.8, 0.2, 1});  // crosses the first
  std::vector<Scene<S>> out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Scene<S> s;
      s.name = "tiny_" + std::to_string(i) + "x" + std::to_string(j);
      s.a = m[i];
      s.b = m[j];
      s.expected_pairs = long(i) * long(j) == 0 ? 0 : (i == 1 && j == 1 ? 1 : (i * j == 2 ? 2 : 4));
      out.push_back(s);
    }
  return out;
}

/// The base scene under poses: 180-degree turns (exact matrices and makeTransform's rounded
/// one), a rounded 90-degree turn, and random rotations of both meshes.
template <class S>
std::vector<Scene<S>> posedScenes() {
  const BaseScene base = baseScene();
  std::vector<Scene<S>> out;
  const struct {
    const char* name;
    const int (*R)[3];
  } turns[] = {{"rot180_x", kRx180}, {"rot180_y", kRy180}, {"rot180_z", kRz180}};
  for (const auto& t : turns) {
    Scene<S> s;
    s.name = t.name;
    // A's local copy is pre-turned by the same 180 degrees (its own inverse): the world scene is
    // the base scene.
    TriangleMesh<double> a = base.a;
    for (V3& v : a.vertices) {
      const V3 p = v;
      v = {t.R[0][0] * p.x + t.R[0][1] * p.y + t.R[0][2] * p.z,
           t.R[1][0] * p.x + t.R[1][1] * p.y + t.R[1][2] * p.z,
           t.R[2][0] * p.x + t.R[2][1] * p.y + t.R[2][2] * p.z};
    }
    s.a = transformed<S>(a, 1, {0, 0, 0});
    s.b = transformed<S>(base.b, 1, {0, 0, 0});
    s.pose_a = exactPose<S>(t.R, {0, 0, 0});
    s.nonempty = true;
    out.push_back(s);
  }
  {
    Scene<S> s;
    s.name = "rot180_diag_rounded";
    s.a = transformed<S>(base.a, 1, {0, 0, 0});
    s.b = transformed<S>(base.b, 1, {0, 0, 0});
    s.pose_a = makeTransform<S>({1, 1, 0}, S(3.141592653589793), {0, 0, 0});
    s.pose_b = makeTransform<S>({0, 1, 1}, S(3.141592653589793), {S(0.1), 0, 0});
    out.push_back(s);
  }
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Scene<S> s;
    s.name = "random_poses_s" + std::to_string(seed);
    s.a = transformed<S>(base.a, 1, {0, 0, 0});
    s.b = transformed<S>(base.b, 1, {0, 0, 0});
    std::mt19937_64 rng(seed);
    s.pose_a = kdet_test::randomPose<S>(rng, -0.5, 0.5);
    s.pose_b = kdet_test::randomPose<S>(rng, -0.5, 0.5);
    out.push_back(s);
  }
  return out;
}

template <class S>
std::vector<Scene<S>> sceneTable() {
  std::vector<Scene<S>> t;
  t.push_back(scaled<S>(1, 0, "base"));
  for (double off : {1e3, 1e5, 1e7}) {
    t.push_back(farBaked<S>(off));
    t.push_back(farPosed<S>(off));
    t.push_back(farRandomPose<S>(off, 7));
  }
  t.push_back(scaled<S>(1e-6, 0, "size_1e-6"));
  t.push_back(scaled<S>(1e6, 0, "size_1e6"));
  t.push_back(scaled<S>(1e-6, 1, "size_1e-6_at_1"));
  if (std::is_same<S, double>::value) {
    // Near the ends of the predicates' validity range (coordinates 0 or of magnitude in
    // [2^-247, 2^330]); in float these would underflow to 0 or overflow.
    t.push_back(scaled<S>(1e-70, 0, "size_1e-70"));
    t.push_back(scaled<S>(1e90, 0, "size_1e90"));
    t.push_back(scaled<S>(1e-60, 1e-55, "size_1e-60_at_1e-55"));
  }
  t.push_back(sizeRatio<S>());
  t.push_back(sizeRatioSelf<S>());
  t.push_back(slivers<S>());
  t.push_back(degenerate<S>());
  t.push_back(coplanarAndTouching<S>());
  t.push_back(nearParallel<S>());
  t.push_back(fan<S>(10000, false));
  t.push_back(fan<S>(2000, true));
  t.push_back(crumpled<S>(12, 3));
  for (auto& s : tinyMeshes<S>()) t.push_back(s);
  for (auto& s : posedScenes<S>()) t.push_back(s);
  return t;
}


// ------------------------------------------------------------------ helpers


/// A's vertices in B's frame, exactly as the library computes them (detail/pose.h).
template <class S>
std::vector<Vec3<S>> mappedA(const TriangleMesh<S>& a, const Transform<S>& pa, const Transform<S>& pb) {
  const detail::RelativePose rp = detail::relativePose(pa, pb);
  std::vector<Vec3<S>> v = a.vertices;
  if (!rp.identity)
    for (Vec3<S>& p : v) p = detail::mapPoint(rp.a_to_b, p);
  return v;
}

template <class S>
const char* precisionName() {
  return std::is_same<S, float>::value ? "float" : "double";
}

}  // namespace kdet_extremes
