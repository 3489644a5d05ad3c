// The GPU BVH baseline (issue 5): linear BVH (Morton codes, CUB radix sort, parallel hierarchy
// construction), bottom-up refit with atomic flags, stack traversal, the library's exact triangle
// test. See gpu_bvh.cuh for the contract. Written for this suite.

#include "gpu_bvh.cuh"

#include <cooperative_groups.h>
#include <cuda_runtime.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <cub/device/device_radix_sort.cuh>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include "cuda/staged_upload.h"
#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "src/kept_self_result.h"

namespace cg = cooperative_groups;
using kdet_fcl::Predicate;
using kdet_fcl::TrianglePair;
using kdet_fcl::Vec3;

namespace kdet_bvh {
namespace {

void check(cudaError_t e, const char* what, int line) {
  if (e != cudaSuccess)
    throw std::runtime_error(std::string("gpu_bvh: ") + what + " (line " + std::to_string(line) +
                             "): " + cudaGetErrorString(e));
}
#define BVH_TRY(x) check((x), #x, __LINE__)
#define BVH_LAUNCHED() check(cudaGetLastError(), "kernel launch", __LINE__)

/// Grow-only device buffer (contents not kept on growth).
template <class T>
struct Buf {
  T* p = nullptr;
  std::size_t cap = 0;
  Buf() = default;
  Buf(const Buf&) = delete;
  Buf& operator=(const Buf&) = delete;
  ~Buf() { release(); }
  void reserve(std::size_t n) {
    if (p != nullptr && n <= cap) return;
    release();
    const std::size_t want = n == 0 ? 1 : n + n / 8;
    BVH_TRY(cudaMalloc(reinterpret_cast<void**>(&p), want * sizeof(T)));
    cap = want;
  }
  void release() {
    if (p != nullptr) (void)cudaFree(p);
    p = nullptr;
    cap = 0;
  }
  std::size_t bytes() const { return cap * sizeof(T); }
};

/// Grow-only pinned host buffer.
struct Pinned {
  void* p = nullptr;
  std::size_t cap = 0;
  ~Pinned() {
    if (p != nullptr) (void)cudaFreeHost(p);
  }
  void* reserve(std::size_t bytes) {
    if (p == nullptr || bytes > cap) {
      if (p != nullptr) (void)cudaFreeHost(p);
      p = nullptr;
      cap = std::max<std::size_t>(bytes + bytes / 8, 4096);
      BVH_TRY(cudaMallocHost(&p, cap));
    }
    return p;
  }
};

/// CUDA-event timing of one API call: marks split it into stages.
struct Timer {
  bool on = false;
  BvhTimes t;
  cudaEvent_t ev[32];
  int created = 0, used = 0;
  double* dest[32];
  void record() {
    if (used == created) BVH_TRY(cudaEventCreate(&ev[created++]));
    BVH_TRY(cudaEventRecord(ev[used++], 0));
  }
  void begin() {
    used = 0;
    if (on) record();
  }
  /// The time since the previous mark goes to `field`.
  void mark(double* field) {
    if (!on || used >= 32) return;
    dest[used - 1] = field;
    record();
  }
  void end() {
    if (!on || used < 2) return;
    BVH_TRY(cudaEventSynchronize(ev[used - 1]));
    for (int k = 1; k < used; ++k) {
      float ms = 0;
      BVH_TRY(cudaEventElapsedTime(&ms, ev[k - 1], ev[k]));
      *dest[k - 1] += ms;
    }
    float tot = 0;
    BVH_TRY(cudaEventElapsedTime(&tot, ev[0], ev[used - 1]));
    t.total_ms += tot;
  }
};
Timer g_timer;

/// Module scratch shared by all queries (the calls are synchronous).
struct Scratch {
  Buf<unsigned long long> cand, pairs, sorted, counters;
  Buf<uint2> unpacked;
  Buf<unsigned char> cub, mapped;
  Pinned host_counters, host_pairs;
  kdet_fcl::staging::CopyPool copy_pool;  // the threads of reads into kept results (downloadInto)
  std::size_t cand_cap = 0, pair_cap = 0, forced_cap = 0;
  int sms = 0;
  std::size_t bytes() const {
    return cand.bytes() + pairs.bytes() + sorted.bytes() + counters.bytes() + unpacked.bytes() +
           cub.bytes() + mapped.bytes();
  }
};
Scratch& scratch() {
  static Scratch* s = new Scratch;  // never destroyed: no CUDA calls after the runtime's teardown
  if (s->sms == 0) {
    int dev = 0;
    BVH_TRY(cudaGetDevice(&dev));
    BVH_TRY(cudaDeviceGetAttribute(&s->sms, cudaDevAttrMultiProcessorCount, dev));
  }
  return *s;
}

constexpr int kBlock = 128;
unsigned blocks(std::size_t n, int b = kBlock) { return unsigned((n + b - 1) / b); }

// ---- geometry helpers ----

template <class S>
struct Box {
  Vec3<S> lo, hi;
};

template <class S>
__device__ __forceinline__ S mn(S a, S b) {
  return a < b ? a : b;
}
template <class S>
__device__ __forceinline__ S mx(S a, S b) {
  return a < b ? b : a;
}

template <class S>
__device__ __forceinline__ Box<S> triBox(const Vec3<S>* v, const std::uint32_t* t, std::uint32_t i) {
  const Vec3<S> a = v[t[3 * i]], b = v[t[3 * i + 1]], c = v[t[3 * i + 2]];
  return {{mn(mn(a.x, b.x), c.x), mn(mn(a.y, b.y), c.y), mn(mn(a.z, b.z), c.z)},
          {mx(mx(a.x, b.x), c.x), mx(mx(a.y, b.y), c.y), mx(mx(a.z, b.z), c.z)}};
}

/// Closed boxes: touching counts (so touching triangles always become candidates).
template <class S>
__device__ __forceinline__ bool overlap(const Box<S>& a, const Vec3<S>& lo, const Vec3<S>& hi) {
  return a.lo.x <= hi.x && lo.x <= a.hi.x && a.lo.y <= hi.y && lo.y <= a.hi.y &&
         a.lo.z <= hi.z && lo.z <= a.hi.z;
}

// ---- build ----

__device__ __forceinline__ unsigned orderedBits(float f) {
  const unsigned u = __float_as_uint(f);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
__host__ __device__ __forceinline__ float fromOrdered(unsigned e) {
  const unsigned u = (e & 0x80000000u) ? (e & 0x7fffffffu) : ~e;
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

template <class S>
__device__ __forceinline__ Vec3<float> centroid(const Box<S>& b) {
  return {0.5f * (float(b.lo.x) + float(b.hi.x)), 0.5f * (float(b.lo.y) + float(b.hi.y)),
          0.5f * (float(b.lo.z) + float(b.hi.z))};
}

/// bnd[0..2]: ordered min of the centroids, bnd[3..5]: ordered max (warp-reduced, then atomics).
template <class S>
__global__ void boundsKernel(std::uint32_t n, const Vec3<S>* __restrict__ v,
                             const std::uint32_t* __restrict__ t, unsigned* bnd) {
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  unsigned e[6] = {~0u, ~0u, ~0u, 0u, 0u, 0u};
  if (i < n) {
    const Vec3<float> c = centroid(triBox(v, t, i));
    e[0] = e[3] = orderedBits(c.x);
    e[1] = e[4] = orderedBits(c.y);
    e[2] = e[5] = orderedBits(c.z);
  }
  for (int k = 0; k < 3; ++k) e[k] = __reduce_min_sync(0xffffffffu, e[k]);
  for (int k = 3; k < 6; ++k) e[k] = __reduce_max_sync(0xffffffffu, e[k]);
  if ((threadIdx.x & 31) == 0) {
    for (int k = 0; k < 3; ++k) atomicMin(&bnd[k], e[k]);
    for (int k = 3; k < 6; ++k) atomicMax(&bnd[k], e[k]);
  }
}

__device__ __forceinline__ std::uint32_t spread10(std::uint32_t x) {
  x &= 0x3ffu;
  x = (x | (x << 16)) & 0x030000ffu;
  x = (x | (x << 8)) & 0x0300f00fu;
  x = (x | (x << 4)) & 0x030c30c3u;
  x = (x | (x << 2)) & 0x09249249u;
  return x;
}

template <class S>
__global__ void mortonKernel(std::uint32_t n, const Vec3<S>* __restrict__ v,
                             const std::uint32_t* __restrict__ t, const unsigned* __restrict__ bnd,
                             std::uint32_t* __restrict__ code, std::uint32_t* __restrict__ idx) {
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const Vec3<float> c = centroid(triBox(v, t, i));
  float lo[3], ext[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = fromOrdered(bnd[k]);
    ext[k] = fromOrdered(bnd[3 + k]) - lo[k];
  }
  const float p[3] = {c.x, c.y, c.z};
  std::uint32_t q[3];
  for (int k = 0; k < 3; ++k) {
    const float u = ext[k] > 0 ? (p[k] - lo[k]) / ext[k] : 0.f;
    q[k] = std::uint32_t(fminf(fmaxf(u * 1024.f, 0.f), 1023.f));
  }
  code[i] = (spread10(q[0]) << 2) | (spread10(q[1]) << 1) | spread10(q[2]);
  idx[i] = i;
}

/// Common-prefix length of sorted keys i and j, ties broken by position (-1 outside [0, n)).
__device__ __forceinline__ int delta(const std::uint32_t* __restrict__ code, int n, int i, int j) {
  if (j < 0 || j >= n) return -1;
  const unsigned long long a = (static_cast<unsigned long long>(code[i]) << 32) | unsigned(i);
  const unsigned long long b = (static_cast<unsigned long long>(code[j]) << 32) | unsigned(j);
  return __clzll(a ^ b);
}

/// Internal node i of n-1: its key range [first, last] and split (Karras 2012). Node ids:
/// internal 0..n-2 (root 0), leaf of sorted position p: n-1+p.
__global__ void hierarchyKernel(int n, const std::uint32_t* __restrict__ code, int* left,
                                int* right, int* parent, std::uint32_t* range_end) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n - 1) return;
  const int d = delta(code, n, i, i + 1) > delta(code, n, i, i - 1) ? 1 : -1;
  const int dmin = delta(code, n, i, i - d);
  long long lmax = 2;
  while (delta(code, n, i, int(i + lmax * d)) > dmin) lmax <<= 1;
  int l = 0;
  for (long long t = lmax >> 1; t >= 1; t >>= 1)
    if (delta(code, n, i, int(i + (l + t) * d)) > dmin) l += int(t);
  const int j = i + l * d;
  const int dnode = delta(code, n, i, j);
  int s = 0;
  for (int div = 2;; div <<= 1) {
    const int t = (l + div - 1) / div;
    if (delta(code, n, i, i + (s + t) * d) > dnode) s += t;
    if (t <= 1) break;
  }
  const int gamma = i + s * d + (d < 0 ? -1 : 0);
  const int first = i < j ? i : j, last = i < j ? j : i;
  const int L = first == gamma ? n - 1 + gamma : gamma;
  const int R = last == gamma + 1 ? n - 1 + gamma + 1 : gamma + 1;
  left[i] = L;
  right[i] = R;
  parent[L] = i;
  parent[R] = i;
  range_end[i] = std::uint32_t(last);
  if (i == 0) parent[0] = -1;
}

template <class S>
__device__ __forceinline__ Vec3<S> loadCg(const Vec3<S>* p) {
  return {__ldcg(&p->x), __ldcg(&p->y), __ldcg(&p->z)};
}

/// Leaf boxes from the vertices, then bottom-up: the second child to reach a node writes it.
template <class S>
__global__ void refitKernel(std::uint32_t n, const Vec3<S>* __restrict__ v,
                            const std::uint32_t* __restrict__ t,
                            const std::uint32_t* __restrict__ leaf_tri,
                            const int* __restrict__ parent, const int* __restrict__ left,
                            const int* __restrict__ right, Vec3<S>* lo, Vec3<S>* hi,
                            unsigned* flags) {
  const std::uint32_t p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p >= n) return;
  const Box<S> b = triBox(v, t, leaf_tri[p]);
  const int leaf = int(n - 1 + p);
  lo[leaf] = b.lo;
  hi[leaf] = b.hi;
  int cur = parent[leaf];
  while (cur >= 0) {
    __threadfence();
    if (atomicAdd(&flags[cur], 1u) == 0) return;  // the sibling is not done yet
    __threadfence();
    const int L = left[cur], R = right[cur];
    const Vec3<S> a0 = loadCg(lo + L), a1 = loadCg(hi + L), b0 = loadCg(lo + R),
                  b1 = loadCg(hi + R);
    lo[cur] = {mn(a0.x, b0.x), mn(a0.y, b0.y), mn(a0.z, b0.z)};
    hi[cur] = {mx(a1.x, b1.x), mx(a1.y, b1.y), mx(a1.z, b1.z)};
    cur = parent[cur];
  }
}

// ---- queries ----

template <class S>
struct TreeView {
  int n;
  const Vec3<S>* lo;
  const Vec3<S>* hi;
  const int* left;
  const int* right;
  const std::uint32_t* range_end;
  const std::uint32_t* leaf_tri;
};

struct Sink {
  unsigned long long* data;
  unsigned long long* count;
  unsigned long long cap;
};

/// Appends (a, b) with one atomic per group of converged threads.
__device__ __forceinline__ void emit(const Sink& s, std::uint32_t a, std::uint32_t b) {
  const cg::coalesced_group g = cg::coalesced_threads();
  unsigned long long base = 0;
  if (g.thread_rank() == 0) base = atomicAdd(s.count, static_cast<unsigned long long>(g.size()));
  base = g.shfl(base, 0) + g.thread_rank();
  if (base < s.cap) s.data[base] = (static_cast<unsigned long long>(a) << 32) | b;
}

/// Stack traversal of T for the box (qlo, qhi): onLeaf(position) for every leaf whose box
/// overlaps and whose position satisfies keep(max position under the node).
template <class S, class Keep, class OnLeaf>
__device__ __forceinline__ void traverse(const TreeView<S>& T, const Vec3<S>& qlo,
                                         const Vec3<S>& qhi, Keep keep, OnLeaf onLeaf) {
  const int n = T.n;
  auto visit = [&](int node) {
    const bool leaf = node >= n - 1;
    const std::uint32_t maxpos = leaf ? std::uint32_t(node - (n - 1)) : T.range_end[node];
    if (!keep(maxpos)) return false;
    const Box<S> b{T.lo[node], T.hi[node]};
    return overlap(b, qlo, qhi);
  };
  if (n == 1) {
    if (visit(0)) onLeaf(0u);
    return;
  }
  int stack[64];
  int sp = 0, node = 0;
  if (!visit(0)) return;
  for (;;) {
    const int L = T.left[node], R = T.right[node];
    bool oL = visit(L), oR = visit(R);
    if (oL && L >= n - 1) {
      onLeaf(std::uint32_t(L - (n - 1)));
      oL = false;
    }
    if (oR && R >= n - 1) {
      onLeaf(std::uint32_t(R - (n - 1)));
      oR = false;
    }
    if (!oL && !oR) {
      if (sp == 0) break;
      node = stack[--sp];
    } else {
      node = oL ? L : R;
      if (oL && oR) stack[sp++] = R;
    }
  }
}

/// Each query triangle (in the order `order`, or 0..nq-1) down tree T: candidates (q, j), or
/// (j, q) when `swap`.
template <class S>
__global__ void __launch_bounds__(kBlock)
    interTraverseKernel(std::uint32_t nq, const std::uint32_t* __restrict__ order,
                        const Vec3<S>* __restrict__ qv, const std::uint32_t* __restrict__ qt,
                        TreeView<S> T, bool swap, Sink cand) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= nq) return;
  const std::uint32_t q = order != nullptr ? order[k] : k;
  const Box<S> b = triBox(qv, qt, q);
  traverse(
      T, b.lo, b.hi, [](std::uint32_t) { return true; },
      [&](std::uint32_t pos) {
        const std::uint32_t j = T.leaf_tri[pos];
        if (swap)
          emit(cand, j, q);
        else
          emit(cand, q, j);
      });
}

