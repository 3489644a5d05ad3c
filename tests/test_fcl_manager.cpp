// kdet_fcl::CollisionManager against FCL's NaiveCollisionManager and DynamicAABBTreeCollisionManager
// and against an O(n^2) brute force, in the scenarios of FCL's test_fcl_broadphase_collision_1/2
// (random boxes, spheres, cylinders and meshes; self, object and manager queries; exhaustive,
// binary and k = 10 requests; after perturbing every pose and calling update() / update(obj)).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include <fcl/broadphase/broadphase_bruteforce.h>
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/broadphase/default_broadphase_callbacks.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/geometric_shape_to_BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include "kdet_fcl/collision_manager.h"
#include "kdet_fcl/errors.h"

namespace {

template <class S>
using Obj = fcl::CollisionObject<S>;
template <class S>
using ObjPtr = std::unique_ptr<Obj<S>>;
template <class S>
using Manager = fcl::BroadPhaseCollisionManager<S>;
using Pair = std::pair<const void*, const void*>;

// ---------------------------------------------------------------------------------------------
// Scenes (the shapes and sizes of FCL's test::generateEnvironments / generateEnvironmentsMesh)
// ---------------------------------------------------------------------------------------------

template <class S>
fcl::Transform3<S> randomTransform(std::mt19937& rng, S extent) {
  std::uniform_real_distribution<S> t(-extent, extent), ang(0, S(2 * M_PI));
  fcl::Transform3<S> tf = fcl::Transform3<S>::Identity();
  tf.linear() = (fcl::AngleAxis<S>(ang(rng), fcl::Vector3<S>::UnitX()) *
                 fcl::AngleAxis<S>(ang(rng), fcl::Vector3<S>::UnitY()) *
                 fcl::AngleAxis<S>(ang(rng), fcl::Vector3<S>::UnitZ()))
                    .toRotationMatrix();
  tf.translation() = fcl::Vector3<S>(t(rng), t(rng), t(rng));
  return tf;
}

/// n boxes (5, 10, 20), n spheres (r = 30) and n cylinders (r = 10, l = 40) at random poses in
/// [-extent, extent]^3; as BVHModel<OBBRSS> meshes when `mesh` (spheres and cylinders 16 x 16).
template <class S>
std::vector<ObjPtr<S>> makeEnvironment(std::mt19937& rng, S extent, std::size_t n, bool mesh) {
  std::vector<ObjPtr<S>> objs;
  const fcl::Box<S> box(5, 10, 20);
  const fcl::Sphere<S> sphere(30);
  const fcl::Cylinder<S> cylinder(10, 40);
  const fcl::Transform3<S> I = fcl::Transform3<S>::Identity();
  for (std::size_t i = 0; i < n; ++i) {
    for (int kind = 0; kind < 3; ++kind) {
      std::shared_ptr<fcl::CollisionGeometry<S>> g;
      if (mesh) {
        auto m = std::make_shared<fcl::BVHModel<fcl::OBBRSS<S>>>();
        if (kind == 0) fcl::generateBVHModel(*m, box, I);
        if (kind == 1) fcl::generateBVHModel(*m, sphere, I, 16, 16);
        if (kind == 2) fcl::generateBVHModel(*m, cylinder, I, 16, 16);
        g = m;
      } else if (kind == 0) {
        g = std::make_shared<fcl::Box<S>>(box);
      } else if (kind == 1) {
        g = std::make_shared<fcl::Sphere<S>>(sphere);
      } else {
        g = std::make_shared<fcl::Cylinder<S>>(cylinder);
      }
      objs.emplace_back(new Obj<S>(g, randomTransform<S>(rng, extent)));
    }
  }
  return objs;
}

/// FCL's perturbation: rotate by up to 10 degrees per axis, move by up to 1% of the scale.
template <class S>
void perturb(std::mt19937& rng, const std::vector<Obj<S>*>& objs, S scale) {
  const S max_angle = S(10.0 / 360.0 * 2 * M_PI), max_trans = S(0.01) * scale;
  std::uniform_real_distribution<S> u(-1, 1);
  for (Obj<S>* o : objs) {
    const fcl::Matrix3<S> dR = (fcl::AngleAxis<S>(u(rng) * max_angle, fcl::Vector3<S>::UnitX()) *
                                fcl::AngleAxis<S>(u(rng) * max_angle, fcl::Vector3<S>::UnitY()) *
                                fcl::AngleAxis<S>(u(rng) * max_angle, fcl::Vector3<S>::UnitZ()))
                                   .toRotationMatrix();
    const fcl::Vector3<S> dT(u(rng) * max_trans, u(rng) * max_trans, u(rng) * max_trans);
    const fcl::Matrix3<S> R = o->getRotation();
    const fcl::Vector3<S> T = o->getTranslation();
    o->setTransform(dR * R, dR * T + dT);
    o->computeAABB();
  }
}

template <class S>
std::vector<Obj<S>*> raw(const std::vector<ObjPtr<S>>& v) {
  std::vector<Obj<S>*> r;
  for (const auto& o : v) r.push_back(o.get());
  return r;
}

// ---------------------------------------------------------------------------------------------
// Callbacks
// ---------------------------------------------------------------------------------------------

/// Records every (o1, o2) in call order.
struct Recorder {
  std::vector<Pair> calls;
};

template <class S>
bool recordCallback(Obj<S>* o1, Obj<S>* o2, void* data) {
  static_cast<Recorder*>(data)->calls.emplace_back(o1, o2);
  return false;
}

/// Stops after `limit` calls.
struct Stopper {
  std::size_t calls = 0, limit = 0;
};

template <class S>
bool stopCallback(Obj<S>*, Obj<S>*, void* data) {
  auto* s = static_cast<Stopper*>(data);
  return ++s->calls >= s->limit;
}

template <class S>
bool stopDistanceCallback(Obj<S>*, Obj<S>*, void* data, S&) {
  auto* s = static_cast<Stopper*>(data);
  return ++s->calls >= s->limit;
}

/// Minimum distance over the pairs the manager offers, each pair evaluated in one fixed argument
/// order (by id), so two managers that offer the minimising pair find bit-identical minima.
template <class S>
struct MinDistance {
  std::map<const void*, int> id;
  S min = std::numeric_limits<S>::max();
  std::size_t calls = 0;
  std::vector<Pair> pairs;
};

template <class S>
bool minDistanceCallback(Obj<S>* o1, Obj<S>* o2, void* data, S& dist) {
  auto* d = static_cast<MinDistance<S>*>(data);
  ++d->calls;
  d->pairs.emplace_back(o1, o2);
  Obj<S>* a = o1;
  Obj<S>* b = o2;
  if (d->id.at(a) > d->id.at(b)) std::swap(a, b);
  fcl::DistanceRequest<S> req;
  fcl::DistanceResult<S> res;
  const S v = fcl::distance(a, b, req, res);
  d->min = std::min(d->min, v);
  dist = d->min;
  return d->min <= 0;
}

template <class S>
std::size_t selfContacts(const Manager<S>& m, std::size_t k) {
  fcl::DefaultCollisionData<S> data;
  data.request.num_max_contacts = k;
  m.collide(&data, fcl::DefaultCollisionFunction<S>);
  return data.result.numContacts();
}

template <class S>
std::size_t objectContacts(const Manager<S>& m, Obj<S>* q, std::size_t k) {
  fcl::DefaultCollisionData<S> data;
  data.request.num_max_contacts = k;
  m.collide(q, &data, fcl::DefaultCollisionFunction<S>);
  return data.result.numContacts();
}

template <class S>
std::size_t managerContacts(const Manager<S>& m, Manager<S>* other, std::size_t k) {
  fcl::DefaultCollisionData<S> data;
  data.request.num_max_contacts = k;
  m.collide(other, &data, fcl::DefaultCollisionFunction<S>);
  return data.result.numContacts();
}

// ---------------------------------------------------------------------------------------------
// Brute-force referees (fcl::AABB::overlap on the objects' current boxes)
// ---------------------------------------------------------------------------------------------

template <class S>
std::set<Pair> bruteSelfPairs(const std::vector<Obj<S>*>& objs) {  // (earlier, later)
  std::set<Pair> r;
  for (std::size_t i = 0; i < objs.size(); ++i)
    for (std::size_t j = i + 1; j < objs.size(); ++j)
      if (objs[i]->getAABB().overlap(objs[j]->getAABB())) r.emplace(objs[i], objs[j]);
  return r;
}

template <class S>
std::set<Pair> bruteCrossPairs(const std::vector<Obj<S>*>& mine,
                               const std::vector<Obj<S>*>& theirs) {  // (mine, theirs)
  std::set<Pair> r;
  for (Obj<S>* a : mine)
    for (Obj<S>* b : theirs)
      if (a->getAABB().overlap(b->getAABB())) r.emplace(a, b);
  return r;
}

/// The calls as a set, failing on any repeated pair (in either order when `unordered`).
std::set<Pair> uniqueCalls(const std::vector<Pair>& calls, bool unordered, const char* what) {
  std::set<Pair> seen, r;
  for (const Pair& p : calls) {
    const Pair key = unordered && p.second < p.first ? Pair(p.second, p.first) : p;
    EXPECT_TRUE(seen.insert(key).second) << what << ": a pair was reported twice";
    r.insert(p);
  }
  return r;
}

template <class S>
void expectSelfMatchesBruteForce(const Manager<S>& m, const std::vector<Obj<S>*>& registration_order,
                                 const char* what) {
  Recorder rec;
  m.collide(&rec, recordCallback<S>);
  EXPECT_EQ(uniqueCalls(rec.calls, true, what), bruteSelfPairs(registration_order)) << what;
}

template <class S>
void expectQueryMatchesBruteForce(const Manager<S>& m, const std::vector<Obj<S>*>& managed,
                                  Obj<S>* q, const char* what) {
  Recorder rec;
  m.collide(q, &rec, recordCallback<S>);
  std::set<Pair> want;
  for (Obj<S>* a : managed)
    if (a->getAABB().overlap(q->getAABB())) want.emplace(a, q);
  EXPECT_EQ(uniqueCalls(rec.calls, false, what), want) << what;
}

// ---------------------------------------------------------------------------------------------
// FCL's broadphase scenario: equal contact counts with Naive and DynamicAABBTree
// ---------------------------------------------------------------------------------------------

enum class Mode { Exhaustive, Binary, K10 };

std::size_t contactsFor(Mode mode) {
  return mode == Mode::Exhaustive ? 100000 : mode == Mode::Binary ? 1 : 10;
}

/// Compares self and per-query contact counts; returns (self contacts, queries in contact).
template <class S>
std::pair<std::size_t, std::size_t> expectSameCounts(const std::vector<Manager<S>*>& ms,
                                                     const std::vector<const char*>& names,
                                                     const std::vector<Obj<S>*>& queries,
                                                     std::size_t k, const char* stage) {
  const std::size_t self0 = selfContacts(*ms[0], k);
  for (std::size_t i = 1; i < ms.size(); ++i)
    EXPECT_EQ(selfContacts(*ms[i], k), self0) << stage << ": self collide, " << names[i];
  std::size_t hits = 0;
  for (Obj<S>* q : queries) {
    const std::size_t c0 = objectContacts(*ms[0], q, k);
    hits += c0 > 0;
    for (std::size_t i = 1; i < ms.size(); ++i)
      EXPECT_EQ(objectContacts(*ms[i], q, k), c0) << stage << ": collide(obj), " << names[i];
  }
  return {self0, hits};
}

template <class S>
void runScenario(S scale, std::size_t env_n, std::size_t query_n, Mode mode, bool mesh,
                 unsigned seed, bool expect_contacts) {
  SCOPED_TRACE(testing::Message() << "scale " << scale << ", " << 3 * env_n << " objects, "
                                  << 3 * query_n << " queries, mode " << int(mode)
                                  << (mesh ? ", meshes" : ", shapes"));
  std::mt19937 rng(seed);
  const auto env = makeEnvironment<S>(rng, scale, env_n, mesh);
  const auto query = makeEnvironment<S>(rng, scale, query_n, mesh);
  const std::size_t k = contactsFor(mode);

  fcl::NaiveCollisionManager<S> naive;
  fcl::DynamicAABBTreeCollisionManager<S> tree;
  kdet_fcl::CollisionManager<S> ours;          // bulk registration, no setup()
  kdet_fcl::CollisionManager<S> ours_single;   // one registerObject at a time, then setup()
  naive.registerObjects(raw(env));
  tree.registerObjects(raw(env));
  ours.registerObjects(raw(env));
  for (const auto& o : env) ours_single.registerObject(o.get());
  naive.setup();
  tree.setup();
  ours_single.setup();
  const std::vector<Manager<S>*> ms = {&naive, &tree, &ours, &ours_single};
  const std::vector<const char*> names = {"naive", "tree", "kdet", "kdet (single)"};

  const auto initial = expectSameCounts<S>(ms, names, raw(query), k, "initial");
  std::printf("  [%s] initial: %zu self contacts, %zu of %zu queries in contact\n",
              testing::UnitTest::GetInstance()->current_test_info()->name(), initial.first,
              initial.second, query.size());
  if (expect_contacts) {
    EXPECT_GT(initial.first, 0u) << "the scene should have self contacts";
    EXPECT_GT(initial.second, 0u) << "the scene should have queries in contact";
  }
  expectSelfMatchesBruteForce<S>(ours, raw(env), "initial self");

  // Perturb every pose, then update() (FCL's broad_phase_update_collision_test).
  perturb<S>(rng, raw(env), scale);
  for (Manager<S>* m : ms) m->update();
  expectSameCounts<S>(ms, names, raw(query), k, "after update()");
  expectSelfMatchesBruteForce<S>(ours, raw(env), "self after update()");
  expectSelfMatchesBruteForce<S>(ours_single, raw(env), "self after update() (single)");

  // Perturb again, then update(obj) for every object.
  perturb<S>(rng, raw(env), scale);
  for (Manager<S>* m : ms)
    for (const auto& o : env) m->update(o.get());
  expectSameCounts<S>(ms, names, raw(query), k, "after update(obj)");
  expectSelfMatchesBruteForce<S>(ours, raw(env), "self after update(obj)");
  for (const auto& q : query) expectQueryMatchesBruteForce<S>(ours, raw(env), q.get(), "query");

  // And a third time through update(vector) on a third of the objects (incremental path).
  std::vector<Obj<S>*> moved;
  for (std::size_t i = 0; i < env.size(); i += 3) moved.push_back(env[i].get());
  perturb<S>(rng, moved, scale);
  for (Manager<S>* m : ms) m->update(moved);
  expectSameCounts<S>(ms, names, raw(query), k, "after update(vector)");
  expectSelfMatchesBruteForce<S>(ours_single, raw(env), "self after update(vector)");

  // Manager against manager: ours vs ours (fast path), ours vs FCL's tree and naive as `other`.
  fcl::NaiveCollisionManager<S> naive_q;
  fcl::DynamicAABBTreeCollisionManager<S> tree_q;
  kdet_fcl::CollisionManager<S> ours_q;
  naive_q.registerObjects(raw(query));
  tree_q.registerObjects(raw(query));
  ours_q.registerObjects(raw(query));
  const std::size_t want = managerContacts<S>(naive, &naive_q, k);
  std::printf("  manager vs manager: %zu contacts\n", want);
  EXPECT_EQ(managerContacts<S>(tree, &tree_q, k), want) << "tree vs tree";
  EXPECT_EQ(managerContacts<S>(ours, &ours_q, k), want) << "kdet vs kdet";
  EXPECT_EQ(managerContacts<S>(ours_q, &ours, k), want) << "kdet vs kdet (other direction)";
  EXPECT_EQ(managerContacts<S>(ours, &tree_q, k), want) << "kdet vs tree";
  EXPECT_EQ(managerContacts<S>(ours, &naive_q, k), want) << "kdet vs naive";
}

class Scenario : public testing::TestWithParam<Mode> {};

// FCL's own sizes (scale 2000) leave these scenes almost contact-free, so denser ones follow.
TEST_P(Scenario, ShapesFclScale) { runScenario<double>(2000, 100, 100, GetParam(), false, 11, false); }
TEST_P(Scenario, ShapesLarge) { runScenario<double>(800, 300, 100, GetParam(), false, 12, true); }
TEST_P(Scenario, ShapesDense) { runScenario<double>(300, 100, 50, GetParam(), false, 13, true); }
TEST_P(Scenario, Meshes) { runScenario<double>(200, 15, 10, GetParam(), true, 14, true); }
TEST_P(Scenario, MeshesMedium) { runScenario<double>(300, 25, 15, GetParam(), true, 15, true); }

INSTANTIATE_TEST_SUITE_P(Requests, Scenario,
                         testing::Values(Mode::Exhaustive, Mode::Binary, Mode::K10),
                         [](const testing::TestParamInfo<Mode>& i) {
                           return i.param == Mode::Exhaustive ? std::string("exhaustive")
                                  : i.param == Mode::Binary   ? std::string("binary")
                                                              : std::string("k10");
                         });

// ---------------------------------------------------------------------------------------------
// Pair sets, duplicates and argument order
// ---------------------------------------------------------------------------------------------

TEST(FclManager, NoDuplicatesAndExactPairSets) {
  // FCL's broad_phase_duplicate_check_test, plus the set of reported pairs against brute force.
  std::mt19937 rng(21);
  const auto env = makeEnvironment<double>(rng, 300, 300, false);
  const auto query = makeEnvironment<double>(rng, 300, 30, false);
  kdet_fcl::CollisionManagerd ours;
  ours.registerObjects(raw(env));
  perturb<double>(rng, raw(env), 300.0);
  ours.update();
  expectSelfMatchesBruteForce<double>(ours, raw(env), "self");
  for (const auto& q : query) expectQueryMatchesBruteForce<double>(ours, raw(env), q.get(), "query");

  kdet_fcl::CollisionManagerd ours_q;
  fcl::DynamicAABBTreeCollisionManagerd tree_q;
  fcl::NaiveCollisionManagerd naive_q;
  for (Manager<double>* m : std::vector<Manager<double>*>{&ours_q, &tree_q, &naive_q})
    m->registerObjects(raw(query));
  const std::set<Pair> want = bruteCrossPairs<double>(raw(env), raw(query));
  ASSERT_FALSE(want.empty());
  for (Manager<double>* other : std::vector<Manager<double>*>{&ours_q, &tree_q, &naive_q}) {
    Recorder rec;
    ours.collide(other, &rec, recordCallback<double>);
    EXPECT_EQ(uniqueCalls(rec.calls, false, "manager"), want);
  }
  // Ours as the smaller side of the fast path (the query manager is the larger one).
  Recorder rec;
  ours_q.collide(&ours, &rec, recordCallback<double>);
  EXPECT_EQ(uniqueCalls(rec.calls, false, "manager (reverse)"),
            bruteCrossPairs<double>(raw(query), raw(env)));
}

TEST(FclManager, ArgumentOrderMatchesDynamicAABBTree) {
  std::mt19937 rng(22);
  const auto env = makeEnvironment<double>(rng, 200, 60, false);
  const auto query = makeEnvironment<double>(rng, 200, 20, false);
  fcl::DynamicAABBTreeCollisionManagerd tree, tree_q;
  fcl::NaiveCollisionManagerd naive;
  kdet_fcl::CollisionManagerd ours, ours_q;
  tree.registerObjects(raw(env));
  naive.registerObjects(raw(env));
  ours.registerObjects(raw(env));
  tree_q.registerObjects(raw(query));
  ours_q.registerObjects(raw(query));

  // collide(obj): cb(managed, query), as the tree (Naive passes them the other way round).
  std::size_t nonempty = 0;
  for (const auto& q : query) {
    Recorder t, o;
    tree.collide(q.get(), &t, recordCallback<double>);
    ours.collide(q.get(), &o, recordCallback<double>);
    EXPECT_EQ(std::set<Pair>(o.calls.begin(), o.calls.end()),
              std::set<Pair>(t.calls.begin(), t.calls.end()));
    for (const Pair& p : o.calls) EXPECT_EQ(p.second, q.get());
    nonempty += !o.calls.empty();
  }
  EXPECT_GT(nonempty, 0u);

  // collide(other): cb(this manager's object, other manager's object), as the tree.
  Recorder t, o, o2;
  tree.collide(&tree_q, &t, recordCallback<double>);
  ours.collide(&ours_q, &o, recordCallback<double>);
  ours.collide(&tree_q, &o2, recordCallback<double>);
  ASSERT_FALSE(t.calls.empty());
  EXPECT_EQ(std::set<Pair>(o.calls.begin(), o.calls.end()),
            std::set<Pair>(t.calls.begin(), t.calls.end()));
  EXPECT_EQ(std::set<Pair>(o2.calls.begin(), o2.calls.end()),
            std::set<Pair>(t.calls.begin(), t.calls.end()));

  // Self: the tree's order follows its shape; ours is (earlier registered, later registered),
  // which is exactly NaiveCollisionManager's order.
  Recorder ts, ns, os;
  tree.collide(&ts, recordCallback<double>);
  naive.collide(&ns, recordCallback<double>);
  ours.collide(&os, recordCallback<double>);
  ASSERT_FALSE(ns.calls.empty());
  EXPECT_EQ(std::set<Pair>(os.calls.begin(), os.calls.end()),
            std::set<Pair>(ns.calls.begin(), ns.calls.end()));
  EXPECT_EQ(uniqueCalls(os.calls, true, "self"), bruteSelfPairs<double>(raw(env)));
  std::set<Pair> tree_unordered;
  for (const Pair& p : uniqueCalls(ts.calls, true, "tree self"))
    tree_unordered.insert(p.second < p.first ? Pair(p.second, p.first) : p);
  std::set<Pair> ours_unordered;
  for (const Pair& p : os.calls) ours_unordered.insert(p.second < p.first ? Pair(p.second, p.first) : p);
  EXPECT_EQ(ours_unordered, tree_unordered);

  // A managed object queried against its own manager meets itself, as in FCL.
  Recorder self_query;
  ours.collide(env[0].get(), &self_query, recordCallback<double>);
  EXPECT_EQ(std::count(self_query.calls.begin(), self_query.calls.end(),
                       Pair(env[0].get(), env[0].get())),
            1);
}

TEST(FclManager, MixedSizesUnboundedAndIncremental) {
  // Sizes over eight orders of magnitude, points, a half-space (an AABB of +-max()), objects
  // registered one at a time (each registration queried at once), moved far away and back.
  std::mt19937 rng(23);
  std::vector<ObjPtr<double>> objs;
  std::uniform_real_distribution<double> logsize(-4, 4), pos(-50, 50);
  for (int i = 0; i < 400; ++i) {
    const double s = std::pow(10.0, logsize(rng));
    auto g = std::make_shared<fcl::Box<double>>(s, s * 0.5, s * 2);
    objs.emplace_back(new Obj<double>(g, randomTransform<double>(rng, 50)));
  }
  for (int i = 0; i < 20; ++i) {  // zero-size boxes (points)
    auto g = std::make_shared<fcl::Box<double>>(0, 0, 0);
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.translation() = fcl::Vector3d(pos(rng), pos(rng), pos(rng));
    objs.emplace_back(new Obj<double>(g, tf));
  }
  objs.emplace_back(new Obj<double>(std::make_shared<fcl::Halfspace<double>>(
      fcl::Vector3d(0.3, 0.4, std::sqrt(0.75)), 1.0)));
  objs.emplace_back(new Obj<double>(std::make_shared<fcl::Halfspace<double>>(
      fcl::Vector3d(0, 0, 1), -10.0)));

  kdet_fcl::CollisionManagerd ours;
  std::vector<Obj<double>*> registered;
  for (std::size_t i = 0; i < objs.size(); ++i) {
    ours.registerObject(objs[i].get());
    registered.push_back(objs[i].get());
    if (i % 37 == 0 || i + 1 == objs.size()) {
      expectSelfMatchesBruteForce<double>(ours, registered, "incremental self");
      expectQueryMatchesBruteForce<double>(ours, registered, objs[(i * 7) % objs.size()].get(),
                                           "incremental query");
    }
  }
  EXPECT_EQ(ours.size(), objs.size());

  // Move some objects far outside the grid and one much smaller than anything before (grid
  // rebuilds inside update(obj)), then back.
  for (int round = 0; round < 3; ++round) {
    for (std::size_t i = round; i < 400; i += 9) {
      fcl::Vector3d t = objs[i]->getTranslation();
      objs[i]->setTranslation(round == 1 ? fcl::Vector3d(t / 1e4) : fcl::Vector3d(t * 1e3));
      objs[i]->computeAABB();
      ours.update(objs[i].get());
    }
    auto tiny = std::make_shared<fcl::Box<double>>(1e-9, 1e-9, 1e-9);
    objs.emplace_back(new Obj<double>(tiny, randomTransform<double>(rng, 1)));
    ours.registerObject(objs.back().get());
    registered.push_back(objs.back().get());
    expectSelfMatchesBruteForce<double>(ours, registered, "after far moves");
    for (int j = 0; j < 10; ++j)
      expectQueryMatchesBruteForce<double>(ours, registered, objs[j * 41].get(), "after far moves");
  }

  // Unregister every third object; the rest still answers exactly.
  std::vector<Obj<double>*> kept;
  for (std::size_t i = 0; i < registered.size(); ++i) {
    if (i % 3 == 0)
      ours.unregisterObject(registered[i]);
    else
      kept.push_back(registered[i]);
  }
  EXPECT_EQ(ours.size(), kept.size());
  expectSelfMatchesBruteForce<double>(ours, kept, "after unregister");
  expectQueryMatchesBruteForce<double>(ours, kept, registered[0], "unregistered object as query");
}

// ---------------------------------------------------------------------------------------------
// Incremental changes: a few changed objects are tested directly (pending), many trigger one lazy
// rebuild at the next query; both paths must give exactly the brute-force pairs.
// ---------------------------------------------------------------------------------------------

TEST(FclManager, PendingChangesAndLazyRebuild) {
  std::mt19937 rng(36);
  auto env = makeEnvironment<double>(rng, 150, 100, false);  // 300 objects
  const auto query = makeEnvironment<double>(rng, 150, 10, false);
  kdet_fcl::CollisionManagerd ours, ours_q;
  ours.registerObjects(raw(env));
  ours.setup();
  ours_q.registerObjects(raw(query));
  std::vector<Obj<double>*> live = raw(env);

  auto check = [&](const char* what) {
    expectSelfMatchesBruteForce<double>(ours, live, what);
    for (const auto& q : query) expectQueryMatchesBruteForce<double>(ours, live, q.get(), what);
    for (int j = 0; j < 5; ++j)
      expectQueryMatchesBruteForce<double>(ours, live, live[(j * 53) % live.size()], what);
    Recorder a, b;
    ours.collide(&ours_q, &a, recordCallback<double>);
    EXPECT_EQ(uniqueCalls(a.calls, false, what), bruteCrossPairs<double>(live, raw(query))) << what;
    ours_q.collide(&ours, &b, recordCallback<double>);
    EXPECT_EQ(uniqueCalls(b.calls, false, what), bruteCrossPairs<double>(raw(query), live)) << what;
    const std::size_t total = bruteSelfPairs<double>(live).size();
    for (std::size_t limit : {std::size_t(1), std::size_t(7)}) {
      Stopper st{0, limit};
      ours.collide(&st, stopCallback<double>);
      EXPECT_EQ(st.calls, std::min(limit, total)) << what;
    }
  };
  check("frozen");

  // A few moved objects (below the rebuild threshold): tested as pending objects.
  std::vector<Obj<double>*> few;
  for (std::size_t i = 0; i < 6; ++i) few.push_back(live[i * 41]);
  for (int round = 0; round < 3; ++round) {
    perturb<double>(rng, few, 150.0);
    for (Obj<double>* o : few) ours.update(o);
    check("pending updates");
  }

  // Unregister a pending and a frozen object, register new ones (a freed slot is reused), one of
  // them unbounded (a pending loose object), and a pending object again (a refresh).
  for (Obj<double>* gone : std::vector<Obj<double>*>{few[0], live[7]}) {
    ours.unregisterObject(gone);
    live.erase(std::find(live.begin(), live.end(), gone));
  }
  env.emplace_back(new Obj<double>(std::make_shared<fcl::Box<double>>(40, 3, 3),
                                   randomTransform<double>(rng, 100)));
  env.emplace_back(new Obj<double>(
      std::make_shared<fcl::Halfspace<double>>(fcl::Vector3d(0, 1, 0), 20.0)));
  for (std::size_t i = env.size() - 2; i < env.size(); ++i) {
    env[i]->computeAABB();
    ours.registerObject(env[i].get());
    live.push_back(env[i].get());
  }
  perturb<double>(rng, std::vector<Obj<double>*>{few[1]}, 150.0);
  ours.registerObject(few[1]);
  EXPECT_EQ(ours.size(), live.size());
  check("pending registrations");

  // Many moved objects one by one: the next query rebuilds once.
  perturb<double>(rng, live, 150.0);
  for (Obj<double>* o : live) ours.update(o);
  check("lazy rebuild after update(obj)");

  // update() re-reads everything; update(obj) afterwards must not lose the rebuild.
  perturb<double>(rng, live, 150.0);
  ours.update();
  perturb<double>(rng, std::vector<Obj<double>*>{live[3]}, 150.0);
  ours.update(live[3]);
  check("update() then update(obj)");

  // setup() flushes pending changes (the answers stay the same).
  perturb<double>(rng, std::vector<Obj<double>*>{live[5], live[9]}, 150.0);
  ours.update(live[5]);
  ours.update(live[9]);
  ours.setup();
  check("after setup()");

  // Parallel const queries right after a big change: the lazy rebuild happens once, under a lock.
  perturb<double>(rng, live, 150.0);
  ours.update(live);
  const std::set<Pair> want = bruteSelfPairs<double>(live);
  std::vector<std::set<Pair>> got(2);
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t)
    threads.emplace_back([&, t] {
      Recorder rec;
      ours.collide(&rec, recordCallback<double>);
      got[t] = std::set<Pair>(rec.calls.begin(), rec.calls.end());
    });
  for (auto& th : threads) th.join();
  for (int t = 0; t < 2; ++t) EXPECT_EQ(got[t], want);
}

