// Every pair set equals the O(n^2) brute force with the same exact predicate.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "cpu/worker_pool.h"
#include "kept_self_scenario.h"
#include "scoped_env.h"
#include "test_util.h"

using namespace kdet_fcl;
using kdet_test::sorted;

namespace {

template <class S>
void expectPairQueryMatchesBruteForce(const TriangleMesh<S>& a, const Transform<S>& pa,
                                      const TriangleMesh<S>& b, const Transform<S>& pb,
                                      const char* what) {
  const HashedMesh<S> ha(a, pa), hb(b, pb);
  const QueryResult r = intersectMeshes(ha, hb);
  const auto got = sorted(r.pairs);
  const auto want = bruteForceIntersectMeshes(a, pa, b, pb);
  EXPECT_EQ(got.size(), r.pairs.size());
  ASSERT_EQ(got, want) << what;
  EXPECT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end()) << "pair reported twice";
  EXPECT_TRUE(r.complete);
  EXPECT_EQ(meshesIntersect(ha, hb), !want.empty()) << what;
}

template <class S>
void expectSelfQueryMatchesBruteForce(const TriangleMesh<S>& m, const char* what) {
  const HashedMesh<S> hm(m);
  const auto got = sorted(intersectSelf(hm).pairs);
  ASSERT_EQ(got, bruteForceIntersectSelf(m)) << what;
  for (const auto& p : got) EXPECT_LT(p.a, p.b);
}

template <class S>
class QueryTyped : public ::testing::Test {};
using Precisions = ::testing::Types<float, double>;
TYPED_TEST_SUITE(QueryTyped, Precisions);

/// The pairs of `all` whose triangles' double boxes overlap (a in m1, b in m2).
template <class S>
std::vector<TrianglePair> boxOverlapping(const std::vector<TrianglePair>& all,
                                         const TriangleMesh<S>& m1, const TriangleMesh<S>& m2,
                                         std::size_t* disjoint = nullptr) {
  auto box = [](const TriangleMesh<S>& m, std::uint32_t i) {
    const Triangle& t = m.triangles[i];
    return detail::triangleBox<double>(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]);
  };
  std::vector<TrianglePair> r;
  for (const auto& p : all) {
    if (detail::boxesOverlap(box(m1, p.a), box(m2, p.b))) r.push_back(p);
    else if (disjoint) ++*disjoint;
  }
  return r;
}

TYPED_TEST(QueryTyped, EveryPredicateSeesExactlyTheBoxOverlappingPairs) {
  // Near-coplanar, touching sheets (some vertices a subnormal step off the plane), where the
  // plain predicates, and the exact one below its validity range, accept some pairs whose boxes
  // are a rounding step apart: a query reports, for every predicate, its brute-force set
  // restricted to the pairs whose double boxes overlap. Never more: the hash's compact boxes are
  // rounded outward and keep such pairs, so the scan confirms on the double boxes (the CUDA
  // backend reports the same set).
  using S = TypeParam;
  std::size_t disjoint = 0, total = 0;
  for (bool tilt : {false, true})
    for (std::uint64_t seed : {1u, 2u}) {
      const auto ma = kdet_test::nearCoplanarSheets<S>(12, tilt, seed, true, false);
      const auto mb = kdet_test::nearCoplanarSheets<S>(12, tilt, seed, false, true);
      const auto both = kdet_test::nearCoplanarSheets<S>(12, tilt, seed);
      const HashedMesh<S> ha(ma), hb(mb), hboth(both);
      for (Predicate p : {Predicate::Exact, Predicate::Double, Predicate::Float}) {
        QueryOptions o;
        o.predicate = p;
        const std::string what = std::string(tilt ? "tilted" : "flat") + " seed " +
                                 std::to_string(seed) + " predicate " + std::to_string(int(p));
        const auto inter = boxOverlapping(
            bruteForceIntersectMeshes(ma, Transform<S>(), mb, Transform<S>(), p), ma, mb,
            &disjoint);
        EXPECT_EQ(sorted(intersectMeshes(ha, hb, o).pairs), inter) << what << " inter";
        const auto self = boxOverlapping(bruteForceIntersectSelf(both, p), both, both, &disjoint);
        EXPECT_EQ(sorted(intersectSelf(hboth, o).pairs), self) << what << " self";
        total += inter.size() + self.size();
      }
    }
  EXPECT_GT(total, 1000u);
  // The scenes do hold pairs that a plain predicate accepts across disjoint boxes (else this
  // test could not tell).
  EXPECT_GT(disjoint, 0u);
}

}  // namespace

