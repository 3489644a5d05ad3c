// Cross-checks of kdet_fcl::collide / selfCollide against FCL 0.7 (issue 3): exhaustive pair sets
// on FCL's env/rob scene under random poses for every BV type, the UNC frames, procedural meshes;
// first-contact and k-contact queries; mixed BV types; result accumulation; contact values;
// self-collision; forwarded shape pairs; the structure cache; bad input.

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "fcl/triangle_contact.h"
#include "fcl_test_util.h"
#include "scoped_env.h"
#include "test_util.h"

using namespace kdet_fcl_test;
using kdet_fcl::TriangleMesh;

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

struct EnvRob {
  TriangleMesh<double> env, rob;
  bool ok = false;
};

const EnvRob& envRob() {
  static EnvRob s = [] {
    EnvRob r;
    const std::string e = kdet_test::sharedData("fcl/env.obj");
    const std::string b = kdet_test::sharedData("fcl/rob.obj");
    if (e.empty() || b.empty()) return r;
    r.env = kdet_fcl::readMesh<double>(e);
    r.rob = kdet_fcl::readMesh<double>(b);
    r.ok = true;
    return r;
  }();
  return s;
}

#define REQUIRE_ENV_ROB()                                                     \
  const EnvRob& er = envRob();                                                \
  if (!er.ok) GTEST_SKIP() << "../shared/data/fcl (env.obj, rob.obj) absent"

std::vector<fcl::Transform3d> envPoses(std::size_t n, std::uint64_t seed) {
  // FCL's test_mesh_mesh extents {-3000,-3000,0,3000,3000,3000}, applied to env; rob at identity.
  const double lo[3] = {-3000, -3000, 0}, hi[3] = {3000, 3000, 3000};
  std::mt19937_64 rng(seed);
  std::vector<fcl::Transform3d> poses;
  for (std::size_t i = 0; i < n; ++i) poses.push_back(randomPose<double>(rng, lo, hi));
  return poses;
}

template <class BV>
void crossCheckEnvRob(const char* name, std::size_t num_poses) {
  const EnvRob& er = envRob();
  auto env = makeModel<fcl::BVHModel<BV>>(er.env);
  auto rob = makeModel<fcl::BVHModel<BV>>(er.rob);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  std::size_t colliding = 0, pairs = 0, settled = 0;
  double t_fcl = 0, t_kdet = 0;
  std::vector<std::string> failures;
  for (const fcl::Transform3d& tf : envPoses(num_poses, 1234)) {
    auto t0 = Clock::now();
    const Pairs f = fclPairs<double>(env.get(), tf, rob.get(), I);
    t_fcl += secondsSince(t0);
    t0 = Clock::now();
    bool one = false;
    const Pairs k = kdetPairs<double>(env.get(), tf, rob.get(), I, &one);
    t_kdet += secondsSince(t0);
    EXPECT_TRUE(one) << name << ": one contact per pair with the caller's o1/o2";
    colliding += !k.empty();
    pairs += k.size();
    auto fl = compareSets(name, k, f, er.env, tf, er.rob, I, settled);
    failures.insert(failures.end(), fl.begin(), fl.end());
  }
  for (const auto& f : failures) ADD_FAILURE() << f;
  std::printf("env/rob %-7s %zu poses, %zu colliding, %zu pairs compared, %zu settled; "
              "per query: FCL %.1f us, kdet_fcl %.1f us\n",
              name, num_poses, colliding, pairs, settled, 1e6 * t_fcl / num_poses,
              1e6 * t_kdet / num_poses);
  EXPECT_GT(colliding, 0u);
}

}  // namespace

// ---- (1) env.obj vs rob.obj, as FCL's test_mesh_mesh, for every BV type FCL's matrix has ----

TEST(FclCollideEnvRob, ExhaustiveSetsEqualFclOBB) {
  REQUIRE_ENV_ROB();
  crossCheckEnvRob<fcl::OBBd>("OBB", 200);
}
TEST(FclCollideEnvRob, ExhaustiveSetsEqualFclOBBRSS) {
  REQUIRE_ENV_ROB();
  crossCheckEnvRob<fcl::OBBRSSd>("OBBRSS", 200);
}
TEST(FclCollideEnvRob, ExhaustiveSetsEqualFclRSS) {
  REQUIRE_ENV_ROB();
  crossCheckEnvRob<fcl::RSSd>("RSS", 100);
}
TEST(FclCollideEnvRob, ExhaustiveSetsEqualFclAABB) {
  REQUIRE_ENV_ROB();
  crossCheckEnvRob<fcl::AABBd>("AABB", 100);
}
TEST(FclCollideEnvRob, ExhaustiveSetsEqualFclkIOSAndKDOP) {
  REQUIRE_ENV_ROB();
  crossCheckEnvRob<fcl::kIOSd>("kIOS", 30);
  crossCheckEnvRob<fcl::KDOPd<16>>("KDOP16", 10);
  crossCheckEnvRob<fcl::KDOPd<18>>("KDOP18", 10);
  crossCheckEnvRob<fcl::KDOPd<24>>("KDOP24", 10);
}

// ---- (5) mixed BV types: FCL refuses them; kdet_fcl gives the same-type reference set ----

TEST(FclCollideEnvRob, MixedBVTypesWork) {
  REQUIRE_ENV_ROB();
  auto env_aabb = makeModel<fcl::BVHModel<fcl::AABBd>>(er.env);
  auto env_obb = makeModel<fcl::BVHModel<fcl::OBBd>>(er.env);
  auto rob_obbrss = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(er.rob);
  auto rob_obb = makeModel<fcl::BVHModel<fcl::OBBd>>(er.rob);
  auto rob_kmesh = makeModel<kdet_fcl::Meshd>(er.rob);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  std::size_t nonempty = 0;
  for (const auto& tf : envPoses(40, 99)) {
    const Pairs ref = fclPairs<double>(env_obb.get(), tf, rob_obb.get(), I);
    std::size_t settled = 0;
    for (const Pairs& k : {kdetPairs<double>(env_aabb.get(), tf, rob_obbrss.get(), I),
                           kdetPairs<double>(env_aabb.get(), tf, rob_kmesh.get(), I),
                           kdetPairs<double>(env_obb.get(), tf, rob_kmesh.get(), I)}) {
      for (const auto& f : compareSets("mixed", k, ref, er.env, tf, er.rob, I, settled))
        ADD_FAILURE() << f;
    }
    nonempty += !ref.empty();
  }
  EXPECT_GT(nonempty, 5u);
}