TEST(FclManager, FloatInstantiation) {
  std::mt19937 rng(24);
  const auto env = makeEnvironment<float>(rng, 200, 80, false);
  kdet_fcl::CollisionManagerf ours;
  for (const auto& o : env) ours.registerObject(o.get());
  expectSelfMatchesBruteForce<float>(ours, raw(env), "float self");
  for (int i = 0; i < 10; ++i)
    expectQueryMatchesBruteForce<float>(ours, raw(env), env[i].get(), "float query");
}

// ---------------------------------------------------------------------------------------------
// Early stop
// ---------------------------------------------------------------------------------------------

TEST(FclManager, CallbackReturningTrueStops) {
  std::mt19937 rng(25);
  const auto env = makeEnvironment<double>(rng, 150, 100, false);
  const auto query = makeEnvironment<double>(rng, 150, 30, false);
  kdet_fcl::CollisionManagerd ours, ours_q;
  fcl::DynamicAABBTreeCollisionManagerd tree_q;
  ours.registerObjects(raw(env));
  ours_q.registerObjects(raw(query));
  tree_q.registerObjects(raw(query));
  const std::size_t self_total = bruteSelfPairs<double>(raw(env)).size();
  const std::size_t cross_total = bruteCrossPairs<double>(raw(env), raw(query)).size();
  ASSERT_GT(self_total, 5u);
  ASSERT_GT(cross_total, 5u);
  for (std::size_t limit : {std::size_t(1), std::size_t(3), self_total + 10}) {
    Stopper s{0, limit};
    ours.collide(&s, stopCallback<double>);
    EXPECT_EQ(s.calls, std::min(limit, self_total));
  }
  for (std::size_t limit : {std::size_t(1), std::size_t(4), cross_total + 10}) {
    Stopper a{0, limit}, b{0, limit}, c{0, limit};
    ours.collide(&ours_q, &a, stopCallback<double>);
    ours_q.collide(&ours, &b, stopCallback<double>);
    ours.collide(&tree_q, &c, stopCallback<double>);
    EXPECT_EQ(a.calls, std::min(limit, cross_total));
    EXPECT_EQ(b.calls, std::min(limit, cross_total));
    EXPECT_EQ(c.calls, std::min(limit, cross_total));
  }
  for (const auto& q : query) {
    Recorder all;
    ours.collide(q.get(), &all, recordCallback<double>);
    Stopper s{0, 1};
    ours.collide(q.get(), &s, stopCallback<double>);
    EXPECT_EQ(s.calls, std::min<std::size_t>(1, all.calls.size()));
  }
  Stopper d{0, 2};
  ours.distance(&d, stopDistanceCallback<double>);
  EXPECT_EQ(d.calls, 2u);
  Stopper d2{0, 1};
  ours.distance(query[0].get(), &d2, stopDistanceCallback<double>);
  EXPECT_EQ(d2.calls, 1u);
  Stopper d3{0, 1};
  ours.distance(&tree_q, &d3, stopDistanceCallback<double>);
  EXPECT_EQ(d3.calls, 1u);
}