TYPED_TEST(QueryTyped, RandomSoupsOfSeveralSizeDistributions) {
  using S = TypeParam;
  struct Dist {
    S min_size, max_size;
    const char* name;
  };
  const Dist dists[] = {{S(0.5), S(0.5), "equal sizes"},
                        {S(0.05), S(2), "log-uniform 40x"},
                        {S(0.001), S(8), "log-uniform 8000x"}};
  std::mt19937_64 rng(42);
  int nonempty = 0;
  for (const Dist& d : dists)
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const auto a = makeRandomSoup<S>(400, S(6), d.min_size, d.max_size, seed);
      const auto b = makeRandomSoup<S>(300, S(6), d.min_size, d.max_size, seed + 100);
      const Transform<S> pa = kdet_test::randomPose<S>(rng, -1, 1);
      const Transform<S> pb = kdet_test::randomPose<S>(rng, -1, 1);
      expectPairQueryMatchesBruteForce(a, pa, b, pb, d.name);
      expectPairQueryMatchesBruteForce(a, Transform<S>(), b, Transform<S>(), d.name);
      expectSelfQueryMatchesBruteForce(a, d.name);
      nonempty += bruteForceIntersectSelf(a).empty() ? 0 : 1;
    }
  EXPECT_GT(nonempty, 5);  // the scenes do collide
}

TYPED_TEST(QueryTyped, ClothOverSphereAndClothSelf) {
  using S = TypeParam;
  const auto cloth = makeDrapedCloth<S>(24, S(4), S(1), S(0.03), S(1));
  const auto sphere = makeSphere<S>({0, 0, 0}, S(1), 24, 12);
  expectPairQueryMatchesBruteForce(cloth, Transform<S>(), sphere, Transform<S>(), "cloth/sphere");
  expectSelfQueryMatchesBruteForce(cloth, "cloth self");
  expectSelfQueryMatchesBruteForce(sphere, "sphere self");
  EXPECT_FALSE(bruteForceIntersectMeshes(cloth, Transform<S>(), sphere, Transform<S>()).empty());
  EXPECT_FALSE(bruteForceIntersectSelf(cloth).empty());
  EXPECT_TRUE(bruteForceIntersectSelf(sphere).empty());
}

TEST(Query, FclEnvAgainstRobUnderRandomPoses) {
  const std::string env = kdet_test::sharedData("fcl/env.obj");
  const std::string rob = kdet_test::sharedData("fcl/rob.obj");
  if (env.empty() || rob.empty()) GTEST_SKIP() << "../shared/data is absent";
  const auto menv = readMesh<double>(env);
  const auto mrob = readMesh<double>(rob);
  HashedMesh<double> henv(menv), hrob(mrob);
  std::mt19937_64 rng(2024);
  int colliding = 0;
  std::size_t pairs = 0;
  for (int k = 0; k < 100; ++k) {
    // FCL's test_mesh_mesh: env gets a random pose in [-3000,3000]^2 x [0,3000], rob identity.
    Transform<double> pose = kdet_test::randomPose<double>(rng, -3000, 3000);
    pose.t.z = std::abs(pose.t.z) / 2;
    henv.setPose(pose);
    const auto got = sorted(intersectMeshes(henv, hrob).pairs);
    const auto want = bruteForceIntersectMeshes(menv, pose, mrob, Transform<double>());
    ASSERT_EQ(got, want) << "pose " << k;
    colliding += got.empty() ? 0 : 1;
    pairs += got.size();
  }
  EXPECT_GT(colliding, 10);
  EXPECT_GT(pairs, 100u);
}

TEST(Query, ResultsAndOrderAreIdenticalForOneAndTwoThreads) {
  const auto cloth = makeDrapedCloth<double>(110, 4.0, 1.0, 0.03, 1.0);  // 24k triangles
  const auto sphere = makeSphere<double>({0, 0, 0}, 1.0, 64, 32);
  HashedMesh<double> hc(cloth, Transform<double>(), 1), hs(sphere, Transform<double>(), 2);
  HashedMesh<double> hc2(cloth, Transform<double>(), 2);
  QueryOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const QueryResult r1 = intersectMeshes(hc, hs, one), r2 = intersectMeshes(hc2, hs, two);
  EXPECT_EQ(r1.pairs, r2.pairs);  // same pairs in the same order
  EXPECT_FALSE(r1.pairs.empty());
  EXPECT_EQ(intersectSelf(hc, one).pairs, intersectSelf(hc2, two).pairs);
  EXPECT_FALSE(intersectSelf(hc, one).pairs.empty());
  for (std::size_t k : {std::size_t(1), std::size_t(7), std::size_t(100)}) {
    one.max_pairs = two.max_pairs = k;
    EXPECT_EQ(intersectMeshes(hc, hs, one).pairs, intersectMeshes(hc2, hs, two).pairs) << k;
    EXPECT_EQ(intersectSelf(hc, one).pairs, intersectSelf(hc2, two).pairs) << k;
  }
}