/// Each leaf p down its own tree, keeping leaves after p; pairs sharing a vertex index dropped
/// here (equal coordinates in the exact phase).
template <class S>
__global__ void __launch_bounds__(kBlock)
    selfTraverseKernel(TreeView<S> T, const std::uint32_t* __restrict__ t, Sink cand) {
  const std::uint32_t p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p >= std::uint32_t(T.n)) return;
  const std::uint32_t i = T.leaf_tri[p];
  const int leaf = T.n - 1 + int(p);
  const Vec3<S> lo = T.lo[leaf], hi = T.hi[leaf];
  const std::uint32_t ti0 = t[3 * i], ti1 = t[3 * i + 1], ti2 = t[3 * i + 2];
  traverse(
      T, lo, hi, [&](std::uint32_t maxpos) { return maxpos > p; },
      [&](std::uint32_t pos) {
        if (pos <= p) return;
        const std::uint32_t j = T.leaf_tri[pos];
        const std::uint32_t a = t[3 * j], b = t[3 * j + 1], c = t[3 * j + 2];
        const bool shared = a == ti0 || a == ti1 || a == ti2 || b == ti0 || b == ti1 ||
                            b == ti2 || c == ti0 || c == ti1 || c == ti2;
        if (!shared) emit(cand, i, j);
      });
}

