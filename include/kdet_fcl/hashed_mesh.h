#pragma once
/// \file
/// A triangle mesh together with its kDet hierarchical spatial hash and a rigid pose.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/host_pin.h"
#include "kdet_fcl/triangle_mesh.h"
#include "kdet_fcl/vec3.h"

namespace kdet_fcl {

/// Shape of a built hierarchy (for reports and the k-free analysis).
struct HierarchyStats {
  std::size_t triangles = 0;
  int levels = 0;                ///< number of levels that hold triangles, finest to coarsest span
  int height = 0;                ///< coarsest occupied level index + 1
  double d_min = 0, d_max = 0;   ///< smallest and largest enclosing-sphere diameter
  double cell_size0 = 0;         ///< cell edge length of level 0
  std::size_t cells = 0;         ///< occupied cells over all levels
  std::size_t entries = 0;       ///< (cell, triangle) entries
  std::size_t max_cell_load = 0; ///< most triangles in one cell
  /// Triangles of positive size smaller than a level-0 cell. 0 unless the mesh's size ratio
  /// exceeds what the cell keys hold: the finest cell is then the extent / 2^38, not d_min, so
  /// these share level 0, and those close together are tested pairwise (a query can take
  /// quadratic time in their number; docs/numerics.md section 1).
  std::size_t below_cell0 = 0;
  std::size_t memory_bytes = 0;  ///< bytes held by the CPU hash and its rebuild buffers (not the mesh)
};

namespace detail {
template <class S>
class HierarchicalHash;
class KeptSelfResult;
}

/// A mesh hashed in its own frame plus a rigid pose.
///  - Rigid motion: setPose() costs nothing else; the hash is never rebuilt for a new pose.
///  - Deformation (same topology): updateVertices() validates and stores the new positions (a
///    copy), or a simulation writes them into vertexWriteBuffer() and commitVertices() validates
///    them in place (no copy); the CPU hash is rebuilt in O(n) by the first CPU query that needs
///    it (lazily, so a mesh queried only on the GPU never pays for a CPU re-hash).
///  - Topology change (fracture, insertion, deletion): setMesh(), likewise.
/// Not thread-safe for mutation (setPose, updateVertices, vertexWriteBuffer, commitVertices,
/// setMesh, assignment) while any other call is in flight. Concurrent const calls (queries,
/// hash(), stats()) from several threads are safe, also right after a mutation: the first one
/// rebuilds the CPU hash under a lock, the others wait for it; once the hash is current, a query
/// only checks an atomic flag.
template <class S>
class HashedMesh {
 public:
  /// Validates the mesh (throws InvalidInputError). The CPU hash is built on first use (see
  /// hash()). An empty mesh is allowed (it intersects nothing).
  explicit HashedMesh(TriangleMesh<S> mesh, const Transform<S>& pose = Transform<S>::identity(),
                      int threads = 0);
  ~HashedMesh();
  HashedMesh(HashedMesh&&) noexcept;
  HashedMesh& operator=(HashedMesh&&) noexcept;
  HashedMesh(const HashedMesh&) = delete;
  HashedMesh& operator=(const HashedMesh&) = delete;

  /// New rigid pose. Throws InvalidInputError for non-finite entries or a rotation that is not
  /// orthonormal with determinant +1 within orthonormalTolerance(). No re-hash.
  void setPose(const Transform<S>& pose);
  const Transform<S>& pose() const { return pose_; }

  /// New vertex positions, same count and topology. Throws InvalidInputError (and leaves the
  /// mesh unchanged) on a wrong count or a non-finite coordinate. The positions are copied into
  /// the mesh's own vertex array, which keeps its address (mesh().vertices.data()). Marks the CPU
  /// hash stale: it is rebuilt by the next CPU query (or prepareCpuHash()), not here. Once the
  /// CUDA backend has registered that array for its DMA, a copy in several threads goes by
  /// non-temporal stores (src/cpu/dma_passes.h; KDET_FCL_DMA_PASSES=0|1 never, always; another
  /// value of it throws InvalidInputError, the mesh unchanged). Where the CUDA backend holds this
  /// mesh and that array is registered (1.5 MiB and up), the copy goes in pieces and each run of
  /// pieces written goes to the device meanwhile, as commitVertices' check does (see there).
  void updateVertices(const std::vector<Vec3<S>>& vertices);

