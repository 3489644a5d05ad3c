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

}  // namespace detail
}  // namespace kdet_fcl
