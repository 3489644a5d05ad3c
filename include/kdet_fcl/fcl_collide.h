#pragma once
/// \file
/// The FCL drop-in: kdet_fcl::collide, selfCollide, distance and the default broadphase
/// callbacks, with FCL 0.7's signatures and result conventions. Swap `fcl::collide` for
/// `kdet_fcl::collide` and mesh-mesh pairs run through kDet; everything else goes to FCL.
///
/// Which pairs take the kDet path: both geometries are triangle meshes (`getObjectType() ==
/// OT_BVH` and `getModelType() == BVH_MODEL_TRIANGLES`): an `fcl::BVHModel<BV>` of any BV type
/// FCL has (AABB, OBB, RSS, kIOS, OBBRSS, KDOP<16|18|24>) or a kdet_fcl::Mesh<S>, in any mix of
/// BV types (FCL itself refuses mixed pairs). Every other pair (shapes, octrees) is forwarded to
/// `fcl::collide` unchanged, except where FCL 0.7 crashes whatever the pose: a point-cloud
/// BVHModel (vertices without triangles; UnsupportedQueryError) and a Convex against a Plane
/// under GST_LIBCCD (libccd's test segfaults; it runs under GST_INDEP).
///
/// Result conventions on the kDet path (FCL's, fcl-notes §1.5):
///  - one fcl::Contact per intersecting triangle pair (closed triangles, decided exactly: touching
///    and coplanar overlap count, as in FCL); b1/b2 are indices into the models' tri_indices,
///    b1 on the first argument; o1/o2 are the caller's geometries (never copies).
///  - `result` is never cleared: contacts accumulate, `num_max_contacts` caps the total (the
///    search stops once the remaining budget is found), and the return value is
///    `result.numContacts()`, earlier contacts included.
///  - `num_max_contacts == 0`: prints FCL's warning and returns 0. A request that
///    `isSatisfied(result)` on entry returns at once. Contacts are added only when both
///    geometries `isOccupied()`.
///  - With a cap, which pairs are returned is kDet's deterministic order (FCL's is its BVH
///    traversal order): only exhaustive sets are comparable between the two.
///  - `enable_contact`: pos = a point of the intersection of the two triangles (world frame);
///    normal = the negated unit normal of triangle b2 (by its winding), rotated to world: it
///    points from o1 into o2 for outward-wound meshes (fallbacks for degenerate triangles: b1's
///    normal, then the centroid direction, then +z); penetration_depth = how far the deepest
///    vertex of triangle b1 lies behind b2's plane (>= 0; a local per-pair measure like FCL's).
///    All finite, for degenerate and coplanar pairs too. (FCL adds 0-2 contacts per pair at mesh
///    vertices; here it is always exactly one per pair.)
///  - `enable_cost`: as FCL: for every intersecting pair a CostSource (the overlap of the two
///    triangles' world-frame boxes, density = product of the cost_density values) is added with
///    `num_max_cost_sources`; the search is then exhaustive (FCL's isSatisfied() is false).
///    Pairs of geometries that are neither occupied nor free add cost sources only, as in FCL.
///
/// Bad input throws InvalidInputError (FCL would return garbage or crash): a null geometry or
/// collision object, NaN/Inf vertices, out-of-range indices or a largest coordinate magnitude
/// outside [2^-247, 2^330] (TriangleMesh::validateForQueries) in a mesh on the kDet path, a mesh
/// that is not built (between beginModel and endModel, or inside an update/replace block), a
/// non-finite pose (any pair), and a pose whose rotation is not orthonormal within
/// HashedMesh::orthonormalTolerance() (kDet path); the default callbacks throw it for null data.
///
/// The structure cache (plain BVHModels). kDet hashes each mesh once in its own frame; a new pose
/// costs nothing more. The hash of a plain fcl::BVHModel is kept in a process-wide cache keyed by
/// the geometry's address (user_data is never touched). Before each query the cache checks the
/// model against what it hashed:
///  - CacheValidation::Checksum (the default): the vertices/tri_indices pointers, num_vertices,
///    num_tris, and a 64-bit checksum of the vertex and triangle arrays. O(n) memory reads per
///    query (a few microseconds per 10k triangles, far below a re-hash), and never stale:
///    beginUpdateModel's pointer swap, replace/update calls, direct writes into `vertices`, and a
///    new model at a recycled address are all seen. Any change re-hashes that model (O(n)); when
///    only the vertices changed (the same triangle array, counts and triangle checksum), the new
///    positions go straight into the model's HashedMesh (commitVertices) and its triangles are
///    neither copied nor checked again.
///  - CacheValidation::Trust: only pointers and counts are compared (O(1)). After changing
///    vertices in place (replace/update calls, direct writes) call notifyDeformed(model).
/// kdet_fcl::Mesh<S> never needs either: it bumps a version in its own end*Model methods, and a
/// topology version in beginModel/endModel and notifyDeformed only, so its update and replace
/// families take the vertices-only path too.
/// Entries live until forget(model) or clearCache(); call forget() before deleting a model that
/// will not be queried again (a stale entry at a recycled address is detected, but keeps memory).
/// Thread safety: queries may run concurrently from any threads; the cache has a mutex, and each
/// model's entry a mutex held for the query, so queries that share a geometry serialise.