  /// For a simulation that writes each frame's positions straight into the mesh, with no copy:
  /// the mesh's second vertex buffer, numVertices() positions whose contents are unspecified (in
  /// practice the positions of two commits ago). Write every new position there, then call
  /// commitVertices(). The buffer is allocated on the first call (kept until setMesh); the
  /// pointer is valid until the next commitVertices(), setMesh() or the mesh's end. After a
  /// commit it points at the mesh's current positions: call vertexWriteBuffer() again for the
  /// next frame, never write through the old pointer.
  Vec3<S>* vertexWriteBuffer();

  /// Makes the positions written into vertexWriteBuffer() the mesh's, as updateVertices() does,
  /// but without copying them: they are checked in place (one pass), then the two buffers trade
  /// places (so mesh().vertices.data() alternates between two addresses, and a registration of
  /// each with a device runtime, detail::HostPin, moves with its buffer). Throws
  /// InvalidInputError, naming the first non-finite coordinate, and leaves the mesh unchanged
  /// (its positions, version and hash) when a written coordinate is not finite, or when
  /// vertexWriteBuffer() was never called since construction or setMesh(). A buffer of 4 MB or
  /// more that the CUDA backend has registered for its DMA, checked in several threads, is
  /// demoted from their private caches line by line as it is read (src/cpu/dma_passes.h; the
  /// same knob as updateVertices). Where the CUDA backend holds this mesh and has registered the
  /// buffer (1.5 MiB and up, cuda_backend.h: startCommitCopy), the check goes in pieces and the
  /// pieces found finite are copied to the device meanwhile; the commit returns once the copies
  /// are done, and the next GPU query skips the upload. A refused commit leaves the device to
  /// upload the positions the mesh kept. The commit never waits for another thread's GPU query
  /// (it then leaves the upload to the query); KDET_FCL_CUDA_COMMIT_COPY=0 turns the copy off.
  void commitVertices();

  std::size_t numVertices() const { return mesh_.vertices.size(); }

  /// Replaces the whole mesh (topology change). Validates first; on error the old mesh is kept.
  /// Marks the CPU hash stale, like updateVertices().
  void setMesh(TriangleMesh<S> mesh);

  const TriangleMesh<S>& mesh() const { return mesh_; }
  std::size_t numTriangles() const { return mesh_.triangles.size(); }

  /// Identifies the current geometry: a new value after every change of geometry (not after
  /// setPose), unique within the process (no two meshes ever share one), and increasing.
  std::uint64_t version() const { return version_; }

  /// Identifies the current triangles: a new value when they may have changed (construction,
  /// setMesh), the same after updateVertices and setPose; unique within the process, like
  /// version(). A cache of the topology keyed by it (the CUDA backend's) needs no comparison of
  /// the triangles after a deformation.
  std::uint64_t topologyVersion() const { return topology_version_; }

  /// Identifies this HashedMesh object: drawn at construction, unique in the process (no two
  /// constructed meshes ever share one), kept by setPose, updateVertices, commitVertices and
  /// setMesh, and moved with the mesh (a move leaves the source's value as it was). A cache of
  /// what one mesh's queries learned (the CUDA backend's forecasts) keyed by the mesh's address
  /// checks it, so that a new mesh at a freed mesh's address starts afresh.
  std::uint64_t identity() const { return identity_; }

  /// The CPU hierarchy's shape and memory. Builds the CPU hash if it is stale (like a query).
  HierarchyStats stats() const;

  /// The tolerance on |R^T R - I| and |det R - 1| that setPose() accepts.
  static double orthonormalTolerance();

