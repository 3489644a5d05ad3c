// manager_bench: kdet_fcl::CollisionManager against FCL 0.7's DynamicAABBTreeCollisionManager,
// SpatialHashingCollisionManager and (for small scenes) NaiveCollisionManager, same scenes, same
// process, median of repeated runs.
//
// FCL's spatial hash calls back for every object sharing a cell, with no AABB test (fcl-notes
// section 2), so the counting callback tests AABB overlap itself for every manager: the counts are
// then the overlapping pairs whatever the manager, and are cross-checked. Its grid follows FCL's
// own broadphase tests: cell = min extent of computeBound(env) / 20, over that bound, with the
// unordered_map table (SparseHashTable; the default SimpleHashTable aliases keys mod 1000).
//
// Scenes (axis-aligned fcl::Box objects, so the stored AABB is the box):
//   mixed   n boxes with edges log-uniform over two orders of magnitude, uniform in a cube sized
//           for ~18 overlapping pairs per object (10k: ~175k pairs)
//   sparse  n small boxes on a jittered lattice, no two overlapping
//   fcl     FCL's broadphase test environment (boxes 5x10x20, spheres r 30, cylinders 10x40 at
//           random poses in [-scale, scale]^3)
// Operations (each a median over --reps runs):
//   build     registerObjects + setup on an empty manager
//   self      collide(cdata, cb): all overlapping pairs
//   query     collide(obj) for 1000 query objects from the same distribution
//   mgr       collide(other manager of the same type holding the 1000 query objects)
//   upd1%     update(obj) for 1% of the objects after moving them, then self collide
//   upd100%   update(obj) for every object after moving them all (each moved by ~1% of a box)
//   self'     the self collide that follows upd100% (includes any deferred rebuild)
//
// Usage: manager_bench [--n N[,N...]] [--reps R] [--scene mixed|sparse|fcl|all] [--only kdet]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <fcl/broadphase/broadphase_bruteforce.h>
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/broadphase/broadphase_spatialhash.h>
#include <fcl/broadphase/detail/sparse_hash_table.h>
#include <fcl/broadphase/detail/spatial_hash.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>

#include "bench_util.h"
#include "kdet_fcl/collision_manager.h"

namespace {

using Obj = fcl::CollisionObjectd;
using ObjPtr = std::unique_ptr<Obj>;
using Manager = fcl::BroadPhaseCollisionManagerd;
using Clock = std::chrono::steady_clock;

double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Counter {
  std::size_t pairs = 0;
};

bool countCallback(Obj* a, Obj* b, void* data) {
  if (a->getAABB().overlap(b->getAABB())) ++static_cast<Counter*>(data)->pairs;
  return false;
}

using SpatialHashManager = fcl::SpatialHashingCollisionManager<
    double, fcl::detail::SparseHashTable<fcl::AABBd, Obj*, fcl::detail::SpatialHash<double>>>;

/// FCL's spatial hash set up as its own broadphase tests do (see the header comment).
std::unique_ptr<Manager> makeSpatialHash(const std::vector<Obj*>& env) {
  std::vector<Obj*> objs = env;
  fcl::Vector3d lo, hi;
  SpatialHashManager::computeBound(objs, lo, hi);
  const double cell = std::max((hi - lo).minCoeff() / 20, 1e-9);
  return std::make_unique<SpatialHashManager>(cell, lo, hi);
}

ObjPtr axisBox(double ex, double ey, double ez, const fcl::Vector3d& center) {
  auto o = std::make_unique<Obj>(std::make_shared<fcl::Box<double>>(ex, ey, ez));
  o->setTranslation(center);
  o->computeAABB();
  return o;
}

fcl::Transform3d randomPose(std::mt19937& rng, double extent) {
  std::uniform_real_distribution<double> t(-extent, extent), ang(0, 2 * M_PI);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = (fcl::AngleAxisd(ang(rng), fcl::Vector3d::UnitX()) *
                 fcl::AngleAxisd(ang(rng), fcl::Vector3d::UnitY()) *
                 fcl::AngleAxisd(ang(rng), fcl::Vector3d::UnitZ()))
                    .toRotationMatrix();
  tf.translation() = fcl::Vector3d(t(rng), t(rng), t(rng));
  return tf;
}

struct Scene {
  std::string name;
  std::vector<ObjPtr> env, queries;
  double move = 0;  // translation step of the update benchmarks
};

/// n boxes, edges log-uniform in [1, 100] (aspect up to 2:1), in a cube of side L sized for about
/// 18 overlapping pairs per object.
Scene mixedScene(std::size_t n, unsigned seed) {
  Scene s;
  s.name = "mixed";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> logsize(0, 2), aspect(0.5, 1);
  // E[(a+b)^3] for independent log-uniform edges ~ the swept volume of a pair; 18 pairs/object.
  const double L = 300.0 * std::cbrt(double(n) / 10000.0);
  std::uniform_real_distribution<double> pos(0, L);
  auto make = [&](std::vector<ObjPtr>& out, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
      const double e = std::pow(10.0, logsize(rng));
      out.push_back(axisBox(e * aspect(rng), e * aspect(rng), e * aspect(rng),
                            fcl::Vector3d(pos(rng), pos(rng), pos(rng))));
    }
  };
  make(s.env, n);
  make(s.queries, 1000);
  s.move = 0.05;
  return s;
}