// ---- (4) first contact and k contacts: isCollision() and counts agree with FCL ----

TEST(FclCollideEnvRob, FirstAndKContactsAgreeWithFcl) {
  REQUIRE_ENV_ROB();
  auto env = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(er.env);
  auto rob = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(er.rob);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  const Pairs none;
  for (const auto& tf : envPoses(100, 7)) {
    const Pairs all = kdetPairs<double>(env.get(), tf, rob.get(), I);
    for (std::size_t k : {1u, 2u, 10u, 50u}) {
      fcl::CollisionRequestd req(k, false);
      fcl::CollisionResultd rf, rk;
      const std::size_t nf = fcl::collide(env.get(), tf, rob.get(), I, req, rf);
      const std::size_t nk = kdet_fcl::collide(env.get(), tf, rob.get(), I, req, rk);
      EXPECT_EQ(rf.isCollision(), rk.isCollision());
      EXPECT_EQ(nf, nk) << "k=" << k;
      EXPECT_EQ(nk, std::min<std::size_t>(k, all.size()));
      // The k pairs returned are true pairs of the exhaustive set.
      for (const Pair& p : pairsOf(rk)) EXPECT_TRUE(std::binary_search(all.begin(), all.end(), p));
    }
  }
}

// ---- (2) the UNC frames: two consecutive frames as two objects (many nearly coincident pairs) --

namespace {

void crossCheckFrames(const char* name, const TriangleMesh<double>& a,
                      const TriangleMesh<double>& b, std::size_t min_pairs) {
  auto fa = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(a);
  auto fb = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(b);
  auto ka = makeModel<fcl::BVHModel<fcl::AABBd>>(a);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  auto t0 = Clock::now();
  const Pairs f = fclPairs<double>(fa.get(), I, fb.get(), I);
  const double tf = secondsSince(t0);
  t0 = Clock::now();
  const Pairs k = kdetPairs<double>(ka.get(), I, fb.get(), I);
  const double tk = secondsSince(t0);
  std::size_t settled = 0;
  for (const auto& fl : compareSets(name, k, f, a, I, b, I, settled)) ADD_FAILURE() << fl;
  std::printf("%s: %zu x %zu triangles, FCL %zu pairs (%.3f s), kdet_fcl %zu pairs (%.3f s), "
              "%zu settled\n",
              name, a.triangles.size(), b.triangles.size(), f.size(), tf, k.size(), tk, settled);
  EXPECT_GE(k.size(), min_pairs);
}

}  // namespace

TEST(FclCollideUnc, FunnelFramesEqualFcl) {
  const std::string p0 = kdet_test::sharedData("unc/cloth-funnel/227.ply");
  const std::string p1 = kdet_test::sharedData("unc/cloth-funnel/228.ply");
  if (p0.empty() || p1.empty()) GTEST_SKIP() << "UNC funnel frames absent";
  crossCheckFrames("funnel 227 vs 228", kdet_fcl::readMesh<double>(p0),
                   kdet_fcl::readMesh<double>(p1), 1000);
}

TEST(FclCollideUnc, ClothBallFramesEqualFcl) {
  const std::string p0 = kdet_test::sharedData("unc/cloth-ball/cloth_ball92.ply");
  const std::string p1 = kdet_test::sharedData("unc/cloth-ball/cloth_ball93.ply");
  if (p0.empty() || p1.empty()) GTEST_SKIP() << "UNC cloth-ball frames absent";
  // The whole frames: 92,230 x 92,230 triangles, 286,764 intersecting pairs (FCL takes a few
  // seconds here).
  crossCheckFrames("cloth-ball 92 vs 93", kdet_fcl::readMesh<double>(p0),
                   kdet_fcl::readMesh<double>(p1), 200000);
}

// ---- (3) procedural meshes ----

TEST(FclCollideProcedural, SphereVsDrapedClothEqualFcl) {
  const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 48, 24);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  for (double time : {0.3, 0.7, 1.0}) {
    const TriangleMesh<double> cloth = kdet_fcl::makeDrapedCloth<double>(40, 3.0, 1.0, 0.05, time);
    auto fc = makeModel<fcl::BVHModel<fcl::OBBd>>(cloth);
    auto fs = makeModel<fcl::BVHModel<fcl::OBBd>>(ball);
    auto rc = makeModel<fcl::BVHModel<fcl::RSSd>>(cloth);
    auto rs = makeModel<fcl::BVHModel<fcl::RSSd>>(ball);
    std::mt19937_64 rng(5);
    const double lo[3] = {-0.2, -0.2, -0.2}, hi[3] = {0.2, 0.2, 0.2};
    for (int i = 0; i < 5; ++i) {
      const fcl::Transform3d tf = i == 0 ? I : randomPose<double>(rng, lo, hi);
      std::size_t settled = 0;
      const Pairs f = fclPairs<double>(fc.get(), tf, fs.get(), I);
      const Pairs k = kdetPairs<double>(fc.get(), tf, fs.get(), I);
      for (const auto& fl : compareSets("cloth/sphere OBB", k, f, cloth, tf, ball, I, settled))
        ADD_FAILURE() << fl;
      const Pairs fr = fclPairs<double>(rc.get(), tf, rs.get(), I);
      for (const auto& fl : compareSets("cloth/sphere RSS", k, fr, cloth, tf, ball, I, settled))
        ADD_FAILURE() << fl;
      if (i == 0 && time == 1.0) EXPECT_FALSE(k.empty());
    }
  }
}

TEST(FclCollideProcedural, FloatMeshesEqualFcl) {
  const TriangleMesh<float> ball = kdet_fcl::makeSphere<float>({0, 0, 0}, 1.0f, 32, 16);
  const TriangleMesh<float> cloth = kdet_fcl::makeDrapedCloth<float>(24, 3.0f, 1.0f, 0.05f, 1.0f);
  auto fc = makeModel<fcl::BVHModel<fcl::OBBRSSf>>(cloth);
  auto fs = makeModel<fcl::BVHModel<fcl::OBBRSSf>>(ball);
  const fcl::Transform3f I = fcl::Transform3f::Identity();
  const Pairs f = fclPairs<float>(fc.get(), I, fs.get(), I);
  const Pairs k = kdetPairs<float>(fc.get(), I, fs.get(), I);
  std::size_t settled = 0;
  for (const auto& fl : compareSets("float cloth/sphere", k, f, cloth, I, ball, I, settled))
    ADD_FAILURE() << fl;
  EXPECT_FALSE(k.empty());
}

