#pragma once
/// \file
/// FCL 0.7's collide and distance without its crashes: kdet_fcl::guardedCollide and
/// guardedDistance (double). Debian's FCL 0.7 (built with its assertions on) segfaults, aborts
/// or hangs on some pairs and poses, and answers pairs it has no test for with "no collision" or
/// DBL_MAX; a sweep of every ordered pair of its geometry types at fixed and random poses found
/// them (benchmarks/results/python-compat/). These calls answer where FCL answers and throw
/// UnsupportedQueryError where it cannot, or take the path that does answer:
///  - no test in FCL's own function tables (any TriangleP; Ellipsoid-Halfspace distance):
///    UnsupportedQueryError;
///  - collide: two unbounded shapes (Halfspace, Plane; FCL reports overlapping ones apart when
///    contacts are asked for): UnsupportedQueryError; Convex-Plane runs with GST_INDEP (libccd's
///    test crashes); mesh pairs are kDet's (kdet_fcl::collide);
///  - distance to a Halfspace or Plane (libccd segfaults, indep answers wrongly):
///    UnsupportedQueryError;
///  - unsigned distances run with GST_INDEP (libccd's GJK aborts on exactly touching pairs such
///    as Sphere-Ellipsoid);
///  - signed distances: a collision test first. Apart: the unsigned distance. Touching (the
///    deepest contact within 1e-9 of the objects' size, or the collision test and the GJK
///    disagreeing within FCL's tolerance): 0. Overlapping shapes: FCL's libccd answer (its
///    indep one aborts). A mesh or an octree with a shape: minus the deepest contact's
///    penetration depth, both nearest points at it (FCL's rule, which it applies to one contact
///    and asserts deeper than 0). Two meshes: the unsigned distance (FCL's has no sign). Two
///    spheres: closed form (FCL's hangs on coincident centres);
///  - FCL's exceptions (e.g. "Error with configuration") become UnsupportedQueryError.
/// kdet_fcl::collide and kdet_fcl::distance keep FCL's own behaviour except for FCL's failures
/// that do not depend on the pose (Convex-Plane under GST_LIBCCD runs on GST_INDEP; a distance to
/// a Halfspace or Plane throws UnsupportedQueryError); the Python API (kdet_fcl.fcl) runs on these.

#include <cstddef>

#include <fcl/geometry/collision_geometry.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>
#include <fcl/narrowphase/distance_request.h>
#include <fcl/narrowphase/distance_result.h>

#include "kdet_fcl/errors.h"

namespace kdet_fcl {

/// Who answers a guarded collide: kDet for mesh pairs (kdet_fcl::collide), or FCL 0.7 for every
/// pair (fcl::collide, for cross-checks).
enum class CollideEngine { Kdet, Fcl };

/// The GJK solver guardedCollide runs a and b with (`requested`, or GST_INDEP for Convex-Plane);
/// throws UnsupportedQueryError for a pair FCL 0.7 cannot answer (above).
fcl::GJKSolverType guardedCollideSolver(const fcl::CollisionGeometryd* a,
                                        const fcl::CollisionGeometryd* b,
                                        fcl::GJKSolverType requested);

/// kdet_fcl::collide (or fcl::collide) with guardedCollideSolver's solver; FCL's conventions.
std::size_t guardedCollide(const fcl::CollisionGeometryd* a, const fcl::Transform3d& ta,
                           const fcl::CollisionGeometryd* b, const fcl::Transform3d& tb,
                           const fcl::CollisionRequestd& request, fcl::CollisionResultd& result,
                           CollideEngine engine = CollideEngine::Kdet);

/// FCL 0.7's distance where it answers (above); FCL's conventions: -1 (unsigned, shapes) or 0
/// (meshes) for objects in collision, nearest points in world coordinates. The request's
/// gjk_solver_type is not used (see the rules above).
double guardedDistance(const fcl::CollisionGeometryd* a, const fcl::Transform3d& ta,
                       const fcl::CollisionGeometryd* b, const fcl::Transform3d& tb,
                       const fcl::DistanceRequestd& request, fcl::DistanceResultd& result);

}  // namespace kdet_fcl
