// An FCL program that knows nothing of kdet_fcl: it links libfcl alone. Run it as it is, and
// under LD_PRELOAD=libkdet_fcl_interpose.so, where its mesh-mesh fcl::collide calls go through
// kDet (README "Unmodified FCL programs"). tests/interpose_tests.cmake compares the two runs.
//
//   example_unmodified_fcl            the checks: one line per query, pairs as counts and hashes
//   example_unmodified_fcl bench [n]  times n rounds (default 15): of the checks' small sphere and
//                                     torus at their 12 poses (every pair; first contact), and of
//                                     an 80k-triangle sheet against a 20k-triangle sphere, rigid
//                                     and deforming; medians in ms
//
// Meshes are built here (a UV sphere, a torus, a wavy sheet); no data files.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <fcl/fcl.h>

#include "fcl_only_meshes.h"

namespace {

using namespace fcl_only;

// A deterministic pose near the origin: rotation about a generic axis, translation within 0.8.
fcl::Transform3d pose(int i) {
  std::uint64_t x = 0x9E3779B97F4A7C15ull * std::uint64_t(i + 1);
  auto next = [&x] {
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdull;
    x ^= x >> 33;
    return double(x >> 11) / double(1ull << 53);
  };
  fcl::Vector3d axis(next() - 0.5, next() - 0.5, next() - 0.5 + 1e-3);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = fcl::AngleAxisd(2 * kPi * next(), axis.normalized()).toRotationMatrix();
  tf.translation() = fcl::Vector3d(next() - 0.5, next() - 0.5, next() - 0.5) * 1.6;
  return tf;
}

// The contacts' (b1, b2) as a count and an order-free hash.
void printPairs(const char* what, int i, const fcl::CollisionResultd& r) {
  std::vector<std::pair<std::intptr_t, std::intptr_t>> p;
  for (std::size_t k = 0; k < r.numContacts(); ++k)
    p.emplace_back(r.getContact(k).b1, r.getContact(k).b2);
  std::sort(p.begin(), p.end());
  std::uint64_t h = 1469598103934665603ull;
  for (const auto& q : p)
    for (std::intptr_t v : {q.first, q.second}) h = (h ^ std::uint64_t(v)) * 1099511628211ull;
  std::printf("%s %d: collision %d, contacts %zu, pairs %016llx\n", what, i, int(r.isCollision()),
              r.numContacts(), static_cast<unsigned long long>(h));
}

const fcl::CollisionRequestd kAll(std::numeric_limits<int>::max(), false);

int checks() {
  const Soup ball = sphere(1.0, 48, 24), ring = torus(0.9, 0.3, 64, 24);
  auto ball_obbrss = model<fcl::OBBRSSd>(ball);
  auto ring_obbrss = model<fcl::OBBRSSd>(ring);
  fcl::CollisionObjectd a(ball_obbrss), b(ring_obbrss);

  // Every pair, objects, at 12 poses; then the first contact only.
  for (int i = 0; i < 12; ++i) {
    b.setTransform(pose(i));
    b.computeAABB();
    fcl::CollisionResultd all, first;
    fcl::collide(&a, &b, kAll, all);
    printPairs("objects", i, all);
    fcl::collide(&a, &b, fcl::CollisionRequestd(1, false), first);
    std::printf("first %d: collision %d, contacts %zu\n", i, int(first.isCollision()),
                first.numContacts());
  }

  // The geometry overload, OBB models; results accumulate over two calls, as in FCL.
  auto ball_obb = model<fcl::OBBd>(ball);
  auto ring_obb = model<fcl::OBBd>(ring);
  for (int i = 0; i < 4; ++i) {
    fcl::CollisionResultd r;
    fcl::collide(ball_obb.get(), fcl::Transform3d::Identity(), ring_obb.get(), pose(i), kAll, r);
    printPairs("geometries", i, r);
    fcl::collide(ball_obb.get(), fcl::Transform3d::Identity(), ring_obb.get(), pose(i), kAll, r);
    std::printf("geometries %d twice: contacts %zu\n", i, r.numContacts());
  }

  // Shapes: FCL's own narrow phase either way.
  {
    auto box = std::make_shared<fcl::Boxd>(0.5, 0.5, 0.5);
    auto ball_shape = std::make_shared<fcl::Sphered>(0.4);
    fcl::CollisionObjectd box_obj(box, pose(1)), ball_obj(ball_shape, pose(2));
    fcl::CollisionResultd r1, r2;
    fcl::collide(&box_obj, &ball_obj, kAll, r1);
    fcl::collide(&a, &box_obj, fcl::CollisionRequestd(1, false), r2);
    std::printf("shapes: box-sphere collision %d, mesh-box collision %d\n", int(r1.isCollision()),
                int(r2.isCollision()));
  }

  // A deforming model through FCL's update calls: the torus swells frame by frame.
  {
    auto ring_model = model<fcl::OBBRSSd>(ring);
    fcl::CollisionObjectd r(ring_model, pose(3));
    r.computeAABB();
    for (int f = 0; f < 4; ++f) {
      const Soup swollen = torus(0.9, 0.3 + 0.05 * f, 64, 24);
      ring_model->beginUpdateModel();
      for (const auto& p : swollen.points) ring_model->updateVertex(p);
      ring_model->endUpdateModel();
      r.computeAABB();
      fcl::CollisionResultd res;
      fcl::collide(&a, &r, kAll, res);
      printPairs("deforming", f, res);
    }
  }

  // FCL's replace calls write the vertices in place (the model's arrays stay where they were).
  {
    auto ring_model = model<fcl::OBBRSSd>(ring);
    fcl::CollisionObjectd r(ring_model, pose(4));
    r.computeAABB();
    fcl::CollisionResultd before, after;
    fcl::collide(&a, &r, kAll, before);
    printPairs("replaced", 0, before);
    const Soup thin = torus(0.9, 0.15, 64, 24);
    ring_model->beginReplaceModel();
    for (const auto& p : thin.points) ring_model->replaceVertex(p);
    ring_model->endReplaceModel();
    r.computeAABB();
    fcl::collide(&a, &r, kAll, after);
    printPairs("replaced", 1, after);
  }

  // A broadphase manager whose callback calls fcl::collide (as MoveIt's does).
  {
    std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
    for (int i = 0; i < 6; ++i) {
      auto geometry = i % 2 == 0 ? std::static_pointer_cast<fcl::CollisionGeometryd>(ball_obbrss)
                                 : std::static_pointer_cast<fcl::CollisionGeometryd>(ring_obbrss);
      objects.emplace_back(new fcl::CollisionObjectd(geometry, pose(20 + i)));
    }
    objects.emplace_back(new fcl::CollisionObjectd(std::make_shared<fcl::Boxd>(1, 1, 1), pose(30)));
    fcl::DynamicAABBTreeCollisionManagerd manager;
    for (auto& o : objects) manager.registerObject(o.get());
    manager.setup();
    struct Tally {
      std::size_t pairs = 0, contacts = 0;
    } tally;
    manager.collide(&tally, [](fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
      fcl::CollisionResultd r;
      fcl::collide(o1, o2, kAll, r);
      auto* t = static_cast<Tally*>(data);
      t->pairs += r.isCollision() ? 1 : 0;
      t->contacts += r.numContacts();
      return false;
    });
    std::printf("manager: colliding object pairs %zu, contacts %zu\n", tally.pairs, tally.contacts);
  }

  // Models made and destroyed, as a planner's scene changes.
  std::size_t made = 0, found = 0;
  for (int i = 0; i < 30; ++i) {
    auto m1 = model<fcl::OBBRSSd>(sphere(1.0, 16 + i % 3, 8));
    auto m2 = model<fcl::OBBRSSd>(torus(0.9, 0.3, 24, 8));
    fcl::CollisionResultd r;
    fcl::collide(m1.get(), fcl::Transform3d::Identity(), m2.get(), pose(i), kAll, r);
    made += 2;
    found += r.numContacts();
  }
  std::printf("lifetime: models made and destroyed %zu, contacts %zu\n", made, found);

  // A pose that is not a rigid motion (scaled by 1.5): kDet refuses it, so the pair goes to FCL.
  {
    fcl::Transform3d scaled = pose(5);
    scaled.linear() *= 1.5;
    fcl::CollisionResultd r;
    fcl::collide(ball_obbrss.get(), fcl::Transform3d::Identity(), ring_obbrss.get(), scaled,
                 kAll, r);
    printPairs("scaled", 0, r);
  }

  // Mixed BV types: FCL has no OBB-RSS function (it warns and finds nothing); kDet does not care.
  {
    auto ring_rss = model<fcl::RSSd>(ring);
    fcl::CollisionResultd r;
    fcl::collide(ball_obb.get(), fcl::Transform3d::Identity(), ring_rss.get(), pose(0), kAll, r);
    printPairs("mixed", 0, r);
  }
  return 0;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int bench(int n) {
  // Small meshes, as a planner's links: the checks' sphere and torus at their 12 poses.
  {
    auto ball_model = model<fcl::OBBRSSd>(sphere(1.0, 48, 24));
    auto ring_model = model<fcl::OBBRSSd>(torus(0.9, 0.3, 64, 24));
    fcl::CollisionObjectd a(ball_model), b(ring_model);
    std::vector<double> all_ms, first_ms;
    for (int round = 0; round < n + 2; ++round)
      for (int i = 0; i < 12; ++i) {
        b.setTransform(pose(i));
        b.computeAABB();
        fcl::CollisionResultd all, first;
        auto t0 = std::chrono::steady_clock::now();
        fcl::collide(&a, &b, kAll, all);
        auto t1 = std::chrono::steady_clock::now();
        fcl::collide(&a, &b, fcl::CollisionRequestd(1, false), first);
        if (round >= 2) {
          all_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
          first_ms.push_back(msSince(t1));
        }
      }
    std::printf("bench small: sphere %d and torus %d triangles, OBBRSS, 12 poses\n",
                ball_model->num_tris, ring_model->num_tris);
    std::printf("bench small every pair: median %.4f ms per check\n", median(all_ms));
    std::printf("bench small first contact: median %.4f ms per check\n", median(first_ms));
  }

  const int side = 200;  // 200 x 200 quads: 80,000 triangles
  Soup cloth = sheet(side, 0.0);
  auto cloth_model = model<fcl::OBBRSSd>(cloth);
  auto ball_model = model<fcl::OBBRSSd>(sphere(1.0, 140, 72));
  fcl::CollisionObjectd c(cloth_model), s(ball_model);
  std::printf("bench: sheet %d triangles, sphere %d triangles, OBBRSS, every pair\n",
              cloth_model->num_tris, ball_model->num_tris);

  std::vector<double> rigid, deform;
  std::size_t contacts = 0;
  for (int i = 0; i < n + 2; ++i) {  // two warm-up checks
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.translation() = fcl::Vector3d(0.01 * i, 0, 0);
    s.setTransform(tf);
    s.computeAABB();
    fcl::CollisionResultd r;
    auto t0 = std::chrono::steady_clock::now();
    fcl::collide(&c, &s, kAll, r);
    if (i >= 2) rigid.push_back(msSince(t0));
    contacts = r.numContacts();
  }
  std::printf("bench rigid: median %.3f ms per check (%zu contacts)\n", median(rigid), contacts);

  std::vector<double> update, check;
  for (int i = 0; i < n + 2; ++i) {
    const double t = 0.1 * i;
    auto t0 = std::chrono::steady_clock::now();
    cloth_model->beginUpdateModel();  // FCL's refit: the program pays it either way
    for (int j = 0; j <= side; ++j)
      for (int k = 0; k <= side; ++k)
        cloth_model->updateVertex(sheetPoint(double(k) / side, double(j) / side, t));
    cloth_model->endUpdateModel();
    c.computeAABB();
    const double updated = msSince(t0);
    fcl::CollisionResultd r;
    auto t1 = std::chrono::steady_clock::now();
    fcl::collide(&c, &s, kAll, r);
    if (i >= 2) {
      check.push_back(msSince(t1));
      update.push_back(updated);
      deform.push_back(msSince(t0));
    }
    contacts = r.numContacts();
  }
  std::printf("bench deforming: median %.3f ms per frame = update %.3f ms (FCL's refit) + check "
              "%.3f ms (%zu contacts)\n",
              median(deform), median(update), median(check), contacts);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "bench") == 0) {
    const int n = argc >= 3 ? std::atoi(argv[2]) : 15;
    if (n < 1 || n > 100000) {
      std::fprintf(stderr, "usage: example_unmodified_fcl [bench [checks 1..100000]]\n");
      return 2;
    }
    return bench(n);
  }
  if (argc != 1) {
    std::fprintf(stderr, "usage: example_unmodified_fcl [bench [checks 1..100000]]\n");
    return 2;
  }
  return checks();
}
