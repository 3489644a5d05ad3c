#include "kdet_fcl/hashed_mesh.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <type_traits>
#include <string>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "commit_copy.h"
#include "coordinate_range.h"
#include "cpu/dma_passes.h"
#include "cpu/hierarchical_hash.h"
#include "cpu/parallel.h"
#include "kept_self_result.h"
#include "kdet_fcl/errors.h"

#ifndef KDET_FCL_HAVE_CUDA
#define KDET_FCL_HAVE_CUDA 0
#endif
#if KDET_FCL_HAVE_CUDA
#include "../cuda/cuda_backend.h"
#endif

namespace kdet_fcl {
namespace {

/// The running minimum, maximum and finiteness sum of one coordinate (finiteBounds).
template <class S>
struct Extent {
  S lo = std::numeric_limits<S>::infinity(), hi = -std::numeric_limits<S>::infinity(), sum = 0;
  void take(S x) {
    sum += x - x;  // 0 for finite x, NaN otherwise; a NaN stays in the sum
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
};

#if defined(__SSE2__)
/// The SSE2 operations on four floats (__m128) or two doubles (__m128d) that finiteBounds uses.
inline __m128 vSplat(float x) { return _mm_set1_ps(x); }
inline __m128d vSplat(double x) { return _mm_set1_pd(x); }
inline __m128 vLoad(const float* p) { return _mm_loadu_ps(p); }
inline __m128d vLoad(const double* p) { return _mm_loadu_pd(p); }
inline void vStore(float* p, __m128 x) { _mm_storeu_ps(p, x); }
inline void vStore(double* p, __m128d x) { _mm_storeu_pd(p, x); }
inline __m128 vAdd(__m128 a, __m128 b) { return _mm_add_ps(a, b); }
inline __m128d vAdd(__m128d a, __m128d b) { return _mm_add_pd(a, b); }
inline __m128 vSub(__m128 a, __m128 b) { return _mm_sub_ps(a, b); }
inline __m128d vSub(__m128d a, __m128d b) { return _mm_sub_pd(a, b); }
inline __m128 vMin(__m128 a, __m128 b) { return _mm_min_ps(a, b); }
inline __m128d vMin(__m128d a, __m128d b) { return _mm_min_pd(a, b); }
inline __m128 vMax(__m128 a, __m128 b) { return _mm_max_ps(a, b); }
inline __m128d vMax(__m128d a, __m128d b) { return _mm_max_pd(a, b); }

/// The vector form of Extent (V: four floats or two doubles): one register each for the minima,
/// maxima and sums. vMin/vMax take the running value as their second operand, so that a NaN
/// coordinate leaves it, as std::min(lo, x) does; the sums catch the NaN.
template <class V, class S>
struct Lanes {
  V lo = vSplat(std::numeric_limits<S>::infinity());
  V hi = vSplat(-std::numeric_limits<S>::infinity());
  V sum = vSplat(S(0));
  void take(V x) {
    sum = vAdd(sum, vSub(x, x));
    lo = vMin(x, lo);
    hi = vMax(x, hi);
  }
};

/// Lanes of S in the vector V.
template <class V, class S>
constexpr int kLanes = int(sizeof(V) / sizeof(S));

/// The coordinates of the first `count` vertices at `p` (count a multiple of W = kLanes, the
/// vertices per step) into e[0..2]: the step's 3 W values are loaded as three vectors of W lanes
/// each, whose lane k of vector r holds axis (r W + k) mod 3.
template <class V, class S>
void takeVectors(const S* p, std::size_t count, Extent<S> e[3]) {
  constexpr int W = kLanes<V, S>;
  Lanes<V, S> v[3];
  for (std::size_t i = 0; i < 3 * count; i += 3 * W)
    for (int r = 0; r < 3; ++r) v[r].take(vLoad(p + i + r * W));
  for (int r = 0; r < 3; ++r) {
    S l[W], h[W], t[W];
    vStore(l, v[r].lo);
    vStore(h, v[r].hi);
    vStore(t, v[r].sum);
    for (int k = 0; k < W; ++k) {
      Extent<S>& a = e[(r * W + k) % 3];
      a.sum += t[k];
      a.lo = std::min(a.lo, l[k]);
      a.hi = std::max(a.hi, h[k]);
    }
  }
}

/// The SSE2 vector of S.
template <class S>
struct VectorOf;
template <>
struct VectorOf<float> {
  using type = __m128;
};
template <>
struct VectorOf<double> {
  using type = __m128d;
};
template <class S>
using Vector = typename VectorOf<S>::type;
/// Vertices per vector step: one per lane.
template <class S>
constexpr std::size_t kStep = kLanes<Vector<S>, S>;
#endif

/// The n vertices at v taken into e[0..2] (finiteBounds), in one pass with no branch per vertex.
/// With SSE2, a step of 4 float or 2 double vertices is three vector loads feeding three
/// independent chains of vector minima, maxima and sums; the scalar loop's three chains each wait
/// on the latency of every step (updateVertices of the 92k cloth: 88-121 us with scalar loops,
/// 31 us with this; benchmarks/RESULTS.md).
template <class S>
void takeRange(const Vec3<S>* v, std::size_t n, Extent<S> e[3]) {
  static_assert(sizeof(Vec3<S>) == 3 * sizeof(S), "Vec3 must be three packed coordinates");
  std::size_t i = 0;
#if defined(__SSE2__)
  i = n / kStep<S> * kStep<S>;
  if (i > 0) takeVectors<Vector<S>>(&v[0].x, i, e);
#endif
  for (; i < n; ++i) {
    e[0].take(v[i].x);
    e[1].take(v[i].y);
    e[2].take(v[i].z);
  }
}

/// takeRange with each 64-byte line of v demoted from this core's private caches once it is read
/// (cpu::demoteLines, cpu/dma_passes.h): the array goes in blocks of 16 KB, each demoted while it
/// is still in the first-level cache. The same extents as takeRange (minima, maxima and sums of
/// x - x, whose verdict does not depend on the order).
template <class S>
void takeRangeDemoting(const Vec3<S>* v, std::size_t n, Extent<S> e[3]) {
  constexpr std::size_t kBlock = (std::size_t(16) << 10) / sizeof(Vec3<S>);
  for (std::size_t i = 0; i < n; i += kBlock) {
    const std::size_t m = std::min(kBlock, n - i);
    takeRange(v + i, m, e);
    cpu::demoteLines(v + i, m * sizeof(Vec3<S>));
  }
}

/// The threads of a pass over `count` vertices of S (cpu::vertexPassThreads).
template <class S>
int vertexThreads(std::size_t count, int threads) {
  return cpu::vertexPassThreads(count * sizeof(Vec3<S>), threads);
}

using cpu::shareOf;

/// The extents of the n parts at `parts` merged into *out (min, max and sums: the same bounds and
/// the same verdict whatever the split); whether every coordinate was finite.
template <class S>
bool mergedBounds(const std::array<Extent<S>, 3>* parts, std::size_t n,
                  detail::Aabb<double>* out) {
  Extent<S> e[3];
  for (std::size_t k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) {
      e[a].sum += parts[k][a].sum;
      e[a].lo = std::min(e[a].lo, parts[k][a].lo);
      e[a].hi = std::max(e[a].hi, parts[k][a].hi);
    }
  *out = detail::Aabb<double>{{double(e[0].lo), double(e[1].lo), double(e[2].lo)},
                              {double(e[0].hi), double(e[1].hi), double(e[2].hi)}};
  return e[0].sum == S(0) && e[1].sum == S(0) && e[2].sum == S(0);
}

/// The bounds of `v` in double (empty for no vertex), by takeRange in t threads (vertexThreads);
/// false when a coordinate is not finite (its sum of x - x is then not 0). `demote`: each line of
/// v leaves the reading core's private caches once read (takeRangeDemoting).
template <class S>
bool finiteBounds(const std::vector<Vec3<S>>& v, detail::Aabb<double>* out, int t, bool demote) {
  const auto take = demote ? takeRangeDemoting<S> : takeRange<S>;
  if (t <= 1) {
    std::array<Extent<S>, 3> e;
    take(v.data(), v.size(), e.data());
    return mergedBounds(&e, 1, out);
  }
  // Each thread's share into its own extents, merged after.
  const std::size_t per = shareOf(v.size(), t);
  std::vector<std::array<Extent<S>, 3>> part(static_cast<std::size_t>(t));
  cpu::parallelFor(v.size(), per, t, [&](std::size_t lo, std::size_t hi) {
    take(v.data() + lo, hi - lo, part[lo / per].data());
  });
  return mergedBounds(part.data(), part.size(), out);
}

/// InvalidInputError naming the first non-finite coordinate of `v`, or the vertex that puts its
/// largest magnitude outside the exact range (TriangleMesh::validateForQueries), prefixed by `what`
/// (updateVertices, commitVertices).
template <class S>
[[noreturn]] void throwBadVertices(const std::vector<Vec3<S>>& v, const char* what) {
  TriangleMesh<S> probe;  // the error path: the message names the first bad vertex
  probe.vertices = v;
  probe.validateForQueries(false, what);
  throw InvalidInputError(std::string(what) + ": a non-finite coordinate");
}

/// Whether finite bounds `b` keep the mesh's largest coordinate magnitude in the exact range
/// (detail::inExactRange: what TriangleMesh::validateForQueries requires, read off the bounds).
bool boundsInRange(const detail::Aabb<double>& b) {
  return detail::inExactRange(detail::largestMagnitude(b));
}

/// The bounds of the new positions `v` (finiteBounds in t threads, vertexThreads' count,
/// demoting each line where `demote`), or throwBadVertices' error.
template <class S>
detail::Aabb<double> checkedBounds(const std::vector<Vec3<S>>& v, int t, const char* what,
                                   bool demote) {
  detail::Aabb<double> b;
  if (finiteBounds(v, &b, t, demote) && boundsInRange(b)) return b;
  throwBadVertices(v, what);
}

/// Copies src[lo, hi) to dst + lo: by non-temporal stores where `stream` (cpu::streamCopy, into a
/// buffer the GPU reads by DMA next), else plainly.
template <class S>
void copyVertexRange(const std::vector<Vec3<S>>& src, Vec3<S>* dst, std::size_t lo,
                     std::size_t hi, bool stream) {
  if (stream)
    cpu::streamCopy(dst + lo, src.data() + lo, (hi - lo) * sizeof(Vec3<S>));
  else
    std::copy(src.begin() + lo, src.begin() + hi, dst + lo);
}

/// The CUDA backend's copy of the `bytes` of `mesh`'s vertex buffer at `buffer` (registered as
/// `pin`) while a vertex pass goes over it (commit_copy.h), or nullptr: none taken, or no CUDA.
template <class S>
std::unique_ptr<detail::CommitCopy> deviceCopy(const HashedMesh<S>& mesh, const void* buffer,
                                               std::size_t bytes, const detail::HostPin& pin) {
#if KDET_FCL_HAVE_CUDA
  return cuda::startCommitCopy(mesh, buffer, bytes, pin);
#else
  (void)mesh, (void)buffer, (void)bytes, (void)pin;
  return nullptr;
#endif
}

}  // namespace

namespace detail {
namespace {

/// The pieces of a pass over n elements of `elem` bytes with a copy whose batch is batch_bytes:
/// `per` elements a piece (at most kCommitPieceBytes, and no more than the batch), `pieces`
/// pieces (at least one), a batch of `batch` pieces.
struct PieceLayout {
  std::size_t per = 1, pieces = 1, batch = 1;
};
PieceLayout pieceLayout(std::size_t n, std::size_t elem, std::size_t batch_bytes) {
  PieceLayout L;
  batch_bytes = std::max<std::size_t>(1, batch_bytes);
  L.per = std::max<std::size_t>(1, std::min(kCommitPieceBytes, batch_bytes) / elem);
  L.pieces = std::max<std::size_t>(1, (n + L.per - 1) / L.per);
  const std::size_t per_bytes = L.per * elem;
  L.batch = std::max<std::size_t>(1, (batch_bytes + per_bytes - 1) / per_bytes);
  return L;
}

/// work(c, lo, hi) for each piece c (elements [lo, hi)) of layout L on `threads` threads, the
/// pieces taken in address order; work returns false to refuse its piece, and no further piece
/// starts. Meanwhile the run of accepted pieces from the start goes to copy.piece() a batch at a
/// time, by whichever thread finds the sender free (none waits for it), and the rest once every
/// piece is done. Returns false when a piece was refused (nothing past it was sent then).
template <class Work>
bool pipelinedPieces(std::size_t n, std::size_t elem, const PieceLayout& L, int threads,
                     CommitCopy& copy, Work&& work) {
  // done[c]: piece c was accepted. `sent` pieces from the start have gone to the copy.
  std::unique_ptr<std::atomic<bool>[]> done(new std::atomic<bool>[L.pieces]);
  for (std::size_t c = 0; c < L.pieces; ++c) done[c].store(false, std::memory_order_relaxed);
  std::mutex sender;
  std::size_t sent = 0;  // under `sender`
  auto send = [&](std::size_t at_least) {
    std::size_t k = sent;
    while (k < L.pieces && done[k].load(std::memory_order_acquire)) ++k;
    if (k - sent < at_least || k == sent) return;
    const std::size_t lo = sent * L.per, hi = std::min(n, k * L.per);
    if (hi > lo) copy.piece(lo * elem, (hi - lo) * elem);
    sent = k;
  };
  std::atomic<bool> refused{false};
  cpu::forEachChunk(L.pieces, threads, [&](std::size_t c) {
    const std::size_t lo = std::min(n, c * L.per), hi = std::min(n, (c + 1) * L.per);
    if (!work(c, lo, hi)) {
      refused.store(true, std::memory_order_relaxed);
      return false;
    }
    done[c].store(true, std::memory_order_release);
    std::unique_lock<std::mutex> lock(sender, std::try_to_lock);
    if (lock.owns_lock()) send(L.batch);
    return true;
  });
  if (refused.load()) return false;
  std::lock_guard<std::mutex> lock(sender);
  send(1);  // the rest
  return true;
}

}  // namespace

template <class S>
bool checkedPieces(const std::vector<Vec3<S>>& v, int threads, bool demote, CommitCopy& copy,
                   Aabb<double>* out) {
  const auto take = demote ? takeRangeDemoting<S> : takeRange<S>;
  const PieceLayout L = pieceLayout(v.size(), sizeof(Vec3<S>), copy.batchBytes());
  std::vector<std::array<Extent<S>, 3>> part(L.pieces);
  const bool finite = pipelinedPieces(
      v.size(), sizeof(Vec3<S>), L, threads, copy,
      [&](std::size_t c, std::size_t lo, std::size_t hi) {
        take(v.data() + lo, hi - lo, part[c].data());
        const auto& e = part[c];
        return e[0].sum == S(0) && e[1].sum == S(0) && e[2].sum == S(0);
      });
  return finite && mergedBounds(part.data(), part.size(), out);
}

template <class S>
void copiedPieces(const std::vector<Vec3<S>>& src, Vec3<S>* dst, int threads, bool stream,
                  CommitCopy& copy) {
  const PieceLayout L = pieceLayout(src.size(), sizeof(Vec3<S>), copy.batchBytes());
  pipelinedPieces(src.size(), sizeof(Vec3<S>), L, threads, copy,
                  [&](std::size_t, std::size_t lo, std::size_t hi) {
                    copyVertexRange(src, dst, lo, hi, stream);
                    return true;
                  });
}

template bool checkedPieces(const std::vector<Vec3<float>>&, int, bool, CommitCopy&,
                            Aabb<double>*);
template bool checkedPieces(const std::vector<Vec3<double>>&, int, bool, CommitCopy&,
                            Aabb<double>*);
template void copiedPieces(const std::vector<Vec3<float>>&, Vec3<float>*, int, bool,
                           CommitCopy&);
template void copiedPieces(const std::vector<Vec3<double>>&, Vec3<double>*, int, bool,
                           CommitCopy&);

}  // namespace detail

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
  mesh_.validateForQueries(false, "HashedMesh");
  setPose(pose);
  hash_ = std::make_unique<detail::HierarchicalHash<S>>();
  lazy_ = std::make_unique<Lazy>();
  kept_self_ = std::make_unique<detail::KeptSelfResult>("KDET_FCL_CPU_SELF_CACHE");
  // Unique in the process, as versions are: a new mesh at a freed mesh's address gets a new one.
  static std::atomic<std::uint64_t> next_identity{1};
  identity_ = next_identity.fetch_add(1);
  topologyChanged();
  geometryChanged();
}

template <class S>
HashedMesh<S>::~HashedMesh() {
  host_pin_.reset();  // before mesh_ frees the buffer it is for
  write_pin_.reset();
}
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
  // One pass over the new coordinates checks them and gives their bounds, before the mesh is
  // touched; then they are copied into the mesh's own buffer, which keeps its address (no
  // allocation, no page faults; benchmarks/update_bench, RESULTS.md).
  // Large arrays are checked and copied by several threads (vertexThreads).
  const int t = vertexThreads<S>(vertices.size(), threads_);
  const detail::Aabb<double> b = checkedBounds(vertices, t, "updateVertices", false);
  // Into a buffer the GPU reads by DMA next (registered by the CUDA backend), a copy in several
  // threads goes by non-temporal stores, leaving no line in their caches (cpu/dma_passes.h).
  const bool stream = cpu::streamCopyInto(host_pin_.pinned(), t);
  // Where the GPU holds this mesh and reads the buffer by DMA next, the CUDA backend may take
  // the copy's pieces as they are written (commit_copy.h); the next query then skips the upload.
  const std::unique_ptr<detail::CommitCopy> copy = deviceCopy(
      *this, mesh_.vertices.data(), vertices.size() * sizeof(Vec3<S>), host_pin_);
  if (copy) {
    detail::copiedPieces(vertices, mesh_.vertices.data(), t, stream, *copy);
  } else {
    // (One thread: a single chunk, copied in place by the caller's thread.)
    cpu::parallelFor(vertices.size(), shareOf(vertices.size(), t), t,
                     [&](std::size_t lo, std::size_t hi) {
                       copyVertexRange(vertices, mesh_.vertices.data(), lo, hi, stream);
                     });
  }
  geometryChanged(b);
  if (copy) copy->finish(true, version_);
}