// ---- (6) result conventions: accumulation, return value, num_max_contacts == 0, satisfied ----

namespace {
struct TwoBoxesOfTriangles {
  std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> a, b;
  fcl::Transform3d ta = fcl::Transform3d::Identity(), tb = fcl::Transform3d::Identity();
  std::size_t total = 0;
  TwoBoxesOfTriangles() {
    const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
    const TriangleMesh<double> cloth = kdet_fcl::makeDrapedCloth<double>(16, 3.0, 1.0, 0.05, 1.0);
    a = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(cloth);
    b = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
    total = fclPairs<double>(a.get(), ta, b.get(), tb).size();
  }
};
}  // namespace

TEST(FclCollideSemantics, ResultsAccumulateAndReturnTotal) {
  TwoBoxesOfTriangles s;
  ASSERT_GT(s.total, 10u);
  fcl::CollisionRequestd req(std::numeric_limits<int>::max(), false);
  fcl::CollisionResultd res;
  EXPECT_EQ(kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req, res), s.total);
  EXPECT_EQ(kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req, res), 2 * s.total);
  EXPECT_EQ(res.numContacts(), 2 * s.total);
  // Same as FCL.
  fcl::CollisionResultd rf;
  fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req, rf);
  EXPECT_EQ(fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req, rf), 2 * s.total);

  // A capped request counts the contacts already there.
  fcl::CollisionRequestd req5(5, false);
  fcl::CollisionResultd r5;
  EXPECT_EQ(kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req5, r5), 5u);
  EXPECT_EQ(kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req5, r5), 5u);  // satisfied
  fcl::CollisionRequestd req8(8, false);
  EXPECT_EQ(kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req8, r5), 8u);  // 3 more
  fcl::CollisionResultd f5;
  fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req5, f5);
  fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req5, f5);
  EXPECT_EQ(fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req8, f5), 8u);

  // num_max_contacts == 0: FCL warns and returns 0 whatever the result holds.
  fcl::CollisionRequestd req0(0, false);
  EXPECT_EQ(kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req0, r5), 0u);
  EXPECT_EQ(fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req0, f5), 0u);
  EXPECT_EQ(r5.numContacts(), 8u);

  // Free/unoccupied geometries add no contacts (FCL's isOccupied rule).
  s.a->cost_density = 0.5;  // below threshold_occupied (1): not occupied
  fcl::CollisionResultd ru, fu;
  EXPECT_EQ(kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req, ru), 0u);
  EXPECT_EQ(fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req, fu), 0u);
  // ... but with enable_cost they add cost sources, as in FCL.
  fcl::CollisionRequestd rc(std::numeric_limits<int>::max(), false, 1000, true);
  fcl::CollisionResultd kc, fc;
  kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, rc, kc);
  fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, rc, fc);
  EXPECT_EQ(kc.numCostSources(), fc.numCostSources());
  EXPECT_GT(kc.numCostSources(), 0u);
  s.a->cost_density = 1;
}

TEST(FclCollideSemantics, EnableCostMatchesFcl) {
  TwoBoxesOfTriangles s;
  for (std::size_t max_sources : {1u, 5u, 100000u}) {
    fcl::CollisionRequestd req(3, false, max_sources, true);
    fcl::CollisionResultd rk, rf;
    kdet_fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req, rk);
    fcl::collide(s.a.get(), s.ta, s.b.get(), s.tb, req, rf);
    EXPECT_EQ(rk.numContacts(), rf.numContacts());
    ASSERT_EQ(rk.numCostSources(), rf.numCostSources());
    std::vector<fcl::CostSourced> ck, cf;
    rk.getCostSources(ck);
    rf.getCostSources(cf);
    for (std::size_t i = 0; i < ck.size(); ++i) EXPECT_NEAR(ck[i].total_cost, cf[i].total_cost, 1e-9);
  }
}

// ---- (7) enable_contact: finite values, unit normal, pos on both triangles ----

namespace {

double pointTriangleDistance(const kdet_fcl::Vec3<double>& p, const kdet_fcl::Vec3<double> T[3]) {
  return std::sqrt(kdet_fcl::detail::triangleDistanceSquared(p, p, p, T[0], T[1], T[2]));
}

template <class S>
void checkContacts(const fcl::CollisionResult<S>& res, const TriangleMesh<S>& A,
                   const fcl::Transform3<S>& ta, const TriangleMesh<S>& B,
                   const fcl::Transform3<S>& tb, double tol) {
  for (std::size_t i = 0; i < res.numContacts(); ++i) {
    const fcl::Contact<S>& c = res.getContact(i);
    ASSERT_TRUE(c.pos.allFinite());
    ASSERT_TRUE(c.normal.allFinite());
    ASSERT_TRUE(std::isfinite(c.penetration_depth));
    EXPECT_GE(c.penetration_depth, 0);
    EXPECT_NEAR(c.normal.norm(), 1.0, 1e-5);
    kdet_fcl::Vec3<double> P[3], Q[3];
    for (int k = 0; k < 3; ++k) {
      P[k] = worldPoint(ta, A.vertices[A.triangles[c.b1][k]]);
      Q[k] = worldPoint(tb, B.vertices[B.triangles[c.b2][k]]);
    }
    const kdet_fcl::Vec3<double> p{double(c.pos[0]), double(c.pos[1]), double(c.pos[2])};
    EXPECT_LE(pointTriangleDistance(p, P), tol) << "pair " << c.b1 << "," << c.b2;
    EXPECT_LE(pointTriangleDistance(p, Q), tol) << "pair " << c.b1 << "," << c.b2;
  }
}

}  // namespace

TEST(FclCollideContacts, EnvRobContactValues) {
  REQUIRE_ENV_ROB();
  auto env = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(er.env);
  auto rob = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(er.rob);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  std::size_t checked = 0;
  for (const auto& tf : envPoses(40, 1234)) {
    fcl::CollisionRequestd req(std::numeric_limits<int>::max(), true);
    fcl::CollisionResultd res;
    kdet_fcl::collide(env.get(), tf, rob.get(), I, req, res);
    EXPECT_EQ(pairsOf(res), kdetPairs<double>(env.get(), tf, rob.get(), I));
    EXPECT_EQ(pairsOf(res, false).size(), res.numContacts());  // one contact per pair
    checkContacts(res, er.env, tf, er.rob, I, 1e-6 * 3000);
    checked += res.numContacts();
  }
  EXPECT_GT(checked, 100u);
}

