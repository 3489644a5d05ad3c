#pragma once
// One triangle mesh appended to another (its vertices after the other's, its vertex indices
// shifted): the benchmark scenes' compound meshes and the GPU LBVH baseline's joint form
// (kdet_bvh::jointMesh) share it.

#include <cstdint>

#include "kdet_fcl/triangle_mesh.h"

namespace kdet_bench {

template <class S>
void appendMesh(kdet_fcl::TriangleMesh<S>& dst, const kdet_fcl::TriangleMesh<S>& src) {
  const auto base = static_cast<std::uint32_t>(dst.vertices.size());
  dst.vertices.insert(dst.vertices.end(), src.vertices.begin(), src.vertices.end());
  dst.triangles.reserve(dst.triangles.size() + src.triangles.size());
  for (const kdet_fcl::Triangle& t : src.triangles)
    dst.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

}  // namespace kdet_bench
