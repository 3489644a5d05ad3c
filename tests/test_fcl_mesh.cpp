// kdet_fcl::Mesh<S> (issue 3): a BVHModel<OBBRSS> that FCL's own collide, objects and managers
// accept with FCL's results, whose kDet hash follows every build, update and replace, and whose
// KdetOnly mode skips FCL's refits; a large model's passes over its positions (the local AABB,
// a deformation's conversion) in several threads give what one thread gives.

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>

#include "fcl/mesh_cache.h"
#include "fcl_test_util.h"
#include "test_util.h"

using namespace kdet_fcl_test;
using kdet_fcl::TriangleMesh;

namespace {

std::vector<fcl::Vector3d> shifted(const TriangleMesh<double>& m, double dz) {
  std::vector<fcl::Vector3d> ps;
  for (const auto& v : m.vertices) ps.emplace_back(v.x, v.y, v.z + dz);
  return ps;
}

struct Scene {
  TriangleMesh<double> ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 32, 16);
  TriangleMesh<double> cloth = kdet_fcl::makeDrapedCloth<double>(24, 3.0, 1.0, 0.05, 1.0);
};

/// Every intersecting pair of two FCL models' current data (world = model frame), by brute force.
template <class BV>
Pairs bruteForcePairs(const fcl::BVHModel<BV>& a, const fcl::BVHModel<BV>& b) {
  auto toMesh = [](const fcl::BVHModel<BV>& m) {
    TriangleMesh<double> t;
    for (int i = 0; i < m.num_vertices; ++i)
      t.vertices.push_back({m.vertices[i][0], m.vertices[i][1], m.vertices[i][2]});
    for (int i = 0; i < m.num_tris; ++i)
      t.triangles.push_back({std::uint32_t(m.tri_indices[i][0]), std::uint32_t(m.tri_indices[i][1]),
                             std::uint32_t(m.tri_indices[i][2])});
    return t;
  };
  Pairs p;
  for (const auto& q : kdet_fcl::bruteForceIntersectMeshes(toMesh(a), {}, toMesh(b), {}))
    p.emplace_back(long(q.a), long(q.b));
  std::sort(p.begin(), p.end());
  return p;
}

}  // namespace

TEST(FclMesh, IsABVHModelAndFclGivesFclsResult) {
  Scene s;
  auto km = makeModel<kdet_fcl::Meshd>(s.ball);
  auto fm = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(s.ball);
  auto cloth = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(s.cloth);
  EXPECT_EQ(km->getModelType(), fcl::BVH_MODEL_TRIANGLES);
  EXPECT_EQ(km->getNodeType(), fcl::BV_OBBRSS);
  EXPECT_EQ(km->getObjectType(), fcl::OT_BVH);
  EXPECT_EQ(km->num_tris, int(s.ball.triangles.size()));
  EXPECT_EQ(km->num_vertices, int(s.ball.vertices.size()));
  EXPECT_EQ(km->getNumBVs(), fm->getNumBVs());
  EXPECT_TRUE(kdet_fcl::isKdetMesh<double>(km.get()));

  std::mt19937_64 rng(11);
  const double lo[3] = {-0.3, -0.3, -0.3}, hi[3] = {0.3, 0.3, 0.3};
  for (int i = 0; i < 10; ++i) {
    const fcl::Transform3d tf = randomPose<double>(rng, lo, hi);
    fcl::CollisionObjectd ok(km, tf), of(fm, tf), oc(cloth);
    for (bool contact : {false, true}) {
      fcl::CollisionRequestd req(std::numeric_limits<int>::max(), contact);
      fcl::CollisionResultd rk, rf;
      fcl::collide(&oc, &ok, req, rk);  // FCL's own collide on a kdet_fcl::Mesh
      fcl::collide(&oc, &of, req, rf);
      ASSERT_EQ(rk.numContacts(), rf.numContacts());
      for (std::size_t c = 0; c < rk.numContacts(); ++c) {
        EXPECT_EQ(rk.getContact(c).b1, rf.getContact(c).b1);
        EXPECT_EQ(rk.getContact(c).b2, rf.getContact(c).b2);
      }
    }
    // ... and kdet_fcl::collide gives the same set.
    fcl::CollisionRequestd req(std::numeric_limits<int>::max(), false);
    fcl::CollisionResultd rk;
    kdet_fcl::collide(&oc, &ok, req, rk);
    EXPECT_EQ(pairsOf(rk), fclPairs<double>(cloth.get(), fcl::Transform3d::Identity(), fm.get(), tf));
  }
  // Distance through FCL on the Mesh equals the plain model's.
  fcl::Transform3d far = fcl::Transform3d::Identity();
  far.translation() << 4, 0, 0;
  fcl::DistanceRequestd dreq;
  fcl::DistanceResultd d1, d2;
  EXPECT_DOUBLE_EQ(fcl::distance(km.get(), far, cloth.get(), fcl::Transform3d::Identity(), dreq, d1),
                   fcl::distance(fm.get(), far, cloth.get(), fcl::Transform3d::Identity(), dreq, d2));
  // Inside an FCL manager.
  fcl::CollisionObjectd ok(km), oc(cloth);
  fcl::DynamicAABBTreeCollisionManagerd mgr;
  mgr.registerObject(&ok);
  mgr.registerObject(&oc);
  fcl::DefaultCollisionData<double> dk, df;
  dk.request.num_max_contacts = df.request.num_max_contacts = 100000;
  mgr.collide(&dk, kdet_fcl::DefaultCollisionFunction<double>);
  mgr.collide(&df, fcl::DefaultCollisionFunction<double>);
  EXPECT_EQ(dk.result.numContacts(), df.result.numContacts());
  EXPECT_GT(df.result.numContacts(), 0u);
}