// ---------------------------------------------------------------------------------------------
// Registration, bookkeeping, empty managers, bad input
// ---------------------------------------------------------------------------------------------

TEST(FclManager, RegisterUnregisterClearGetObjects) {
  std::mt19937 rng(26);
  const auto env = makeEnvironment<double>(rng, 100, 20, false);
  kdet_fcl::CollisionManagerd m;
  EXPECT_TRUE(m.empty());
  EXPECT_EQ(m.size(), 0u);
  std::vector<Obj<double>*> got = {env[0].get()};
  m.getObjects(got);
  EXPECT_TRUE(got.empty());

  m.registerObjects(raw(env));
  EXPECT_FALSE(m.empty());
  EXPECT_EQ(m.size(), env.size());
  m.getObjects(got);
  EXPECT_EQ(got, raw(env));  // registration order

  m.registerObject(env[3].get());  // again: no duplicate
  m.registerObjects({env[4].get(), env[4].get()});
  EXPECT_EQ(m.size(), env.size());
  expectSelfMatchesBruteForce<double>(m, raw(env), "after re-registration");

  m.unregisterObject(env[5].get());
  m.unregisterObject(env[5].get());  // unknown now: ignored
  EXPECT_EQ(m.size(), env.size() - 1);
  std::vector<Obj<double>*> rest = raw(env);
  rest.erase(rest.begin() + 5);
  m.getObjects(got);
  EXPECT_EQ(got, rest);
  expectSelfMatchesBruteForce<double>(m, rest, "after unregister");
  m.update(env[5].get());  // not managed: ignored
  EXPECT_EQ(m.size(), env.size() - 1);

  m.clear();
  EXPECT_TRUE(m.empty());
  m.getObjects(got);
  EXPECT_TRUE(got.empty());
  m.registerObject(env[0].get());
  EXPECT_EQ(m.size(), 1u);
  for (const auto& o : env) m.unregisterObject(o.get());
  EXPECT_TRUE(m.empty());
}

