// fcl::collide for float, compiled once (see kdet_fcl/detail/fcl_float_instances.h). FCL's code,
// not ours: CMakeLists.txt builds this file without sanitizer instrumentation, as libfcl itself is.
#include "kdet_fcl/detail/fcl_float_instances.h"

namespace fcl {

template std::size_t collide(const CollisionObject<float>* o1, const CollisionObject<float>* o2,
                             const CollisionRequest<float>& request,
                             CollisionResult<float>& result);

template std::size_t collide(const CollisionGeometry<float>* o1, const Transform3<float>& tf1,
                             const CollisionGeometry<float>* o2, const Transform3<float>& tf2,
                             const CollisionRequest<float>& request,
                             CollisionResult<float>& result);

}  // namespace fcl
