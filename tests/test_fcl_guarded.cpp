// kdet_fcl::guardedCollide and guardedDistance (include/kdet_fcl/fcl_guarded.h): the pairs and
// poses where FCL 0.7 crashes, aborts, hangs or has no test are refused or answered, and where
// FCL answers, the answer is FCL's; and the drop-in's own guards against FCL's failures that do
// not depend on the pose. Each case below aborted, crashed or went unanswered in FCL 0.7 itself
// (benchmarks/results/python-compat/): a regression here ends the test process.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/convex.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/ellipsoid.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/plane.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/geometry/shape/triangle_p.h>
#include <fcl/narrowphase/distance.h>

#include "fcl_test_util.h"
#include "kdet_fcl/kdet_fcl.h"

namespace {

using kdet_fcl::guardedCollide;
using kdet_fcl::guardedDistance;
using kdet_fcl::UnsupportedQueryError;

fcl::Transform3d at(double x, double y = 0, double z = 0) {
  fcl::Transform3d t = fcl::Transform3d::Identity();
  t.translation() = fcl::Vector3d(x, y, z);
  return t;
}

double distance(const fcl::CollisionGeometryd& a, const fcl::Transform3d& ta,
                const fcl::CollisionGeometryd& b, const fcl::Transform3d& tb, bool is_signed,
                fcl::DistanceResultd* out = nullptr) {
  fcl::DistanceRequestd request(true, is_signed);
  fcl::DistanceResultd result;
  const double d = guardedDistance(&a, ta, &b, tb, request, result);
  if (out) *out = result;
  return d;
}

bool collides(const fcl::CollisionGeometryd& a, const fcl::Transform3d& ta,
              const fcl::CollisionGeometryd& b, const fcl::Transform3d& tb,
              fcl::GJKSolverType solver = fcl::GST_LIBCCD) {
  fcl::CollisionRequestd request(1, true);
  request.gjk_solver_type = solver;
  fcl::CollisionResultd result;
  return guardedCollide(&a, ta, &b, tb, request, result) > 0;
}

std::shared_ptr<fcl::Convexd> cube() {  // [-0.5, 0.5]^3, faces counter-clockwise from outside
  auto v = std::make_shared<std::vector<fcl::Vector3d>>();
  for (double x : {-.5, .5})
    for (double y : {-.5, .5})
      for (double z : {-.5, .5}) v->emplace_back(x, y, z);
  auto f = std::make_shared<std::vector<int>>(std::vector<int>{
      4, 0, 1, 3, 2, 4, 4, 6, 7, 5, 4, 0, 4, 5, 1, 4, 2, 3, 7, 6, 4, 0, 2, 6, 4, 4, 1, 5, 7, 3});
  return std::make_shared<fcl::Convexd>(v, 6, f);
}

TEST(FclGuarded, PairsFclHasNoAnswerForAreRefused) {
  const fcl::TrianglePd tri(fcl::Vector3d(0, 0, 0), fcl::Vector3d(1, 0, 0), fcl::Vector3d(0, 1, 0));
  const fcl::Boxd box(1, 1, 1);
  const fcl::Halfspaced half(fcl::Vector3d(0, 0, 1), 0);
  const fcl::Planed plane(fcl::Vector3d(0, 0, 1), 0);
  // FCL: a warning and "no collision" / DBL_MAX for the triangle (it overlaps the box).
  EXPECT_THROW(collides(tri, at(0.2), box, at(0)), UnsupportedQueryError);
  EXPECT_THROW(distance(tri, at(0.2), box, at(0), false), UnsupportedQueryError);
  // FCL: a segfault with libccd, a wrong distance with indep.
  EXPECT_THROW(distance(box, at(0, 0, 3), half, at(0), false), UnsupportedQueryError);
  EXPECT_THROW(distance(plane, at(0), box, at(0, 0, 3), true), UnsupportedQueryError);
  // FCL: overlapping halfspaces reported apart when contacts are asked for.
  EXPECT_THROW(collides(plane, at(0), half, at(0, 0, 0.2)), UnsupportedQueryError);
  // A bounded shape against them still collides as FCL answers it.
  EXPECT_TRUE(collides(box, at(0, 0, 0.4), half, at(0)));
  EXPECT_FALSE(collides(box, at(0, 0, 0.6), half, at(0)));
  // Convex-Plane: libccd's test segfaults; it runs on indep.
  const auto c = cube();
  for (auto solver : {fcl::GST_LIBCCD, fcl::GST_INDEP}) {
    EXPECT_TRUE(collides(*c, at(0, 0, 0.3), plane, at(0), solver));
    EXPECT_FALSE(collides(*c, at(0, 0, 2), plane, at(0), solver));
    EXPECT_EQ(kdet_fcl::guardedCollideSolver(c.get(), &plane, solver), fcl::GST_INDEP);
  }
}

TEST(FclGuarded, TouchingAndCoincidentShapesAreAnswered) {
  // Exactly touching along x: libccd's GJK asserted "A is not in region 1" and aborted, on
  // unsigned distances too.
  const fcl::Sphered s(0.5);
  const fcl::Ellipsoidd e(0.5, 0.4, 0.3);
  const fcl::Cylinderd cyl(0.5, 1.0);
  const fcl::CollisionGeometryd* others[] = {&e, &cyl};
  for (const fcl::CollisionGeometryd* o : others) {
    const double d = distance(s, at(-1.0), *o, at(0), false);
    EXPECT_TRUE(d == -1 || std::fabs(d) <= 1e-9) << d;  // -1: FCL's "in collision"
    EXPECT_LE(std::fabs(distance(s, at(-1.0), *o, at(0), true)), 1e-6);
    EXPECT_NEAR(distance(s, at(-1.25), *o, at(0), true), 0.25, 1e-6);
  }
  const double ee = distance(e, at(-1.0), e, at(0), false);
  EXPECT_TRUE(ee == -1 || std::fabs(ee) <= 1e-9) << ee;
  // Coincident spheres: FCL's signed distance never returned; here it is closed-form.
  fcl::DistanceResultd r;
  EXPECT_EQ(distance(s, at(0), fcl::Sphered(0.3), at(0), true, &r), -0.8);
  EXPECT_NEAR(distance(s, at(0.1), fcl::Sphered(0.3), at(0), true, &r), -0.7, 1e-12);
  EXPECT_NEAR(r.nearest_points[0].x(), -0.4, 1e-12);
  EXPECT_NEAR(r.nearest_points[1].x(), 0.3, 1e-12);
}

TEST(FclGuarded, AMeshOverlappingAConvexHasASignedDistance) {
  // FCL took one contact, asserted its depth above 0 and aborted at this pose.
  const auto sphere = kdet_fcl::makeSphere<double>({0, 0, 0}, 0.7, 12, 8);
  const auto mesh = kdet_fcl_test::makeModel<kdet_fcl::Meshd>(sphere);
  const auto c = cube();
  for (auto solver : {fcl::GST_LIBCCD, fcl::GST_INDEP}) {
    fcl::DistanceRequestd request(true, true);
    request.gjk_solver_type = solver;
    fcl::DistanceResultd result;
    const double d = guardedDistance(mesh.get(), at(-0.9, -0.5, -0.8), c.get(), at(0), request,
                                     result);
    EXPECT_LE(d, 0);
    EXPECT_TRUE(std::isfinite(d));
  }
  EXPECT_TRUE(collides(*mesh, at(-0.9, -0.5, -0.8), *c, at(0)));
}

TEST(FclGuarded, WhereFclAnswersTheAnswerIsFcls) {
  const fcl::Boxd box(1, 1, 1);
  const fcl::Capsuled cap(0.3, 1.0);
  for (double x : {1.2, 2.0, 3.5}) {
    fcl::DistanceRequestd request;
    request.gjk_solver_type = fcl::GST_INDEP;
    fcl::DistanceResultd fr;
    const double fcl_d = fcl::distance(&box, at(x, 0.1), &cap, at(0), request, fr);
    EXPECT_DOUBLE_EQ(distance(box, at(x, 0.1), cap, at(0), false), fcl_d);
    EXPECT_DOUBLE_EQ(distance(box, at(x, 0.1), cap, at(0), true), fcl_d);  // apart: the same
    EXPECT_NEAR(fcl_d, x - 0.8, 1e-6);  // GJK answers to about 1e-7
  }
  // Overlapping shapes: FCL's libccd signed distance (penetration 0.5 + 0.3 - 0.6).
  EXPECT_NEAR(distance(box, at(0.6), cap, at(0), true), -0.2, 1e-4);
  // Collisions: FCL's own engine and kDet's give the same verdicts on shapes.
  for (double x : {0.5, 0.79, 0.81, 2.0}) {
    fcl::CollisionRequestd request;
    fcl::CollisionResultd a, b;
    EXPECT_EQ(guardedCollide(&box, at(x), &cap, at(0), request, a),
              guardedCollide(&box, at(x), &cap, at(0), request, b, kdet_fcl::CollideEngine::Fcl));
    EXPECT_EQ(a.isCollision(), x < 0.8) << x;
  }
}

TEST(FclGuarded, BadInputThrows) {
  const fcl::Boxd box(1, 1, 1);
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  EXPECT_THROW(guardedCollide(nullptr, at(0), &box, at(0), request, result),
               kdet_fcl::InvalidInputError);
  EXPECT_THROW(guardedCollide(&box, at(NAN), &box, at(0), request, result,
                              kdet_fcl::CollideEngine::Fcl),
               kdet_fcl::InvalidInputError);
  EXPECT_THROW(distance(box, at(0, INFINITY), box, at(0), true), kdet_fcl::InvalidInputError);
  EXPECT_THROW(distance(fcl::Sphered(1), at(NAN), fcl::Sphered(1), at(0), true),
               kdet_fcl::InvalidInputError);
}

TEST(FclGuarded, TheDropInNoLongerReachesFclsCrashesByType) {
  // The failures FCL 0.7 has whatever the pose, in kdet_fcl::collide and kdet_fcl::distance
  // themselves (the drop-in; the LD_PRELOAD interposer's collide): a Convex-Plane collide under
  // GST_LIBCCD segfaulted and now runs under GST_INDEP, which answers it; a distance to a
  // Halfspace or Plane segfaulted under GST_LIBCCD (a manager's distance with a ground plane in
  // it, too) and answers wrongly under GST_INDEP: UnsupportedQueryError for both.
  const auto c = cube();
  const fcl::Planed plane(fcl::Vector3d(0, 0, 1), 0);
  const fcl::Halfspaced half(fcl::Vector3d(0, 0, 1), 0);
  const fcl::Boxd box(1, 1, 1);
  const auto mesh = kdet_fcl_test::makeModel<fcl::BVHModel<fcl::OBBRSSd>>(
      kdet_fcl::makeSphere<double>({0, 0, 0}, 0.5, 12, 6));
  for (double z : {0.3, 2.0}) {
    fcl::CollisionRequestd request(1, true), indep(1, true);
    indep.gjk_solver_type = fcl::GST_INDEP;
    fcl::CollisionResultd ours, theirs;
    EXPECT_EQ(kdet_fcl::collide(c.get(), at(0, 0, z), &plane, at(0), request, ours),
              fcl::collide(c.get(), at(0, 0, z), &plane, at(0), indep, theirs));
    EXPECT_EQ(ours.isCollision(), z < 0.5) << z;
    fcl::CollisionResultd mirrored;
    EXPECT_EQ(kdet_fcl::collide(&plane, at(0), c.get(), at(0, 0, z), request, mirrored),
              ours.numContacts());
  }
  const fcl::CollisionGeometryd* unbounded[] = {&plane, &half};
  const fcl::CollisionGeometryd* others[] = {&box, c.get(), mesh.get()};
  for (const fcl::CollisionGeometryd* u : unbounded)
    for (const fcl::CollisionGeometryd* o : others)
      for (auto solver : {fcl::GST_LIBCCD, fcl::GST_INDEP}) {
        fcl::DistanceRequestd request;
        request.gjk_solver_type = solver;
        fcl::DistanceResultd result;
        EXPECT_THROW(kdet_fcl::distance(o, at(0, 0, 3), u, at(0), request, result),
                     kdet_fcl::UnsupportedQueryError);
        EXPECT_THROW(kdet_fcl::distance(u, at(0), o, at(0, 0, 3), request, result),
                     kdet_fcl::UnsupportedQueryError);
      }
  // Shapes FCL answers keep FCL's answer.
  fcl::DistanceRequestd request;
  fcl::DistanceResultd a, b;
  EXPECT_EQ(kdet_fcl::distance(&box, at(3), c.get(), at(0), request, a),
            fcl::distance(&box, at(3), c.get(), at(0), request, b));
}

TEST(FclGuarded, ModelsThatAreNotBuiltThrowInsteadOfReachingFcl) {
  // FCL's traversals read the hierarchy of a model between beginModel and endModel (or an empty
  // one, whose endModel FCL refuses) and crashed in kdet_fcl::distance, in kdet_fcl::collide with
  // a shape, and in the guarded calls.
  const fcl::Boxd box(1, 1, 1);
  fcl::BVHModel<fcl::OBBRSSd> empty, open;
  empty.beginModel();
  empty.endModel();  // refused: FCL prints an error
  open.beginModel();
  open.addTriangle(fcl::Vector3d(0, 0, 0), fcl::Vector3d(1, 0, 0), fcl::Vector3d(0, 1, 0));
  fcl::CollisionRequestd request;
  fcl::DistanceRequestd drequest;
  for (const fcl::CollisionGeometryd* m : {static_cast<const fcl::CollisionGeometryd*>(&empty),
                                           static_cast<const fcl::CollisionGeometryd*>(&open)}) {
    fcl::CollisionResultd cr;
    fcl::DistanceResultd dr;
    EXPECT_THROW(kdet_fcl::distance(m, at(0), &box, at(0), drequest, dr),
                 kdet_fcl::InvalidInputError);
    EXPECT_THROW(guardedDistance(&box, at(0), m, at(0), drequest, dr), kdet_fcl::InvalidInputError);
    EXPECT_THROW(guardedCollide(m, at(0), &box, at(0), request, cr, kdet_fcl::CollideEngine::Fcl),
                 kdet_fcl::InvalidInputError);
  }
  fcl::CollisionResultd cr;
  EXPECT_THROW(kdet_fcl::collide(&open, at(0), &box, at(0), request, cr),
               kdet_fcl::InvalidInputError);
  // An empty model meets nothing on the kDet path (kdet_fcl::collide's contract).
  EXPECT_EQ(kdet_fcl::collide(&empty, at(0), &box, at(0), request, cr), 0u);
  EXPECT_EQ(guardedCollide(&empty, at(0), &box, at(0), request, cr), 0u);
}

}  // namespace