TEST(FclManager, EmptyManagers) {
  std::mt19937 rng(27);
  const auto env = makeEnvironment<double>(rng, 100, 5, false);
  kdet_fcl::CollisionManagerd empty, full, empty2;
  fcl::DynamicAABBTreeCollisionManagerd tree_empty;
  full.registerObjects(raw(env));
  Recorder r;
  MinDistance<double> d;
  empty.collide(&r, recordCallback<double>);
  empty.collide(env[0].get(), &r, recordCallback<double>);
  empty.collide(&full, &r, recordCallback<double>);
  empty.collide(&empty2, &r, recordCallback<double>);
  full.collide(&empty, &r, recordCallback<double>);
  full.collide(&tree_empty, &r, recordCallback<double>);
  empty.distance(&d, minDistanceCallback<double>);
  empty.distance(env[0].get(), &d, minDistanceCallback<double>);
  empty.distance(&full, &d, minDistanceCallback<double>);
  full.distance(&empty, &d, minDistanceCallback<double>);
  full.distance(&tree_empty, &d, minDistanceCallback<double>);
  empty.setup();
  empty.update();
  empty.update(std::vector<Obj<double>*>{});
  EXPECT_TRUE(r.calls.empty());
  EXPECT_EQ(d.calls, 0u);

  kdet_fcl::CollisionManagerd one;  // one object: no self pair
  one.registerObject(env[0].get());
  one.collide(&r, recordCallback<double>);
  EXPECT_TRUE(r.calls.empty());
}