  /// Builds the CPU hash now if the geometry changed since it was last built (otherwise the first
  /// CPU query does it): for callers that want the O(n) re-hash outside their queries, e.g. to
  /// time it. Throws what hash() throws.
  void prepareCpuHash() const { (void)hash(); }
  /// Whether the CPU hash is current on every level (false from a geometry change until the
  /// next CPU query that needs every level, stats() or prepareCpuHash(): a self query does, an
  /// inter-object query builds only the levels its lookups visit).
  bool cpuHashFresh() const;

  /// The box of the mesh's vertices in its own frame (lo > hi when it has none), kept current by
  /// every geometry change without building the hash. It contains every triangle.
  const detail::Aabb<double>& localBounds() const { return bounds_; }

  /// Internal: the CPU hierarchy (used by the CPU backend and the analysis) with the cell tables
  /// of every level. Built here on first use after a geometry change (thread-safe, see the class
  /// comment). If that build fails (std::bad_alloc, or InvalidInputError for a mesh too large for
  /// 32-bit entry indices) the exception propagates to the caller (the query), and the mesh, its
  /// pose and version are untouched and still valid: the hash stays stale (or keeps the levels
  /// it had) and the next call tries again.
  const detail::HierarchicalHash<S>& hash() const { return hashFrom(0); }
  /// Internal: the same, with the cell tables of levels >= from_level at least (the per-triangle
  /// data always; no table at all for HierarchicalHash::kNoTable). For queries whose lookups
  /// start no lower than from_level (see cpu::intersectMeshes).
  const detail::HierarchicalHash<S>& hashFrom(int from_level) const;

  /// Internal: the CPU backend's kept self-query result of this mesh (see QueryResult::kept).
  detail::KeptSelfResult& keptSelf() const { return *kept_self_; }

  /// Internal: the registration of the vertex buffer (mesh().vertices) for direct device copies,
  /// made by the CUDA backend and dropped here before that buffer can change (see HostPin).
  detail::HostPin& hostPin() const { return host_pin_; }

 private:
  /// After new triangles (construction, setMesh): a new topology version.
  void topologyChanged();
  /// After a geometry change: a new version, fresh bounds, the CPU hash marked stale.
  void geometryChanged();
  /// The same with the new bounds known (updateVertices computes them while checking).
  void geometryChanged(const detail::Aabb<double>& bounds);

  struct Lazy;  // the lock and the "CPU hash is current" flag (on the heap: movable class)

  // Declared before mesh_ and write_buffer_: a move assignment drops this mesh's registrations
  // before it frees the vertex buffers they are for (members are assigned in declaration order);
  // the destructor and setMesh drop them first too.
  mutable detail::HostPin host_pin_;
  mutable detail::HostPin write_pin_;  // the registration of write_buffer_ (commitVertices)
  TriangleMesh<S> mesh_;
  // The second vertex buffer (vertexWriteBuffer; empty until asked for). Each buffer's pin
  // record (host_pin_ for mesh_.vertices, write_pin_ for this one) trades places with it.
  std::vector<Vec3<S>> write_buffer_;
  Transform<S> pose_;
  detail::Aabb<double> bounds_{};
  // Rebuilt in place: the buffers of the last build are reused (a deforming mesh rebuilds
  // without allocating).
  std::unique_ptr<detail::HierarchicalHash<S>> hash_;
  std::unique_ptr<Lazy> lazy_;
  std::unique_ptr<detail::KeptSelfResult> kept_self_;
  std::uint64_t version_ = 0;
  std::uint64_t topology_version_ = 0;
  std::uint64_t identity_ = 0;
  int threads_ = 0;
};

/// Throws InvalidInputError (message prefixed by `what`) unless `pose` is finite and its rotation
/// is orthonormal with determinant +1 within HashedMesh<S>::orthonormalTolerance().
template <class S>
void validatePose(const Transform<S>& pose, const std::string& what);

extern template class HashedMesh<float>;
extern template class HashedMesh<double>;

}  // namespace kdet_fcl