// A capped query runs its first chunks (one of each mesh's sample) on the calling thread and
// wakes workers only if its pairs are not all there (src/cpu/query.cpp, runChunks): a first
// contact on a large pair costs no thread's wake-up, and the pairs are the same for any thread
// count whether the cap is met in those chunks, at their end or later.
TEST(Query, ACappedQueryMetInItsFirstChunksWakesNoWorker) {
  const auto cloth = makeDrapedCloth<double>(150, 4.0, 1.0, 0.03, 1.0);  // 45k triangles
  const auto sphere = makeSphere<double>({0, 0, 0}, 1.0, 96, 48);
  HashedMesh<double> hc(cloth, Transform<double>(), 1), hs(sphere, Transform<double>(), 1);
  QueryOptions o;
  o.threads = 1;
  const QueryResult all = intersectMeshes(hc, hs, o);
  ASSERT_GT(all.pairs.size(), 200u);
  // Each CTest case runs in a process of its own: no parallel job has started a worker yet
  // (run alone by gtest_filter, or after other tests in one process, the check is skipped).
  const int before = cpu::WorkerPool::shared().workers();
  o.threads = 8;
  o.max_pairs = 1;
  const QueryResult first = intersectMeshes(hc, hs, o);
  ASSERT_EQ(first.pairs.size(), 1u);
  if (before == 0) EXPECT_EQ(cpu::WorkerPool::shared().workers(), 0) << "a worker was started";
  // The caps land before, at and after the first chunks' pairs: equal across thread counts.
  QueryOptions serial;
  serial.threads = 1;
  serial.max_pairs = all.pairs.size() + 1;
  const std::vector<TrianglePair> order = intersectMeshes(hc, hs, serial).pairs;
  for (std::size_t k : {std::size_t(1), std::size_t(2), std::size_t(31), std::size_t(64),
                        std::size_t(200), all.pairs.size(), all.pairs.size() + 1}) {
    for (int t : {1, 2, 8}) {
      QueryOptions c;
      c.threads = t;
      c.max_pairs = k;
      const QueryResult r = intersectMeshes(hc, hs, c);
      ASSERT_EQ(r.pairs.size(), std::min(k, order.size())) << k << " " << t;
      EXPECT_TRUE(std::equal(r.pairs.begin(), r.pairs.end(), order.begin())) << k << " " << t;
      EXPECT_EQ(r.complete, k > order.size()) << k << " " << t;
    }
  }
  // An uncapped query on 8 threads does start workers: the check above can fail.
  if (before == 0) {
    o.max_pairs = 0;
    EXPECT_EQ(intersectMeshes(hc, hs, o).pairs.size(), all.pairs.size());
    EXPECT_GT(cpu::WorkerPool::shared().workers(), 0);
  }
}