/// n boxes of edge 0.3..0.5 at the points of a lattice of spacing 1 (jittered by 0.2): no pairs.
Scene sparseScene(std::size_t n, unsigned seed) {
  Scene s;
  s.name = "sparse";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jit(-0.1, 0.1), edge(0.3, 0.5);
  const int side = int(std::ceil(std::cbrt(double(n))));
  std::vector<fcl::Vector3d> points;
  for (int x = 0; x < side; ++x)
    for (int y = 0; y < side; ++y)
      for (int z = 0; z < side; ++z) points.emplace_back(x, y, z);
  std::shuffle(points.begin(), points.end(), rng);
  for (std::size_t i = 0; i < n; ++i)
    s.env.push_back(axisBox(edge(rng), edge(rng), edge(rng),
                            points[i] + fcl::Vector3d(jit(rng), jit(rng), jit(rng))));
  std::uniform_real_distribution<double> pos(0, side - 1);
  for (int i = 0; i < 1000; ++i)
    s.queries.push_back(
        axisBox(edge(rng), edge(rng), edge(rng), fcl::Vector3d(pos(rng), pos(rng), pos(rng))));
  s.move = 0.01;
  return s;
}

/// FCL's test::generateEnvironments shapes at random poses in [-scale, scale]^3, n objects.
Scene fclScene(std::size_t n, unsigned seed) {
  Scene s;
  s.name = "fcl";
  std::mt19937 rng(seed);
  const double scale = 400.0 * std::cbrt(double(n) / 10000.0);
  auto make = [&](std::vector<ObjPtr>& out, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
      std::shared_ptr<fcl::CollisionGeometryd> g;
      if (i % 3 == 0) g = std::make_shared<fcl::Boxd>(5, 10, 20);
      if (i % 3 == 1) g = std::make_shared<fcl::Sphered>(30);
      if (i % 3 == 2) g = std::make_shared<fcl::Cylinderd>(10, 40);
      out.push_back(std::make_unique<Obj>(g, randomPose(rng, scale)));
      out.back()->computeAABB();
    }
  };
  make(s.env, n);
  make(s.queries, 1000);
  s.move = 0.2;
  return s;
}

std::vector<Obj*> raw(const std::vector<ObjPtr>& v) {
  std::vector<Obj*> r;
  for (const auto& o : v) r.push_back(o.get());
  return r;
}

struct Row {
  std::string scene, manager;
  std::size_t n = 0;
  double build = 0, self = 0, query = 0, mgr = 0, upd1 = 0, upd1_self = 0, upd_all = 0,
         upd_all_self = 0;
  std::size_t self_pairs = 0, query_pairs = 0, mgr_pairs = 0;
};

using Factory = std::function<std::unique_ptr<Manager>()>;

