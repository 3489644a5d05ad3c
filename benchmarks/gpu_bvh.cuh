#pragma once
// The GPU BVH baseline of the benchmark suite (issue 5): the stand-in for the paper's GPU BVH peer.
// Host-only interface (no CUDA header), so gpu_bench.cpp and the tests compile it with any C++17
// compiler; the kernels are in gpu_bvh.cu.
//
//  - Build: a linear BVH. Each triangle's box centroid gets a 30-bit Morton code inside the
//    mesh's bounds; CUB radix-sorts (code, triangle); the n-1 internal nodes are made in parallel
//    from the sorted codes (one thread per internal node finds its range and split, Karras' scheme,
//    ties broken by sorted position), then refit.
//  - Refit (every frame of a deforming mesh): one thread per leaf computes its box from the
//    vertices and climbs; at each internal node the first child to arrive stops (atomic flag), the
//    second writes the union and goes on.
//  - Queries: inter-object: each triangle of the query mesh (the smaller one when the relative pose
//    is the identity, else the first one mapped into the second's frame) walks the other mesh's
//    tree (stack traversal, one thread per triangle, in Morton order); self: each leaf walks its
//    own tree and keeps only leaves after it in the Morton order, and pairs sharing a vertex (the
//    same index or equal coordinates) are dropped, the library's self rules. Candidates go to a
//    device buffer (warp-aggregated atomic counter); a second kernel decides each candidate with
//    the library's exact closed-triangle test (detail::trianglesIntersectWith, the same function
//    and the same coordinates as kDet: A mapped into B's frame with detail::mapPoint, rounded to
//    S). Both buffers are sized from the last query; an overflow is seen on the device, the host
//    grows the buffers and re-runs. Pairs are radix-sorted by (a, b) on the device.
//
// Every call is synchronous and runs on the legacy default stream of this module's runtime.

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "kdet_fcl/predicate.h"
#include "mesh_append.h"
#include "kdet_fcl/query.h"
#include "kdet_fcl/triangle_mesh.h"
#include "kdet_fcl/vec3.h"

namespace kdet_bvh {

/// Device times (CUDA events) of the calls since the last resetTimes(); a call adds its part.
struct BvhTimes {
  double upload_ms = 0;    ///< host->device vertex copies (pinned staging)
  double refit_ms = 0;     ///< leaf boxes + bottom-up refit
  double build_ms = 0;     ///< Morton codes + sort + hierarchy + refit (full rebuilds)
  double traverse_ms = 0;  ///< tree traversal (candidate pairs), all passes
  double exact_ms = 0;     ///< exact tests + counter read-back, all passes
  double output_ms = 0;    ///< pair sort + device->host copy
  double total_ms = 0;     ///< sum of each call's first-to-last event
  std::uint64_t candidates = 0;  ///< pairs that reached the exact test
  int passes = 0;                ///< query passes (> 1 after an output overflow)
};
void setTiming(bool on);
void resetTimes();
BvhTimes times();

/// Makes CUDA device `device` the calling thread's current device, on which the baseline then
/// allocates and runs (the benchmarks put it on kDet's, kdet_fcl::cudaDevice(), so that both
/// methods share a GPU). Call it before the first GPU BVH, from the thread that runs them. Throws
/// std::runtime_error with the CUDA error text when the runtime refuses.
void useDevice(int device);

/// Bytes of device memory held by the module's shared scratch (candidate/pair/sort buffers).
std::size_t scratchBytes();
/// Forces the next query's first pass to use buffers of at most k entries (tests the overflow
/// path); 0 restores the default.
void setInitialCapacity(std::size_t k);

/// A grow-only device buffer of pairs (cudaMalloc'd), for gpu_bench's runs of kDet's queries that
/// leave their pairs on the device (intersectSelfOnDevice, intersectMeshesOnDevice).
class DevicePairBuffer {
 public:
  DevicePairBuffer() = default;
  ~DevicePairBuffer();
  DevicePairBuffer(const DevicePairBuffer&) = delete;
  DevicePairBuffer& operator=(const DevicePairBuffer&) = delete;
  /// Room for at least n pairs (the contents are not kept when it grows).
  void reserve(std::size_t n);
  kdet_fcl::TrianglePair* data() const { return p_; }
  std::size_t capacity() const { return cap_; }
  /// The first n pairs, copied to the host.
  std::vector<kdet_fcl::TrianglePair> read(std::size_t n) const;

