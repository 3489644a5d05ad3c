#pragma once
/// \file
/// kdet_fcl::Mesh<S>: an fcl::BVHModel<fcl::OBBRSS<S>> that also keeps its kDet hash current.
///
/// It is a real BVHModel<OBBRSS> (the BV type MoveIt and python-fcl use), so it goes into
/// fcl::CollisionObject<S>, FCL's managers and FCL's own fcl::collide, which give FCL's result,
/// while kdet_fcl::collide/selfCollide use its kDet hash with no cache look-up and no checksum.
/// Build and deform it with FCL's interface; the end*Model methods below hide FCL's (which are
/// not virtual) to rebuild the kDet hash and bump version():
/// \code
///   auto mesh = std::make_shared<kdet_fcl::Meshd>();
///   mesh->beginModel();
///   mesh->addSubModel(points, triangles);
///   mesh->endModel();                         // FCL's BVH + kDet's hash
///   fcl::CollisionObjectd obj(mesh, pose);
///   kdet_fcl::collide(&obj, &other, request, result);
///   mesh->beginUpdateModel();                 // next frame of a deforming mesh
///   mesh->updateSubModel(next_points);
///   mesh->endUpdateModel();                   // FCL refit (MeshMode::Fcl); kDet re-hashes lazily
/// \endcode
/// Call these methods on the Mesh itself: through a `BVHModel<OBBRSS<S>>*` FCL's versions run and
/// kDet learns nothing; call notifyDeformed() afterwards in that case (also after writing into
/// `vertices` directly).
///
/// MeshMode::KdetOnly (for deforming meshes queried only through kdet_fcl): endUpdateModel() and
/// endReplaceModel() skip FCL's BVH refit/rebuild (the O(n) cost a deforming mesh should not pay
/// twice) and only re-hash for kDet. FCL's hierarchy is then stale: calling FCL's own
/// fcl::collide/fcl::distance or an FCL manager's narrowphase on such a mesh is UNSUPPORTED
/// (wrong results) unless refitFcl() was called after the last change. kdet_fcl::collide,
/// kdet_fcl::distance and the DefaultCollisionFunction/DefaultDistanceFunction drop-ins call
/// refitFcl() themselves before forwarding a pair to FCL (mesh vs shape, distance).
/// computeLocalAABB() is kept current in both modes, so broadphase AABBs are right.
///
/// Not thread-safe for mutation (like BVHModel); concurrent queries are fine.

#include <cstdint>
#include <memory>
#include <vector>

#include <fcl/math/bv/OBBRSS.h>
#include <fcl/math/bv/utility.h>  // before BVH_model.h: its inline part needs fit()
#include <fcl/geometry/bvh/BVH_model.h>

namespace kdet_fcl {

namespace detail {
template <class S>
struct FclMeshEntry;
template <class S>
struct MeshAccess;
}  // namespace detail

/// Whether a kdet_fcl::Mesh keeps FCL's BVH current on every deformation.
enum class MeshMode {
  Fcl,       ///< FCL's BVH and kDet's hash are both kept current (the default)
  KdetOnly,  ///< only kDet's hash; FCL's BVH is refitted on demand (refitFcl())
};

/// A BVHModel<OBBRSS<S>> with a kDet hash beside it (see the file comment).
template <class S>
class Mesh : public fcl::BVHModel<fcl::OBBRSS<S>> {
 public:
  using Base = fcl::BVHModel<fcl::OBBRSS<S>>;

  Mesh();
  explicit Mesh(MeshMode mode);
  /// Deep copy (FCL's copy constructor); the kDet hash is rebuilt lazily on first use.
  Mesh(const Mesh& other);
  Mesh& operator=(const Mesh&) = delete;  // BVHModel has no safe assignment
  ~Mesh();

  /// A Mesh with the same vertices and triangles as any FCL model (built or at least filled).
  template <class BV>
  static std::shared_ptr<Mesh> fromModel(const fcl::BVHModel<BV>& model,
                                         MeshMode mode = MeshMode::Fcl) {
    auto m = std::make_shared<Mesh>(mode);
    std::vector<fcl::Vector3<S>> ps(model.vertices, model.vertices + model.num_vertices);
    std::vector<fcl::Triangle> ts(model.tri_indices, model.tri_indices + model.num_tris);
    m->beginModel(model.num_tris, model.num_vertices);
    m->addSubModel(ps, ts);
    m->endModel();
    return m;
  }