TEST(FclMesh, UpdateAndReplaceAreNeverStale) {
  Scene s;
  auto km = makeModel<kdet_fcl::Meshd>(s.ball);
  auto cloth = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(s.cloth);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  auto check = [&](const char* what) {
    // FCL's own collide on the Mesh (its BVH kept current) is the reference.
    EXPECT_EQ(kdetPairs<double>(cloth.get(), I, km.get(), I), fclPairs<double>(cloth.get(), I, km.get(), I))
        << what;
  };
  check("built");
  const std::uint64_t v0 = km->version();
  km->beginReplaceModel();
  km->replaceSubModel(shifted(s.ball, 10));
  EXPECT_EQ(km->endReplaceModel(), fcl::BVH_OK);
  EXPECT_GT(km->version(), v0);
  EXPECT_TRUE(kdetPairs<double>(cloth.get(), I, km.get(), I).empty());
  check("replaced");
  // replaceTriangle/replaceVertex (3 and 1 vertices each); FCL allows replace only before the
  // first update (it needs BVH_BUILD_STATE_PROCESSED).
  km->beginReplaceModel();
  const auto ps = shifted(s.ball, 0.05);
  for (std::size_t i = 0; i + 2 < ps.size(); i += 3) km->replaceTriangle(ps[i], ps[i + 1], ps[i + 2]);
  for (std::size_t i = ps.size() / 3 * 3; i < ps.size(); ++i) km->replaceVertex(ps[i]);
  EXPECT_EQ(km->endReplaceModel(), fcl::BVH_OK);
  check("replaceTriangle");
  for (double dz : {0.0, 0.2, 10.0, -0.1}) {
    km->beginUpdateModel();
    for (const auto& p : shifted(s.ball, dz)) km->updateVertex(p);
    EXPECT_EQ(km->endUpdateModel(), fcl::BVH_OK);
    check("updated");
  }
  // An incomplete update is refused as FCL refuses it.
  km->beginUpdateModel();
  km->updateVertex(ps[0]);
  EXPECT_EQ(km->endUpdateModel(), fcl::BVH_ERR_INCORRECT_DATA);
  // Direct writes + notifyDeformed. (FCL's beginModel on a built model only clears it and
  // returns an error; the second call begins.)
  km->beginModel();
  km->beginModel();
  km->addSubModel(shifted(s.ball, 0), [&] {
    std::vector<fcl::Triangle> ts;
    for (const auto& t : s.ball.triangles) ts.emplace_back(t[0], t[1], t[2]);
    return ts;
  }());
  EXPECT_EQ(km->endModel(), fcl::BVH_OK);
  check("rebuilt");
  for (int i = 0; i < km->num_vertices; ++i) km->vertices[i][2] += 20;
  km->notifyDeformed();
  EXPECT_TRUE(kdetPairs<double>(cloth.get(), I, km.get(), I).empty());
  kdet_fcl::forget<double>(cloth.get());
}

