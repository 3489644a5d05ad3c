#pragma once
/// \file
/// FCL 0.7's float entry points, compiled once into libkdet_fcl.
///
/// libfcl ships `fcl::collide` and `fcl::distance` compiled for double only. Every translation
/// unit that calls them for float instantiates FCL's whole narrow phase: the collision and
/// distance function tables for both GJK solvers, every shape pair and every BVH traversal.
/// That costs minutes of compile time per translation unit (over ten under AddressSanitizer).
/// These explicit instantiation declarations make such calls link to the one copy in
/// libkdet_fcl (src/fcl/fcl_float_collide.cpp, src/fcl/fcl_float_distance.cpp) instead, the way
/// libfcl's own headers do for double. Included by kdet_fcl/fcl_collide.h, so every user of the
/// FCL adapter gets it.

#include <cstddef>

#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

namespace fcl {

extern template std::size_t collide(const CollisionObject<float>* o1,
                                    const CollisionObject<float>* o2,
                                    const CollisionRequest<float>& request,
                                    CollisionResult<float>& result);

extern template std::size_t collide(const CollisionGeometry<float>* o1,
                                    const Transform3<float>& tf1,
                                    const CollisionGeometry<float>* o2,
                                    const Transform3<float>& tf2,
                                    const CollisionRequest<float>& request,
                                    CollisionResult<float>& result);

extern template float distance(const CollisionObject<float>* o1, const CollisionObject<float>* o2,
                               const DistanceRequest<float>& request,
                               DistanceResult<float>& result);

extern template float distance(const CollisionGeometry<float>* o1, const Transform3<float>& tf1,
                               const CollisionGeometry<float>* o2, const Transform3<float>& tf2,
                               const DistanceRequest<float>& request,
                               DistanceResult<float>& result);

}  // namespace fcl
