/// \file
/// precision_bench: the speed/accuracy trade of the triangle test (issue 5, "The speed/accuracy
/// trade"). For every scene (generic and near-degenerate), every mesh precision (HashedMesh<float>
/// and HashedMesh<double>), every predicate mode (Predicate::Exact, Double, Float) and every backend
/// available (the CPU always; CUDA when the library was built with it and a device exists), it
/// measures the time per query and the reported pair set's precision and recall against an
/// exact-arithmetic ground truth.
///
/// Ground truth: tests/exact_referee.h (GMP integers, written independently of the library's
/// predicate) evaluated on every pair whose closed boxes overlap (an exact sweep; box overlap is
/// necessary for intersection, so the truth is complete), on exactly the coordinates the library
/// decides on: A's vertices mapped into B's frame and rounded to the mesh precision
/// (detail::relativePose + detail::mapPoint), B's as stored. Self queries exclude pairs that share
/// a vertex (the same index or bit-equal coordinates), as intersectSelf does. Each scene is defined
/// once (mostly in double) and rounded to float for the HashedMesh<float> rows, so the float and
/// the double rows of a scene have their own truths.
///
/// Timing: the query call only (hashes are built beforehand; the CPU backend's hash is not touched
/// by a query, the CUDA backend uploads a mesh on its first query and caches it, which the warm-up
/// absorbs). One warm-up query per mode, then `repeats` samples per mode, the three modes
/// interleaved round robin (load from other processes hits them alike); a sample times a batch of
/// k back-to-back queries (k chosen so a sample lasts >= ~2 ms, for microsecond-sized scenes) with
/// std::chrono::steady_clock; the median sample / k is reported. The GPU query API is synchronous
/// (it returns the pairs on the host), so wall time is the GPU time per query, transfers included.
///
/// Exit status: 0; 2 when Predicate::Exact differs from the ground truth anywhere (a library bug,
/// printed loudly); 1 on bad usage or an exception.
///
///   precision_bench [--out DIR] [--repeats N] [--small] [--only a,b] [--threads T] [--no-plot]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "bench_util.h"
#include "exact_referee.h"
#include "extremes_scenes.h"
#include "kdet_fcl/kdet_fcl.h"
#include "test_util.h"

using namespace kdet_fcl;
using Clock = std::chrono::steady_clock;

namespace {

// ------------------------------------------------------------------ options

struct Options {
  std::string out = "precision_out";
  int repeats = 7;
  bool small = false;
  bool plot = true;
  bool inject = false;  // --inject-exact-error: drop one Exact pair to test the failure path
  int threads = 0;
  std::vector<std::string> only;
  std::string command;
};

[[noreturn]] void usage(int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: precision_bench [--out DIR] [--repeats N] [--small] [--only a,b] [--threads T] [--no-plot]\n"
               "  --out DIR      where precision.md, precision.json, precision.dat/.gp/.png go (default precision_out)\n"
               "  --repeats N    timed samples per row after one warm-up query (default 7; --small: 1)\n"
               "  --small        small scenes (smoke test, seconds; not meant for timing)\n"
               "  --only a,b     only these scenes (names as in the table; a prefix ending in '*' matches)\n"
               "  --threads T    QueryOptions::threads of the CPU backend (default 0: all cores)\n"
               "  --no-plot      do not run gnuplot (the .dat and .gp files are still written)\n"
               "  --inject-exact-error  drop one pair of the first non-empty Exact result (tests the failure path)\n"
               "exit status: 0 ok; 2 when Predicate::Exact differs from the exact ground truth; 1 on error\n");
  std::exit(code);
}

Options parse(int argc, char** argv) {
  Options o;
  bool repeats_set = false;
  for (int i = 0; i < argc; ++i) o.command += (i ? " " : "") + std::string(argv[i]);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(1);
      return argv[++i];
    };
    if (a == "--out") o.out = value();
    else if (a == "--repeats") {
      o.repeats = int(kdet_bench_util::parseIntArg("precision_bench", "--repeats", value().c_str(), 1, 1000000, 1));
      repeats_set = true;
    }
    else if (a == "--small") o.small = true;
    else if (a == "--no-plot") o.plot = false;
    else if (a == "--inject-exact-error") o.inject = true;
    else if (a == "--threads")
      o.threads = int(kdet_bench_util::parseIntArg("precision_bench", "--threads", value().c_str(), 0, 4096, 1));
    else if (a == "--only") {
      std::stringstream ss(value());
      std::string item;
      while (std::getline(ss, item, ',')) if (!item.empty()) o.only.push_back(item);
    } else if (a == "-h" || a == "--help") usage(0);
    else {
      std::fprintf(stderr, "precision_bench: unknown argument '%s'\n", a.c_str());
      usage(1);
    }
  }
  if (o.small && !repeats_set) o.repeats = 1;
  return o;
}

bool selected(const Options& o, const std::string& name) {
  if (o.only.empty()) return true;
  for (const std::string& s : o.only) {
    if (s == name) return true;
    if (!s.empty() && s.back() == '*' && name.compare(0, s.size() - 1, s, 0, s.size() - 1) == 0) return true;
  }
  return false;
}

// ------------------------------------------------------------------ scenes