template <class S>
__global__ void mapKernel(std::uint32_t n, const Vec3<S>* __restrict__ v,
                          kdet_fcl::Transform<double> a_to_b, Vec3<S>* __restrict__ out) {
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) out[i] = kdet_fcl::detail::mapPoint(a_to_b, v[i]);
}

/// The exact test of each candidate (a of A in B's frame, b of B).
template <class S, class K>
__global__ void __launch_bounds__(kBlock)
    interExactKernel(const unsigned long long* __restrict__ cand, const unsigned long long* count,
                     unsigned long long cap, const Vec3<S>* __restrict__ va,
                     const std::uint32_t* __restrict__ ta, const Vec3<S>* __restrict__ vb,
                     const std::uint32_t* __restrict__ tb, Sink out) {
  const unsigned long long m = *count < cap ? *count : cap;
  for (unsigned long long k = blockIdx.x * blockDim.x + threadIdx.x; k < m;
       k += gridDim.x * blockDim.x) {
    const unsigned long long c = cand[k];
    const auto i = std::uint32_t(c >> 32), j = std::uint32_t(c);
    if (kdet_fcl::detail::trianglesIntersectWith<K>(va[ta[3 * i]], va[ta[3 * i + 1]],
                                                    va[ta[3 * i + 2]], vb[tb[3 * j]],
                                                    vb[tb[3 * j + 1]], vb[tb[3 * j + 2]]))
      emit(out, i, j);
  }
}

