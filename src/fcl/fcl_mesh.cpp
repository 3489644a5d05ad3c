// kdet_fcl::Mesh<S>: FCL's BVHModel<OBBRSS> plus an eagerly kept kDet hash (fcl_mesh.h).

#include "kdet_fcl/fcl_mesh.h"

#include <atomic>
#include <cmath>
#include <iostream>
#include <mutex>
#include <vector>

#include "kdet_fcl/fcl_mesh.h"  // BVH_model.h with the includes it needs

#include "cpu/parallel.h"
#include "fcl/mesh_cache.h"
#include "kdet_fcl/errors.h"
#include "kdet_fcl/fcl_collide.h"  // collideOptions()

namespace kdet_fcl {

template <class S>
Mesh<S>::Mesh() : entry_(std::make_shared<detail::FclMeshEntry<S>>()) {}

template <class S>
Mesh<S>::Mesh(MeshMode mode) : mode_(mode), entry_(std::make_shared<detail::FclMeshEntry<S>>()) {}

template <class S>
Mesh<S>::Mesh(const Mesh& other)
    : Base(other),
      mode_(other.mode_),
      version_(other.version_),
      topology_version_(other.topology_version_),
      num_changed_(other.num_changed_),
      fcl_stale_(other.fcl_stale_),
      entry_(std::make_shared<detail::FclMeshEntry<S>>()) {}

template <class S>
Mesh<S>::~Mesh() = default;

template <class S>
int Mesh<S>::endChange(int code) {
  ++version_;
  if (code != fcl::BVH_OK) return code;
  this->computeLocalAABB();
  // Re-hash now, so the cost lands here and not in the next query. Invalid data (NaN) is left
  // for the queries to report.
  detail::FclMeshView<S> v;
  detail::viewOf<S>(this, v);
  if (v.triangles_model) {
    std::lock_guard<std::mutex> lock(entry_->mutex);
    try {
      detail::syncEntry(*entry_, v);
    } catch (const InvalidInputError&) {
    }
  }
  return code;
}

template <class S>
void Mesh<S>::computeLocalAABB() {
  const auto n = static_cast<std::size_t>(this->num_vertices > 0 ? this->num_vertices : 0);
  const int t = cpu::vertexPassThreads(n * sizeof(fcl::Vector3<S>), collideOptions().threads);
  if (t <= 1 || this->vertices == nullptr) {
    Base::computeLocalAABB();
    return;
  }
  // FCL's two passes, each share in its own thread: the share's box (merged after: minima and
  // maxima, the same box whatever the split), then its largest squared distance from the box's
  // centre (a maximum: the same). Where a coordinate is not finite, FCL's own serial passes,
  // whose outcome may then depend on the order.
  const fcl::Vector3<S>* p = this->vertices;
  const std::size_t per = cpu::shareOf(n, t);
  std::vector<fcl::AABB<S>> box(static_cast<std::size_t>(t));
  std::vector<S> far(static_cast<std::size_t>(t), S(0));
  std::atomic<bool> finite{true};
  cpu::parallelFor(n, per, t, [&](std::size_t lo, std::size_t hi) {
    fcl::AABB<S> b;
    bool ok = true;
    for (std::size_t i = lo; i < hi; ++i) {
      ok = ok && p[i].allFinite();
      b += p[i];
    }
    box[lo / per] = b;
    if (!ok) finite.store(false, std::memory_order_relaxed);
  });
  if (!finite.load()) {
    Base::computeLocalAABB();
    return;
  }
  fcl::AABB<S> all;
  for (const fcl::AABB<S>& b : box) all += b;
  const fcl::Vector3<S> center = all.center();
  cpu::parallelFor(n, per, t, [&](std::size_t lo, std::size_t hi) {
    S r2 = 0;
    for (std::size_t i = lo; i < hi; ++i) {
      const S r = (center - p[i]).squaredNorm();
      if (r > r2) r2 = r;
    }
    far[lo / per] = r2;
  });
  S r2 = 0;
  for (const S r : far)
    if (r > r2) r2 = r;
  this->aabb_center = center;
  this->aabb_radius = std::sqrt(r2);
  this->aabb_local = all;
}

template <class S>
int Mesh<S>::beginModel(int num_tris, int num_vertices) {
  ++version_;
  ++topology_version_;
  fcl_stale_ = false;
  return Base::beginModel(num_tris, num_vertices);
}

template <class S>
int Mesh<S>::endModel() {
  // A point cloud (vertices, no triangles): FCL 0.7's endModel shrinks the triangle array to
  // `new Triangle[0]`, a pointer that is not null, and its BV fitter then reads triangles through
  // it (a segfault, or BVs from garbage); every FCL query of a point cloud crashes as well. It is
  // left unbuilt, so that queries report it (InvalidInputError) instead of crashing.
  if (this->build_state == fcl::BVH_BUILD_STATE_BEGUN && this->num_tris == 0 &&
      this->num_vertices > 0) {
    std::cerr << "BVH Error! kdet_fcl::Mesh::endModel: vertices without triangles (a point "
                 "cloud); FCL 0.7 crashes building and querying it, so it is not built.\n";
    return fcl::BVH_ERR_UNSUPPORTED_FUNCTION;
  }
  // FCL's BVH is always built here (KdetOnly skips only refits): a later refitFcl() needs it.
  const int code = Base::endModel();
  fcl_stale_ = false;
  ++topology_version_;
  return endChange(code);
}

template <class S>
int Mesh<S>::beginReplaceModel() {
  num_changed_ = 0;
  ++version_;
  return Base::beginReplaceModel();
}

template <class S>
int Mesh<S>::replaceVertex(const fcl::Vector3<S>& p) {
  const int code = Base::replaceVertex(p);
  if (code == fcl::BVH_OK) num_changed_ += 1;
  return code;
}

template <class S>
int Mesh<S>::replaceTriangle(const fcl::Vector3<S>& p1, const fcl::Vector3<S>& p2,
                             const fcl::Vector3<S>& p3) {
  const int code = Base::replaceTriangle(p1, p2, p3);
  if (code == fcl::BVH_OK) num_changed_ += 3;
  return code;
}

template <class S>
int Mesh<S>::replaceSubModel(const std::vector<fcl::Vector3<S>>& ps) {
  const int code = Base::replaceSubModel(ps);
  if (code == fcl::BVH_OK) num_changed_ += int(ps.size());
  return code;
}

template <class S>
int Mesh<S>::endReplaceModel(bool refit, bool bottomup) {
  if (mode_ == MeshMode::Fcl) return endChange(Base::endReplaceModel(refit, bottomup));
  // KdetOnly: FCL's checks and state change, without its refit.
  if (this->build_state != fcl::BVH_BUILD_STATE_REPLACE_BEGUN) {
    std::cerr << "BVH Warning! Call endReplaceModel() in a wrong order. endReplaceModel() was "
                 "ignored. \n";
    return fcl::BVH_ERR_BUILD_OUT_OF_SEQUENCE;
  }
  if (num_changed_ != this->num_vertices) {
    std::cerr << "BVH Error! The replaced model should have the same number of vertices as the "
                 "old model.\n";
    return fcl::BVH_ERR_INCORRECT_DATA;
  }
  this->build_state = fcl::BVH_BUILD_STATE_PROCESSED;
  fcl_stale_ = true;
  return endChange(fcl::BVH_OK);
}

template <class S>
int Mesh<S>::beginUpdateModel() {
  num_changed_ = 0;
  ++version_;
  return Base::beginUpdateModel();
}

template <class S>
int Mesh<S>::updateVertex(const fcl::Vector3<S>& p) {
  const int code = Base::updateVertex(p);
  if (code == fcl::BVH_OK) num_changed_ += 1;
  return code;
}

template <class S>
int Mesh<S>::updateTriangle(const fcl::Vector3<S>& p1, const fcl::Vector3<S>& p2,
                            const fcl::Vector3<S>& p3) {
  const int code = Base::updateTriangle(p1, p2, p3);
  if (code == fcl::BVH_OK) num_changed_ += 3;
  return code;
}

template <class S>
int Mesh<S>::updateSubModel(const std::vector<fcl::Vector3<S>>& ps) {
  const int code = Base::updateSubModel(ps);
  if (code == fcl::BVH_OK) num_changed_ += int(ps.size());
  return code;
}

template <class S>
int Mesh<S>::endUpdateModel(bool refit, bool bottomup) {
  if (mode_ == MeshMode::Fcl) return endChange(Base::endUpdateModel(refit, bottomup));
  if (this->build_state != fcl::BVH_BUILD_STATE_UPDATE_BEGUN) {
    std::cerr << "BVH Warning! Call endUpdateModel() in a wrong order. endUpdateModel() was "
                 "ignored. \n";
    return fcl::BVH_ERR_BUILD_OUT_OF_SEQUENCE;
  }
  if (num_changed_ != this->num_vertices) {
    std::cerr << "BVH Error! The updated model should have the same number of vertices as the "
                 "old model.\n";
    return fcl::BVH_ERR_INCORRECT_DATA;
  }
  this->build_state = fcl::BVH_BUILD_STATE_UPDATED;
  fcl_stale_ = true;
  return endChange(fcl::BVH_OK);
}

template <class S>
void Mesh<S>::setMode(MeshMode mode) {
  mode_ = mode;
  if (mode == MeshMode::Fcl) refitFcl();
}

template <class S>
bool Mesh<S>::refitFcl() {
  if (!fcl_stale_) return false;
  // FCL's only public way to refit: replace every vertex by itself, then endReplaceModel.
  const fcl::BVHBuildState state = this->build_state;
  const std::vector<fcl::Vector3<S>> ps(this->vertices, this->vertices + this->num_vertices);
  this->build_state = fcl::BVH_BUILD_STATE_PROCESSED;  // beginReplaceModel's precondition
  Base::beginReplaceModel();
  Base::replaceSubModel(ps);
  Base::endReplaceModel(true, true);
  this->build_state = state;
  fcl_stale_ = false;
  return true;
}

template class Mesh<float>;
template class Mesh<double>;

}  // namespace kdet_fcl
