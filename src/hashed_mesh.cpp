#include "kdet_fcl/hashed_mesh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <type_traits>
#include <string>
#include <utility>

#include "cpu/hierarchical_hash.h"
#include "kept_self_result.h"
#include "kdet_fcl/errors.h"

namespace kdet_fcl {

template <class S>
struct HashedMesh<S>::Lazy {
  std::mutex mutex;               // held while the CPU hash is rebuilt or extended
  std::atomic<bool> fresh{false};  // the CPU hash's per-triangle data match mesh_
  // With `fresh`: the lowest level whose cells are in the hash's tables (coveredFrom()).
  std::atomic<int> covered_from{detail::HierarchicalHash<S>::kNoTable};
};

template <class S>
HashedMesh<S>::HashedMesh(TriangleMesh<S> mesh, const Transform<S>& pose, int threads)
    : mesh_(std::move(mesh)), threads_(threads) {
  mesh_.validate(false, "HashedMesh");
  setPose(pose);
  hash_ = std::make_unique<detail::HierarchicalHash<S>>();
  lazy_ = std::make_unique<Lazy>();
  kept_self_ = std::make_unique<detail::KeptSelfResult>("KDET_FCL_CPU_SELF_CACHE");
  geometryChanged();
}

template <class S>
HashedMesh<S>::~HashedMesh() = default;
template <class S>
HashedMesh<S>::HashedMesh(HashedMesh&&) noexcept = default;
template <class S>
HashedMesh<S>& HashedMesh<S>::operator=(HashedMesh&&) noexcept = default;

template <class S>
double HashedMesh<S>::orthonormalTolerance() {
  return std::is_same<S, float>::value ? 1e-5 : 1e-6;
}

template <class S>
void validatePose(const Transform<S>& pose, const std::string& what) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(pose.t[i])) throw InvalidInputError(what + ": non-finite translation");
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(pose.R[i][j])) throw InvalidInputError(what + ": non-finite rotation");
  }
  const double tol = HashedMesh<S>::orthonormalTolerance();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += double(pose.R[k][i]) * double(pose.R[k][j]);
      if (std::fabs(s - (i == j ? 1.0 : 0.0)) > tol)
        throw InvalidInputError(
            what + ": the rotation is not orthonormal (|R^T R - I| exceeds " +
            std::to_string(tol) + "); scaling and shearing are not supported");
    }
  const auto& R = pose.R;
  const double det = double(R[0][0]) * (double(R[1][1]) * R[2][2] - double(R[1][2]) * R[2][1]) -
                     double(R[0][1]) * (double(R[1][0]) * R[2][2] - double(R[1][2]) * R[2][0]) +
                     double(R[0][2]) * (double(R[1][0]) * R[2][1] - double(R[1][1]) * R[2][0]);
  if (std::fabs(det - 1.0) > 4 * tol)
    throw InvalidInputError(what + ": the rotation has determinant " + std::to_string(det) +
                            " (a reflection, not a rotation)");
}

template <class S>
void HashedMesh<S>::setPose(const Transform<S>& pose) {
  validatePose(pose, "setPose");
  pose_ = pose;
}

template <class S>
void HashedMesh<S>::updateVertices(const std::vector<Vec3<S>>& vertices) {
  if (vertices.size() != mesh_.vertices.size())
    throw InvalidInputError("updateVertices: got " + std::to_string(vertices.size()) +
                            " vertices, the mesh has " + std::to_string(mesh_.vertices.size()) +
                            " (use setMesh() to change the topology)");
  TriangleMesh<S> probe;  // validate the new coordinates before touching the mesh
  probe.vertices = vertices;
  probe.validate(false, "updateVertices");
  mesh_.vertices = std::move(probe.vertices);
  geometryChanged();
}

template <class S>
void HashedMesh<S>::setMesh(TriangleMesh<S> mesh) {
  mesh.validate(false, "setMesh");
  mesh_ = std::move(mesh);
  geometryChanged();
}

template <class S>
void HashedMesh<S>::geometryChanged() {
  // noexcept in effect: nothing below allocates or throws.
  const double inf = std::numeric_limits<double>::infinity();
  detail::Aabb<double> b{{inf, inf, inf}, {-inf, -inf, -inf}};
  for (const Vec3<S>& p : mesh_.vertices)
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::min(b.lo[a], double(p[a]));
      b.hi[a] = std::max(b.hi[a], double(p[a]));
    }
  bounds_ = b;
  lazy_->fresh.store(false, std::memory_order_release);
  kept_self_->drop();  // a kept self result is of the old geometry
  // Versions are unique in the process, so a cache keyed by (address, version) can never mistake
  // a new mesh at a freed mesh's address for the old one.
  static std::atomic<std::uint64_t> next_version{1};
  version_ = next_version.fetch_add(1);
}

template <class S>
const detail::HierarchicalHash<S>& HashedMesh<S>::hashFrom(int from_level) const {
  // Fast path: current, and the tables reach down far enough. The tables' level never rises
  // while `fresh` holds, so a stale read of covered_from only sends a caller to the lock.
  if (lazy_->fresh.load(std::memory_order_acquire) &&
      lazy_->covered_from.load(std::memory_order_acquire) <= from_level)
    return *hash_;
  std::lock_guard<std::mutex> lock(lazy_->mutex);
  if (!lazy_->fresh.load(std::memory_order_relaxed)) {
    // Rebuilt in place (reusing its buffers). On an exception the hash is left empty and
    // stale, so the next call rebuilds it; the mesh itself is untouched.
    hash_->build(mesh_.vertices, mesh_.triangles, threads_, from_level);
    lazy_->covered_from.store(hash_->coveredFrom(), std::memory_order_release);
    lazy_->fresh.store(true, std::memory_order_release);
  } else if (hash_->coveredFrom() > from_level) {
    // Adds a table for the missing levels; the tables built before are not touched, so
    // concurrent lookups on the levels they cover (which their callers asked for) go on. On an
    // exception the hash is as before (current, with fewer levels), and so is covered_from.
    hash_->cover(from_level, threads_);
    lazy_->covered_from.store(hash_->coveredFrom(), std::memory_order_release);
  }
  return *hash_;
}

template <class S>
bool HashedMesh<S>::cpuHashFresh() const {
  return lazy_->fresh.load(std::memory_order_acquire) &&
         lazy_->covered_from.load(std::memory_order_acquire) == 0;
}

template <class S>
HierarchyStats HashedMesh<S>::stats() const {
  return hash().stats();
}

template class HashedMesh<float>;
template class HashedMesh<double>;
template void validatePose(const Transform<float>&, const std::string&);
template void validatePose(const Transform<double>&, const std::string&);

}  // namespace kdet_fcl