 private:
  kdet_fcl::TrianglePair* p_ = nullptr;
  std::size_t cap_ = 0;
};

template <class S>
class GpuBvh {
 public:
  GpuBvh();
  ~GpuBvh();
  GpuBvh(const GpuBvh&) = delete;
  GpuBvh& operator=(const GpuBvh&) = delete;

  /// Uploads the mesh (topology + vertices) and builds its hierarchy.
  void setMesh(const kdet_fcl::TriangleMesh<S>& mesh);
  /// The caller promises that every vertex array it passes to updateVertices/rebuildVertices
  /// stays alive and unchanged while this tree lives (the benchmark's frame meshes do). Then
  /// arrays of 1 MiB and up are registered as page-locked memory on their first upload and
  /// copied to the device straight from there, as the kDet backend does with its meshes' own
  /// buffers (KDET_FCL_CUDA_PIN_VERTICES=0: staged, for both). Off by default.
  void setStableSources(bool on);
  /// New vertex positions (same count): uploads them and refits the tree (topology kept).
  void updateVertices(const std::vector<kdet_fcl::Vec3<S>>& vertices);
  /// New vertex positions: uploads them and rebuilds the tree from scratch (Morton sort).
  void rebuildVertices(const std::vector<kdet_fcl::Vec3<S>>& vertices);

  std::size_t numTriangles() const;
  std::size_t deviceBytes() const;

  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// Every pair (i of a, j of b) of intersecting closed triangles, decided on a's vertices mapped
/// into b's frame (as kdet_fcl::intersectMeshes). Sorted by (a, b). With `keep` (a result the
/// caller keeps across frames), the pairs are read back into its storage, which the returned
/// vector then holds, as the backend reads them into a result kept across frames
/// (kdet_fcl::staging::downloadInto: several threads where that pays).
template <class S>
std::vector<kdet_fcl::TrianglePair> intersect(GpuBvh<S>& a, const kdet_fcl::Transform<S>& pose_a,
                                              GpuBvh<S>& b, const kdet_fcl::Transform<S>& pose_b,
                                              kdet_fcl::Predicate predicate =
                                                  kdet_fcl::Predicate::Exact,
                                              std::vector<kdet_fcl::TrianglePair>* keep = nullptr);

/// Every pair (i < j) of intersecting triangles of one mesh, except pairs sharing a vertex (index
/// or coordinates), as kdet_fcl::intersectSelf. Sorted by (a, b). With split > 0 the tree holds
/// two meshes (triangles [0, split) are the first's; the benchmark's joint form of two deforming
/// meshes, as kdet_fcl::intersectAll on the GPU): a pair across them is never adjacent and is
/// decided as intersect() decides it, so the result is both self queries' and the inter query's
/// pairs in one list (split it with splitJoint). `keep` as intersect()'s.
template <class S>
std::vector<kdet_fcl::TrianglePair> intersectSelf(GpuBvh<S>& mesh,
                                                  kdet_fcl::Predicate predicate =
                                                      kdet_fcl::Predicate::Exact,
                                                  std::uint32_t split = 0,
                                                  std::vector<kdet_fcl::TrianglePair>* keep =
                                                      nullptr);

/// The two meshes as one (the second's vertices after the first's, its vertex indices shifted),
/// for intersectSelf with split = a.triangles.size().
template <class S>
kdet_fcl::TriangleMesh<S> jointMesh(const kdet_fcl::TriangleMesh<S>& a,
                                    const kdet_fcl::TriangleMesh<S>& b) {
  kdet_fcl::TriangleMesh<S> m = a;
  kdet_bench::appendMesh(m, b);
  return m;
}

/// A joint result (intersectSelf with split > 0) dealt out: [0] the first mesh's self pairs,
/// [1] the second's, [2] the pairs across (first's triangle, second's), each in its own mesh's
/// indices and, from a sorted joint list, in (a, b) order.
inline std::array<std::vector<kdet_fcl::TrianglePair>, 3> splitJoint(
    const std::vector<kdet_fcl::TrianglePair>& pairs, std::uint32_t split) {
  std::array<std::vector<kdet_fcl::TrianglePair>, 3> r;
  for (const kdet_fcl::TrianglePair& p : pairs) {
    if (p.b < split) r[0].push_back(p);
    else if (p.a >= split) r[1].push_back({p.a - split, p.b - split});
    else r[2].push_back({p.a, p.b - split});
  }
  return r;
}

}  // namespace kdet_bvh