#include <cstddef>
#include <cstdint>

#include <fcl/broadphase/default_broadphase_callbacks.h>
#include <fcl/geometry/collision_geometry.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>
#include <fcl/narrowphase/distance_request.h>
#include <fcl/narrowphase/distance_result.h>

#include "kdet_fcl/detail/fcl_float_instances.h"
#include "kdet_fcl/query.h"

namespace kdet_fcl {

/// FCL's `collide` for two collision objects (see the file comment for the semantics).
/// Returns result.numContacts() (all contacts in `result`, earlier ones included).
template <typename S>
std::size_t collide(const fcl::CollisionObject<S>* o1, const fcl::CollisionObject<S>* o2,
                    const fcl::CollisionRequest<S>& request, fcl::CollisionResult<S>& result);

/// FCL's `collide` for two geometries at the given world poses.
template <typename S>
std::size_t collide(const fcl::CollisionGeometry<S>* o1, const fcl::Transform3<S>& tf1,
                    const fcl::CollisionGeometry<S>* o2, const fcl::Transform3<S>& tf2,
                    const fcl::CollisionRequest<S>& request, fcl::CollisionResult<S>& result);

/// Self-collision of one triangle mesh (FCL has none): a Contact for each pair of intersecting
/// triangles b1 < b2 of the mesh, except pairs that share a vertex (the same index, or equal
/// coordinates, so triangle soups work); o1 = o2 = the geometry. Same conventions as collide()
/// (accumulation, cap, return value, enable_contact in the object's world frame, enable_cost).
/// A geometry that is not a triangle mesh adds nothing (returns result.numContacts()).
template <typename S>
std::size_t selfCollide(const fcl::CollisionObject<S>* o, const fcl::CollisionRequest<S>& request,
                        fcl::CollisionResult<S>& result);

/// selfCollide() for a geometry at a world pose.
template <typename S>
std::size_t selfCollide(const fcl::CollisionGeometry<S>* o, const fcl::Transform3<S>& tf,
                        const fcl::CollisionRequest<S>& request, fcl::CollisionResult<S>& result);

/// FCL's `distance`: forwarded to fcl::distance (a kdet_fcl::Mesh in MeshMode::KdetOnly gets its
/// FCL hierarchy refitted first). Throws InvalidInputError for a null geometry, a non-finite pose
/// or an unbuilt model, and UnsupportedQueryError for a distance to a Halfspace or Plane (FCL 0.7
/// segfaults on it under GST_LIBCCD and answers it wrongly under GST_INDEP) or a point cloud.
template <typename S>
S distance(const fcl::CollisionObject<S>* o1, const fcl::CollisionObject<S>* o2,
           const fcl::DistanceRequest<S>& request, fcl::DistanceResult<S>& result);

/// FCL's `distance` for two geometries at the given world poses (forwarded, as above).
template <typename S>
S distance(const fcl::CollisionGeometry<S>* o1, const fcl::Transform3<S>& tf1,
           const fcl::CollisionGeometry<S>* o2, const fcl::Transform3<S>& tf2,
           const fcl::DistanceRequest<S>& request, fcl::DistanceResult<S>& result);

/// Drop-in for fcl::DefaultCollisionFunction: the same `done` logic, with kdet_fcl::collide
/// (so mesh pairs met by a broadphase manager go through kDet). `data` is an
/// fcl::DefaultCollisionData<S>*.
template <typename S>
bool DefaultCollisionFunction(fcl::CollisionObject<S>* o1, fcl::CollisionObject<S>* o2,
                              void* data);

/// Drop-in for fcl::DefaultDistanceFunction (`data` is an fcl::DefaultDistanceData<S>*), calling
/// kdet_fcl::distance.
template <typename S>
bool DefaultDistanceFunction(fcl::CollisionObject<S>* o1, fcl::CollisionObject<S>* o2,
                             void* data, S& dist);

/// Whether collide() takes the kDet path for this geometry (a triangle mesh, built or not).
template <typename S>
bool isKdetMesh(const fcl::CollisionGeometry<S>* geometry);

// ---- The structure cache of plain BVHModels (see the file comment). ----

/// How the cache decides that a plain BVHModel is unchanged.
enum class CacheValidation {
  Checksum,  ///< pointers, counts and a checksum of the arrays: O(n) per query, never stale
  Trust,     ///< pointers and counts only: O(1); call notifyDeformed() after in-place changes
};

/// Sets the process-wide validation policy (default Checksum). Thread-safe.
void setCacheValidation(CacheValidation policy);
CacheValidation cacheValidation();

/// The geometry changed in place: the next query re-hashes it. For a kdet_fcl::Mesh it bumps the
/// mesh's version (needed only after direct writes into `vertices` or after calling FCL's
/// methods through a base-class pointer). Thread-safe; a geometry never seen is ignored.
template <typename S>
void notifyDeformed(const fcl::CollisionGeometry<S>* geometry);

/// Drops the cache entry of a plain BVHModel (no-op otherwise). Thread-safe; an in-flight query
/// keeps its entry alive until it returns.
template <typename S>
void forget(const fcl::CollisionGeometry<S>* geometry);

/// Drops every cache entry (both precisions).
void clearCache();

/// Number of cached plain BVHModels (both precisions).
std::size_t cacheSize();

/// Threads and backend that collide()/selfCollide() use for their kDet queries (the max_pairs
/// field is ignored: it comes from the request). Default: QueryOptions{} (all hardware threads
/// for large meshes, CPU backend). Thread-safe.
void setCollideOptions(const QueryOptions& options);
QueryOptions collideOptions();

extern template std::size_t collide(const fcl::CollisionObject<float>*,
                                    const fcl::CollisionObject<float>*,
                                    const fcl::CollisionRequest<float>&,
                                    fcl::CollisionResult<float>&);
extern template std::size_t collide(const fcl::CollisionObject<double>*,
                                    const fcl::CollisionObject<double>*,
                                    const fcl::CollisionRequest<double>&,
                                    fcl::CollisionResult<double>&);
extern template std::size_t collide(const fcl::CollisionGeometry<float>*,
                                    const fcl::Transform3<float>&,
                                    const fcl::CollisionGeometry<float>*,
                                    const fcl::Transform3<float>&,
                                    const fcl::CollisionRequest<float>&,
                                    fcl::CollisionResult<float>&);
extern template std::size_t collide(const fcl::CollisionGeometry<double>*,
                                    const fcl::Transform3<double>&,
                                    const fcl::CollisionGeometry<double>*,
                                    const fcl::Transform3<double>&,
                                    const fcl::CollisionRequest<double>&,
                                    fcl::CollisionResult<double>&);
extern template std::size_t selfCollide(const fcl::CollisionObject<float>*,
                                        const fcl::CollisionRequest<float>&,
                                        fcl::CollisionResult<float>&);
extern template std::size_t selfCollide(const fcl::CollisionObject<double>*,
                                        const fcl::CollisionRequest<double>&,
                                        fcl::CollisionResult<double>&);
extern template std::size_t selfCollide(const fcl::CollisionGeometry<float>*,
                                        const fcl::Transform3<float>&,
                                        const fcl::CollisionRequest<float>&,
                                        fcl::CollisionResult<float>&);
extern template std::size_t selfCollide(const fcl::CollisionGeometry<double>*,
                                        const fcl::Transform3<double>&,
                                        const fcl::CollisionRequest<double>&,
                                        fcl::CollisionResult<double>&);
extern template float distance(const fcl::CollisionObject<float>*,
                               const fcl::CollisionObject<float>*,
                               const fcl::DistanceRequest<float>&, fcl::DistanceResult<float>&);
extern template double distance(const fcl::CollisionObject<double>*,
                                const fcl::CollisionObject<double>*,
                                const fcl::DistanceRequest<double>&,
                                fcl::DistanceResult<double>&);
extern template float distance(const fcl::CollisionGeometry<float>*,
                               const fcl::Transform3<float>&,
                               const fcl::CollisionGeometry<float>*,
                               const fcl::Transform3<float>&, const fcl::DistanceRequest<float>&,
                               fcl::DistanceResult<float>&);
extern template double distance(const fcl::CollisionGeometry<double>*,
                                const fcl::Transform3<double>&,
                                const fcl::CollisionGeometry<double>*,
                                const fcl::Transform3<double>&,
                                const fcl::DistanceRequest<double>&,
                                fcl::DistanceResult<double>&);
extern template bool DefaultCollisionFunction(fcl::CollisionObject<float>*,
                                              fcl::CollisionObject<float>*, void*);
extern template bool DefaultCollisionFunction(fcl::CollisionObject<double>*,
                                              fcl::CollisionObject<double>*, void*);
extern template bool DefaultDistanceFunction(fcl::CollisionObject<float>*,
                                             fcl::CollisionObject<float>*, void*, float&);
extern template bool DefaultDistanceFunction(fcl::CollisionObject<double>*,
                                             fcl::CollisionObject<double>*, void*, double&);
extern template bool isKdetMesh(const fcl::CollisionGeometry<float>*);
extern template bool isKdetMesh(const fcl::CollisionGeometry<double>*);
extern template void notifyDeformed(const fcl::CollisionGeometry<float>*);
extern template void notifyDeformed(const fcl::CollisionGeometry<double>*);
extern template void forget(const fcl::CollisionGeometry<float>*);
extern template void forget(const fcl::CollisionGeometry<double>*);

}  // namespace kdet_fcl