TEST(FclMesh, KdetOnlyModeSkipsFclRefitAndStaysCorrectForKdet) {
  Scene s;
  auto km = std::make_shared<kdet_fcl::Meshd>(kdet_fcl::MeshMode::KdetOnly);
  {
    std::vector<fcl::Triangle> ts;
    for (const auto& t : s.ball.triangles) ts.emplace_back(t[0], t[1], t[2]);
    km->beginModel();
    km->addSubModel(shifted(s.ball, 0), ts);
    ASSERT_EQ(km->endModel(), fcl::BVH_OK);
  }
  auto ref = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(s.ball);
  auto cloth = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(s.cloth);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  EXPECT_TRUE(km->fclCurrent());
  for (double dz : {0.1, 10.0, -0.2}) {
    km->beginUpdateModel();
    km->updateSubModel(shifted(s.ball, dz));
    ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
    EXPECT_FALSE(km->fclCurrent());  // FCL's BVH was not refitted
    ref->beginReplaceModel();
    ref->replaceSubModel(shifted(s.ball, dz));
    ref->endReplaceModel();
    EXPECT_EQ(kdetPairs<double>(cloth.get(), I, km.get(), I), fclPairs<double>(cloth.get(), I, ref.get(), I));
  }
  // Forwarded pairs (mesh vs shape) refit on demand, so they stay right.
  auto box = std::make_shared<fcl::Boxd>(0.2, 0.2, 0.2);
  fcl::Transform3d tb = fcl::Transform3d::Identity();
  tb.translation() << 0, 0, -1.2;  // touches the ball moved by -0.2
  fcl::CollisionRequestd req(10, false);
  fcl::CollisionResultd rk, rf;
  kdet_fcl::collide(km.get(), I, box.get(), tb, req, rk);
  EXPECT_TRUE(km->fclCurrent());
  fcl::collide(ref.get(), I, box.get(), tb, req, rf);
  EXPECT_EQ(rk.numContacts(), rf.numContacts());
  EXPECT_GT(rk.numContacts(), 0u);
  // refitFcl() / setMode(Fcl) bring FCL's BVH current for FCL's own collide.
  km->beginUpdateModel();
  km->updateSubModel(shifted(s.ball, 0.05));
  ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
  EXPECT_FALSE(km->fclCurrent());
  km->setMode(kdet_fcl::MeshMode::Fcl);
  EXPECT_TRUE(km->fclCurrent());
  ref->beginReplaceModel();
  ref->replaceSubModel(shifted(s.ball, 0.05));
  ref->endReplaceModel();
  EXPECT_EQ(fclPairs<double>(cloth.get(), I, km.get(), I), fclPairs<double>(cloth.get(), I, ref.get(), I));
  kdet_fcl::clearCache();
}