/// Self: pairs with a vertex of equal coordinates are adjacent; the others get the exact test.
/// Two meshes in one tree (split > 0: triangles [0, split) are the first's): a pair across them
/// is never adjacent, and its test takes the first mesh's triangle first, as intersect() does.
template <class S, class K>
__global__ void __launch_bounds__(kBlock)
    selfExactKernel(const unsigned long long* __restrict__ cand, const unsigned long long* count,
                    unsigned long long cap, const Vec3<S>* __restrict__ v,
                    const std::uint32_t* __restrict__ t, std::uint32_t split, Sink out) {
  const unsigned long long m = *count < cap ? *count : cap;
  for (unsigned long long k = blockIdx.x * blockDim.x + threadIdx.x; k < m;
       k += gridDim.x * blockDim.x) {
    const unsigned long long c = cand[k];
    auto i = std::uint32_t(c >> 32), j = std::uint32_t(c);
    const bool same = (i < split) == (j < split);
    if (!same && i > j) {
      const std::uint32_t x = i;
      i = j;
      j = x;
    }
    const Vec3<S> vi[3] = {v[t[3 * i]], v[t[3 * i + 1]], v[t[3 * i + 2]]};
    const Vec3<S> vj[3] = {v[t[3 * j]], v[t[3 * j + 1]], v[t[3 * j + 2]]};
    bool adjacent = false;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) adjacent = adjacent || vi[a] == vj[b];
    if (!(adjacent && same) &&
        kdet_fcl::detail::trianglesIntersectWith<K>(vi[0], vi[1], vi[2], vj[0], vj[1], vj[2]))
      emit(out, i < j ? i : j, i < j ? j : i);
  }
}