TEST(FclCollideContacts, ProceduralAndFloatContactValues) {
  const TriangleMesh<float> ball = kdet_fcl::makeSphere<float>({0, 0, 0}, 1.0f, 32, 16);
  const TriangleMesh<float> cloth = kdet_fcl::makeDrapedCloth<float>(24, 3.0f, 1.0f, 0.05f, 1.0f);
  auto fc = makeModel<fcl::BVHModel<fcl::OBBf>>(cloth);
  auto fs = makeModel<kdet_fcl::Meshf>(ball);
  fcl::Transform3f tf = fcl::Transform3f::Identity();
  tf.translation() << 0.01f, -0.02f, 0.03f;
  tf.linear() = Eigen::AngleAxisf(0.3f, Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
  fcl::CollisionRequestf req(1000000, true);
  fcl::CollisionResultf res;
  kdet_fcl::collide(fc.get(), tf, fs.get(), fcl::Transform3f::Identity(), req, res);
  ASSERT_GT(res.numContacts(), 10u);
  checkContacts(res, cloth, tf, ball, fcl::Transform3f::Identity(), 1e-5);
}

TEST(FclCollideContacts, DegenerateAndCoplanarPairsGiveFiniteValues) {
  using V = kdet_fcl::Vec3<double>;
  auto check = [](std::vector<V> p, std::vector<V> q) {
    const V P[3] = {p[0], p[1], p[2]}, Q[3] = {q[0], q[1], q[2]};
    ASSERT_TRUE(kdet_fcl::detail::trianglesIntersect(P[0], P[1], P[2], Q[0], Q[1], Q[2]));
    const kdet_fcl::detail::TriangleContact c = kdet_fcl::detail::triangleContact(P, Q);
    EXPECT_TRUE(std::isfinite(c.pos.x) && std::isfinite(c.pos.y) && std::isfinite(c.pos.z));
    EXPECT_NEAR(std::sqrt(kdet_fcl::dot(c.normal, c.normal)), 1.0, 1e-12);
    EXPECT_TRUE(std::isfinite(c.depth));
    EXPECT_LE(pointTriangleDistance(c.pos, P), 1e-9);
    EXPECT_LE(pointTriangleDistance(c.pos, Q), 1e-9);
  };
  // Coplanar overlap.
  check({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}, {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}});
  // Coplanar, one inside the other.
  check({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}}, {{0.5, 0.5, 0}, {1, 0.5, 0}, {0.5, 1, 0}});
  // Touching at a vertex; along an edge.
  check({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{1, 0, 0}, {2, 0, 1}, {2, 1, 1}});
  check({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}});
  // Proper crossing.
  check({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}, {{0.5, 0.5, -1}, {0.5, 0.5, 1}, {1.5, 0.2, 0}});
  // Degenerate: a segment through a triangle, a point on a triangle, two crossing segments.
  check({{0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.2, 0.2, 0}}, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  check({{0.2, 0.2, 0}, {0.2, 0.2, 0}, {0.2, 0.2, 0}}, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  check({{-1, 0, 0}, {1, 0, 0}, {0, 0, 0}}, {{0, -1, 0}, {0, 1, 0}, {0, 0.5, 0}});
  // Far from the origin.
  check({{1e7, 1e7, 0}, {1e7 + 2, 1e7, 0}, {1e7, 1e7 + 2, 0}},
        {{1e7 + 0.5, 1e7 + 0.5, -1}, {1e7 + 0.5, 1e7 + 0.5, 1}, {1e7 + 1.5, 1e7 + 0.2, 0}});
}

// ---- (8) selfCollide equals FCL's mesh-vs-itself, filtered of identical/vertex-sharing pairs --

namespace {

template <class S>
Pairs fclSelfPairs(const TriangleMesh<S>& m) {
  auto model = makeModel<fcl::BVHModel<fcl::OBBRSS<S>>>(m);
  const fcl::Transform3<S> I = fcl::Transform3<S>::Identity();
  Pairs out;
  for (const Pair& p : fclPairs<S>(model.get(), I, model.get(), I)) {
    if (p.first >= p.second) continue;
    bool share = false;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const auto ia = m.triangles[p.first][a], ib = m.triangles[p.second][b];
        share = share || ia == ib || m.vertices[ia] == m.vertices[ib];
      }
    if (!share) out.push_back(p);
  }
  return out;
}

template <class S>
void checkSelf(const char* name, const TriangleMesh<S>& m, std::size_t min_pairs) {
  auto model = makeModel<fcl::BVHModel<fcl::OBBRSS<S>>>(m);
  const fcl::Transform3<S> I = fcl::Transform3<S>::Identity();
  auto t0 = Clock::now();
  const Pairs f = fclSelfPairs(m);
  const double tf = secondsSince(t0);
  fcl::CollisionRequest<S> req(std::numeric_limits<int>::max(), false);
  fcl::CollisionResult<S> res;
  t0 = Clock::now();
  const std::size_t n = kdet_fcl::selfCollide(model.get(), I, req, res);
  const double tk = secondsSince(t0);
  EXPECT_EQ(n, res.numContacts());
  Pairs k = pairsOf(res, false);
  EXPECT_EQ(k.size(), n);
  for (const Pair& p : k) EXPECT_LT(p.first, p.second);
  std::size_t settled = 0;
  for (const auto& fl : compareSets(name, k, f, m, I, m, I, settled)) ADD_FAILURE() << fl;
  std::printf("self %s: %zu triangles, FCL (filtered) %zu pairs (%.3f s), selfCollide %zu "
              "(%.3f s), %zu settled\n",
              name, m.triangles.size(), f.size(), tf, k.size(), tk, settled);
  EXPECT_GE(k.size(), min_pairs);
}

}  // namespace

TEST(FclSelfCollide, ProceduralSelfIntersectingCloth) {
  checkSelf("draped cloth", kdet_fcl::makeDrapedCloth<double>(40, 3.0, 1.0, 0.05, 1.0), 1);
  checkSelf("float draped cloth", kdet_fcl::makeDrapedCloth<float>(30, 3.0f, 1.0f, 0.05f, 1.0f),
            1);
  // Two overlapping spheres in one soup-like mesh.
  TriangleMesh<double> two = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  const TriangleMesh<double> s2 = kdet_fcl::makeSphere<double>({0.7, 0.1, 0.2}, 0.8, 24, 12);
  const auto off = std::uint32_t(two.vertices.size());
  two.vertices.insert(two.vertices.end(), s2.vertices.begin(), s2.vertices.end());
  for (auto t : s2.triangles) two.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  checkSelf("two spheres", two, 10);
}