TEST(FclMesh, CopyFromModelFloatAndSelfCollide) {
  Scene s;
  auto obb = makeModel<fcl::BVHModel<fcl::OBBd>>(s.cloth);
  auto km = kdet_fcl::Meshd::fromModel(*obb);
  kdet_fcl::Meshd copy(*km);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  fcl::CollisionRequestd req(std::numeric_limits<int>::max(), false);
  fcl::CollisionResultd r1, r2, r3;
  kdet_fcl::selfCollide(obb.get(), I, req, r1);
  kdet_fcl::selfCollide(km.get(), I, req, r2);
  kdet_fcl::selfCollide(&copy, I, req, r3);
  EXPECT_GT(r1.numContacts(), 0u);
  EXPECT_EQ(pairsOf(r1), pairsOf(r2));
  EXPECT_EQ(pairsOf(r1), pairsOf(r3));
  // float
  const TriangleMesh<float> ball = kdet_fcl::makeSphere<float>({0, 0, 0}, 1.0f, 16, 8);
  auto kf = makeModel<kdet_fcl::Meshf>(ball);
  auto ff = makeModel<fcl::BVHModel<fcl::OBBRSSf>>(ball);
  fcl::Transform3f tf = fcl::Transform3f::Identity();
  tf.translation() << 0.5f, 0.1f, 0;
  EXPECT_EQ(kdetPairs<float>(kf.get(), fcl::Transform3f::Identity(), ff.get(), tf),
            fclPairs<float>(ff.get(), fcl::Transform3f::Identity(), ff.get(), tf));
  kdet_fcl::clearCache();
}

TEST(FclMesh, NaNVerticesThrowOnQueryNotOnBuild) {
  Scene s;
  auto ps = shifted(s.ball, 0);
  ps[5][1] = std::nan("");
  std::vector<fcl::Triangle> ts;
  for (const auto& t : s.ball.triangles) ts.emplace_back(t[0], t[1], t[2]);
  kdet_fcl::Meshd m;
  m.beginModel();
  m.addSubModel(ps, ts);
  EXPECT_EQ(m.endModel(), fcl::BVH_OK);  // FCL builds it
  fcl::CollisionRequestd req;
  fcl::CollisionResultd res;
  EXPECT_THROW(kdet_fcl::collide<double>(&m, fcl::Transform3d::Identity(), &m,
                                         fcl::Transform3d::Identity(), req, res),
               kdet_fcl::InvalidInputError);
}