__global__ void unpackKernel(std::uint32_t m, const unsigned long long* __restrict__ keys,
                             uint2* __restrict__ out) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < m) out[k] = make_uint2(std::uint32_t(keys[k] >> 32), std::uint32_t(keys[k]));
}

int bitsFor(std::uint64_t x) {
  int b = 0;
  while (x > 0) ++b, x >>= 1;
  return std::max(b, 1);
}

}  // namespace

void setTiming(bool on) { g_timer.on = on; }
void useDevice(int device) { BVH_TRY(cudaSetDevice(device)); }
void resetTimes() { g_timer.t = BvhTimes{}; }
BvhTimes times() { return g_timer.t; }
std::size_t scratchBytes() { return scratch().bytes(); }
void setInitialCapacity(std::size_t k) {
  Scratch& s = scratch();
  s.forced_cap = k;
  s.cand_cap = s.pair_cap = 0;
}

DevicePairBuffer::~DevicePairBuffer() {
  if (p_ != nullptr) (void)cudaFree(p_);
}
void DevicePairBuffer::reserve(std::size_t n) {
  if (n <= cap_) return;
  if (p_ != nullptr) BVH_TRY(cudaFree(p_));
  p_ = nullptr;
  cap_ = 0;
  const std::size_t want = n + n / 8;
  BVH_TRY(cudaMalloc(reinterpret_cast<void**>(&p_), want * sizeof(kdet_fcl::TrianglePair)));
  cap_ = want;
}
std::vector<kdet_fcl::TrianglePair> DevicePairBuffer::read(std::size_t n) const {
  if (n > cap_) throw std::runtime_error("gpu_bvh: DevicePairBuffer::read past the capacity");
  std::vector<kdet_fcl::TrianglePair> v(n);
  if (n > 0)
    BVH_TRY(cudaMemcpy(v.data(), p_, n * sizeof(kdet_fcl::TrianglePair), cudaMemcpyDeviceToHost));
  return v;
}

// ---- the mesh ----

template <class S>
struct GpuBvh<S>::Impl {
  std::uint32_t n = 0, nv = 0;
  Buf<Vec3<S>> v, lo, hi;
  Buf<std::uint32_t> t, range_end, leaf_tri, code, code_sorted, idx;
  Buf<int> left, right, parent;
  Buf<unsigned> flags, bnd;
  Buf<unsigned char> cub;