TEST(FclSelfCollide, UncClothFrames) {
  const std::string p = kdet_test::sharedData("unc/cloth-funnel/228.ply");
  if (p.empty()) GTEST_SKIP() << "UNC frames absent";
  checkSelf("funnel 228", kdet_fcl::readMesh<double>(p), 0);
  const std::string q = kdet_test::sharedData("unc/cloth-ball/cloth_ball92.ply");
  if (q.empty()) GTEST_SKIP() << "UNC cloth-ball absent";
  checkSelf("cloth-ball 92", kdet_fcl::readMesh<double>(q), 0);
}

TEST(FclSelfCollide, ConventionsAndContacts) {
  const TriangleMesh<double> cloth = kdet_fcl::makeDrapedCloth<double>(30, 3.0, 1.0, 0.05, 1.0);
  auto model = makeModel<fcl::BVHModel<fcl::OBBd>>(cloth);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() << 5, 6, 7;
  fcl::CollisionObjectd obj(model, tf);
  fcl::CollisionRequestd req(std::numeric_limits<int>::max(), true);
  fcl::CollisionResultd res;
  const std::size_t n = kdet_fcl::selfCollide(&obj, req, res);
  ASSERT_GT(n, 0u);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(res.getContact(i).o1, model.get());
    EXPECT_EQ(res.getContact(i).o2, model.get());
  }
  checkContacts(res, cloth, tf, cloth, tf, 1e-6);
  fcl::CollisionRequestd one(1, false);
  fcl::CollisionResultd r1;
  EXPECT_EQ(kdet_fcl::selfCollide(&obj, one, r1), 1u);
  EXPECT_EQ(kdet_fcl::selfCollide(&obj, one, r1), 1u);
  // A shape has no self-collisions.
  fcl::CollisionObjectd box(std::make_shared<fcl::Boxd>(1, 1, 1));
  EXPECT_EQ(kdet_fcl::selfCollide(&box, req, r1), 1u);
}

