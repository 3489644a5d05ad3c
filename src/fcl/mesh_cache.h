#pragma once
// Internal to the FCL adapter: the kDet structure kept for one FCL triangle mesh (a cache entry
// of a plain BVHModel, or the entry a kdet_fcl::Mesh owns), and what the adapter reads of a model.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>

#include <fcl/geometry/bvh/BVH_internal.h>
#include <fcl/geometry/collision_geometry.h>

#include "kdet_fcl/fcl_mesh.h"
#include "kdet_fcl/hashed_mesh.h"

namespace kdet_fcl {
namespace detail {

/// What the adapter reads of any BVHModel<BV> (its public members), whatever BV is.
template <class S>
struct FclMeshView {
  const fcl::Vector3<S>* vertices = nullptr;
  const fcl::Triangle* triangles = nullptr;
  int num_vertices = 0;
  int num_tris = 0;
  fcl::BVHBuildState build_state = fcl::BVH_BUILD_STATE_EMPTY;
  bool triangles_model = false;     ///< getModelType() == BVH_MODEL_TRIANGLES
  const Mesh<S>* kdet_mesh = nullptr;  ///< set when the geometry is a kdet_fcl::Mesh<S>
};

/// Fills `view` when `g` is a BVHModel of any BV type; false for shapes, octrees and others.
template <class S>
bool viewOf(const fcl::CollisionGeometry<S>* g, FclMeshView<S>& view);

/// The kDet structure of one mesh and the fingerprint of the data it was built from.
template <class S>
struct FclMeshEntry {
  std::mutex mutex;                     ///< held by a query for its whole duration
  std::unique_ptr<HashedMesh<S>> hashed;
  std::unique_ptr<HashedMesh<S>> twin;  ///< the same mesh at a second pose (mesh vs itself)
  std::uint64_t twin_of = 0;            ///< hashed->version() the twin was built from
  // Fingerprint of the source data (valid when `hashed` is set).
  const void* vertices = nullptr;
  const void* triangles = nullptr;
  int num_vertices = -1, num_tris = -1;
  std::uint64_t vertex_checksum = 0;    ///< plain models, CacheValidation::Checksum
  std::uint64_t triangle_checksum = 0;  ///< plain models, CacheValidation::Checksum
  std::uint64_t mesh_version = 0;   ///< kdet_fcl::Mesh
  std::uint64_t mesh_topology = 0;  ///< kdet_fcl::Mesh::topologyVersion()
  std::atomic<bool> dirty{false};  ///< notifyDeformed() was called
};

/// Brings `e` up to date with `view` (caller holds e.mutex). Throws InvalidInputError for
/// unbuilt models and invalid data (NaN/Inf, bad indices); `e` then keeps its previous state.
template <class S>
void syncEntry(FclMeshEntry<S>& e, const FclMeshView<S>& view);

/// Access to kdet_fcl::Mesh's private entry and staleness flag.
template <class S>
struct MeshAccess {
  static const std::shared_ptr<FclMeshEntry<S>>& entry(const Mesh<S>& m) { return m.entry_; }
  static bool fclStale(const Mesh<S>& m) { return m.fcl_stale_; }
};

}  // namespace detail
}  // namespace kdet_fcl