  TreeView<S> view() const {
    return {int(n), lo.p, hi.p, left.p, right.p, range_end.p, leaf_tri.p};
  }
  std::size_t bytes() const {
    return v.bytes() + lo.bytes() + hi.bytes() + t.bytes() + range_end.bytes() +
           leaf_tri.bytes() + code.bytes() + code_sorted.bytes() + idx.bytes() + left.bytes() +
           right.bytes() + parent.bytes() + flags.bytes() + bnd.bytes() + cub.bytes();
  }
  /// The self-query result of an unchanged mesh, kept by the same rule and code as kDet's
  /// backends (src/kept_self_result.h; KDET_FCL_CUDA_SELF_CACHE=0 turns it off here too), so
  /// both sides of the comparison skip the same work. `geometry` counts the setMesh,
  /// updateVertices and rebuildVertices calls.
  std::uint64_t geometry = 0;
  kdet_fcl::detail::KeptSelfResult kept_self{"KDET_FCL_CUDA_SELF_CACHE"};
  void newGeometry() {
    ++geometry;
    kept_self.drop();
  }
  /// Pinned staging of this mesh's uploads (per mesh: two meshes' uploads can be in flight) and
  /// an event after its last transfer, which the next upload waits for before it rewrites it.
  Pinned staging;
  cudaEvent_t staged = nullptr;
  /// setStableSources: the caller's vertex arrays, registered as page-locked memory on their
  /// first upload (nullptr: refused), dropped with this tree after its last transfer.
  bool stable_sources = false;
  std::map<const void*, std::shared_ptr<void>> pins;
  ~Impl() {
    if (staged != nullptr) {
      (void)cudaEventSynchronize(staged);  // no transfer from a registered array in flight
      (void)cudaEventDestroy(staged);
    }
    pins.clear();
  }
  /// The same copy as the kDet backend (cuda/staged_upload.h): staged by several threads, or,
  /// for arrays of staging::kPinMinBytes and up that the caller declared stable, one DMA from the
  /// array itself, registered once (the kDet backend registers its meshes' own buffers so).
  void upload(const std::vector<Vec3<S>>& vertices) {
    if (vertices.size() != nv) throw std::invalid_argument("gpu_bvh: vertex count changed");
    const std::size_t bytes = vertices.size() * sizeof(Vec3<S>);
    if (staged == nullptr) BVH_TRY(cudaEventCreateWithFlags(&staged, cudaEventDisableTiming));
    BVH_TRY(cudaEventSynchronize(staged));
    bool pinned = false;
    if (stable_sources && bytes >= kdet_fcl::staging::kPinMinBytes &&
        kdet_fcl::staging::pinVerticesOn()) {
      auto it = pins.find(vertices.data());
      if (it == pins.end())
        it = pins.emplace(vertices.data(),
                          kdet_fcl::staging::pinHostMemory(vertices.data(), bytes)).first;
      pinned = it->second != nullptr;
    }
    void* h = staging.reserve(bytes);
    BVH_TRY(pinned ? kdet_fcl::staging::pinnedUpload(v.p, vertices.data(), bytes, h, 0)
                   : kdet_fcl::staging::stagedUpload(v.p, vertices.data(), bytes, h, 0));
    BVH_TRY(cudaEventRecord(staged, 0));
  }
  void refit() {
    if (n == 0) return;
    if (n > 1) BVH_TRY(cudaMemsetAsync(flags.p, 0, (n - 1) * sizeof(unsigned), 0));
    refitKernel<S><<<blocks(n), kBlock>>>(n, v.p, t.p, leaf_tri.p, parent.p, left.p, right.p,
                                          lo.p, hi.p, flags.p);
    BVH_LAUNCHED();
  }
  void build() {
    if (n == 0) return;
    const unsigned init[6] = {~0u, ~0u, ~0u, 0u, 0u, 0u};
    BVH_TRY(cudaMemcpyAsync(bnd.p, init, sizeof init, cudaMemcpyHostToDevice, 0));
    boundsKernel<S><<<blocks(n), kBlock>>>(n, v.p, t.p, bnd.p);
    BVH_LAUNCHED();
    mortonKernel<S><<<blocks(n), kBlock>>>(n, v.p, t.p, bnd.p, code.p, idx.p);
    BVH_LAUNCHED();
    std::size_t temp = 0;
    BVH_TRY(cub::DeviceRadixSort::SortPairs(nullptr, temp, code.p, code_sorted.p, idx.p,
                                            leaf_tri.p, int(n), 0, 30, 0));
    cub.reserve(temp);
    BVH_TRY(cub::DeviceRadixSort::SortPairs(cub.p, temp, code.p, code_sorted.p, idx.p,
                                            leaf_tri.p, int(n), 0, 30, 0));
    if (n > 1) {
      hierarchyKernel<<<blocks(n - 1), kBlock>>>(int(n), code_sorted.p, left.p, right.p,
                                                 parent.p, range_end.p);
      BVH_LAUNCHED();
    } else {
      const int none = -1;
      BVH_TRY(cudaMemcpyAsync(parent.p, &none, sizeof none, cudaMemcpyHostToDevice, 0));
    }
    refit();
  }
};

template <class S>
GpuBvh<S>::GpuBvh() : impl_(new Impl) {}
template <class S>
GpuBvh<S>::~GpuBvh() = default;

template <class S>
void GpuBvh<S>::setMesh(const kdet_fcl::TriangleMesh<S>& mesh) {
  Impl& m = *impl_;
  m.newGeometry();
  m.n = std::uint32_t(mesh.triangles.size());
  m.nv = std::uint32_t(mesh.vertices.size());
  const std::size_t nodes = m.n == 0 ? 1 : 2 * std::size_t(m.n) - 1;
  m.v.reserve(m.nv);
  m.t.reserve(3 * std::size_t(m.n));
  m.lo.reserve(nodes);
  m.hi.reserve(nodes);
  m.left.reserve(m.n);
  m.right.reserve(m.n);
  m.range_end.reserve(m.n);
  m.flags.reserve(m.n);
  m.parent.reserve(nodes);
  m.leaf_tri.reserve(m.n);
  m.code.reserve(m.n);
  m.code_sorted.reserve(m.n);
  m.idx.reserve(m.n);
  m.bnd.reserve(6);
  if (m.nv > 0)
    BVH_TRY(cudaMemcpy(m.v.p, mesh.vertices.data(), m.nv * sizeof(Vec3<S>),
                       cudaMemcpyHostToDevice));
  if (m.n > 0)
    BVH_TRY(cudaMemcpy(m.t.p, mesh.triangles.data(), 3 * std::size_t(m.n) * sizeof(std::uint32_t),
                       cudaMemcpyHostToDevice));
  g_timer.begin();
  m.build();
  g_timer.mark(&g_timer.t.build_ms);
  g_timer.end();
  BVH_TRY(cudaDeviceSynchronize());
}

template <class S>
void GpuBvh<S>::setStableSources(bool on) {
  impl_->stable_sources = on;
}

