#pragma once
// A query that goes to FCL itself (fcl_guarded.cpp's CollideEngine::Fcl): the checks and the
// refit kdet_fcl::collide makes before it forwards a pair (fcl_collide.cpp).
#include <fcl/geometry/collision_geometry.h>

namespace kdet_fcl {
namespace detail {

/// Throws InvalidInputError for a null geometry, a non-finite pose or a BVHModel that is not
/// built (or empty); refits FCL's BVH of a kdet_fcl::Mesh kept for kDet only
/// (MeshMode::KdetOnly) that changed since FCL last saw it.
void prepareFclQuery(const fcl::CollisionGeometryd* a, const fcl::Transform3d& ta,
                     const fcl::CollisionGeometryd* b, const fcl::Transform3d& tb,
                     const char* what);

/// Whether FCL 0.7's own collide of geometries of these node types segfaults under GST_LIBCCD
/// whatever their poses: a Convex against a Plane (libccd's test; benchmarks/results/
/// python-compat/). kdet_fcl::collide runs such a pair with GST_INDEP, which answers it.
bool libccdCollideCrashes(fcl::NODE_TYPE a, fcl::NODE_TYPE b);

/// Whether FCL 0.7's distance of a and b crashes or answers wrongly whatever their poses: a
/// Halfspace or Plane with any geometry FCL has a distance for (GST_LIBCCD segfaults, GST_INDEP
/// answers wrongly). kdet_fcl::distance and guardedDistance refuse them (UnsupportedQueryError).
bool distanceToUnboundedShape(fcl::NODE_TYPE a, fcl::OBJECT_TYPE a_object, fcl::NODE_TYPE b,
                              fcl::OBJECT_TYPE b_object);

}  // namespace detail
}  // namespace kdet_fcl
