#pragma once
/// \file
/// A triangle mesh together with its kDet hierarchical spatial hash and a rigid pose.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

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
  std::size_t memory_bytes = 0;  ///< bytes held by the hash and its rebuild buffers (not the mesh)
};

namespace detail {
template <class S>
class HierarchicalHash;
}

/// A mesh hashed in its own frame plus a rigid pose.
///  - Rigid motion: setPose() costs nothing else; the hash is never rebuilt for a new pose.
///  - Deformation (same topology): updateVertices() re-hashes in O(n).
///  - Topology change (fracture, insertion, deletion): setMesh() rebuilds in O(n).
/// Not thread-safe for mutation; concurrent const queries are fine.
template <class S>
class HashedMesh {
 public:
  /// Validates the mesh (throws InvalidInputError) and builds the hash. An empty mesh is allowed
  /// (it intersects nothing).
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

  /// New vertex positions, same count and topology; re-hashes. Throws InvalidInputError (and
  /// leaves the mesh unchanged) on a wrong count or a non-finite coordinate.
  void updateVertices(const std::vector<Vec3<S>>& vertices);

  /// Replaces the whole mesh (topology change); rebuilds. Validates first; on error the old mesh
  /// is kept.
  void setMesh(TriangleMesh<S> mesh);

  const TriangleMesh<S>& mesh() const { return mesh_; }
  std::size_t numTriangles() const { return mesh_.triangles.size(); }

  /// Identifies the current geometry: a new value after every change of geometry (not after
  /// setPose), unique within the process (no two meshes ever share one), and increasing.
  std::uint64_t version() const { return version_; }

  HierarchyStats stats() const;

  /// The tolerance on |R^T R - I| and |det R - 1| that setPose() accepts.
  static double orthonormalTolerance();

  /// Internal: the hierarchy (used by the backends and the analysis).
  const detail::HierarchicalHash<S>& hash() const { return *hash_; }

 private:
  /// Builds the hash of (vertices, triangles) into the spare structure and swaps it in: if the
  /// build throws (out of memory), the current mesh and hash are untouched.
  void rehash(const std::vector<Vec3<S>>& vertices, const std::vector<Triangle>& triangles);

  TriangleMesh<S> mesh_;
  Transform<S> pose_;
  std::unique_ptr<detail::HierarchicalHash<S>> hash_;
  std::unique_ptr<detail::HierarchicalHash<S>> spare_;  // reused buffers for the next rebuild
  std::uint64_t version_ = 0;
  int threads_ = 0;
};

/// Throws InvalidInputError (message prefixed by `what`) unless `pose` is finite and its rotation
/// is orthonormal with determinant +1 within HashedMesh<S>::orthonormalTolerance().
template <class S>
void validatePose(const Transform<S>& pose, const std::string& what);

extern template class HashedMesh<float>;
extern template class HashedMesh<double>;

}  // namespace kdet_fcl