// A deformation (the update or replace family) brings the new positions into the kDet hash
// without a new mesh: its HashedMesh keeps its topology version (so the CUDA backend keeps its
// copy of the triangles), and only a new model (beginModel ... endModel) or notifyDeformed() gives
// a new one. Every answer equals brute force on the model's current data. A NaN brought in by an update is refused by the next query with the
// vertex named, and the hash keeps the positions before it.
TEST(FclMesh, DeformationsKeepTheHashedTrianglesAndNewModelsReplaceThem) {
  Scene s;
  auto km = makeModel<kdet_fcl::Meshd>(s.cloth);
  auto ball = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(s.ball);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  const auto& entry = kdet_fcl::detail::MeshAccess<double>::entry(*km);
  ASSERT_TRUE(entry->hashed != nullptr);  // hashed by endModel
  const std::uint64_t mesh_topology = km->topologyVersion();
  const std::uint64_t hashed_topology = entry->hashed->topologyVersion();
  // The replace family (FCL allows it only before the first update): vertices only.
  km->beginReplaceModel();
  km->replaceSubModel(shifted(s.cloth, -0.25));
  ASSERT_EQ(km->endReplaceModel(), fcl::BVH_OK);
  std::size_t pairs = kdetPairs<double>(km.get(), I, ball.get(), I).size();
  EXPECT_EQ(kdetPairs<double>(km.get(), I, ball.get(), I), bruteForcePairs(*km, *ball));
  EXPECT_EQ(entry->hashed->topologyVersion(), hashed_topology);
  EXPECT_EQ(km->topologyVersion(), mesh_topology);
  for (double dz : {-0.1, -0.2, -0.3, 0.05}) {
    const std::uint64_t v0 = entry->hashed->version();
    km->beginUpdateModel();
    km->updateSubModel(shifted(s.cloth, dz));
    ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
    const Pairs got = kdetPairs<double>(km.get(), I, ball.get(), I);
    EXPECT_EQ(got, bruteForcePairs(*km, *ball)) << dz;
    pairs += got.size();
    EXPECT_EQ(km->topologyVersion(), mesh_topology) << dz;
    EXPECT_EQ(entry->hashed->topologyVersion(), hashed_topology) << dz;
    EXPECT_GT(entry->hashed->version(), v0) << dz;
    EXPECT_EQ(entry->hashed->mesh().vertices[3].z, km->vertices[3][2]) << dz;
  }
  EXPECT_GT(pairs, 0u);  // the frames test something
  // A NaN: FCL refits it; the next kdet_fcl query refuses it, naming the vertex, and the hash
  // keeps the last good positions; the next good update is taken in.
  const std::vector<kdet_fcl::Vec3<double>> good = entry->hashed->mesh().vertices;
  auto bad = shifted(s.cloth, -0.15);
  bad[7][0] = std::nan("");
  km->beginUpdateModel();
  km->updateSubModel(bad);
  ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
  try {
    (void)kdetPairs<double>(km.get(), I, ball.get(), I);
    ADD_FAILURE() << "a NaN vertex was accepted";
  } catch (const kdet_fcl::InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("kdet_fcl: BVHModel"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("vertex 7"), std::string::npos) << e.what();
  }
  EXPECT_EQ(entry->hashed->mesh().vertices, good);
  km->beginUpdateModel();
  km->updateSubModel(shifted(s.cloth, -0.15));
  ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
  EXPECT_EQ(kdetPairs<double>(km.get(), I, ball.get(), I), bruteForcePairs(*km, *ball));
  EXPECT_EQ(entry->hashed->topologyVersion(), hashed_topology);
  // Triangles written directly and announced: a new topology, the new triangles hashed.
  std::swap(km->tri_indices[0], km->tri_indices[km->num_tris / 2]);
  for (int t = 1; t < km->num_tris; t += 2) {
    const fcl::Triangle r = km->tri_indices[t];
    km->tri_indices[t] = fcl::Triangle(r[0], r[2], r[1]);
  }
  km->tri_indices[km->num_tris - 1] = fcl::Triangle(0, std::size_t(km->num_vertices) / 2, std::size_t(km->num_vertices) - 1);
  km->notifyDeformed();
  EXPECT_GT(km->topologyVersion(), mesh_topology);
  EXPECT_EQ(kdetPairs<double>(km.get(), I, ball.get(), I), bruteForcePairs(*km, *ball));
  EXPECT_NE(entry->hashed->topologyVersion(), hashed_topology);
  EXPECT_EQ(entry->hashed->mesh().triangles.back()[1], std::uint32_t(km->num_vertices / 2));
  // A new model: a new topology.
  const std::uint64_t t1 = entry->hashed->topologyVersion();
  km->beginModel();
  km->beginModel();  // (FCL's first call on a built model only clears it)
  std::vector<fcl::Triangle> ts;
  for (const auto& t : s.ball.triangles) ts.emplace_back(t[0], t[1], t[2]);
  km->addSubModel(shifted(s.ball, 0.5), ts);
  ASSERT_EQ(km->endModel(), fcl::BVH_OK);
  EXPECT_NE(entry->hashed->topologyVersion(), t1);
  EXPECT_EQ(entry->hashed->numTriangles(), s.ball.triangles.size());
  EXPECT_EQ(kdetPairs<double>(km.get(), I, ball.get(), I), bruteForcePairs(*km, *ball));
  kdet_fcl::forget<double>(ball.get());
}

// A plain BVHModel under CacheValidation::Checksum: positions written in place are taken in as a
// deformation, and triangles written in place (same arrays, same counts) as a new mesh, each
// answered as brute force answers the model's current data.
TEST(FclMesh, APlainModelsTrianglesWrittenInPlaceAreHashedAnew) {
  Scene s;
  ASSERT_EQ(kdet_fcl::cacheValidation(), kdet_fcl::CacheValidation::Checksum);
  auto cloth = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(s.cloth);
  auto ball = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(s.ball);
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  EXPECT_EQ(kdetPairs<double>(cloth.get(), I, ball.get(), I), bruteForcePairs(*cloth, *ball));
  for (int i = 0; i < cloth->num_vertices; ++i) cloth->vertices[i][2] -= 0.2;  // deformed
  const Pairs deformed = kdetPairs<double>(cloth.get(), I, ball.get(), I);
  EXPECT_EQ(deformed, bruteForcePairs(*cloth, *ball));
  ASSERT_FALSE(deformed.empty());
  // Each triangle that meets the ball now spans far-apart vertices of the cloth.
  for (const auto& p : deformed)
    cloth->tri_indices[p.first] = fcl::Triangle(0, std::size_t(cloth->num_vertices) - 1, 24);
  const Pairs rewired = kdetPairs<double>(cloth.get(), I, ball.get(), I);
  EXPECT_EQ(rewired, bruteForcePairs(*cloth, *ball));
  EXPECT_NE(rewired, deformed);
  kdet_fcl::forget<double>(cloth.get());
  kdet_fcl::forget<double>(ball.get());
}