template <class S>
void GpuBvh<S>::updateVertices(const std::vector<Vec3<S>>& vertices) {
  impl_->newGeometry();
  g_timer.begin();
  impl_->upload(vertices);
  g_timer.mark(&g_timer.t.upload_ms);
  impl_->refit();
  g_timer.mark(&g_timer.t.refit_ms);
  g_timer.end();
}

template <class S>
void GpuBvh<S>::rebuildVertices(const std::vector<Vec3<S>>& vertices) {
  impl_->newGeometry();
  g_timer.begin();
  impl_->upload(vertices);
  g_timer.mark(&g_timer.t.upload_ms);
  impl_->build();
  g_timer.mark(&g_timer.t.build_ms);
  g_timer.end();
}

template <class S>
std::size_t GpuBvh<S>::numTriangles() const {
  return impl_->n;
}
template <class S>
std::size_t GpuBvh<S>::deviceBytes() const {
  return impl_->bytes();
}

// ---- query driver ----

namespace {

/// Runs traverse() then exact() until neither buffer overflowed, then sorts and copies the pairs.
template <class Traverse, class Exact>
std::vector<TrianglePair> runQuery(std::size_t n_hint, int a_bits, Traverse traverse,
                                   Exact exact, std::vector<TrianglePair>* keep) {
  Scratch& s = scratch();
  if (s.cand_cap == 0) {
    s.cand_cap = std::max<std::size_t>(1 << 16, 4 * n_hint);
    s.pair_cap = std::max<std::size_t>(1 << 14, n_hint);
  }
  if (s.forced_cap > 0) s.cand_cap = s.pair_cap = s.forced_cap;
  s.counters.reserve(2);
  auto* hc = static_cast<unsigned long long*>(s.host_counters.reserve(2 * sizeof(long long)));
  unsigned long long nc = 0, np = 0;
  for (int pass = 0;; ++pass) {
    s.cand.reserve(s.cand_cap);
    s.pairs.reserve(s.pair_cap);
    BVH_TRY(cudaMemsetAsync(s.counters.p, 0, 2 * sizeof(unsigned long long), 0));
    traverse(Sink{s.cand.p, s.counters.p, s.cand_cap});
    g_timer.mark(&g_timer.t.traverse_ms);
    exact(s.cand.p, s.counters.p, s.cand_cap, Sink{s.pairs.p, s.counters.p + 1, s.pair_cap});
    BVH_TRY(cudaMemcpyAsync(hc, s.counters.p, 2 * sizeof(unsigned long long),
                            cudaMemcpyDeviceToHost, 0));
    BVH_TRY(cudaStreamSynchronize(0));
    g_timer.mark(&g_timer.t.exact_ms);
    nc = hc[0];
    np = hc[1];
    g_timer.t.passes++;
    if (nc <= s.cand_cap && np <= s.pair_cap) break;
    if (nc > s.cand_cap) s.cand_cap = nc + nc / 4;
    if (np > s.pair_cap) s.pair_cap = np + np / 4;
    s.forced_cap = 0;
  }
  g_timer.t.candidates += nc;
  if (s.forced_cap == 0) {  // next time: start from what this query needed
    s.cand_cap = std::max<std::size_t>(s.cand_cap, nc + nc / 4);
    s.pair_cap = std::max<std::size_t>(s.pair_cap, np + np / 4);
  }
  std::vector<TrianglePair> out;
  if (keep != nullptr) out = std::move(*keep);  // the caller's storage (its pairs replaced)
  if (np == 0) out.clear();
  if (np > 0) {
    s.sorted.reserve(np);
    s.unpacked.reserve(np);
    std::size_t temp = 0;
    const int end_bit = 32 + a_bits;
    BVH_TRY(cub::DeviceRadixSort::SortKeys(nullptr, temp, s.pairs.p, s.sorted.p, int(np), 0,
                                           end_bit, 0));
    s.cub.reserve(temp);
    BVH_TRY(cub::DeviceRadixSort::SortKeys(s.cub.p, temp, s.pairs.p, s.sorted.p, int(np), 0,
                                           end_bit, 0));
    unpackKernel<<<blocks(np, 256), 256>>>(std::uint32_t(np), s.sorted.p, s.unpacked.p);
    BVH_LAUNCHED();
    static_assert(sizeof(TrianglePair) == sizeof(uint2), "TrianglePair layout");
    // The backend's read-back (cuda/staged_upload.h), so both pay the same transfer.
    auto* h = static_cast<TrianglePair*>(s.host_pairs.reserve(np * sizeof(uint2)));
    // Into the kept storage by several threads where that pays, as the backend's results kept
    // across frames; a new result's empty vector goes by one thread.
    BVH_TRY(kdet_fcl::staging::downloadInto(reinterpret_cast<const TrianglePair*>(s.unpacked.p),
                                            np, h, 0, s.copy_pool, out));
  }
  g_timer.mark(&g_timer.t.output_ms);
  return out;
}

unsigned exactGrid(std::size_t cap) {
  return unsigned(std::min<std::size_t>(blocks(cap), std::size_t(scratch().sms) * 16));
}

template <class F>
void withKernel(Predicate p, F&& f) {
  switch (p) {
    case Predicate::Double:
      f(kdet_fcl::detail::PlainKernel<double>{});
      break;
    case Predicate::Float:
      f(kdet_fcl::detail::PlainKernel<float>{});
      break;
    default:
      f(kdet_fcl::detail::ExactKernel{});
  }
}

}  // namespace