TEST(FclManager, NaNBoxesThrowAndLeaveTheManagerUnchanged) {
  std::mt19937 rng(28);
  const auto env = makeEnvironment<double>(rng, 100, 20, false);
  kdet_fcl::CollisionManagerd m;
  m.registerObjects(raw(env));
  const double nan = std::numeric_limits<double>::quiet_NaN();

  Obj<double> bad(std::make_shared<fcl::Sphere<double>>(1.0));
  bad.setTranslation(fcl::Vector3d(nan, 0, 0));
  bad.computeAABB();
  EXPECT_THROW(m.registerObject(&bad), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.registerObjects({env[0].get(), &bad}), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.registerObject(nullptr), kdet_fcl::InvalidInputError);
  Recorder r;
  // A null callback (FCL's managers call it unchecked).
  EXPECT_THROW(m.collide(&r, nullptr), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.collide(env[0].get(), &r, nullptr), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.collide(&m, &r, nullptr), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.distance(&r, nullptr), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.distance(env[0].get(), &r, nullptr), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.distance(&m, &r, nullptr), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.collide(&bad, &r, recordCallback<double>), kdet_fcl::InvalidInputError);
  MinDistance<double> d;
  EXPECT_THROW(m.distance(&bad, &d, minDistanceCallback<double>), kdet_fcl::InvalidInputError);
  EXPECT_EQ(m.size(), env.size());

  fcl::NaiveCollisionManagerd other;
  other.registerObject(&bad);
  EXPECT_THROW(m.collide(&other, &r, recordCallback<double>), kdet_fcl::InvalidInputError);
  EXPECT_TRUE(r.calls.empty());

  // A managed object turning NaN: update() and update(obj) throw, the old boxes stay.
  const fcl::Vector3d t = env[2]->getTranslation();
  env[2]->setTranslation(fcl::Vector3d(0, nan, 0));
  env[2]->computeAABB();
  EXPECT_THROW(m.update(), kdet_fcl::InvalidInputError);
  EXPECT_THROW(m.update(env[2].get()), kdet_fcl::InvalidInputError);
  env[2]->setTranslation(t);
  env[2]->computeAABB();
  expectSelfMatchesBruteForce<double>(m, raw(env), "after rejected updates");
}