TEST(Query, MaxPairsStopsEarlyWithTruePairsInTheCappedOrder) {
  const auto cloth = makeDrapedCloth<double>(40, 4.0, 1.0, 0.03, 1.0);
  const auto sphere = makeSphere<double>({0, 0, 0}, 1.0, 32, 16);
  HashedMesh<double> hc(cloth), hs(sphere);
  const QueryResult all = intersectMeshes(hc, hs);
  ASSERT_GT(all.pairs.size(), 20u);
  const std::vector<TrianglePair> all_sorted = sorted(all.pairs);
  // A capped query visits a spread sample first (src/cpu/query.cpp, VisitOrder): its pairs are
  // true pairs, each once, and a smaller cap's pairs are the first ones of a larger cap's.
  QueryOptions every;
  every.max_pairs = all.pairs.size() + 1;  // more than there are: the capped order, whole
  const QueryResult capped_all = intersectMeshes(hc, hs, every);
  EXPECT_TRUE(capped_all.complete);
  EXPECT_EQ(sorted(capped_all.pairs), all_sorted);
  for (std::size_t k : {std::size_t(1), std::size_t(5), std::size_t(20)}) {
    QueryOptions o;
    o.max_pairs = k;
    const QueryResult part = intersectMeshes(hc, hs, o);
    ASSERT_EQ(part.pairs.size(), k);
    EXPECT_FALSE(part.complete);
    EXPECT_TRUE(std::equal(part.pairs.begin(), part.pairs.end(), capped_all.pairs.begin())) << k;
    for (const TrianglePair& p : part.pairs)
      EXPECT_TRUE(std::binary_search(all_sorted.begin(), all_sorted.end(), p)) << k;
    // Paying only for what is asked: fewer exact tests than the full query.
    EXPECT_LT(part.stats.triangle_tests, all.stats.triangle_tests);
  }
  // Above kSampleMaxPairs (4096) a cap keeps the full query's order: a prefix of it.
  {
    QueryOptions o;
    o.max_pairs = 5000;
    EXPECT_EQ(intersectMeshes(hc, hs, o).pairs, all.pairs);
  }
  QueryOptions o;
  o.max_pairs = all.pairs.size() + 1;
  const QueryResult more = intersectMeshes(hc, hs, o);
  EXPECT_EQ(sorted(more.pairs), all_sorted);
  EXPECT_TRUE(more.complete);
  EXPECT_TRUE(meshesIntersect(hc, hs));
  hc.setPose(makeTransform<double>({1, 0, 0}, 0.3, {10, 0, 0}));
  EXPECT_FALSE(meshesIntersect(hc, hs));
}

// A capped query (max_pairs > 0) visits a spread sample of each mesh first (VisitOrder in
// src/cpu/query.cpp), so its first pair comes early wherever the contact lies. Here a sphere
// (numbered ring by ring) lies wholly inside a torus's bounds and cuts its tube along a band
// round its equator: in index order the query looked up most of the sphere before that band.
TEST(Query, ACappedQueryMeetsAContactEarlyWhereverItLies) {
  const auto ball = makeSphere<double>({0, 0, 0}, 0.62, 48, 24);
  TriangleMesh<double> ring;  // R 0.9, r 0.3, 64 x 24 quads
  const double pi = 3.14159265358979323846;
  auto at = [&](int i, int j) {
    const double th = 2 * pi * (i % 64) / 64, ph = 2 * pi * (j % 24) / 24;
    return Vec3<double>{(0.9 + 0.3 * std::cos(ph)) * std::cos(th),
                        (0.9 + 0.3 * std::cos(ph)) * std::sin(th), 0.3 * std::sin(ph)};
  };
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 64; ++i) {
      ring.addTriangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      ring.addTriangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  QueryOptions one_thread, first;
  one_thread.threads = first.threads = 1;
  first.max_pairs = 1;
  for (const bool ball_first : {true, false}) {
    HashedMesh<double> a(ball_first ? ball : ring), b(ball_first ? ring : ball);
    const QueryResult full = intersectMeshes(a, b, one_thread);
    ASSERT_GT(full.pairs.size(), 10u) << ball_first;
    const QueryResult got = intersectMeshes(a, b, first);
    ASSERT_EQ(got.pairs.size(), 1u) << ball_first;
    const auto want = sorted(full.pairs);
    EXPECT_TRUE(std::binary_search(want.begin(), want.end(), got.pairs[0])) << ball_first;
    EXPECT_LT(got.stats.lookups * 4, full.stats.lookups) << ball_first;
  }
  // The two as one mesh: its self query's first pair.
  TriangleMesh<double> both = ball;
  for (const Triangle& t : ring.triangles)
    both.addTriangle(ring.vertices[t[0]], ring.vertices[t[1]], ring.vertices[t[2]]);
  HashedMesh<double> h(both);
  const QueryResult self_full = intersectSelf(h, one_thread);
  ASSERT_GT(self_full.pairs.size(), 10u);
  const QueryResult self_first = intersectSelf(h, first);
  ASSERT_EQ(self_first.pairs.size(), 1u);
  const auto self_want = sorted(self_full.pairs);
  EXPECT_TRUE(std::binary_search(self_want.begin(), self_want.end(), self_first.pairs[0]));
  EXPECT_LT(self_first.stats.lookups * 4, self_full.stats.lookups);
}

