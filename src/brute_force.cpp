// O(n*m) references with the same exact predicate and the same mapping of A into B's frame as
// the backends: a pair set from any backend must equal these exactly.

#include <algorithm>

#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "kdet_fcl/query.h"

namespace kdet_fcl {

template <class S>
std::vector<TrianglePair> bruteForceIntersectMeshes(const TriangleMesh<S>& a,
                                                    const Transform<S>& pose_a,
                                                    const TriangleMesh<S>& b,
                                                    const Transform<S>& pose_b,
                                                    Predicate predicate) {
  a.validateForQueries(false, "bruteForceIntersectMeshes: first mesh");
  b.validateForQueries(false, "bruteForceIntersectMeshes: second mesh");
  validatePose(pose_a, "bruteForceIntersectMeshes: first pose");
  validatePose(pose_b, "bruteForceIntersectMeshes: second pose");
  const detail::RelativePose rp = detail::relativePose(pose_a, pose_b);
  std::vector<Vec3<S>> va(a.vertices);
  if (!rp.identity)
    for (Vec3<S>& p : va) p = detail::mapPoint(rp.a_to_b, p);
  std::vector<TrianglePair> out;
  for (std::size_t i = 0; i < a.triangles.size(); ++i) {
    const Triangle& ti = a.triangles[i];
    for (std::size_t j = 0; j < b.triangles.size(); ++j) {
      const Triangle& tj = b.triangles[j];
      if (detail::trianglesIntersect(predicate, va[ti[0]], va[ti[1]], va[ti[2]], b.vertices[tj[0]],
                                     b.vertices[tj[1]], b.vertices[tj[2]]))
        out.push_back({std::uint32_t(i), std::uint32_t(j)});
    }
  }
  return out;
}

template <class S>
std::vector<TrianglePair> bruteForceIntersectSelf(const TriangleMesh<S>& m, Predicate predicate) {
  m.validateForQueries(false, "bruteForceIntersectSelf");
  const auto& v = m.vertices;
  std::vector<TrianglePair> out;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    const Triangle& ti = m.triangles[i];
    for (std::size_t j = i + 1; j < m.triangles.size(); ++j) {
      const Triangle& tj = m.triangles[j];
      if (m.sharesVertex(std::uint32_t(i), std::uint32_t(j))) continue;  // adjacent
      if (detail::trianglesIntersect(predicate, v[ti[0]], v[ti[1]], v[ti[2]], v[tj[0]], v[tj[1]],
                                     v[tj[2]]))
        out.push_back({std::uint32_t(i), std::uint32_t(j)});
    }
  }
  return out;
}

template std::vector<TrianglePair> bruteForceIntersectMeshes(const TriangleMesh<float>&,
                                                             const Transform<float>&,
                                                             const TriangleMesh<float>&,
                                                             const Transform<float>&,
                                                             Predicate);
template std::vector<TrianglePair> bruteForceIntersectMeshes(const TriangleMesh<double>&,
                                                             const Transform<double>&,
                                                             const TriangleMesh<double>&,
                                                             const Transform<double>&,
                                                             Predicate);
template std::vector<TrianglePair> bruteForceIntersectSelf(const TriangleMesh<float>&, Predicate);
template std::vector<TrianglePair> bruteForceIntersectSelf(const TriangleMesh<double>&, Predicate);

}  // namespace kdet_fcl