template <class S>
struct Built {
  TriangleMesh<S> a, b;  // b empty for a self query
  Transform<S> pose_a = Transform<S>::identity(), pose_b = Transform<S>::identity();
};

struct SceneDef {
  std::string name;
  std::string cls;   // "generic" or "near-degenerate"
  std::string note;  // how it is built
  bool self = false;
  std::function<Built<float>()> build_f;
  std::function<Built<double>()> build_d;
};

using MeshD = TriangleMesh<double>;
using V3 = Vec3<double>;

/// A definition in double, rounded once to S.
template <class S>
Built<S> fromDouble(const MeshD& a, const MeshD& b) {
  Built<S> r;
  r.a = kdet_test::convert<S>(a);
  r.b = kdet_test::convert<S>(b);
  return r;
}

SceneDef doubleScene(std::string name, std::string cls, std::string note, bool self,
                     std::function<std::pair<MeshD, MeshD>()> make) {
  SceneDef d;
  d.name = std::move(name);
  d.cls = std::move(cls);
  d.note = std::move(note);
  d.self = self;
  auto cache = std::make_shared<std::pair<MeshD, MeshD>>();
  auto get = [cache, make]() -> const std::pair<MeshD, MeshD>& {
    if (cache->first.triangles.empty() && cache->second.triangles.empty()) *cache = make();
    return *cache;
  };
  d.build_f = [get]() { const auto& m = get(); return fromDouble<float>(m.first, m.second); };
  d.build_d = [get]() { const auto& m = get(); return fromDouble<double>(m.first, m.second); };
  return d;
}

/// A scene of tests/extremes_scenes.h, built in each precision by its own constructor (the
/// one-ulp constructions are per precision), a vs b.
template <template <class> class F>
SceneDef extremesScene(std::string name, std::string note) {
  SceneDef d;
  d.name = std::move(name);
  d.cls = "near-degenerate";
  d.note = std::move(note);
  d.self = false;
  d.build_f = []() {
    const auto s = F<float>::make();
    Built<float> r;
    r.a = s.a, r.b = s.b, r.pose_a = s.pose_a, r.pose_b = s.pose_b;
    return r;
  };
  d.build_d = []() {
    const auto s = F<double>::make();
    Built<double> r;
    r.a = s.a, r.b = s.b, r.pose_a = s.pose_a, r.pose_b = s.pose_b;
    return r;
  };
  return d;
}
template <class S> struct ExBase { static kdet_extremes::Scene<S> make() { return kdet_extremes::scaled<S>(1, 0, "base"); } };
template <class S> struct ExCoplanar { static kdet_extremes::Scene<S> make() { return kdet_extremes::coplanarAndTouching<S>(); } };
template <class S> struct ExNearParallel { static kdet_extremes::Scene<S> make() { return kdet_extremes::nearParallel<S>(); } };
template <class S> struct ExSlivers { static kdet_extremes::Scene<S> make() { return kdet_extremes::slivers<S>(); } };
template <class S> struct ExDegenerate { static kdet_extremes::Scene<S> make() { return kdet_extremes::degenerate<S>(); } };
template <class S> struct ExFarPose5 { static kdet_extremes::Scene<S> make() { return kdet_extremes::farRandomPose<S>(1e5, 7); } };

/// A fixed "random" rotation (unit quaternion from a seed) applied to a double mesh, plus a shift.
void rotate(MeshD& m, std::uint64_t seed, const V3& shift) {
  std::mt19937_64 rng(seed);
  const Transform<double> T = kdet_test::randomPose<double>(rng, 0, 0);
  for (V3& v : m.vertices) {
    const V3 p = v;
    v = {T.R[0][0] * p.x + T.R[0][1] * p.y + T.R[0][2] * p.z + shift.x,
         T.R[1][0] * p.x + T.R[1][1] * p.y + T.R[1][2] * p.z + shift.y,
         T.R[2][0] * p.x + T.R[2][1] * p.y + T.R[2][2] * p.z + shift.z};
  }
}

/// An (m x m)-quad grid of edge `size` in the plane z = 0, centred at the origin, turned in its
/// plane by `angle` and shifted by (dx, dy); `z(x, y)` lifts it.
MeshD grid(int m, double size, double angle, double dx, double dy,
           const std::function<double(double, double)>& z = {}) {
  MeshD g;
  const double c = std::cos(angle), s = std::sin(angle), h = size / m;
  for (int i = 0; i <= m; ++i)
    for (int j = 0; j <= m; ++j) {
      const double u = -size / 2 + h * i, v = -size / 2 + h * j;
      const double x = c * u - s * v + dx, y = s * u + c * v + dy;
      g.vertices.push_back({x, y, z ? z(x, y) : 0.0});
    }
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const auto v = [&](int a, int b) { return std::uint32_t(a * (m + 1) + b); };
      g.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      g.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  return g;
}