// The capped order visits every triangle exactly once at every mesh size (the sample, then the
// rest; sizes around the sample's step of 8 and the chunk of 256): a cap above the pair count
// finds the full query's pairs, each once.
TEST(Query, ACappedQueryVisitsEveryTriangleOnceAtAnySize) {
  for (std::size_t n : {1, 2, 3, 7, 8, 9, 16, 23, 24, 25, 31, 33, 64, 65, 255, 256, 257, 1000,
                        2047, 2049}) {
    const double extent = std::max(1.0, 0.5 * std::cbrt(double(n)));  // some pairs, not too many
    const auto a = makeRandomSoup<double>(n, extent, 0.3, 0.9, 100 + n);
    const auto b = makeRandomSoup<double>(n + 5, extent, 0.3, 0.9, 200 + n);
    HashedMesh<double> ha(a), hb(b);
    const QueryResult full = intersectMeshes(ha, hb);
    const QueryResult self_full = intersectSelf(ha);
    QueryOptions capped;
    capped.max_pairs = 4096;  // sampled (kSampleMaxPairs), above every pair count here
    const QueryResult inter = intersectMeshes(ha, hb, capped);
    ASSERT_LT(full.pairs.size(), 4096u) << n;
    EXPECT_TRUE(inter.complete) << n;
    EXPECT_EQ(sorted(inter.pairs), sorted(full.pairs)) << n;
    EXPECT_EQ(inter.pairs.size(), full.pairs.size()) << n;
    const QueryResult self = intersectSelf(ha, capped);
    ASSERT_LT(self_full.pairs.size(), 4096u) << n;
    EXPECT_EQ(sorted(self.pairs), sorted(self_full.pairs)) << n;
    EXPECT_EQ(self.pairs.size(), self_full.pairs.size()) << n;
    if (n >= 64) {  // the check has something to find (about n / 5 inter pairs)
      EXPECT_GT(full.pairs.size(), n / 10) << n;
      EXPECT_GT(self_full.pairs.size(), 0u) << n;
    }
  }
}

TEST(Query, TouchingAndCoincidentGeometryCounts) {
  // Two unit squares (two triangles each) sharing the plane z = 0 and touching along x = 1.
  TriangleMesh<double> a, b;
  a.addTriangle({0, 0, 0}, {1, 0, 0}, {1, 1, 0});
  a.addTriangle({0, 0, 0}, {1, 1, 0}, {0, 1, 0});
  b.addTriangle({1, 0, 0}, {2, 0, 0}, {2, 1, 0});
  b.addTriangle({1, 0, 0}, {2, 1, 0}, {1, 1, 0});
  expectPairQueryMatchesBruteForce(a, Transform<double>(), b, Transform<double>(), "touching");
  EXPECT_FALSE(bruteForceIntersectMeshes(a, Transform<double>(), b, Transform<double>()).empty());
  // A mesh against an identical copy: every pair that shares a point.
  const auto s = makeSphere<double>({0, 0, 0}, 1.0, 12, 6);
  expectPairQueryMatchesBruteForce(s, Transform<double>(), s, Transform<double>(), "coincident");
  // The same, far from the origin and rotated by 180 degrees about z.
  const Transform<double> far = makeTransform<double>({0, 0, 1}, 3.14159265358979323846, {1e5, -1e5, 1e5});
  expectPairQueryMatchesBruteForce(s, far, s, far, "coincident far away");
}

TEST(Query, DeformationAndTopologyChangesAreSeen) {
  auto cloth = makeDrapedCloth<double>(30, 4.0, 1.0, 0.03, 0.0);  // flat, above the sphere
  const auto sphere = makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  HashedMesh<double> hc(cloth), hs(sphere);
  EXPECT_TRUE(intersectMeshes(hc, hs).pairs.empty());
  for (double t : {0.3, 0.7, 1.0}) {
    const auto frame = makeDrapedCloth<double>(30, 4.0, 1.0, 0.03, t);
    hc.updateVertices(frame.vertices);
    ASSERT_EQ(sorted(intersectMeshes(hc, hs).pairs),
              bruteForceIntersectMeshes(frame, Transform<double>(), sphere, Transform<double>()));
    ASSERT_EQ(sorted(intersectSelf(hc).pairs), bruteForceIntersectSelf(frame));
  }
  EXPECT_FALSE(intersectMeshes(hc, hs).pairs.empty());
  // Fracture: drop every other triangle and add a loose piece through the sphere.
  TriangleMesh<double> broken;
  broken.vertices = hc.mesh().vertices;
  for (std::size_t i = 0; i < hc.mesh().triangles.size(); i += 2)
    broken.triangles.push_back(hc.mesh().triangles[i]);
  broken.addTriangle({-2, -2, 0}, {2, -2, 0}, {0, 2, 0});
  hc.setMesh(broken);
  ASSERT_EQ(sorted(intersectMeshes(hc, hs).pairs),
            bruteForceIntersectMeshes(broken, Transform<double>(), sphere, Transform<double>()));
  ASSERT_EQ(sorted(intersectSelf(hc).pairs), bruteForceIntersectSelf(broken));
}