// ---------------------------------------------------------------------------------------------
// Distance: the minimum equals NaiveCollisionManager's
// ---------------------------------------------------------------------------------------------

template <class S>
void expectSameMinimum(const MinDistance<S>& ours, const MinDistance<S>& naive, const char* what) {
  if (naive.min > 0)
    EXPECT_EQ(ours.min, naive.min) << what;
  else
    EXPECT_LE(ours.min, 0) << what;  // in contact: both stop at the first touching pair
}

TEST(FclManager, DistanceMatchesNaive) {
  for (unsigned seed : {31u, 32u, 33u}) {
    std::mt19937 rng(seed);
    const double scale = seed == 33u ? 150 : 1000;
    const auto env = makeEnvironment<double>(rng, scale, 12, false);
    const auto query = makeEnvironment<double>(rng, scale, 4, false);
    std::map<const void*, int> id;
    for (const auto& o : env) id.emplace(o.get(), int(id.size()));
    for (const auto& o : query) id.emplace(o.get(), int(id.size()));

    fcl::NaiveCollisionManagerd naive, naive_q;
    fcl::DynamicAABBTreeCollisionManagerd tree_q;
    kdet_fcl::CollisionManagerd ours, ours_q;
    naive.registerObjects(raw(env));
    ours.registerObjects(raw(env));
    naive_q.registerObjects(raw(query));
    ours_q.registerObjects(raw(query));
    tree_q.registerObjects(raw(query));
    perturb<double>(rng, raw(env), scale);
    naive.update();
    ours.update();

    MinDistance<double> n_self, o_self;
    n_self.id = o_self.id = id;
    naive.distance(&n_self, minDistanceCallback<double>);
    ours.distance(&o_self, minDistanceCallback<double>);
    expectSameMinimum(o_self, n_self, "self distance");
    for (const Pair& p : o_self.pairs) EXPECT_LT(id.at(p.first), id.at(p.second));  // (earlier, later)

    for (const auto& q : query) {
      MinDistance<double> n, o;
      n.id = o.id = id;
      naive.distance(q.get(), &n, minDistanceCallback<double>);
      ours.distance(q.get(), &o, minDistanceCallback<double>);
      expectSameMinimum(o, n, "distance(obj)");
      for (const Pair& p : o.pairs) EXPECT_EQ(p.second, q.get());  // cb(managed, query)
    }

    MinDistance<double> n_m;
    n_m.id = id;
    naive.distance(&naive_q, &n_m, minDistanceCallback<double>);
    for (Manager<double>* other : std::vector<Manager<double>*>{&ours_q, &tree_q, &naive_q}) {
      MinDistance<double> o;
      o.id = id;
      ours.distance(other, &o, minDistanceCallback<double>);
      expectSameMinimum(o, n_m, "distance(other)");
      for (const Pair& p : o.pairs) EXPECT_LT(id.at(p.first), int(env.size()));  // cb(ours, theirs)
    }
    MinDistance<double> self_as_other;
    self_as_other.id = id;
    ours.distance(&ours, &self_as_other, minDistanceCallback<double>);
    expectSameMinimum(self_as_other, n_self, "distance(this)");
  }
}