/// Moves objects [i0, ...) with stride `stride` by +step (sign = +1) or back (sign = -1).
void moveObjects(const std::vector<Obj*>& objs, std::size_t stride, double step, int sign,
                 std::vector<Obj*>& moved) {
  moved.clear();
  for (std::size_t i = 0; i < objs.size(); i += stride) {
    Obj* o = objs[i];
    o->setTranslation(o->getTranslation() + sign * fcl::Vector3d(step, -0.5 * step, 0.25 * step));
    o->computeAABB();
    moved.push_back(o);
  }
}

Row measure(const Scene& sc, const std::string& name, const Factory& make, int reps) {
  std::fprintf(stderr, "manager_bench: %s n=%zu %s ...\n", sc.name.c_str(), sc.env.size(),
               name.c_str());
  Row row;
  row.scene = sc.name;
  row.manager = name;
  row.n = sc.env.size();
  const std::vector<Obj*> env = raw(sc.env), queries = raw(sc.queries);
  std::vector<double> t_build, t_self, t_query, t_mgr, t_u1, t_u1s, t_ua, t_uas;

  for (int r = 0; r < reps; ++r) {
    auto m = make();
    const auto a = Clock::now();
    m->registerObjects(env);
    m->setup();
    t_build.push_back(ms(a, Clock::now()));
  }
  auto m = make();
  m->registerObjects(env);
  m->setup();
  auto q = make();
  q->registerObjects(queries);
  q->setup();
  Counter warm;
  m->collide(&warm, countCallback);  // warm-up (and a lazy structure's first build)

  for (int r = 0; r < reps; ++r) {
    Counter c;
    const auto a = Clock::now();
    m->collide(&c, countCallback);
    t_self.push_back(ms(a, Clock::now()));
    row.self_pairs = c.pairs;
  }
  for (int r = 0; r < reps; ++r) {
    Counter c;
    const auto a = Clock::now();
    for (Obj* o : queries) m->collide(o, &c, countCallback);
    t_query.push_back(ms(a, Clock::now()));
    row.query_pairs = c.pairs;
  }
  for (int r = 0; r < reps; ++r) {
    Counter c;
    const auto a = Clock::now();
    m->collide(q.get(), &c, countCallback);
    t_mgr.push_back(ms(a, Clock::now()));
    row.mgr_pairs = c.pairs;
  }
  std::vector<Obj*> moved;
  for (int r = 0; r < reps; ++r) {
    for (std::size_t stride : {std::size_t(100), std::size_t(1)}) {
      for (int sign : {1, -1}) {  // there and back: the scene stays the same over the runs
        moveObjects(env, stride, sc.move, sign, moved);
        const auto a = Clock::now();
        for (Obj* o : moved) m->update(o);
        const auto b = Clock::now();
        Counter c;
        m->collide(&c, countCallback);
        const auto e = Clock::now();
        if (sign == 1) {
          (stride == 1 ? t_ua : t_u1).push_back(ms(a, b));
          (stride == 1 ? t_uas : t_u1s).push_back(ms(b, e));
        }
      }
    }
  }
  row.build = median(t_build);
  row.self = median(t_self);
  row.query = median(t_query);
  row.mgr = median(t_mgr);
  row.upd1 = median(t_u1);
  row.upd1_self = median(t_u1s);
  row.upd_all = median(t_ua);
  row.upd_all_self = median(t_uas);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::size_t> sizes = {1000, 10000};
  int reps = 7;
  std::string which = "all", only;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--n") && i + 1 < argc) {
      sizes.clear();
      for (char* p = std::strtok(argv[++i], ","); p; p = std::strtok(nullptr, ","))
        sizes.push_back(std::size_t(
            kdet_bench_util::parseIntArg("manager_bench", "--n", p, 1, 100000000, 2)));
      if (sizes.empty()) {
        std::fprintf(stderr, "manager_bench: --n wants one or more sizes, e.g. --n 1000,10000\n");
        return 2;
      }
    } else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) {
      reps = int(kdet_bench_util::parseIntArg("manager_bench", "--reps", argv[++i], 1, 100000, 2));
    } else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) {
      only = argv[++i];  // kdet, dyn-tree or spatial-hash (profiling; skips the cross-check)
    } else if (!std::strcmp(argv[i], "--scene") && i + 1 < argc) {
      which = argv[++i];
    } else {
      std::fprintf(stderr, "usage: %s [--n N[,N...]] [--reps R] [--scene mixed|sparse|fcl|all]\n",
                   argv[0]);
      return 2;
    }
  }
  std::vector<Row> rows;
  for (std::size_t n : sizes) {
    std::vector<Scene> scenes;
    if (which == "all" || which == "mixed") scenes.push_back(mixedScene(n, 1));
    if (which == "all" || which == "sparse") scenes.push_back(sparseScene(n, 2));
    if (which == "all" || which == "fcl") scenes.push_back(fclScene(n, 3));
    for (const Scene& sc : scenes) {
      const std::vector<Obj*> env = raw(sc.env);
      const Factory spatial = [env] { return makeSpatialHash(env); };
      if (!only.empty()) {
        if (only == "kdet")
          rows.push_back(measure(
              sc, "kdet", [] { return std::make_unique<kdet_fcl::CollisionManagerd>(); }, reps));
        if (only == "dyn-tree")
          rows.push_back(measure(
              sc, "dyn-tree",
              [] { return std::make_unique<fcl::DynamicAABBTreeCollisionManagerd>(); }, reps));
        if (only == "spatial-hash") rows.push_back(measure(sc, "spatial-hash", spatial, reps));
        continue;
      }
      rows.push_back(measure(sc, "kdet", [] { return std::make_unique<kdet_fcl::CollisionManagerd>(); },
                             reps));
      rows.push_back(measure(
          sc, "dyn-tree", [] { return std::make_unique<fcl::DynamicAABBTreeCollisionManagerd>(); },
          reps));
      rows.push_back(measure(sc, "spatial-hash", spatial, reps));
      if (n <= 2000)
        rows.push_back(measure(
            sc, "naive", [] { return std::make_unique<fcl::NaiveCollisionManagerd>(); }, reps));
    }
  }
  std::printf("median of %d runs, ms; query = 1000 collide(obj); mgr = collide(manager of the 1000 "
              "queries); upd = update(obj) loop, +self = the self collide after it\n",
              reps);
  std::printf("| scene | n | manager | pairs | build | self | query | mgr | upd1%% | +self | "
              "upd100%% | +self |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  bool mismatch = false;
  for (const Row& r : rows) {
    if (!only.empty()) {
      std::printf("| %s | %zu | %s | %zu | %.2f | %.2f | %.2f | %.2f | %.3f | %.2f | %.2f | %.2f |\n",
                  r.scene.c_str(), r.n, r.manager.c_str(), r.self_pairs, r.build, r.self, r.query,
                  r.mgr, r.upd1, r.upd1_self, r.upd_all, r.upd_all_self);
      continue;
    }
    std::printf("| %s | %zu | %s | %zu | %.2f | %.2f | %.2f | %.2f | %.3f | %.2f | %.2f | %.2f |\n",
                r.scene.c_str(), r.n, r.manager.c_str(), r.self_pairs, r.build, r.self, r.query,
                r.mgr, r.upd1, r.upd1_self, r.upd_all, r.upd_all_self);
    // The reference is the kdet row of the same scene and size (measured first).
    const Row* ref = &r;
    while (ref > rows.data() && ref->manager != "kdet") --ref;
    if (r.self_pairs != ref->self_pairs || r.query_pairs != ref->query_pairs ||
        r.mgr_pairs != ref->mgr_pairs) {
      std::printf("  ^ disagrees with %s: self %zu/%zu, query %zu/%zu, mgr %zu/%zu\n",
                  ref->manager.c_str(), r.self_pairs, ref->self_pairs, r.query_pairs,
                  ref->query_pairs, r.mgr_pairs, ref->mgr_pairs);
      mismatch = true;
    }
  }
  if (mismatch) {
    std::printf("ERROR: the managers disagree on pair counts\n");
    return 1;
  }
  return 0;
}