TEST(Query, SelfCollisionSkipsVertexSharingPairsInSoups) {
  // The same strip as an indexed mesh and as a soup: adjacency by index and by coordinates.
  TriangleMesh<double> indexed;
  indexed.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  indexed.triangles = {{0, 1, 2}, {1, 3, 2}};
  TriangleMesh<double> soup;
  soup.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  soup.addTriangle({1, 0, 0}, {1, 1, 0}, {0, 1, 0});
  EXPECT_TRUE(intersectSelf(HashedMesh<double>(indexed)).pairs.empty());
  EXPECT_TRUE(intersectSelf(HashedMesh<double>(soup)).pairs.empty());
  // A third triangle piercing both (sharing no vertex) collides with both.
  soup.addTriangle({0.5, 0.2, -1}, {0.6, 0.8, 1}, {0.4, 0.5, 1});
  const auto got = sorted(intersectSelf(HashedMesh<double>(soup)).pairs);
  EXPECT_EQ(got, (std::vector<TrianglePair>{{0, 2}, {1, 2}}));
  EXPECT_EQ(got, bruteForceIntersectSelf(soup));
}

TEST(Query, IntersectAllGivesEachSelfAndTheInterPairs) {
  // Two strips that touch along one edge's coordinates: within a strip the shared edge makes its
  // triangles adjacent (no pair), across the strips the touch is a pair. A third triangle
  // pierces strip a. intersectAll must give the three queries' pairs (checked against brute
  // force), also with max_pairs, and throw the same typed error as they do for a missing device.
  TriangleMesh<double> a, b;
  a.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  a.addTriangle({1, 0, 0}, {1, 1, 0}, {0, 1, 0});
  a.addTriangle({0.5, 0.2, -1}, {0.6, 0.8, 1}, {0.4, 0.5, 1});
  b.addTriangle({1, 0, 0}, {2, 0, 0}, {1, 1, 0});
  b.addTriangle({2, 0, 0}, {2, 1, 0}, {1, 1, 0});
  const HashedMesh<double> ha(a), hb(b);
  const AllPairsResult all = intersectAll(ha, hb);
  EXPECT_EQ(sorted(all.self_a.pairs), bruteForceIntersectSelf(a));
  EXPECT_EQ(sorted(all.self_b.pairs), bruteForceIntersectSelf(b));
  EXPECT_EQ(sorted(all.inter.pairs), bruteForceIntersectMeshes(a, Transform<double>(), b, Transform<double>()));
  EXPECT_EQ(all.self_a.pairs.size(), 2u);
  EXPECT_TRUE(all.self_b.pairs.empty());
  // a0 and b0 share the point (1, 0, 0), a1 and b0 an edge, a1 and b1 the point (1, 1, 0).
  EXPECT_EQ(sorted(all.inter.pairs), (std::vector<TrianglePair>{{0, 0}, {1, 0}, {1, 1}}));
  QueryOptions one;
  one.max_pairs = 1;
  const AllPairsResult first = intersectAll(ha, hb, one);
  EXPECT_EQ(first.self_a.pairs.size(), 1u);
  EXPECT_FALSE(first.self_a.complete);
  EXPECT_EQ(first.inter.pairs, intersectMeshes(ha, hb, one).pairs);
  if (cudaDeviceCount() == 0) {
    QueryOptions cuda;
    cuda.backend = Backend::Cuda;
    EXPECT_THROW(intersectAll(ha, hb, cuda), BackendUnavailableError);
  }
}