/// A sheet of (m x m) unit quads in z = 0 and vertical fins standing on it: fins along grid lines
/// (their bottom edges overlap the sheet's edges: collinear edge contacts), fins through the
/// middle of the quads (line contacts across faces and diagonals), and fins one step above.
std::pair<MeshD, MeshD> touchingScene(int m) {
  MeshD a;
  for (int i = 0; i <= m; ++i)
    for (int j = 0; j <= m; ++j) a.vertices.push_back({double(i), double(j), 0.0});
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const auto v = [&](int p, int q) { return std::uint32_t(p * (m + 1) + q); };
      a.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      a.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  MeshD b;
  auto fin = [&](double x, double z0) {  // a strip in the plane x = const, from y = 0 to m
    for (int j = 0; j < m; ++j) {
      b.addTriangle({x, double(j), z0}, {x, double(j + 1), z0}, {x, double(j + 1), z0 + 1});
      b.addTriangle({x, double(j), z0}, {x, double(j + 1), z0 + 1}, {x, double(j), z0 + 1});
    }
  };
  for (int i = 1; i < m; i += 3) {
    fin(double(i), 0.0);        // on a grid line
    fin(i + 1.5, 0.0);          // across the quads
    if (i + 2 < m) fin(i + 2.0, 1.0 / 64);  // just above (no contact)
  }
  // Pyramids standing on the sheet with their apex down on a vertex, an edge midpoint, a face.
  for (int i = 2; i + 2 < m; i += 5)
    for (int j = 2; j + 2 < m; j += 5) {
      const V3 apexes[3] = {{double(i), double(j), 0}, {i + 0.5, double(j + 1), 0}, {i + 2.25, j + 2.5, 0}};
      for (const V3& p : apexes) {
        b.addTriangle(p, {p.x - 0.5, p.y - 0.5, 1}, {p.x + 0.5, p.y - 0.5, 1});
        b.addTriangle(p, {p.x + 0.5, p.y - 0.5, 1}, {p.x, p.y + 0.5, 1});
        b.addTriangle(p, {p.x, p.y + 0.5, 1}, {p.x - 0.5, p.y - 0.5, 1});
      }
    }
  return {a, b};
}

struct Sizes {
  int cloth, sphere_seg, soup, touch, sheet, far_cloth, far_seg, slivers;
};