namespace {

/// FCL's local AABB of a model, bit for bit (NaN included).
struct LocalAabb {
  double lo[3], hi[3], center[3], radius;
  template <class Model>
  explicit LocalAabb(const Model& m) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = m.aabb_local.min_[a];
      hi[a] = m.aabb_local.max_[a];
      center[a] = m.aabb_center[a];
    }
    radius = m.aabb_radius;
  }
  bool operator==(const LocalAabb& o) const { return std::memcmp(this, &o, sizeof(*this)) == 0; }
};

/// Runs body() with collideOptions().threads = threads; the options are restored on every way
/// out.
template <class F>
void withCollideThreads(int threads, F&& body) {
  struct Restore {
    kdet_fcl::QueryOptions saved = kdet_fcl::collideOptions();
    ~Restore() { kdet_fcl::setCollideOptions(saved); }
  } restore;
  kdet_fcl::QueryOptions o = restore.saved;
  o.threads = threads;
  kdet_fcl::setCollideOptions(o);
  body();
}

/// FCL's own local AABB of positions `ps` (BVHModel::computeLocalAABB on a model filled, not built).
LocalAabb fclLocalAabb(const std::vector<fcl::Vector3d>& ps) {
  fcl::BVHModel<fcl::OBBRSSd> m;
  m.beginModel(0, int(ps.size()));
  for (const auto& p : ps) m.addVertex(p);
  m.computeLocalAABB();
  return LocalAabb(m);
}

/// A kdet_fcl::Mesh in KdetOnly mode built from `m` (nullptr where endModel fails).
std::shared_ptr<kdet_fcl::Meshd> kdetOnlyModel(const TriangleMesh<double>& m) {
  auto km = std::make_shared<kdet_fcl::Meshd>(kdet_fcl::MeshMode::KdetOnly);
  std::vector<fcl::Triangle> ts;
  for (const auto& t : m.triangles) ts.emplace_back(t[0], t[1], t[2]);
  km->beginModel();
  km->addSubModel(shifted(m, 0), ts);
  return km->endModel() == fcl::BVH_OK ? km : nullptr;
}

std::vector<fcl::Vector3d> positionsOf(const fcl::BVHModel<fcl::OBBRSSd>& m) {
  return std::vector<fcl::Vector3d>(m.vertices, m.vertices + m.num_vertices);
}

}  // namespace