TEST(Query, ResultsKeptAcrossFramesAreReplacedByEachFramesResult) {
  // intersectMeshes, intersectSelf and intersectAll into a result the caller keeps: each call
  // replaces it by the by-value call's result (pairs, complete, kept), whatever it held.
  kdet_test::ScopedEnv keep_on("KDET_FCL_CPU_SELF_CACHE", nullptr);  // (off in test binaries)
  HashedMesh<double> a(makeRandomSoup<double>(500, 3.0, 0.2, 2.0, 77));
  HashedMesh<double> b(makeRandomSoup<double>(400, 3.0, 0.2, 2.0, 78));
  QueryResult inter, self;
  AllPairsResult all;
  inter.pairs.assign(100000, TrianglePair{7, 7});  // stale: more pairs than any frame has
  self.kept = true;
  all.self_b.complete = false;
  for (std::uint64_t seed : {78, 79, 80}) {
    b.updateVertices(makeRandomSoup<double>(400, 3.0, 0.2, 2.0, seed).vertices);
    const std::string what = "seed " + std::to_string(seed);
    intersectMeshes(a, b, inter);
    EXPECT_EQ(inter.pairs, intersectMeshes(a, b).pairs) << what;
    EXPECT_TRUE(inter.complete) << what;
    const QueryResult by_value = intersectSelf(b);
    intersectSelf(b, self);  // (the geometry's second self query: it runs and keeps its result)
    EXPECT_EQ(self.pairs, by_value.pairs) << what;
    EXPECT_FALSE(self.kept) << what;
    intersectAll(a, b, all);
    EXPECT_EQ(all.self_a.pairs, intersectSelf(a).pairs) << what;
    EXPECT_EQ(all.self_b.pairs, intersectSelf(b).pairs) << what;
    EXPECT_EQ(all.inter.pairs, inter.pairs) << what;
    EXPECT_TRUE(all.self_a.complete && all.self_b.complete && all.inter.complete) << what;
    EXPECT_FALSE(inter.pairs.empty()) << what;
  }
  // The third self query of that geometry is answered from the kept result.
  const std::vector<TrianglePair> ran = self.pairs;
  intersectSelf(b, self);
  EXPECT_TRUE(self.kept);
  EXPECT_EQ(self.pairs, ran);
  QueryOptions two;
  two.max_pairs = 2;
  intersectMeshes(a, b, inter, two);
  EXPECT_EQ(inter.pairs, intersectMeshes(a, b, two).pairs);
  EXPECT_EQ(inter.pairs.size(), 2u);
  EXPECT_FALSE(inter.complete);
  if (cudaDeviceCount() == 0) {
    QueryOptions cuda;
    cuda.backend = Backend::Cuda;
    EXPECT_THROW(intersectAll(a, b, all, cuda), BackendUnavailableError);
    EXPECT_THROW(intersectSelf(a, self, cuda), BackendUnavailableError);
    EXPECT_THROW(intersectMeshes(a, b, inter, cuda), BackendUnavailableError);
  }
}

TEST(Query, CudaBackendRequestIsATypedError) {
  if (cudaDeviceCount() > 0) GTEST_SKIP() << "a CUDA device is present (the cuda tests cover it)";
  HashedMesh<double> a(makeSphere<double>({0, 0, 0}, 1.0, 8, 4));
  QueryOptions o;
  o.backend = Backend::Cuda;
  EXPECT_THROW(intersectMeshes(a, a, o), BackendUnavailableError);
  EXPECT_THROW(intersectSelf(a, o), BackendUnavailableError);
  o.backend = Backend::Auto;
  EXPECT_NO_THROW(intersectSelf(a, o));
}

TEST(Query, EveryPredicateModeMatchesItsBruteForce) {
  // Each mode is a different predicate. On this generic scene every pair a mode accepts has
  // overlapping boxes, so the hierarchy finds exactly that mode's brute-force set (in general the
  // plain modes may also accept pairs with disjoint boxes, which no query reports: see
  // docs/numerics.md), and the Double mode agrees with the exact one.
  const auto a = makeRandomSoup<double>(500, 3.0, 0.2, 2.0, 77);
  const auto b = makeRandomSoup<double>(400, 3.0, 0.2, 2.0, 78);
  std::mt19937_64 rng(9);
  const Transform<double> pa = kdet_test::randomPose<double>(rng, -0.5, 0.5);
  const HashedMesh<double> ha(a, pa), hb(b);
  const auto exact = bruteForceIntersectMeshes(a, pa, b, Transform<double>());
  ASSERT_FALSE(exact.empty());
  for (Predicate p : {Predicate::Exact, Predicate::Double, Predicate::Float}) {
    QueryOptions o;
    o.predicate = p;
    const auto want = bruteForceIntersectMeshes(a, pa, b, Transform<double>(), p);
    EXPECT_EQ(sorted(intersectMeshes(ha, hb, o).pairs), want) << int(p);
    EXPECT_EQ(sorted(intersectSelf(ha, o).pairs), bruteForceIntersectSelf(a, p)) << int(p);
    if (p == Predicate::Double) EXPECT_EQ(want, exact);  // generic position: no rounding trap
  }
  // Touching geometry is where the plain modes may err; Exact must report the shared edge.
  TriangleMesh<double> t1, t2;
  t1.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  t2.addTriangle({1, 0, 0}, {0, 1, 0}, {0.3, 0.3, 1});  // shares the edge (1,0,0)-(0,1,0)
  EXPECT_EQ(bruteForceIntersectMeshes(t1, Transform<double>(), t2, Transform<double>()).size(), 1u);
}