std::vector<SceneDef> makeScenes(const Sizes& z) {
  std::vector<SceneDef> v;
  const int cn = z.cloth;
  auto cloth = [cn]() { return makeDrapedCloth<double>(cn, 3.0, 1.0, 0.02, 1.0); };
  const int seg = z.sphere_seg;
  // ---- generic
  v.push_back(doubleScene("cloth_self", "generic",
                          "makeDrapedCloth(n=" + std::to_string(cn) + ", size 3, sphere 1, penetration 0.02, t=1): self query",
                          true, [cloth]() { return std::make_pair(cloth(), MeshD{}); }));
  v.push_back(doubleScene("cloth_sphere", "generic",
                          "the same cloth vs makeSphere(r=1, " + std::to_string(seg) + "x" + std::to_string(seg / 2) + ")",
                          false, [cloth, seg]() { return std::make_pair(cloth(), makeSphere<double>({0, 0, 0}, 1.0, seg, seg / 2)); }));
  const int sn = z.soup;
  v.push_back(doubleScene("soup_self", "generic",
                          "makeRandomSoup(" + std::to_string(sn) + ", extent 1, sizes 0.005..0.05, seed 5): self query",
                          true, [sn]() { return std::make_pair(makeRandomSoup<double>(sn, 1.0, 0.005, 0.05, 5), MeshD{}); }));
  // ---- near-degenerate, at scale
  const int tm = z.touch;
  v.push_back(doubleScene("touching", "near-degenerate",
                          "unit-quad sheet " + std::to_string(tm) + "^2 in z=0 vs fins on grid lines / across quads / 1/64 above, "
                          "pyramids with apex on a vertex, an edge, a face (small integers: exact in every mode)",
                          false, [tm]() { return touchingScene(tm); }));
  v.push_back(doubleScene("touching_rotated", "near-degenerate",
                          "the touching scene scaled by 1/" + std::to_string(tm) + ", turned by a random rotation and shifted "
                          "by (0.3, 0.2, 0.1), rounded: the contacts become rounding-level near-contacts",
                          false, [tm]() {
                            auto s = touchingScene(tm);
                            for (MeshD* m : {&s.first, &s.second})
                              for (V3& p : m->vertices) p = {p.x / tm, p.y / tm, p.z / tm};
                            rotate(s.first, 11, {0.3, 0.2, 0.1});
                            rotate(s.second, 11, {0.3, 0.2, 0.1});
                            return s;
                          }));
  const int gm = z.sheet;
  v.push_back(doubleScene("coplanar_tilted", "near-degenerate",
                          "two " + std::to_string(gm) + "^2-quad sheets of edge 1 in one plane (B turned 30 deg in the plane "
                          "and shifted), the pair turned by a random rotation and rounded",
                          false, [gm]() {
                            MeshD a = grid(gm, 1.0, 0.0, 0.0, 0.0);
                            MeshD b = grid(gm, 1.0, 0.5235987755982988, 0.0037, 0.0021);
                            rotate(a, 12, {0.1, 0.2, 0.3});
                            rotate(b, 12, {0.1, 0.2, 0.3});
                            return std::make_pair(a, b);
                          }));
  v.push_back(doubleScene("near_parallel", "near-degenerate",
                          "two " + std::to_string(gm) + "^2-quad sheets of edge 1, B turned 17 deg in the plane and tilted "
                          "by 1e-6 rad about the line x = 0.1 (they cross there; elsewhere gaps up to 6e-7), turned by a random "
                          "rotation and rounded",
                          false, [gm]() {
                            MeshD a = grid(gm, 1.0, 0.0, 0.0, 0.0);
                            MeshD b = grid(gm, 1.0, 0.29670597283903605, 0.0013, 0.0029,
                                           [](double x, double) { return 1e-6 * (x - 0.1); });
                            rotate(a, 13, {-0.2, 0.1, 0.4});
                            rotate(b, 13, {-0.2, 0.1, 0.4});
                            return std::make_pair(a, b);
                          }));
  const int fc = z.far_cloth, fs = z.far_seg;
  for (int e : {3, 4, 5, 6}) {
    const double off = std::pow(10.0, e);
    v.push_back(doubleScene("far_1e" + std::to_string(e), "near-degenerate",
                            "makeDrapedCloth(n=" + std::to_string(fc) + ") vs makeSphere(" + std::to_string(fs) + "x" +
                                std::to_string(fs / 2) + "), both baked at (1e" + std::to_string(e) + ", 1e" +
                                std::to_string(e) + ", 1e" + std::to_string(e) + ")",
                            false, [fc, fs, off]() {
                              MeshD a = makeDrapedCloth<double>(fc, 3.0, 1.0, 0.02, 1.0);
                              MeshD b = makeSphere<double>({0, 0, 0}, 1.0, fs, fs / 2);
                              for (MeshD* m : {&a, &b})
                                for (V3& p : m->vertices) p = {p.x + off, p.y + off, p.z + off};
                              return std::make_pair(a, b);
                            }));
  }
  const int ns = z.slivers;
  v.push_back(doubleScene("slivers", "near-degenerate",
                          "a fan of " + std::to_string(ns) + " slivers (aspect ratio up to 1e6) in the plane z=1 vs " +
                              std::to_string(ns) + " vertical slivers (width 1e-6) crossing it, touching it with an edge, "
                              "or one double-ulp above",
                          false, [ns]() {
                            MeshD a, b;
                            const double up = std::nextafter(1.0, 2.0), pi = 3.141592653589793;
                            for (int k = 0; k < ns; ++k) {
                              const double ang = 2 * pi * k / ns, c = std::cos(ang), s = std::sin(ang);
                              const double w = std::pow(10.0, -(k % 7)) * 0.5;
                              a.addTriangle({0.01 * c, 0.01 * s, 1}, {c, s, 1}, {0.5 * c - w * s * 0.1, 0.5 * s + w * c * 0.1, 1});
                              const double ang2 = ang + pi / ns * (k % 2 ? 0.999 : 0.0);
                              const double x = 0.75 * std::cos(ang2), y = 0.75 * std::sin(ang2);
                              if (k % 3 == 0) b.addTriangle({x, y, 0.5}, {x, y, 1.5}, {x + 1e-6, y, 1.5});
                              if (k % 3 == 1) b.addTriangle({x, y, 1}, {x, y, 1.5}, {x + 1e-6, y, 1.5});
                              if (k % 3 == 2) b.addTriangle({x, y, up}, {x, y, 1.5}, {x + 1e-6, y, 1.5});
                            }
                            return std::make_pair(a, b);
                          }));
  // ---- the constructed cases of tests/extremes_scenes.h (docs/numerics.md), as they are
  v.push_back(extremesScene<ExBase>("ext_base", "extremes base: 72-triangle sheet at z=1/2 vs sphere (vertices on the sheet's plane) + hand-placed vertex/edge/coplanar contacts"));
  v.push_back(extremesScene<ExCoplanar>("ext_coplanar_touching", "extremes coplanar_touching_duplicates: duplicates, coplanar overlap/touch, 1-ulp gap, hinges"));
  v.push_back(extremesScene<ExNearParallel>("ext_near_parallel", "extremes near_parallel: parallel one ulp above/below, crossing by one ulp, tilted plane"));
  v.push_back(extremesScene<ExSlivers>("ext_slivers", "extremes slivers_needles: aspect ratio to 1e6, 1e-12 needles, one-ulp misses"));
  v.push_back(extremesScene<ExDegenerate>("ext_degenerate", "extremes degenerate: points, segments, repeated vertices"));
  v.push_back(extremesScene<ExFarPose5>("ext_far_random_pose_5", "extremes far_random_pose_5_s7: the base scene under one random rotation at 1e5 (mapped, rounded)"));
  return v;
}

// ------------------------------------------------------------------ measuring

struct Row {
  std::string scene, cls, backend, scalar, mode;
  bool self = false;
  std::size_t triangles = 0;
  double ms = 0;       // median time per query
  int batch = 1, samples = 0;
  std::size_t pairs = 0, truth = 0, misses = 0, extras = 0;
  double precision = 1, recall = 1;
  bool exact_mismatch = false;
};

const char* modeName(Predicate p) {
  return p == Predicate::Exact ? "exact" : p == Predicate::Double ? "double" : "float";
}