// A model of 1.5 MB of positions and more takes its local AABB in several threads (512 KB a
// thread, where that makes at least 3): the values of FCL's own serial passes exactly, after a
// build and after each update, whatever the threads; with a NaN, FCL's passes themselves.
TEST(FclMesh, ALargeModelsLocalAabbInThreadsIsFcls) {
  TriangleMesh<double> cloth = kdet_fcl::makeDrapedCloth<double>(260, 3.0, 1.0, 0.05, 1.0);
  const std::size_t nv = cloth.vertices.size();
  ASSERT_GE(nv * sizeof(fcl::Vector3d), std::size_t(1536) << 10);
  // Extremes in the middle shares too (the cloth's own lie at its border, the first and last).
  cloth.vertices[nv / 3] = {-7.5, 0.25, 9.0};
  cloth.vertices[nv / 2 + 11] = {6.0, -8.0, -0.5};
  auto km = kdetOnlyModel(cloth);  // endModel: computeLocalAABB, in the default threads
  ASSERT_TRUE(km != nullptr);
  EXPECT_TRUE(LocalAabb(*km) == fclLocalAabb(positionsOf(*km)));
  EXPECT_EQ(km->aabb_local.min_[0], -7.5);
  EXPECT_EQ(km->aabb_local.min_[1], -8.0);
  for (int threads : {1, 3, 4, 8, 0}) {
    withCollideThreads(threads, [&] {
      for (double dz : {-0.4, 0.7}) {
        std::vector<fcl::Vector3d> ps = shifted(cloth, dz);
        ps[nv - 5] = fcl::Vector3d(11.0 + dz, 3.0, dz);  // the far point in the last share
        km->beginUpdateModel();
        km->updateSubModel(ps);
        ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
        EXPECT_TRUE(LocalAabb(*km) == fclLocalAabb(ps)) << threads << " threads, dz " << dz;
        EXPECT_EQ(km->aabb_local.max_[0], 11.0 + dz);
      }
      // A NaN in a middle share: FCL's own passes (whose NaN handling depends on the order).
      std::vector<fcl::Vector3d> ps = shifted(cloth, 0.1);
      ps[nv / 2][1] = std::nan("");
      km->beginUpdateModel();
      km->updateSubModel(ps);
      ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
      EXPECT_TRUE(LocalAabb(*km) == fclLocalAabb(ps)) << threads << " threads, NaN";
    });
  }
}

// A deformation of a large model (positions of 1.5 MB and more) is converted into the hash's
// write buffer by several threads: every position of every share arrives, the triangles keep
// their topology version, and a NaN in any share is refused by the next query, naming it.
TEST(FclMesh, ALargeDeformationIsTakenInByThreadsWithEveryPosition) {
  const TriangleMesh<double> cloth = kdet_fcl::makeDrapedCloth<double>(260, 3.0, 1.0, 0.05, 1.0);
  const std::size_t nv = cloth.vertices.size();
  ASSERT_GE(nv * sizeof(fcl::Vector3d), std::size_t(1536) << 10);
  auto ball = makeModel<fcl::BVHModel<fcl::OBBRSSd>>(kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 16, 8));
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  auto km = kdetOnlyModel(cloth);
  ASSERT_TRUE(km != nullptr);
  const auto& entry = kdet_fcl::detail::MeshAccess<double>::entry(*km);
  ASSERT_TRUE(entry->hashed != nullptr);
  const std::uint64_t topology = entry->hashed->topologyVersion();
  for (int threads : {3, 4, 0}) {
    withCollideThreads(threads, [&] {
      for (double dz : {-0.2, 0.3}) {
        std::vector<fcl::Vector3d> ps = shifted(cloth, dz);
        for (std::size_t i = 0; i < nv; i += 997) ps[i][0] += 1e-3 * double(i % 7);
        km->beginUpdateModel();
        km->updateSubModel(ps);
        ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
        const auto& v = entry->hashed->mesh().vertices;
        ASSERT_EQ(v.size(), nv);
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < nv; ++i)
          wrong += !(v[i].x == ps[i][0] && v[i].y == ps[i][1] && v[i].z == ps[i][2]);
        EXPECT_EQ(wrong, 0u) << threads << " threads, dz " << dz;
        EXPECT_EQ(entry->hashed->topologyVersion(), topology) << "taken in as a deformation";
      }
      std::vector<fcl::Vector3d> bad = shifted(cloth, 0.1);
      const std::size_t at = nv - 3 - std::size_t(threads);  // in the last share
      bad[at][2] = std::numeric_limits<double>::infinity();
      km->beginUpdateModel();
      km->updateSubModel(bad);
      ASSERT_EQ(km->endUpdateModel(), fcl::BVH_OK);
      try {
        (void)kdetPairs<double>(km.get(), I, ball.get(), I);
        ADD_FAILURE() << "a non-finite vertex was accepted, " << threads << " threads";
      } catch (const kdet_fcl::InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("vertex " + std::to_string(at)), std::string::npos)
            << e.what();
      }
    });
  }
}