TEST(FclSelfCollide, AnUnchangedModelKeepsItsPairsAndAnyChangeIsSeen) {
  // Kept self results on (the test binaries turn them off by default): repeated selfCollide
  // calls on an unchanged model are answered from the kept pairs, which must stay the exact
  // pairs, with contacts at the current pose; every kind of change must be seen.
  kdet_test::ScopedEnv keep_on("KDET_FCL_CPU_SELF_CACHE", nullptr);
  TriangleMesh<double> two = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  const TriangleMesh<double> s2 = kdet_fcl::makeSphere<double>({0.7, 0.1, 0.2}, 0.8, 24, 12);
  const auto off = std::uint32_t(two.vertices.size());
  two.vertices.insert(two.vertices.end(), s2.vertices.begin(), s2.vertices.end());
  for (auto t : s2.triangles) two.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  auto model = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(two);
  const fcl::CollisionRequestd req(std::numeric_limits<int>::max(), true);
  // selfCollide at pose tf: its pairs must be the exact pairs of `mesh`, its contacts at tf.
  auto check = [&](const TriangleMesh<double>& mesh, const fcl::Transform3d& tf,
                   const std::string& what) {
    fcl::CollisionResultd res;
    const std::size_t n = kdet_fcl::selfCollide(model.get(), tf, req, res);
    EXPECT_EQ(n, res.numContacts()) << what;
    Pairs want;  // the exact ground truth (checkSelf above compares selfCollide with FCL)
    for (const auto& q : kdet_fcl::bruteForceIntersectSelf(mesh)) want.emplace_back(q.a, q.b);
    EXPECT_EQ(pairsOf(res, false), want) << what;
    checkContacts(res, mesh, tf, mesh, tf, 1e-6);
    return n;
  };
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  EXPECT_GT(check(two, tf, "first"), 10u);
  for (int k = 0; k < 3; ++k) check(two, tf, "unchanged " + std::to_string(k));
  tf.translation() << 5, -6, 7;
  tf.linear() = Eigen::AngleAxisd(0.8, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  check(two, tf, "unchanged, new pose");
  // Replaced in place: the second sphere moved apart (no self pairs between the spheres).
  TriangleMesh<double> apart = two;
  for (std::size_t v = off; v < apart.vertices.size(); ++v) apart.vertices[v].x += 10.0;
  std::vector<fcl::Vector3d> ps;
  for (const auto& v : apart.vertices) ps.emplace_back(v.x, v.y, v.z);
  model->beginReplaceModel();
  model->replaceSubModel(ps);
  model->endReplaceModel();
  for (int k = 0; k < 3; ++k) check(apart, tf, "apart " + std::to_string(k));
  // Written directly into the model's vertices (no FCL call): back together.
  for (std::size_t v = 0; v < two.vertices.size(); ++v)
    model->vertices[v] = fcl::Vector3d(two.vertices[v].x, two.vertices[v].y, two.vertices[v].z);
  EXPECT_GT(check(two, tf, "together again"), 10u);
  for (int k = 0; k < 2; ++k) check(two, tf, "together again " + std::to_string(k));
  // A NaN written into a model that holds kept pairs is still refused, and the next valid
  // query after the repair is exact again.
  const fcl::Vector3d saved = model->vertices[3];
  model->vertices[3].x() = std::numeric_limits<double>::quiet_NaN();
  {
    fcl::CollisionResultd res;
    EXPECT_THROW(kdet_fcl::selfCollide(model.get(), tf, req, res), kdet_fcl::InvalidInputError);
  }
  model->vertices[3] = saved;
  EXPECT_GT(check(two, tf, "after the NaN"), 10u);
  kdet_fcl::forget<double>(model.get());
}

// ---- (10) pairs that are not mesh-mesh are forwarded to FCL ----

TEST(FclCollideForward, ShapePairsEqualFcl) {
  const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  auto mesh = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
  auto kmesh = makeModel<kdet_fcl::Meshd>(ball);
  auto box = std::make_shared<fcl::Boxd>(0.5, 0.5, 3.0);
  auto s1 = std::make_shared<fcl::Sphered>(1.0);
  auto s2 = std::make_shared<fcl::Sphered>(0.5);
  fcl::Transform3d t1 = fcl::Transform3d::Identity(), t2 = fcl::Transform3d::Identity();
  t2.translation() << 1.2, 0.1, 0;
  for (bool contact : {false, true}) {
    fcl::CollisionRequestd req(100, contact);
    using G = const fcl::CollisionGeometryd*;
    for (auto [a, b] : {std::pair<G, G>{box.get(), mesh.get()}, {mesh.get(), box.get()},
                        {s1.get(), s2.get()}, {kmesh.get(), s2.get()}}) {
      fcl::CollisionResultd rk, rf;
      const std::size_t nk = kdet_fcl::collide(a, t1, b, t2, req, rk);
      const std::size_t nf = fcl::collide(a, t1, b, t2, req, rf);
      EXPECT_EQ(nk, nf);
      ASSERT_EQ(rk.numContacts(), rf.numContacts());
      for (std::size_t i = 0; i < rk.numContacts(); ++i) {
        EXPECT_EQ(rk.getContact(i).b1, rf.getContact(i).b1);
        EXPECT_EQ(rk.getContact(i).b2, rf.getContact(i).b2);
        if (contact) EXPECT_TRUE(rk.getContact(i).pos.isApprox(rf.getContact(i).pos));
      }
      EXPECT_GT(nk, 0u);
    }
  }
  // distance is forwarded too.
  fcl::DistanceRequestd dreq;
  fcl::DistanceResultd dk, df;
  t2.translation() << 3, 0, 0;
  EXPECT_EQ(kdet_fcl::distance(mesh.get(), t1, s2.get(), t2, dreq, dk),
            fcl::distance(mesh.get(), t1, s2.get(), t2, dreq, df));
}

TEST(FclCollideForward, DefaultCallbacksWithAManager) {
  const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  const TriangleMesh<double> cloth = kdet_fcl::makeDrapedCloth<double>(16, 3.0, 1.0, 0.05, 1.0);
  auto mb = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
  auto mc = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(cloth);
  fcl::CollisionObjectd ob(mb), oc(mc), obox(std::make_shared<fcl::Boxd>(0.3, 0.3, 0.3));
  fcl::DynamicAABBTreeCollisionManagerd mgr;
  mgr.registerObject(&ob);
  mgr.registerObject(&oc);
  mgr.registerObject(&obox);
  mgr.setup();
  for (std::size_t k : {1u, 3u, 100000u}) {
    fcl::DefaultCollisionData<double> dk, df;
    dk.request.num_max_contacts = df.request.num_max_contacts = k;
    mgr.collide(&dk, kdet_fcl::DefaultCollisionFunction<double>);
    mgr.collide(&df, fcl::DefaultCollisionFunction<double>);
    EXPECT_EQ(dk.result.numContacts(), df.result.numContacts()) << k;
    EXPECT_EQ(dk.done, df.done);
  }
  fcl::DefaultDistanceData<double> ddk, ddf;
  mgr.distance(&ddk, kdet_fcl::DefaultDistanceFunction<double>);
  mgr.distance(&ddf, fcl::DefaultDistanceFunction<double>);
  EXPECT_EQ(ddk.result.min_distance, ddf.result.min_distance);
}

// ---- The structure cache: never stale, no re-hash for poses ----

TEST(FclCollideCache, ReplaceAndUpdateAreNeverStale) {
  const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  const TriangleMesh<double> cloth = kdet_fcl::makeDrapedCloth<double>(16, 3.0, 1.0, 0.05, 1.0);
  auto mb = makeModel<fcl::BVHModel<fcl::OBBd>>(ball);
  auto mc = makeModel<fcl::BVHModel<fcl::OBBd>>(cloth);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  auto same = [&] {
    EXPECT_EQ(kdetPairs<double>(mc.get(), I, mb.get(), I), fclPairs<double>(mc.get(), I, mb.get(), I));
  };
  same();
  ASSERT_FALSE(kdetPairs<double>(mc.get(), I, mb.get(), I).empty());
  auto moved = [&](double dz) {
    std::vector<fcl::Vector3d> ps;
    for (const auto& v : ball.vertices) ps.emplace_back(v.x, v.y, v.z + dz);
    return ps;
  };
  // Replace path: vertices change in place, pointers stay.
  mb->beginReplaceModel();
  mb->replaceSubModel(moved(10));
  mb->endReplaceModel();
  EXPECT_TRUE(kdetPairs<double>(mc.get(), I, mb.get(), I).empty());
  same();
  // Update path: FCL swaps vertices/prev_vertices; two updates bring the first pointer back.
  for (double dz : {0.0, 10.0, 0.3, 0.0}) {
    mb->beginUpdateModel();
    mb->updateSubModel(moved(dz));
    mb->endUpdateModel();
    same();
  }
  // Direct writes into vertices (no FCL call at all).
  mb->vertices[0] = fcl::Vector3d(0, 0, 50);
  same();
  // A rebuilt model at the same address with a different topology (FCL's beginModel on a built
  // model only clears it; the second call begins).
  mb->beginModel();
  mb->beginModel();
  mb->addSubModel(moved(0.1), [&] {
    std::vector<fcl::Triangle> ts;
    for (std::size_t t = 0; t + 1 < ball.triangles.size(); t += 2)
      ts.emplace_back(ball.triangles[t][0], ball.triangles[t][1], ball.triangles[t][2]);
    return ts;
  }());
  mb->endModel();
  same();
  // New poses only: still right (the hash is not rebuilt for them).
  std::mt19937_64 rng(3);
  const double lo[3] = {-0.3, -0.3, -0.3}, hi[3] = {0.3, 0.3, 0.3};
  for (int i = 0; i < 5; ++i) {
    const auto tf = randomPose<double>(rng, lo, hi);
    EXPECT_EQ(kdetPairs<double>(mc.get(), tf, mb.get(), I), fclPairs<double>(mc.get(), tf, mb.get(), I));
  }
  kdet_fcl::forget<double>(mb.get());
  kdet_fcl::forget<double>(mc.get());
}

TEST(FclCollideCache, TrustModeNotifyDeformedForgetAndSize) {
  const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  auto a = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
  auto b = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  kdet_fcl::clearCache();
  EXPECT_EQ(kdet_fcl::cacheSize(), 0u);
  const Pairs before = kdetPairs<double>(a.get(), I, b.get(), I);
  EXPECT_EQ(kdet_fcl::cacheSize(), 2u);
  kdet_fcl::setCacheValidation(kdet_fcl::CacheValidation::Trust);
  const std::vector<fcl::Vector3d> orig(b->vertices, b->vertices + b->num_vertices);
  for (int i = 0; i < b->num_vertices; ++i) b->vertices[i][2] += 10;
  EXPECT_EQ(kdetPairs<double>(a.get(), I, b.get(), I), before);  // trusted: not re-read
  kdet_fcl::notifyDeformed<double>(b.get());
  EXPECT_TRUE(kdetPairs<double>(a.get(), I, b.get(), I).empty());
  kdet_fcl::setCacheValidation(kdet_fcl::CacheValidation::Checksum);
  std::copy(orig.begin(), orig.end(), b->vertices);
  EXPECT_EQ(kdetPairs<double>(a.get(), I, b.get(), I), before);
  kdet_fcl::forget<double>(a.get());
  EXPECT_EQ(kdet_fcl::cacheSize(), 1u);
  kdet_fcl::clearCache();
  EXPECT_EQ(kdet_fcl::cacheSize(), 0u);
}

TEST(FclCollideCache, SameMeshAtTwoPosesAndConcurrentQueries) {
  const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  auto a = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
  fcl::Transform3d t2 = fcl::Transform3d::Identity();
  t2.translation() << 0.5, 0.2, 0.1;
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  const Pairs ref = fclPairs<double>(a.get(), I, a.get(), t2);
  ASSERT_FALSE(ref.empty());
  EXPECT_EQ(kdetPairs<double>(a.get(), I, a.get(), t2), ref);
  EXPECT_EQ(kdetPairs<double>(a.get(), I, a.get(), I), fclPairs<double>(a.get(), I, a.get(), I));
  // Two threads on the same geometries with different poses.
  std::vector<Pairs> out(2);
  std::vector<std::thread> ts;
  for (int t = 0; t < 2; ++t)
    ts.emplace_back([&, t] {
      fcl::Transform3d tf = t2;
      tf.translation()[0] += 0.1 * t;
      for (int i = 0; i < 20; ++i) out[t] = kdetPairs<double>(a.get(), I, a.get(), tf);
    });
  for (auto& th : ts) th.join();
  EXPECT_EQ(out[0], ref);
  fcl::Transform3d t3 = t2;
  t3.translation()[0] += 0.1;
  EXPECT_EQ(out[1], fclPairs<double>(a.get(), I, a.get(), t3));
  kdet_fcl::forget<double>(a.get());
}

// ---- Bad input ----

TEST(FclCollideBadInput, NaNVerticesAndPosesThrow) {
  const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 12, 6);
  auto a = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
  auto b = makeModel<fcl::BVHModel<fcl::AABBd>>(ball);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  fcl::CollisionRequestd req;
  fcl::CollisionResultd res;
  fcl::Transform3d bad = I;
  bad.translation()[1] = std::nan("");
  EXPECT_THROW(kdet_fcl::collide(a.get(), bad, b.get(), I, req, res), kdet_fcl::InvalidInputError);
  fcl::Transform3d scaled = I;
  scaled.linear() *= 2;
  EXPECT_THROW(kdet_fcl::collide(a.get(), scaled, b.get(), I, req, res),
               kdet_fcl::InvalidInputError);
  auto s = std::make_shared<fcl::Sphered>(1);
  EXPECT_THROW(kdet_fcl::collide(s.get(), bad, s.get(), I, req, res), kdet_fcl::InvalidInputError);
  fcl::DistanceRequestd dreq;
  fcl::DistanceResultd dres;
  EXPECT_THROW(kdet_fcl::distance(s.get(), bad, s.get(), I, dreq, dres),
               kdet_fcl::InvalidInputError);
  b->vertices[3][0] = std::nan("");
  EXPECT_THROW(kdet_fcl::collide(a.get(), I, b.get(), I, req, res), kdet_fcl::InvalidInputError);
  EXPECT_THROW(kdet_fcl::selfCollide(b.get(), I, req, res), kdet_fcl::InvalidInputError);
  b->vertices[3][0] = 0.5;
  EXPECT_NO_THROW(kdet_fcl::collide(a.get(), I, b.get(), I, req, res));
  // An unbuilt model.
  auto c = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  c->beginModel();
  c->addTriangle(fcl::Vector3d(0, 0, 0), fcl::Vector3d(1, 0, 0), fcl::Vector3d(0, 1, 0));
  res.clear();
  EXPECT_THROW(kdet_fcl::collide(a.get(), I, c.get(), I, req, res), kdet_fcl::InvalidInputError);
  c->endModel();
  EXPECT_NO_THROW(kdet_fcl::collide(a.get(), I, c.get(), I, req, res));
  EXPECT_EQ(res.numContacts(), 1u);
  kdet_fcl::clearCache();
}