template <class S>
Vec3<S>* HashedMesh<S>::vertexWriteBuffer() {
  // (Empty only since construction or setMesh, which also dropped its pin record.)
  if (write_buffer_.size() != mesh_.vertices.size()) write_buffer_.resize(mesh_.vertices.size());
  return write_buffer_.data();
}

template <class S>
void HashedMesh<S>::commitVertices() {
  if (write_buffer_.size() != mesh_.vertices.size())
    throw InvalidInputError(
        "commitVertices: nothing to commit (call vertexWriteBuffer() and write the positions "
        "there first)");
  // The check and the bounds of updateVertices, on the written buffer in place; then the two
  // buffers, and each one's pin record, trade places (no copy, no allocation). A buffer the GPU
  // reads by DMA next (registered by the CUDA backend), of cpu::kDemoteMinBytes or more and
  // checked in several threads, leaves their caches line by line as it is read
  // (cpu/dma_passes.h).
  // Where the GPU holds this mesh and reads the buffer by DMA next, the CUDA backend may take
  // the buffer's checked pieces while the check goes on (commit_copy.h); the next query then
  // skips the upload.
  const int t = vertexThreads<S>(write_buffer_.size(), threads_);
  const std::size_t bytes = write_buffer_.size() * sizeof(Vec3<S>);
  const bool demote = cpu::demoteWhileChecking(write_pin_.pinned(), t, bytes);
  const std::unique_ptr<detail::CommitCopy> copy =
      deviceCopy(*this, write_buffer_.data(), bytes, write_pin_);
  detail::Aabb<double> b;
  if (!copy) {
    b = checkedBounds(write_buffer_, t, "commitVertices", demote);
  } else if (!detail::checkedPieces(write_buffer_, t, demote, *copy, &b) || !boundsInRange(b)) {
    copy->finish(false, 0);
    throwBadVertices(write_buffer_, "commitVertices");
  }
  mesh_.vertices.swap(write_buffer_);
  std::swap(host_pin_, write_pin_);
  geometryChanged(b);
  if (copy) copy->finish(true, version_);
}

template <class S>
void HashedMesh<S>::setMesh(TriangleMesh<S> mesh) {
  mesh.validateForQueries(false, "setMesh");
  host_pin_.reset();  // the vertex buffers are replaced
  write_pin_.reset();
  std::vector<Vec3<S>>().swap(write_buffer_);
  mesh_ = std::move(mesh);
  topologyChanged();
  geometryChanged();
}

template <class S>
void HashedMesh<S>::topologyChanged() {
  // Unique in the process, as versions are (a new mesh at a freed mesh's address gets a new one).
  static std::atomic<std::uint64_t> next_topology{1};
  topology_version_ = next_topology.fetch_add(1);
}

template <class S>
void HashedMesh<S>::geometryChanged() {
  detail::Aabb<double> b;
  const bool finite =
      finiteBounds(mesh_.vertices, &b, vertexThreads<S>(mesh_.vertices.size(), threads_), false);
  (void)finite;  // validated by the caller
  geometryChanged(b);
}

template <class S>
void HashedMesh<S>::geometryChanged(const detail::Aabb<double>& b) {
  // noexcept in effect: nothing below allocates or throws.
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