void compare(std::vector<TrianglePair> got, const std::vector<TrianglePair>& truth, Row& r) {
  std::sort(got.begin(), got.end());
  r.pairs = got.size();
  r.truth = truth.size();
  std::vector<TrianglePair> common;
  std::set_intersection(got.begin(), got.end(), truth.begin(), truth.end(), std::back_inserter(common));
  r.misses = truth.size() - common.size();
  r.extras = got.size() - common.size();
  r.precision = got.empty() ? 1.0 : double(common.size()) / double(got.size());
  r.recall = truth.empty() ? 1.0 : double(common.size()) / double(truth.size());
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Times the queries of the three modes interleaved (round robin over the modes in every
/// repeat, so that load from other processes hits all modes alike): one warm-up call each (its
/// result is the one checked), a batch size per mode so a sample lasts >= ~2 ms, then `repeats`
/// samples per mode; median sample / batch.
template <class Q>
std::vector<QueryResult> timeModes(const std::vector<Q>& queries, int repeats, std::vector<Row>& r) {
  std::vector<QueryResult> first;
  std::vector<int> batch;
  for (const Q& q : queries) {
    first.push_back(q());  // warm-up
    const auto t0 = Clock::now();
    (void)q();
    const double once = std::chrono::duration<double>(Clock::now() - t0).count();
    batch.push_back(once < 2e-3 ? int(std::min(2000.0, std::ceil(2e-3 / std::max(once, 1e-7)))) : 1);
  }
  std::vector<std::vector<double>> samples(queries.size());
  for (int i = 0; i < repeats; ++i)
    for (std::size_t m = 0; m < queries.size(); ++m) {
      const auto s = Clock::now();
      for (int k = 0; k < batch[m]; ++k) {
        QueryResult q = queries[m]();
        if (q.pairs.size() == std::size_t(-1)) std::abort();  // keep the call observable
        if (q.kept) throw std::logic_error("a timed query was answered from a kept result");
      }
      samples[m].push_back(std::chrono::duration<double>(Clock::now() - s).count() / batch[m]);
    }
  for (std::size_t m = 0; m < queries.size(); ++m) {
    r[m].ms = median(samples[m]) * 1e3;
    r[m].batch = batch[m];
    r[m].samples = repeats;
  }
  return first;
}

bool g_injected = false;  // --inject-exact-error done

template <class S>
void runScene(const SceneDef& def, const Built<S>& sc, const Options& o, const std::vector<Backend>& backends,
              std::vector<Row>& rows, int& failures) {
  const char* scalar = std::is_same<S, float>::value ? "float" : "double";
  // Ground truth on the coordinates the library decides on.
  const auto t0 = Clock::now();
  std::vector<TrianglePair> truth;
  if (def.self) {
    truth = kdet_referee::selfPairs(sc.a);
  } else {
    const auto va = kdet_extremes::mappedA(sc.a, sc.pose_a, sc.pose_b);
    truth = kdet_referee::meshPairs(va, sc.a.triangles, sc.b.vertices, sc.b.triangles);
  }
  const double tt = std::chrono::duration<double>(Clock::now() - t0).count();
  std::fprintf(stderr, "precision_bench: %-22s %-6s %7zu triangles, truth %zu pairs (referee %.1f s)\n",
               def.name.c_str(), scalar, sc.a.triangles.size() + sc.b.triangles.size(), truth.size(), tt);

  HashedMesh<S> ha(sc.a, sc.pose_a, o.threads);
  std::unique_ptr<HashedMesh<S>> hb;
  if (!def.self) hb = std::make_unique<HashedMesh<S>>(sc.b, sc.pose_b, o.threads);

  const Predicate modes[3] = {Predicate::Exact, Predicate::Double, Predicate::Float};
  for (Backend be : backends) {
    std::vector<Row> rs(3);
    std::vector<std::function<QueryResult()>> queries;
    for (int m = 0; m < 3; ++m) {
      Row& r = rs[m];
      r.scene = def.name;
      r.cls = def.cls;
      r.backend = be == Backend::Cuda ? "cuda" : "cpu";
      r.scalar = scalar;
      r.mode = modeName(modes[m]);
      r.self = def.self;
      r.triangles = sc.a.triangles.size() + sc.b.triangles.size();
      QueryOptions q;
      q.backend = be;
      q.predicate = modes[m];
      q.threads = o.threads;
      queries.push_back([&def, &ha, &hb, q]() { return def.self ? intersectSelf(ha, q) : intersectMeshes(ha, *hb, q); });
    }
    const std::vector<QueryResult> res = timeModes(queries, o.repeats, rs);
    for (int m = 0; m < 3; ++m) {
      Row& r = rs[m];
      std::vector<TrianglePair> got = res[m].pairs;
      if (o.inject && !g_injected && modes[m] == Predicate::Exact && !got.empty()) got.pop_back(), g_injected = true;
      compare(std::move(got), truth, r);
      if (modes[m] == Predicate::Exact && (r.misses || r.extras)) {
        r.exact_mismatch = true;
        ++failures;
        std::fprintf(stderr,
                     "\n!!!!!!!! precision_bench: BUG: Predicate::Exact differs from the exact ground truth on %s (%s, %s): "
                     "%zu misses, %zu extras (%zu pairs, truth %zu) !!!!!!!!\n\n",
                     r.scene.c_str(), r.scalar.c_str(), r.backend.c_str(), r.misses, r.extras, r.pairs, r.truth);
      }
      std::fprintf(stderr, "precision_bench:   %-4s %-6s %-6s %10.4f ms/query  pairs %8zu  misses %6zu  extras %6zu\n",
                   r.backend.c_str(), r.scalar.c_str(), r.mode.c_str(), r.ms, r.pairs, r.misses, r.extras);
      rows.push_back(r);
    }
  }
}

// ------------------------------------------------------------------ output

std::string jsonEscape(const std::string& s) {
  std::string r;
  for (char c : s) {
    if (c == '"' || c == '\\') r += '\\', r += c;
    else if (c == '\n') r += "\\n";
    else r += c;
  }
  return r;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string fmtMs(double ms) {
  return ms >= 100 ? fmt("%.1f", ms) : ms >= 1 ? fmt("%.2f", ms) : ms >= 0.01 ? fmt("%.4f", ms) : fmt("%.5f", ms);
}

std::string fmtRatio(double x) {
  if (x == 1.0) return "1";
  return fmt("%.6f", x);
}

/// Time of the same scene/scalar/backend in Exact mode.
double exactMs(const std::vector<Row>& rows, const Row& r) {
  for (const Row& e : rows)
    if (e.scene == r.scene && e.scalar == r.scalar && e.backend == r.backend && e.mode == "exact") return e.ms;
  return r.ms;
}

struct Env {
  std::string cpu, gpu, gpu_note;
  unsigned hw_threads = 0;
};

void writeMarkdown(const std::string& path, const std::vector<Row>& rows, const std::vector<SceneDef>& scenes,
                   const Options& o, const Env& env, int failures) {
  std::ofstream f(path);
  f << "# precision_bench: speed/accuracy of the predicate modes\n\n";
  f << "Command: `" << o.command << "`  \n";
  f << "CPU: " << env.cpu << " (" << env.hw_threads << " hardware threads; QueryOptions::threads = " << o.threads
    << ")  \nGPU: " << env.gpu << "  \n";
  f << "Timing: median of " << o.repeats << " samples after one warm-up query; a sample is a batch of k queries "
       "(k in the `batch` column of the JSON: enough for >= ~2 ms) timed with steady_clock, divided by k. "
       "Query only (hash built beforehand). The GPU query API is synchronous, so wall time is the GPU time "
       "per query, transfers included.  \n";
  f << "Truth: tests/exact_referee.h (GMP) on every box-overlapping pair of the coordinates the library "
       "decides on (each scalar type has its own rounded scene and its own truth). misses = truth pairs not "
       "reported; extras = reported pairs not in the truth; precision = correct / reported; recall = correct / truth.  \n";
  f << "Exact-mode check: " << (failures ? "**FAILED (" + std::to_string(failures) + " rows differ from the truth)**" : std::string("every Predicate::Exact row equals the truth")) << "\n\n";

  // Summary per backend/scalar/mode, split by scene class.
  f << "## Summary\n\n"
       "Per backend, scalar and mode: misses / extras summed over the scenes of each class, and the geometric mean "
       "of the time relative to Exact on the same scene, scalar and backend (< 1: faster than Exact).\n\n";
  f << "| backend | scalar | mode | generic: misses / extras | generic: time vs exact | near-degenerate: misses / extras | near-degenerate: time vs exact | min precision | min recall |\n";
  f << "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const char* be : {"cpu", "cuda"})
    for (const char* sc : {"double", "float"})
      for (const char* mo : {"exact", "double", "float"}) {
        std::size_t mis[2] = {0, 0}, ext[2] = {0, 0};
        double lsum[2] = {0, 0};
        int cnt[2] = {0, 0};
        double minp = 1, minr = 1;
        bool any = false;
        for (const Row& r : rows) {
          if (r.backend != be || r.scalar != sc || r.mode != mo) continue;
          any = true;
          const int c = r.cls == "generic" ? 0 : 1;
          mis[c] += r.misses;
          ext[c] += r.extras;
          const double e = exactMs(rows, r);
          if (e > 0 && r.ms > 0) lsum[c] += std::log(r.ms / e), ++cnt[c];
          minp = std::min(minp, r.precision);
          minr = std::min(minr, r.recall);
        }
        if (!any) continue;
        f << "| " << be << " | " << sc << " | " << mo;
        for (int c = 0; c < 2; ++c)
          f << " | " << mis[c] << " / " << ext[c] << " | " << (cnt[c] ? fmt("%.2f", std::exp(lsum[c] / cnt[c])) : "-");
        f << " | " << fmtRatio(minp) << " | " << fmtRatio(minr) << " |\n";
      }

  f << "\n## All rows\n\n";
  f << "| scene | class | triangles | backend | scalar | mode | ms/query | pairs | truth pairs | misses | extras | precision | recall |\n";
  f << "| --- | --- | ---: | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const Row& r : rows) {
    f << "| " << r.scene << (r.self ? " (self)" : "") << " | " << r.cls << " | " << r.triangles << " | " << r.backend
      << " | " << r.scalar << " | " << r.mode << " | " << fmtMs(r.ms) << " | " << r.pairs << " | " << r.truth << " | "
      << r.misses << " | " << r.extras << " | " << fmtRatio(r.precision) << " | " << fmtRatio(r.recall) << " |"
      << (r.exact_mismatch ? " **EXACT MISMATCH**" : "") << "\n";
  }
  f << "\n## Scenes\n\n";
  for (const SceneDef& s : scenes) f << "- `" << s.name << "` (" << s.cls << "): " << s.note << "\n";
  f << "\n![time vs errors](precision.png)\n";
}

void writeJson(const std::string& path, const std::vector<Row>& rows, const std::vector<SceneDef>& scenes,
               const Options& o, const Env& env, int failures) {
  std::ofstream f(path);
  f << "{\n  \"command\": \"" << jsonEscape(o.command) << "\",\n  \"cpu\": \"" << jsonEscape(env.cpu)
    << "\",\n  \"hardware_threads\": " << env.hw_threads << ",\n  \"threads\": " << o.threads
    << ",\n  \"gpu\": \"" << jsonEscape(env.gpu) << "\",\n  \"repeats\": " << o.repeats
    << ",\n  \"small\": " << (o.small ? "true" : "false") << ",\n  \"exact_failures\": " << failures
    << ",\n  \"scenes\": [\n";
  for (std::size_t i = 0; i < scenes.size(); ++i)
    f << "    {\"name\": \"" << scenes[i].name << "\", \"class\": \"" << scenes[i].cls << "\", \"self\": "
      << (scenes[i].self ? "true" : "false") << ", \"note\": \"" << jsonEscape(scenes[i].note) << "\"}"
      << (i + 1 < scenes.size() ? "," : "") << "\n";
  f << "  ],\n  \"rows\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    f << "    {\"scene\": \"" << r.scene << "\", \"class\": \"" << r.cls << "\", \"self\": " << (r.self ? "true" : "false")
      << ", \"triangles\": " << r.triangles << ", \"backend\": \"" << r.backend << "\", \"scalar\": \"" << r.scalar
      << "\", \"mode\": \"" << r.mode << "\", \"ms_per_query\": " << fmt("%.6g", r.ms) << ", \"batch\": " << r.batch
      << ", \"samples\": " << r.samples << ", \"pairs\": " << r.pairs << ", \"truth_pairs\": " << r.truth
      << ", \"misses\": " << r.misses << ", \"extras\": " << r.extras << ", \"precision\": " << fmt("%.9g", r.precision)
      << ", \"recall\": " << fmt("%.9g", r.recall) << ", \"exact_mismatch\": " << (r.exact_mismatch ? "true" : "false")
      << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
  }
  f << "  ]\n}\n";
}

/// precision.dat: one block per (backend, scalar, mode) series; x = time relative to Exact on the
/// same scene/scalar/backend, y = misses + extras + 1 (log scale; 1 = no error), then ms/query,
/// triangles, class (0 generic, 1 near-degenerate) and the scene. precision.gp draws two panels,
/// generic and near-degenerate scenes.
void writePlot(const std::string& dir, const std::vector<Row>& rows, const Options& o, const Env& env) {
  std::ofstream d(dir + "/precision.dat");
  struct Series {
    std::string title;
    int color, pt;
  };
  std::vector<Series> series;
  d << "# time_vs_exact errors_plus_1 ms_per_query triangles class(0 generic, 1 near-degenerate) scene\n";
  const std::map<std::string, int> color = {{"exact", 0}, {"double", 1}, {"float", 2}};
  for (const char* be : {"cpu", "cuda"})
    for (const char* sc : {"double", "float"})
      for (const char* mo : {"exact", "double", "float"}) {
        std::vector<const Row*> sel;
        for (const Row& r : rows)
          if (r.backend == be && r.scalar == sc && r.mode == mo) sel.push_back(&r);
        if (sel.empty()) continue;
        d << "# " << be << " " << sc << " mesh, " << mo << " predicate\n";
        for (const Row* r : sel)
          d << fmt("%.6g", r->ms / std::max(exactMs(rows, *r), 1e-12)) << " " << (r->misses + r->extras + 1) << " "
            << fmt("%.6g", r->ms) << " " << r->triangles << " " << (r->cls == "generic" ? 0 : 1) << " " << r->scene
            << "\n";
        d << "\n\n";
        const bool cuda = std::string(be) == "cuda", fl = std::string(sc) == "float";
        // point types: cpu filled (7 circle, 5 square), cuda open (6 circle, 4 square)
        series.push_back({std::string(be) + ", " + sc + " mesh, " + mo + " predicate", color.at(mo),
                          cuda ? (fl ? 4 : 6) : (fl ? 5 : 7)});
      }
  d.close();
  std::ofstream g(dir + "/precision.gp");
  g << "# gnuplot precision.gp (in this folder) -> precision.png\n";
  g << "set terminal pngcairo size 1400,650 noenhanced font ',10'\nset output 'precision.png'\n";
  g << "set multiplot layout 1,2 title \"kdet_fcl predicate modes: time vs errors, one point per scene"
       " (CPU: " << env.cpu << "; GPU: " << env.gpu << ")\"\n";
  double xlo = 1, xhi = 1, yhi = 10;
  for (const Row& r : rows) {
    const double x = r.ms / std::max(exactMs(rows, r), 1e-12);
    if (x > 0) xlo = std::min(xlo, x), xhi = std::max(xhi, x);
    yhi = std::max(yhi, double(r.misses + r.extras + 1));
  }
  g << "set logscale x\nset logscale y\nset grid\nset xrange [" << fmt("%.4g", xlo / 1.5) << ":" << fmt("%.4g", xhi * 1.5)
    << "]\nset yrange [0.7:" << fmt("%.4g", yhi * 5) << "]\n";
  g << "set xtics (0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1, 1.5, 2, 3, 5, 10, 20, 50, 100)\n";
  g << "set xlabel 'time per query / time of Predicate::Exact (same scene, mesh precision, backend)'\n";
  g << "set ylabel 'misses + extras + 1 against the exact referee (1 = exact answer)'\n";
  const char* colors[3] = {"#1b7837", "#2166ac", "#d6604d"};
  for (int panel = 0; panel < 2; ++panel) {
    g << "set title '" << (panel == 0 ? "generic scenes (cloth self, cloth vs sphere, random soup)"
                                      : "near-degenerate scenes (touching, coplanar, nearly parallel, far, slivers, extremes)")
      << "'\n";
    g << (panel == 0 ? "set key top left box opaque\n" : "unset key\n");
    g << "plot ";
    for (std::size_t i = 0; i < series.size(); ++i) {
      // A small deterministic jitter on x separates the series that sit at x = 1 (Exact).
      g << (i ? ", \\\n     " : "") << "'precision.dat' index " << i << " using ($5 == " << panel << " ? $1*(1+0.015*("
        << (int(i % 6) - 3) << ")) : 1/0):2 with points pt " << series[i].pt << " ps 1.3 lc rgb '"
        << colors[series[i].color] << "' title '" << series[i].title << "'";
    }
    g << "\n";
  }
  g << "unset multiplot\n";
  g.close();
  if (o.plot) {
    const std::string cmd = "cd '" + dir + "' && gnuplot precision.gp 2>&1";
    if (std::system(cmd.c_str()) != 0) std::fprintf(stderr, "precision_bench: gnuplot failed (the .dat/.gp files are written)\n");
  }
}

std::string cpuName() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const auto p = line.find(':');
      if (p != std::string::npos) return line.substr(p + 2);
    }
  return "unknown CPU";
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  // Every timed query must run its predicate: the self queries repeat on unchanged meshes, which
  // the backends would answer from their kept results (QueryResult::kept) unless told not to.
  for (const char* knob : {"KDET_FCL_CPU_SELF_CACHE", "KDET_FCL_CUDA_SELF_CACHE"})
    setenv(knob, "0", 1);
  try {
    Env env;
    env.cpu = cpuName();
    env.hw_threads = std::thread::hardware_concurrency();
    std::vector<Backend> backends = {Backend::Cpu};
    if (builtWithCuda() && cudaDeviceCount() > 0) {
      backends.push_back(Backend::Cuda);
      env.gpu = kdet_bench_util::backendGpu();
      std::fprintf(stderr, "precision_bench: GPU: %s\n", env.gpu.c_str());
    } else {
      env.gpu = builtWithCuda() ? "skipped (no device)" : "skipped (built without CUDA)";
      std::printf("GPU: skipped (no device)%s\n", builtWithCuda() ? "" : " [library built without CUDA]");
    }
    const Sizes full{200, 64, 20000, 100, 120, 50, 32, 1000};
    const Sizes small{12, 12, 300, 12, 10, 8, 8, 60};
    std::vector<SceneDef> all = makeScenes(o.small ? small : full), scenes;
    for (const SceneDef& s : all)
      if (selected(o, s.name)) scenes.push_back(s);
    if (scenes.empty()) {
      std::fprintf(stderr, "precision_bench: --only matched no scene; scenes are:");
      for (const SceneDef& s : all) std::fprintf(stderr, " %s", s.name.c_str());
      std::fprintf(stderr, "\n");
      return 1;
    }
    std::filesystem::create_directories(o.out);
    std::vector<Row> rows;
    int failures = 0;
    const auto t0 = Clock::now();
    for (const SceneDef& s : scenes) {
      runScene<double>(s, s.build_d(), o, backends, rows, failures);
      runScene<float>(s, s.build_f(), o, backends, rows, failures);
    }
    std::fprintf(stderr, "precision_bench: %zu rows in %.1f s\n", rows.size(),
                 std::chrono::duration<double>(Clock::now() - t0).count());
    writeMarkdown(o.out + "/precision.md", rows, scenes, o, env, failures);
    writeJson(o.out + "/precision.json", rows, scenes, o, env, failures);
    writePlot(o.out, rows, o, env);
    std::printf("precision_bench: wrote %s/precision.{md,json,dat,gp,png}\n", o.out.c_str());
    if (failures) {
      std::fprintf(stderr,
                   "\n######## precision_bench: FAILED: Predicate::Exact differs from the exact ground truth in %d "
                   "row(s) (see EXACT MISMATCH in %s/precision.md). This is a library bug. ########\n",
                   failures, o.out.c_str());
      return 2;
    }
    std::printf("precision_bench: Predicate::Exact equals the exact ground truth in every row\n");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "precision_bench: error: %s\n", e.what());
    return 1;
  }
}