// Null objects, null callback data, point clouds and meshes outside the exact coordinate range:
// each crashed, hung or answered wrongly before (a segfault in kdet_fcl::collide for a null
// CollisionObject, and in FCL for every query of a point cloud; no end within 20 s for cubes at 1e154) and is
// now a typed exception.
TEST(FclCollideBadInput, NullObjectsPointCloudsAndHugeMeshesThrow) {
  const TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 12, 6);
  auto a = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  fcl::CollisionRequestd req(100, true);
  fcl::CollisionResultd res;
  fcl::DistanceRequestd dreq;
  fcl::DistanceResultd dres;
  fcl::CollisionObjectd obj(a);
  const fcl::CollisionObjectd* none = nullptr;
  EXPECT_THROW(kdet_fcl::collide(none, &obj, req, res), kdet_fcl::InvalidInputError);
  EXPECT_THROW(kdet_fcl::collide(&obj, none, req, res), kdet_fcl::InvalidInputError);
  EXPECT_THROW(kdet_fcl::selfCollide(none, req, res), kdet_fcl::InvalidInputError);
  EXPECT_THROW(kdet_fcl::distance(none, &obj, dreq, dres), kdet_fcl::InvalidInputError);
  EXPECT_THROW(kdet_fcl::DefaultCollisionFunction<double>(&obj, &obj, nullptr),
               kdet_fcl::InvalidInputError);
  double dist = 0;
  EXPECT_THROW(kdet_fcl::DefaultDistanceFunction<double>(&obj, &obj, nullptr, dist),
               kdet_fcl::InvalidInputError);
  // A built point cloud (FCL's type for vertices without triangles). FCL 0.7's own endModel reads
  // a zero-length triangle array on the way to one, so the test makes it from a built mesh by
  // dropping its triangle count, which is all getModelType() looks at.
  auto cloud = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(ball);
  cloud->num_tris = 0;
  ASSERT_EQ(cloud->getModelType(), fcl::BVH_MODEL_POINTCLOUD);
  auto box = std::make_shared<fcl::Boxd>(1, 1, 1);
  for (const fcl::CollisionGeometryd* other :
       {static_cast<const fcl::CollisionGeometryd*>(a.get()),
        static_cast<const fcl::CollisionGeometryd*>(box.get())}) {
    EXPECT_THROW(kdet_fcl::collide(cloud.get(), I, other, I, req, res),
                 kdet_fcl::UnsupportedQueryError);
    EXPECT_THROW(kdet_fcl::collide(other, I, cloud.get(), I, req, res),
                 kdet_fcl::UnsupportedQueryError);
    EXPECT_THROW(kdet_fcl::distance(other, I, cloud.get(), I, dreq, dres),
                 kdet_fcl::UnsupportedQueryError);
    EXPECT_THROW(kdet_fcl::guardedCollide(cloud.get(), I, other, I, req, res),
                 kdet_fcl::UnsupportedQueryError);
    EXPECT_THROW(kdet_fcl::guardedDistance(other, I, cloud.get(), I, dreq, dres),
                 kdet_fcl::UnsupportedQueryError);
  }
  EXPECT_EQ(kdet_fcl::selfCollide(cloud.get(), I, req, res), 0u);  // not a mesh: adds nothing
  cloud->num_tris = static_cast<int>(ball.numTriangles());  // (its destructor's business)
  // kdet_fcl::Mesh does not build a point cloud (FCL's endModel would read that array): it
  // returns FCL's "unsupported" code and stays unbuilt, so queries say so.
  kdet_fcl::Meshd points;
  points.beginModel(4, 0);
  std::vector<fcl::Vector3d> ps = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  ASSERT_EQ(points.addSubModel(ps, std::vector<fcl::Triangle>{}), fcl::BVH_OK);
  EXPECT_EQ(points.endModel(), fcl::BVH_ERR_UNSUPPORTED_FUNCTION);
  EXPECT_THROW(kdet_fcl::collide(&points, I, a.get(), I, req, res), kdet_fcl::InvalidInputError);
  // A mesh beyond 2^330 (a cube of half-size 1e154 did not finish in the query before).
  TriangleMesh<double> huge = ball;
  for (auto& v : huge.vertices) v = {v.x * 1e154, v.y * 1e154, v.z * 1e154};
  auto h1 = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(huge);
  auto h2 = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(huge);
  try {
    kdet_fcl::collide(h1.get(), I, h2.get(), I, req, res);
    ADD_FAILURE() << "no InvalidInputError";
  } catch (const kdet_fcl::InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("2^330"), std::string::npos) << e.what();
  }
  kdet_fcl::clearCache();
}