  // ---- FCL's building interface (return FCL's BVHReturnCode). ----
  int beginModel(int num_tris = 0, int num_vertices = 0);
  using Base::addSubModel;
  using Base::addTriangle;
  using Base::addVertex;
  /// FCL's endModel (builds the BVH), then computeLocalAABB() and the kDet hash. A mesh with
  /// NaN/Inf coordinates still builds for FCL; kdet_fcl queries on it throw InvalidInputError.
  /// Vertices without triangles (a point cloud, which FCL 0.7 crashes building and querying)
  /// return BVH_ERR_UNSUPPORTED_FUNCTION and stay unbuilt (queries then throw).
  int endModel();

  // ---- FCL's replace family. ----
  int beginReplaceModel();
  int replaceVertex(const fcl::Vector3<S>& p);
  int replaceTriangle(const fcl::Vector3<S>& p1, const fcl::Vector3<S>& p2,
                      const fcl::Vector3<S>& p3);
  int replaceSubModel(const std::vector<fcl::Vector3<S>>& ps);
  /// FCL's endReplaceModel (MeshMode::Fcl) or only its checks (KdetOnly), then
  /// computeLocalAABB(); kDet's hash is marked stale and rebuilt by the next query that needs it
  /// (the CPU re-hash, or the device re-hash on the CUDA backend).
  int endReplaceModel(bool refit = true, bool bottomup = true);

  // ---- FCL's update family (keeps the previous frame in prev_vertices). ----
  int beginUpdateModel();
  int updateVertex(const fcl::Vector3<S>& p);
  int updateTriangle(const fcl::Vector3<S>& p1, const fcl::Vector3<S>& p2,
                     const fcl::Vector3<S>& p3);
  int updateSubModel(const std::vector<fcl::Vector3<S>>& ps);
  /// FCL's endUpdateModel (MeshMode::Fcl) or only its checks (KdetOnly), then
  /// computeLocalAABB(); kDet's hash is marked stale and rebuilt by the next query that needs it.
  int endUpdateModel(bool refit = true, bool bottomup = true);

  /// FCL's computeLocalAABB (aabb_local, aabb_center, aabb_radius), with a large model's two
  /// passes over its vertices split over the vertex passes' threads (collideOptions().threads;
  /// arrays of 1.5 MB and more, 512 KB a thread): the same values as FCL's, since the box and
  /// the radius are minima and maxima. A model with a non-finite coordinate takes FCL's own
  /// passes, as does a small one.
  void computeLocalAABB() override;

  MeshMode mode() const { return mode_; }
  /// Switching to MeshMode::Fcl refits FCL's BVH if it is stale.
  void setMode(MeshMode mode);

  /// Brings FCL's BVH up to date with the vertices (a refit, through FCL's replace path, which
  /// drops prev_vertices) if a KdetOnly deformation left it stale. Returns whether it refitted.
  bool refitFcl();
  /// False while a KdetOnly deformation has left FCL's BVH stale.
  bool fclCurrent() const { return !fcl_stale_; }

  /// Incremented by every (re)build or deformation; kdet_fcl's queries re-hash when it changes.
  std::uint64_t version() const { return version_; }
  /// Incremented when the triangles may have changed: by beginModel/endModel and
  /// notifyDeformed(), not by the update and replace families (which move vertices only). While
  /// it stays, kdet_fcl takes a deformation's new positions into the kDet hash without copying or
  /// checking the triangles again (HashedMesh::commitVertices), and the CUDA backend keeps them.
  std::uint64_t topologyVersion() const { return topology_version_; }
  /// Marks the geometry changed (after direct writes into `vertices` or `tri_indices`, or FCL
  /// calls made through a base-class pointer); the triangles count as changed too.
  void notifyDeformed() {
    ++version_;
    ++topology_version_;
  }

 private:
  friend struct detail::MeshAccess<S>;
  int endChange(int code);

  MeshMode mode_ = MeshMode::Fcl;
  std::uint64_t version_ = 1;
  std::uint64_t topology_version_ = 1;
  int num_changed_ = 0;     // vertices given since begin{Replace,Update}Model
  bool fcl_stale_ = false;  // KdetOnly: FCL's BVH not refitted since the last change
  std::shared_ptr<detail::FclMeshEntry<S>> entry_;
};

using Meshf = Mesh<float>;
using Meshd = Mesh<double>;

extern template class Mesh<float>;
extern template class Mesh<double>;

}  // namespace kdet_fcl
