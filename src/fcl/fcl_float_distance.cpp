// fcl::distance for float, compiled once (see kdet_fcl/detail/fcl_float_instances.h). FCL's code,
// not ours: CMakeLists.txt builds this file without sanitizer instrumentation, as libfcl itself is.
#include "kdet_fcl/detail/fcl_float_instances.h"

namespace fcl {

template float distance(const CollisionObject<float>* o1, const CollisionObject<float>* o2,
                        const DistanceRequest<float>& request, DistanceResult<float>& result);

template float distance(const CollisionGeometry<float>* o1, const Transform3<float>& tf1,
                        const CollisionGeometry<float>* o2, const Transform3<float>& tf2,
                        const DistanceRequest<float>& request, DistanceResult<float>& result);

}  // namespace fcl