// An empty model (endModel with nothing added: FCL prints an error and calls its type unknown)
// meets nothing, against a mesh or a shape, in either place; FCL's own collide crashes on it.
TEST(FclCollideBadInput, AnEmptyModelMeetsNothing) {
  auto a = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(
      kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 12, 6));
  auto empty = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  empty->beginModel();
  empty->endModel();
  ASSERT_EQ(empty->getModelType(), fcl::BVH_MODEL_UNKNOWN);
  auto box = std::make_shared<fcl::Boxd>(1, 1, 1);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  const fcl::CollisionRequestd req(100, true);
  const fcl::CollisionGeometryd* mesh = a.get();
  const fcl::CollisionGeometryd* shape = box.get();
  for (const fcl::CollisionGeometryd* other : {mesh, shape}) {
    fcl::CollisionResultd res;
    EXPECT_EQ(kdet_fcl::collide(empty.get(), I, other, I, req, res), 0u);
    EXPECT_EQ(kdet_fcl::collide(other, I, empty.get(), I, req, res), 0u);
    EXPECT_FALSE(res.isCollision());
  }
  fcl::CollisionResultd self;
  EXPECT_EQ(kdet_fcl::selfCollide(empty.get(), I, req, self), 0u);
  kdet_fcl::clearCache();
}

// The backend reaches the FCL-facing entry points through setCollideOptions(): Cuda without a
// device is a typed error; with a device the contacts equal the CPU's.
TEST(FclCollideBackend, CudaBackendThroughCollideAndSelfCollide) {
  const auto cloth = kdet_fcl::makeDrapedCloth<double>(40, 3.0, 1.0, 0.05, 1.0);
  const auto sphere = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  auto mc = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(cloth);
  auto ms = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(sphere);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  const Pairs cpu = kdetPairs<double>(mc.get(), I, ms.get(), I);
  ASSERT_FALSE(cpu.empty());
  fcl::CollisionObjectd oc(mc, I);
  const fcl::CollisionRequestd req(std::numeric_limits<int>::max(), false);
  fcl::CollisionResultd cpu_self;
  kdet_fcl::selfCollide(&oc, req, cpu_self);
  ASSERT_GT(cpu_self.numContacts(), 0u);

  const kdet_fcl::QueryOptions saved = kdet_fcl::collideOptions();
  kdet_fcl::QueryOptions gpu = saved;
  gpu.backend = kdet_fcl::Backend::Cuda;
  kdet_fcl::setCollideOptions(gpu);
  if (kdet_fcl::cudaDeviceCount() == 0) {
    fcl::CollisionResultd r;
    EXPECT_THROW(kdet_fcl::collide(mc.get(), I, ms.get(), I, req, r), kdet_fcl::BackendUnavailableError);
    EXPECT_THROW(kdet_fcl::selfCollide(&oc, req, r), kdet_fcl::BackendUnavailableError);
    EXPECT_EQ(r.numContacts(), 0u);  // nothing half-written
  } else {
    EXPECT_EQ(kdetPairs<double>(mc.get(), I, ms.get(), I), cpu);
    fcl::CollisionResultd gpu_self;
    kdet_fcl::selfCollide(&oc, req, gpu_self);
    EXPECT_EQ(pairsOf(gpu_self), pairsOf(cpu_self));
    // The cloth deformed in place (seen by the checksum, taken in as new positions only): each
    // frame's GPU contacts equal the CPU's.
    for (double dz : {-0.1, -0.2, 0.15}) {
      for (int i = 0; i < mc->num_vertices; ++i) mc->vertices[i][2] += dz;
      const Pairs on_gpu = kdetPairs<double>(mc.get(), I, ms.get(), I);
      kdet_fcl::setCollideOptions(saved);
      EXPECT_EQ(on_gpu, kdetPairs<double>(mc.get(), I, ms.get(), I)) << dz;
      EXPECT_FALSE(on_gpu.empty()) << dz;
      kdet_fcl::setCollideOptions(gpu);
    }
  }
  kdet_fcl::setCollideOptions(saved);
}