TEST(FclManager, DefaultDistanceFunctionWorks) {
  std::mt19937 rng(34);
  const auto env = makeEnvironment<double>(rng, 500, 10, false);
  fcl::NaiveCollisionManagerd naive;
  kdet_fcl::CollisionManagerd ours;
  naive.registerObjects(raw(env));
  ours.registerObjects(raw(env));
  fcl::DefaultDistanceData<double> a, b;
  naive.distance(&a, fcl::DefaultDistanceFunction<double>);
  ours.distance(&b, fcl::DefaultDistanceFunction<double>);
  if (a.result.min_distance > 0)
    EXPECT_NEAR(b.result.min_distance, a.result.min_distance, 1e-6 * a.result.min_distance);
  else
    EXPECT_LE(b.result.min_distance, 0);
}

TEST(FclManager, UsableWithoutSetup) {
  std::mt19937 rng(35);
  const auto env = makeEnvironment<double>(rng, 100, 30, false);
  kdet_fcl::CollisionManagerd m;
  std::vector<Obj<double>*> so_far;
  for (const auto& o : env) {
    m.registerObject(o.get());  // queryable at once
    so_far.push_back(o.get());
    expectQueryMatchesBruteForce<double>(m, so_far, env[0].get(), "without setup");
  }
  expectSelfMatchesBruteForce<double>(m, so_far, "without setup");
}

}  // namespace