template <class S>
std::vector<TrianglePair> intersect(GpuBvh<S>& A, const kdet_fcl::Transform<S>& pose_a,
                                    GpuBvh<S>& B, const kdet_fcl::Transform<S>& pose_b,
                                    Predicate predicate, std::vector<TrianglePair>* keep) {
  auto& a = A.impl();
  auto& b = B.impl();
  if (a.n == 0 || b.n == 0) return {};
  const kdet_fcl::detail::RelativePose rp = kdet_fcl::detail::relativePose(pose_a, pose_b);
  g_timer.begin();
  Scratch& s = scratch();
  const Vec3<S>* va = a.v.p;
  if (!rp.identity) {
    s.mapped.reserve(std::size_t(a.nv) * sizeof(Vec3<S>));
    auto* mv = reinterpret_cast<Vec3<S>*>(s.mapped.p);
    mapKernel<S><<<blocks(a.nv), kBlock>>>(a.nv, a.v.p, rp.a_to_b, mv);
    BVH_LAUNCHED();
    va = mv;
  }
  // The query side walks the other side's tree: A (mapped) down B's tree, or, for the identity,
  // the smaller mesh down the larger one's tree.
  const bool swap = rp.identity && b.n < a.n;
  std::vector<TrianglePair> out;
  withKernel(predicate, [&](auto k) {
    using K = decltype(k);
    out = runQuery(
        std::max(a.n, b.n), bitsFor(a.n - 1),
        [&](Sink cand) {
          if (!swap)
            interTraverseKernel<S><<<blocks(a.n), kBlock>>>(a.n, a.leaf_tri.p, va, a.t.p,
                                                            b.view(), false, cand);
          else
            interTraverseKernel<S><<<blocks(b.n), kBlock>>>(b.n, b.leaf_tri.p, b.v.p, b.t.p,
                                                            a.view(), true, cand);
          BVH_LAUNCHED();
        },
        [&](const unsigned long long* cand, const unsigned long long* count,
            unsigned long long cap, Sink out_sink) {
          interExactKernel<S, K><<<exactGrid(cap), kBlock>>>(cand, count, cap, va, a.t.p, b.v.p,
                                                             b.t.p, out_sink);
          BVH_LAUNCHED();
        },
        keep);
  });
  g_timer.end();
  return out;
}

template <class S>
std::vector<TrianglePair> intersectSelf(GpuBvh<S>& M, Predicate predicate, std::uint32_t split,
                                        std::vector<TrianglePair>* keep) {
  auto& m = M.impl();
  if (m.n < 2) return {};
  kdet_fcl::QueryOptions options;
  options.predicate = predicate;
  kdet_fcl::detail::KeptSelfResult::Ticket ticket;
  kdet_fcl::QueryResult kept;
  if (keep != nullptr) kept.pairs = std::move(*keep);  // (a kept result is copied into it)
  // (A kept result is of the tree as one mesh: split queries neither use nor keep one.)
  if (split == 0 && m.kept_self.find(m.geometry, options, &kept, &ticket))
    return std::move(kept.pairs);
  g_timer.begin();
  std::vector<TrianglePair> out;
  withKernel(predicate, [&](auto k) {
    using K = decltype(k);
    out = runQuery(
        m.n, bitsFor(m.n - 1),
        [&](Sink cand) {
          selfTraverseKernel<S><<<blocks(m.n), kBlock>>>(m.view(), m.t.p, cand);
          BVH_LAUNCHED();
        },
        [&](const unsigned long long* cand, const unsigned long long* count,
            unsigned long long cap, Sink out_sink) {
          selfExactKernel<S, K><<<exactGrid(cap), kBlock>>>(cand, count, cap, m.v.p, m.t.p,
                                                            split, out_sink);
          BVH_LAUNCHED();
        },
        keep != nullptr ? &kept.pairs : nullptr);
  });
  g_timer.end();
  if (split == 0 && ticket.keep) {
    kdet_fcl::QueryResult r;
    r.pairs = out;
    m.kept_self.offer(ticket, options, r);
  }
  return out;
}

#define KDET_BVH_INSTANTIATE(S)                                                              \
  template class GpuBvh<S>;                                                                  \
  template std::vector<TrianglePair> intersect<S>(GpuBvh<S>&, const kdet_fcl::Transform<S>&, \
                                                  GpuBvh<S>&, const kdet_fcl::Transform<S>&, \
                                                  Predicate, std::vector<TrianglePair>*);    \
  template std::vector<TrianglePair> intersectSelf<S>(GpuBvh<S>&, Predicate, std::uint32_t,  \
                                                      std::vector<TrianglePair>*);
KDET_BVH_INSTANTIATE(float)
KDET_BVH_INSTANTIATE(double)

}  // namespace kdet_bvh