TEST(Query, SelfResultOfAnUnchangedMeshIsKeptAndDroppedOnAnyChange) {
  HashedMesh<double> soup(makeRandomSoup<double>(1500, 6.0, 0.3, 1.2, 17));
  // One self query of `soup`: its pairs, order and completeness equal those of a fresh mesh of
  // the same geometry (whose first self query always runs), and `kept` says whether it ran.
  auto self = [&](const std::string& what, std::size_t max_pairs, Predicate pred,
                  int threads = 0) {
    QueryOptions o;
    o.max_pairs = max_pairs;
    o.predicate = pred;
    o.threads = threads;
    const QueryResult got = intersectSelf(soup, o);
    const HashedMesh<double> fresh(soup.mesh());
    const QueryResult want = intersectSelf(fresh, o);
    EXPECT_FALSE(want.kept) << what;
    EXPECT_EQ(got.pairs, want.pairs) << what;
    EXPECT_EQ(got.complete, want.complete) << what;
    if (got.kept) EXPECT_EQ(got.stats.lookups, 0u) << what << ": a kept answer does no work";
    else EXPECT_GT(got.stats.lookups, 0u) << what;
    if (pred == Predicate::Exact && max_pairs == 0)
      EXPECT_EQ(sorted(got.pairs), bruteForceIntersectSelf(soup.mesh())) << what;
    return std::make_pair(got.pairs, got.kept);
  };
  kdet_test::runKeptSelfScenario(soup, Backend::Cpu, "KDET_FCL_CPU_SELF_CACHE", self);
  // Turned on again: the result kept before the queries with it off is still this geometry's.
  kdet_test::ScopedEnv keep_on("KDET_FCL_CPU_SELF_CACHE", nullptr);
  EXPECT_TRUE(self("on again", 0, Predicate::Exact).second);
  // The thread count does not matter to the pairs, so not to a kept answer either.
  EXPECT_TRUE(self("kept, one thread", 0, Predicate::Exact, 1).second);
  EXPECT_TRUE(self("kept, three threads", 0, Predicate::Exact, 3).second);
  // A moved mesh takes its kept result along; a new mesh in the moved-from object has none.
  HashedMesh<double> taken(std::move(soup));
  soup = HashedMesh<double>(taken.mesh());
  EXPECT_TRUE(intersectSelf(taken).kept);
  EXPECT_FALSE(self("a new mesh in the moved-from object", 0, Predicate::Exact).second);
}

TEST(Query, ConcurrentSelfQueriesOfAnUnchangedMeshAllGetItsPairs) {
  kdet_test::ScopedEnv keep_on("KDET_FCL_CPU_SELF_CACHE", nullptr);
  const HashedMesh<float> mesh(makeRandomSoup<float>(2000, 6.0, 0.3, 1.2, 23));
  const std::vector<TrianglePair> want = bruteForceIntersectSelf(mesh.mesh());
  ASSERT_GT(want.size(), 20u);
  // The first queries compute and one keeps; the others may compute or answer from the kept
  // result while it is stored: every one must get the same pairs.
  std::vector<int> wrong(8, 0);
  std::vector<std::thread> workers;
  for (int w = 0; w < 8; ++w)
    workers.emplace_back([&, w] {
      QueryOptions o;
      o.threads = 1;
      for (int k = 0; k < 12; ++k)
        if (sorted(intersectSelf(mesh, o).pairs) != want) ++wrong[w];
    });
  for (std::thread& t : workers) t.join();
  for (int w = 0; w < 8; ++w) EXPECT_EQ(wrong[w], 0) << "worker " << w;
  // After queries of the same geometry, one of them kept its result.
  const QueryResult last = intersectSelf(mesh);
  EXPECT_TRUE(last.kept);
  EXPECT_EQ(sorted(last.pairs), want);
}
