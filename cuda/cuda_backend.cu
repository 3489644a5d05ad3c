// The CUDA query backend (see cuda_backend.h for the contract).
//
// Per mesh (on a new version only): upload -> per-triangle box/diameter + grid reduction ->
// grid (one thread, the CPU's formulas) -> level + cell count per triangle -> triangles ordered
// by decreasing diameter (32-bit radix sort) -> exclusive scan -> [one host read-back: the grid
// and the entry count] -> (cell key, triangle) entries -> CUB radix sort by cell key (stable, so
// each cell lists its triangles by decreasing diameter) -> run heads -> cells + open-addressing
// table of full keys.
// Per query: relative pose (host, as on the CPU) -> A's vertices mapped into B's frame ->
// phase 1, a tile of G lanes per query triangle: cells of its level and every coarser one, size
// rule (with early exit), box overlap, canonical cell -> candidate pairs -> phase 2, one thread
// per candidate: the exact test -> pairs appended with warp-aggregated atomics -> [host read-back
// of both counts; on overflow grow and rerun] -> radix sort of the pairs -> device->host copy.
// benchmarks/RESULTS-gpu.md has the measurements behind these choices.

#include <cooperative_groups.h>
#include <cuda_runtime_api.h>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdlib>
#include <cstring>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <vector>

#include "cuda_backend.h"
#include "cuda_error.cuh"
#include "device_hash.cuh"
#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/enclosing_sphere.h"
#include "kdet_fcl/detail/hierarchy.h"
#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "kdet_fcl/errors.h"

namespace cg = cooperative_groups;

namespace kdet_fcl {
namespace cuda {
namespace {

using detail::Aabb;
using detail::CellKey;
using detail::GridParams;

constexpr int kBuildBlock = 256;
constexpr int kQueryBlock = 128;
constexpr std::size_t kMaxCachedMeshes = 32;

// ---------------------------------------------------------------------------------------------
// Build kernels
// ---------------------------------------------------------------------------------------------

/// Order-preserving map of a double onto unsigned 64 bits, so atomicMin/atomicMax on integers
/// reduce doubles exactly (min/max never round, so the result is the CPU's).
__device__ __forceinline__ unsigned long long orderedBits(double x) {
  const unsigned long long b = static_cast<unsigned long long>(__double_as_longlong(x));
  return (b >> 63) ? ~b : (b | 0x8000000000000000ull);
}
__device__ __forceinline__ double fromOrderedBits(unsigned long long u) {
  const unsigned long long b = (u >> 63) ? (u & 0x7FFFFFFFFFFFFFFFull) : ~u;
  return __longlong_as_double(static_cast<long long>(b));
}

/// Grid-wide reduction targets: min of box lo and of positive diameters (initialised to all ones),
/// max of box hi and of diameters (initialised to zero), as orderedBits.
struct BuildReduce {
  unsigned long long lo[3], dmin_pos;  // min
  unsigned long long hi[3], dmax;      // max
};

__device__ __forceinline__ double warpMin(double v) {
  for (int o = 16; o > 0; o >>= 1) v = fmin(v, __shfl_xor_sync(0xFFFFFFFFu, v, o));
  return v;
}
__device__ __forceinline__ double warpMax(double v) {
  for (int o = 16; o > 0; o >>= 1) v = fmax(v, __shfl_xor_sync(0xFFFFFFFFu, v, o));
  return v;
}

/// Per triangle: exact box and enclosing diameter (the CPU's functions); per grid: bounds and
/// diameter range. Grid-stride with a bounded grid, so the atomics stay few.
template <class S>
__global__ void __launch_bounds__(kBuildBlock)
    trianglesKernel(std::uint32_t n, const Vec3<S>* __restrict__ v,
                    const std::uint32_t* __restrict__ t, Aabb<S>* __restrict__ box,
                    double* __restrict__ diam, BuildReduce* red) {
  const double inf = __longlong_as_double(0x7FF0000000000000ll);
  double m[8] = {inf, inf, inf, inf, -inf, -inf, -inf, -inf};  // lo xyz, dmin_pos, hi xyz, dmax
  for (std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n;
       i += gridDim.x * blockDim.x) {
    const Vec3<S> p = v[t[3 * i]], q = v[t[3 * i + 1]], r = v[t[3 * i + 2]];
    const Aabb<S> b = detail::triangleBox<S>(p, q, r);
    const double d = detail::enclosingDiameter(p, q, r);
    box[i] = b;
    diam[i] = d;
    m[0] = fmin(m[0], double(b.lo.x));
    m[1] = fmin(m[1], double(b.lo.y));
    m[2] = fmin(m[2], double(b.lo.z));
    if (d > 0) m[3] = fmin(m[3], d);
    m[4] = fmax(m[4], double(b.hi.x));
    m[5] = fmax(m[5], double(b.hi.y));
    m[6] = fmax(m[6], double(b.hi.z));
    m[7] = fmax(m[7], d);
  }
  __shared__ double part[kBuildBlock / 32][8];
  const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
#pragma unroll
  for (int k = 0; k < 8; ++k) m[k] = k < 4 ? warpMin(m[k]) : warpMax(m[k]);
  if (lane == 0)
#pragma unroll
    for (int k = 0; k < 8; ++k) part[warp][k] = m[k];
  __syncthreads();
  if (threadIdx.x < 8) {
    const int k = threadIdx.x;
    double a = part[0][k];
    for (int w = 1; w < kBuildBlock / 32; ++w) a = k < 4 ? fmin(a, part[w][k]) : fmax(a, part[w][k]);
    // Empty contributions (+-inf) are harmless: the reduction of every block includes real data
    // unless n == 0, which the host never launches.
    unsigned long long* target = k < 3 ? &red->lo[k] : k == 3 ? &red->dmin_pos
                               : k < 7 ? &red->hi[k - 4] : &red->dmax;
    if (k < 4) atomicMin(target, orderedBits(a));
    else atomicMax(target, orderedBits(a));
  }
}

/// The grid, with the CPU's formulas (HierarchicalHash::build), in one thread.
__global__ void gridKernel(const BuildReduce* red, BuildInfo* info) {
  if (blockIdx.x != 0 || threadIdx.x != 0) return;
  BuildInfo in;
  for (int a = 0; a < 3; ++a) {
    in.bounds.lo[a] = fromOrderedBits(red->lo[a]);
    in.bounds.hi[a] = fromOrderedBits(red->hi[a]);
  }
  const double dmin_pos = fromOrderedBits(red->dmin_pos);  // +inf when no positive diameter
  in.d_max = fromOrderedBits(red->dmax);
  in.d_min = isfinite(dmin_pos) ? dmin_pos : 0.0;
  double extent = in.bounds.hi.x - in.bounds.lo.x;
  extent = fmax(extent, in.bounds.hi.y - in.bounds.lo.y);
  extent = fmax(extent, in.bounds.hi.z - in.bounds.lo.z);
  double cell0 = in.d_min;
  const double floor_cell = ldexp(extent, -detail::kCellRange);
  if (cell0 < floor_cell) cell0 = floor_cell;
  if (!(cell0 > 0) || !isfinite(1.0 / cell0)) cell0 = extent > 0 ? extent : 1.0;
  for (int a = 0; a < 3; ++a) in.grid.origin[a] = in.bounds.lo[a];
  in.grid.cell0 = cell0;
  in.grid.inv_cell0 = 1.0 / cell0;
  in.grid.num_levels = detail::kMaxLevels;
  in.top_level = detail::levelFor(in.d_max, in.grid);
  in.grid.num_levels = in.top_level + 1;
  // Every cell coordinate on every level is <= the level-0 coordinate of the bounds' max corner.
  std::int64_t cmax = 0;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t c = detail::cellCoordScaled(in.bounds.hi[a], a, 1.0, in.grid);
    cmax = c > cmax ? c : cmax;
  }
  in.coord_bits = cmax > 0 ? 64 - __clzll(static_cast<long long>(cmax)) : 1;
  in.level_bits = in.top_level > 0 ? 32 - __clz(in.top_level) : 1;
  in.fits64 = in.level_bits + 3 * in.coord_bits <= 64;
  in.level_mask = 0;
  *info = in;
}

/// The high 32 bits of a diameter's ordered bit pattern: monotone in the diameter, so entries
/// listed by decreasing sizeKey let a scan stop at the first entry with sizeKey(d_j) <
/// sizeKey(d_query), since every later one is strictly smaller than the query too.
__device__ __forceinline__ std::uint32_t sizeKey(double d) {
  return static_cast<std::uint32_t>(orderedBits(d) >> 32);
}

/// Level and number of covered cells of each triangle; counts[n] = 0 closes the scan.
template <class S>
__global__ void __launch_bounds__(kBuildBlock)
    countKernel(std::uint32_t n, const Aabb<S>* __restrict__ box, const double* __restrict__ diam,
                BuildInfo* info, std::uint8_t* __restrict__ level,
                std::uint32_t* __restrict__ counts, std::uint32_t* __restrict__ size_key,
                std::uint32_t* __restrict__ ids) {
  __shared__ unsigned long long mask;
  if (threadIdx.x == 0) mask = 0;
  __syncthreads();
  const GridParams g = info->grid;
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) {
    const int l = detail::levelFor(diam[i], g);
    const Aabb<S> b = box[i];
    const Aabb<double> bd{{double(b.lo.x), double(b.lo.y), double(b.lo.z)},
                          {double(b.hi.x), double(b.hi.y), double(b.hi.z)}};
    level[i] = static_cast<std::uint8_t>(l);
    counts[i] = static_cast<std::uint32_t>(detail::cellRange(bd, l, g).count());
    size_key[i] = ~sizeKey(diam[i]);  // ascending sort = decreasing diameter
    ids[i] = i;
    atomicOr(&mask, 1ull << l);
  }
  if (i == n) counts[n] = 0;
  __syncthreads();
  if (threadIdx.x == 0 && mask != 0) atomicOr(&info->level_mask, mask);
}

__device__ __forceinline__ unsigned long long compactKey(int level, std::int64_t x, std::int64_t y,
                                                         std::int64_t z, int cb) {
  return (static_cast<unsigned long long>(level) << (3 * cb)) |
         (static_cast<unsigned long long>(x) << (2 * cb)) |
         (static_cast<unsigned long long>(y) << cb) | static_cast<unsigned long long>(z);
}

/// (cell, triangle) entries. kCompact: key = compact 64-bit key (exact, bijective), value =
/// triangle. Otherwise: key = low word of the 128-bit key, hi[] = high word, value = entry index,
/// tri_of[entry] = triangle (sorted in two stable passes).
template <class S, bool kCompact>
__global__ void __launch_bounds__(kBuildBlock)
    fillKernel(std::uint32_t n, const Aabb<S>* __restrict__ box,
               const std::uint8_t* __restrict__ level, const std::uint32_t* __restrict__ offsets,
               const std::uint32_t* __restrict__ by_size, const BuildInfo* info,
               unsigned long long* __restrict__ keys, unsigned long long* __restrict__ hi,
               std::uint32_t* __restrict__ vals, std::uint32_t* __restrict__ tri_of) {
  // Triangles are laid out by decreasing diameter (rank r holds triangle by_size[r]); the stable
  // sort by cell key keeps that order inside each cell.
  const std::uint32_t rank = blockIdx.x * blockDim.x + threadIdx.x;
  if (rank >= n) return;
  const std::uint32_t i = by_size[rank];
  const GridParams g = info->grid;
  const int cb = info->coord_bits;
  const int l = level[i];
  const Aabb<S> b = box[i];
  const Aabb<double> bd{{double(b.lo.x), double(b.lo.y), double(b.lo.z)},
                        {double(b.hi.x), double(b.hi.y), double(b.hi.z)}};
  const detail::CellRange r = detail::cellRange(bd, l, g);
  std::uint32_t e = offsets[rank];
  for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
    for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
      for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z, ++e) {
        if (kCompact) {
          keys[e] = compactKey(l, x, y, z, cb);
          vals[e] = i;
        } else {
          const CellKey k = detail::makeCellKey(l, x, y, z);
          keys[e] = k.lo;
          hi[e] = k.hi;
          vals[e] = e;
          tri_of[e] = i;
        }
      }
}

/// counts in size order, closed by a 0 for the exclusive scan.
__global__ void countsBySizeKernel(std::uint32_t n, const std::uint32_t* __restrict__ counts,
                                   const std::uint32_t* __restrict__ by_size,
                                   std::uint32_t* __restrict__ out) {
  const std::uint32_t r = blockIdx.x * blockDim.x + threadIdx.x;
  if (r < n) out[r] = counts[by_size[r]];
  if (r == n) out[n] = 0;
}

__global__ void gatherKeysKernel(std::uint32_t m, const unsigned long long* __restrict__ src,
                                 const std::uint32_t* __restrict__ perm,
                                 unsigned long long* __restrict__ dst) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < m) dst[k] = src[perm[k]];
}

__global__ void gatherTrisKernel(std::uint32_t m, const std::uint32_t* __restrict__ tri_of,
                                 const std::uint32_t* __restrict__ perm,
                                 std::uint32_t* __restrict__ dst) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < m) dst[k] = tri_of[perm[k]];
}

/// head[k] = 1 where a new cell starts in the sorted entries (full-key comparison).
template <bool kCompact>
__global__ void headsKernel(std::uint32_t m, const unsigned long long* __restrict__ key,
                            const unsigned long long* __restrict__ hi,
                            std::uint32_t* __restrict__ head) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= m) return;
  bool h = k == 0 || key[k] != key[k - 1];
  if (!kCompact && k > 0) h = h || hi[k] != hi[k - 1];
  head[k] = h ? 1u : 0u;
}

/// One thread per run head: the cell's first entry, its full key, and its slot in the table.
template <bool kCompact>
__global__ void cellsKernel(std::uint32_t m, const unsigned long long* __restrict__ key,
                            const unsigned long long* __restrict__ hi,
                            const std::uint32_t* __restrict__ head,
                            const std::uint32_t* __restrict__ cell_index, const BuildInfo* info,
                            std::uint32_t* __restrict__ cell_begin, CellKey* __restrict__ cell_key,
                            unsigned long long* slots, unsigned long long slot_mask) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= m) return;
  if (k == m - 1) cell_begin[cell_index[k] + head[k]] = m;  // sentinel after the last cell
  if (!head[k]) return;
  const std::uint32_t c = cell_index[k];
  cell_begin[c] = k;
  CellKey ck;
  if (kCompact) {
    const int cb = info->coord_bits;
    const unsigned long long u = key[k];
    const unsigned long long cm = (1ull << cb) - 1;
    ck = detail::makeCellKey(static_cast<int>(u >> (3 * cb)),
                             static_cast<std::int64_t>((u >> (2 * cb)) & cm),
                             static_cast<std::int64_t>((u >> cb) & cm),
                             static_cast<std::int64_t>(u & cm));
  } else {
    ck = CellKey{hi[k], key[k]};
  }
  cell_key[c] = ck;
  const unsigned long long h = detail::hashCellKey(ck);
  const unsigned long long val = ((h >> 32) << 32) | c;
  unsigned long long s = h & slot_mask;
  // Keys are unique (one thread per cell), so the first empty slot is ours.
  while (atomicCAS(&slots[s], kEmptySlot, val) != kEmptySlot) s = (s + 1) & slot_mask;
}

// ---------------------------------------------------------------------------------------------
// Query kernels
// ---------------------------------------------------------------------------------------------

/// Where pairs go: key (a << b_bits) | b (so a radix sort on b_bits + a_bits bits sorts (a, b)),
/// appended at an atomic counter; slots past `capacity` are counted but not written, so the host
/// sees count > capacity, grows the buffer and reruns: no pair is ever dropped.
struct PairSink {
  unsigned long long* pairs;
  unsigned long long* count;
  unsigned long long capacity;
  int b_bits;
};

__device__ __forceinline__ void emitPair(const PairSink& out, std::uint32_t a, std::uint32_t b) {
  // One atomic per group of threads emitting together (they are usually a warp's worth).
  cg::coalesced_group g = cg::coalesced_threads();
  unsigned long long base = 0;
  if (g.thread_rank() == 0) base = atomicAdd(out.count, static_cast<unsigned long long>(g.size()));
  base = g.shfl(base, 0);
  const unsigned long long idx = base + g.thread_rank();
  if (idx < out.capacity)
    out.pairs[idx] = (static_cast<unsigned long long>(a) << out.b_bits) | b;
}

template <class S>
__global__ void mapVerticesKernel(std::uint32_t n, const Vec3<S>* __restrict__ v,
                                  Transform<double> a_to_b, Vec3<S>* __restrict__ out) {
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) out[i] = detail::mapPoint(a_to_b, v[i]);
}


/// Phase 1 of an inter-object query: candidate pairs (i of A, j of B) that pass the size rule,
/// the box test and the canonical-cell test, appended to `cand` as (i << 32) | j. Threads
/// [0, na): A's triangle i against B's triangles with d_j >= d_i (looked up in B's frame with A's
/// mapped box). Threads [na, na + nb): B's triangle j against A's triangles with d_i > d_j (looked
/// up in A's frame with B's box mapped back and grown by eps). The exact tests run in phase 2,
/// one thread per candidate, so a warp does not serialise them behind its busiest thread.
template <class S, int G, int MB>
__global__ void __launch_bounds__(kQueryBlock, MB)
    interCandidatesKernel(HashView<S> A, HashView<S> B, const Vec3<S>* __restrict__ va,
                          std::uint32_t na, std::uint32_t nb, bool identity,
                          Transform<double> b_to_a, double eps, PairSink cand) {
  // One tile of G lanes per query triangle (tile-uniform index).
  const auto tile = cg::tiled_partition<G>(cg::this_thread_block());
  const auto idx = static_cast<std::uint32_t>(
      (static_cast<unsigned long long>(blockIdx.x) * blockDim.x + threadIdx.x) / G);
  if (idx < na) {
    const std::uint32_t i = idx;
    const double di = A.diam[i];
    if (di > B.d_max) return;  // nothing in B is as large
    const Aabb<double> q =
        detail::triangleBox<double>(va[A.t[3 * i]], va[A.t[3 * i + 1]], va[A.t[3 * i + 2]]);
    scanCandidatesGroup(
        B, q, di, tile, [&](std::uint32_t, double dj) { return dj >= di; },
        [&](std::uint32_t j) { emitPair(cand, i, j); });
  } else if (idx < na + nb) {
    const std::uint32_t j = idx - na;
    const double dj = B.diam[j];
    if (dj >= A.d_max) return;  // nothing in A is strictly larger
    Aabb<double> q;
    if (identity) {
      q = boxOf(B, j);
    } else {
      Vec3<double> p[3];
      for (int k = 0; k < 3; ++k) {
        const Vec3<S> w = B.v[B.t[3 * j + k]];
        p[k] = b_to_a.apply(Vec3<double>{double(w.x), double(w.y), double(w.z)});
      }
      q = detail::inflate(detail::triangleBox<double>(p[0], p[1], p[2]), eps);
    }
    scanCandidatesGroup(
        A, q, dj, tile, [&](std::uint32_t, double di) { return di > dj; },
        [&](std::uint32_t i) { emitPair(cand, i, j); });
  }
}

/// Phase 1 of a self query: triangle i against the triangles j with (d_j, j) > (d_i, i).
template <class S, int G, int MB>
__global__ void __launch_bounds__(kQueryBlock, MB)
    selfCandidatesKernel(HashView<S> M, std::uint32_t n, PairSink cand) {
  const auto tile = cg::tiled_partition<G>(cg::this_thread_block());
  const auto i = static_cast<std::uint32_t>(
      (static_cast<unsigned long long>(blockIdx.x) * blockDim.x + threadIdx.x) / G);
  if (i >= n) return;
  const double di = M.diam[i];
  const std::uint32_t ti[3] = {M.t[3 * i], M.t[3 * i + 1], M.t[3 * i + 2]};
  const Vec3<S> vi[3] = {M.v[ti[0]], M.v[ti[1]], M.v[ti[2]]};
  scanCandidatesGroup(
      M, boxOf(M, i), di, tile,
      [&](std::uint32_t j, double dj) { return dj > di || (dj == di && j > i); },
      [&](std::uint32_t j) {
        // Adjacent pairs (a shared vertex index or coordinate) never reach phase 2: on a
        // connected mesh they are most of the box-overlapping pairs.
        const std::uint32_t tj[3] = {M.t[3 * j], M.t[3 * j + 1], M.t[3 * j + 2]};
        bool adjacent = false;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) adjacent = adjacent || ti[a] == tj[b];
        if (!adjacent) {
          const Vec3<S> vj[3] = {M.v[tj[0]], M.v[tj[1]], M.v[tj[2]]};
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) adjacent = adjacent || vi[a] == vj[b];
        }
        if (!adjacent) emitPair(cand, i, j);
      });
}

/// Phase 2: the exact test of each candidate (grid-stride over the device-side count, so the
/// host needs no read-back between the phases). Every test uses A's vertices mapped into B's
/// frame (`va`) and B's own vertices, as on the CPU.
template <class S, class K>
__global__ void __launch_bounds__(kQueryBlock)
    interExactKernel(const unsigned long long* __restrict__ cand, const unsigned long long* count,
                     unsigned long long capacity, const Vec3<S>* __restrict__ va,
                     const std::uint32_t* __restrict__ ta, const Vec3<S>* __restrict__ vb,
                     const std::uint32_t* __restrict__ tb, PairSink out) {
  const unsigned long long m = *count < capacity ? *count : capacity;
  for (unsigned long long k = blockIdx.x * blockDim.x + threadIdx.x; k < m;
       k += gridDim.x * blockDim.x) {
    const unsigned long long c = cand[k];
    const auto i = static_cast<std::uint32_t>(c >> 32), j = static_cast<std::uint32_t>(c);
    if (detail::trianglesIntersectWith<K>(va[ta[3 * i]], va[ta[3 * i + 1]], va[ta[3 * i + 2]],
                                          vb[tb[3 * j]], vb[tb[3 * j + 1]], vb[tb[3 * j + 2]]))
      emitPair(out, i, j);
  }
}

/// Phase 2 of a self query: pairs sharing a vertex (index or coordinates) are adjacent, not
/// colliding; the others get the exact test. Emits (min, max).
template <class S, class K>
__global__ void __launch_bounds__(kQueryBlock)
    selfExactKernel(const unsigned long long* __restrict__ cand, const unsigned long long* count,
                    unsigned long long capacity, const Vec3<S>* __restrict__ v,
                    const std::uint32_t* __restrict__ t, PairSink out) {
  const unsigned long long m = *count < capacity ? *count : capacity;
  for (unsigned long long k = blockIdx.x * blockDim.x + threadIdx.x; k < m;
       k += gridDim.x * blockDim.x) {
    const unsigned long long c = cand[k];
    const auto i = static_cast<std::uint32_t>(c >> 32), j = static_cast<std::uint32_t>(c);
    const std::uint32_t ti[3] = {t[3 * i], t[3 * i + 1], t[3 * i + 2]};
    const std::uint32_t tj[3] = {t[3 * j], t[3 * j + 1], t[3 * j + 2]};
    const Vec3<S> vi[3] = {v[ti[0]], v[ti[1]], v[ti[2]]};
    const Vec3<S> vj[3] = {v[tj[0]], v[tj[1]], v[tj[2]]};
    bool adjacent = false;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) adjacent = adjacent || ti[a] == tj[b] || vi[a] == vj[b];
    if (!adjacent &&
        detail::trianglesIntersectWith<K>(vi[0], vi[1], vi[2], vj[0], vj[1], vj[2]))
      emitPair(out, i < j ? i : j, i < j ? j : i);
  }
}

/// Sorted keys -> TrianglePair layout {a, b} (two 32-bit words), in place of the unsorted keys.
__global__ void unpackPairsKernel(std::uint32_t m, const unsigned long long* __restrict__ keys,
                                  int b_bits, uint2* __restrict__ out) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= m) return;
  const unsigned long long u = keys[k];
  out[k] = make_uint2(static_cast<unsigned int>(u >> b_bits),
                      static_cast<unsigned int>(u & ((1ull << b_bits) - 1)));
}

// ---------------------------------------------------------------------------------------------
// Host side: cached meshes, scratch, orchestration
// ---------------------------------------------------------------------------------------------

inline unsigned int blocksFor(unsigned long long n, int block) {
  return static_cast<unsigned int>((n + block - 1) / block);
}

inline int bitsFor(std::size_t n) {  // bits to hold values 0 .. n-1 (at least 1)
  int b = 1;
  while (b < 32 && (std::size_t(1) << b) < n) ++b;
  return b;
}

inline void checkLaunch() { CUDA_TRY(cudaGetLastError()); }

/// Pinned host memory (for the small read-backs and the vertex upload staging).
class PinnedBuffer {
 public:
  PinnedBuffer() = default;
  PinnedBuffer(const PinnedBuffer&) = delete;
  PinnedBuffer& operator=(const PinnedBuffer&) = delete;
  ~PinnedBuffer() { release(); }
  void reserve(std::size_t bytes) {
    if (bytes <= cap_ && p_ != nullptr) return;
    release();
    const std::size_t want = bytes + bytes / 8 + 64;
    CUDA_TRY(cudaMallocHost(&p_, want));
    cap_ = want;
  }
  void release() noexcept {
    if (p_ != nullptr) (void)cudaFreeHost(p_);
    p_ = nullptr;
    cap_ = 0;
  }
  void* data() const { return p_; }

 private:
  void* p_ = nullptr;
  std::size_t cap_ = 0;
};

/// One HashedMesh's device state.
template <class S>
struct CachedMesh {
  const void* owner = nullptr;
  std::uint64_t version = 0;
  std::uint64_t fingerprint = 0;
  std::size_t nv = 0, nt = 0;
  bool valid = false;  // false: the next use rebuilds
  bool force_vertices = false;
  std::vector<Triangle> host_tris;  // what the device triangles hold (topology check)

  DeviceBuffer<Vec3<S>> v;
  DeviceBuffer<std::uint32_t> t;
  DeviceBuffer<Aabb<S>> box;
  DeviceBuffer<double> diam;
  DeviceBuffer<std::uint8_t> level;
  DeviceBuffer<std::uint32_t> entry_tri, cell_begin;
  DeviceBuffer<CellKey> cell_key;
  DeviceBuffer<unsigned long long> slots;
  unsigned long long slot_mask = 0;
  std::uint64_t entries = 0;
  BuildInfo info{};

  HashView<S> view() const {
    HashView<S> h;
    h.v = v.data();
    h.t = t.data();
    h.box = box.data();
    h.diam = diam.data();
    h.entry_tri = entry_tri.data();
    h.cell_begin = cell_begin.data();
    h.cell_key = cell_key.data();
    h.slots = slots.data();
    h.slot_mask = slot_mask;
    h.grid = info.grid;
    h.bounds = info.bounds;
    h.level_mask = info.level_mask;
    h.top_level = info.top_level;
    h.d_max = info.d_max;
    return h;
  }
  std::size_t bytes() const {
    return v.bytes() + t.bytes() + box.bytes() + diam.bytes() + level.bytes() +
           entry_tri.bytes() + cell_begin.bytes() + cell_key.bytes() + slots.bytes();
  }
};

/// A cheap identity check on top of (address, version): sizes, array addresses and a sample of
/// the contents, so that a new HashedMesh at a freed one's address is almost surely noticed.
template <class S>
std::uint64_t fingerprintOf(const TriangleMesh<S>& m) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](const void* p, std::size_t n) {
    const unsigned char* c = static_cast<const unsigned char*>(p);
    for (std::size_t k = 0; k < n; ++k) h = (h ^ c[k]) * 1099511628211ull;
  };
  const std::size_t nv = m.vertices.size(), nt = m.triangles.size();
  const void* pv = m.vertices.data();
  const void* pt = m.triangles.data();
  mix(&nv, sizeof nv);
  mix(&nt, sizeof nt);
  mix(&pv, sizeof pv);
  mix(&pt, sizeof pt);
  const std::size_t samples = 64;
  for (std::size_t k = 0; k < samples && nv > 0; ++k) mix(&m.vertices[k * nv / samples], sizeof(Vec3<S>));
  for (std::size_t k = 0; k < samples && nt > 0; ++k) mix(&m.triangles[k * nt / samples], sizeof(Triangle));
  return h;
}

struct Context {
  std::mutex mutex;
  bool ready = false;
  cudaStream_t stream = nullptr;
  cudaEvent_t ev[6] = {};
  bool profiling = false;
  QueryProfile profile;

  // Scratch shared by all builds and queries (serialised by the mutex).
  DeviceBuffer<unsigned char> cub_temp;
  DeviceBuffer<BuildReduce> red;
  DeviceBuffer<BuildInfo> info;
  DeviceBuffer<std::uint32_t> counts, offsets;
  DeviceBuffer<unsigned long long> keys_a, keys_b, hi_a, hi_b;
  DeviceBuffer<std::uint32_t> vals_a, vals_b, tri_of, head, cell_index;
  DeviceBuffer<std::uint32_t> size_key, size_key_sorted, ids, by_size, counts_by_size;
  DeviceBuffer<Vec3<float>> mapped_f;
  DeviceBuffer<Vec3<double>> mapped_d;
  DeviceBuffer<unsigned long long> cands, pairs, pairs_sorted, pair_count;  // pair_count: 2
  PinnedBuffer host_small;  // BuildInfo + entry total + pair count
  PinnedBuffer staging;     // vertex/triangle uploads
  PinnedBuffer readback;    // sorted pairs on their way into the result

  std::list<CachedMesh<float>> meshes_f;
  std::list<CachedMesh<double>> meshes_d;

  std::list<CachedMesh<float>>& meshes(float*) { return meshes_f; }
  std::list<CachedMesh<double>>& meshes(double*) { return meshes_d; }
  DeviceBuffer<Vec3<float>>& mapped(float*) { return mapped_f; }
  DeviceBuffer<Vec3<double>>& mapped(double*) { return mapped_d; }

  void init() {
    if (ready) return;
    CUDA_TRY(cudaSetDevice(0));
    CUDA_TRY(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
    for (cudaEvent_t& e : ev) CUDA_TRY(cudaEventCreate(&e));
    red.reserve(1);
    info.reserve(1);
    pair_count.reserve(2);
    host_small.reserve(sizeof(BuildInfo) + 3 * sizeof(unsigned long long));
    ready = true;
  }

  BuildInfo* hostInfo() { return static_cast<BuildInfo*>(host_small.data()); }
  unsigned long long* hostTotal() {
    return reinterpret_cast<unsigned long long*>(static_cast<char*>(host_small.data()) +
                                                 sizeof(BuildInfo));
  }
  unsigned long long* hostCount() { return hostTotal() + 1; }

  /// Drops all device memory without throwing (after a CUDA error, or on request): the next
  /// call re-uploads what it needs.
  void releaseAll() noexcept {
    meshes_f.clear();
    meshes_d.clear();
    cub_temp.release();
    counts.release();
    offsets.release();
    keys_a.release();
    keys_b.release();
    hi_a.release();
    hi_b.release();
    vals_a.release();
    vals_b.release();
    tri_of.release();
    head.release();
    cell_index.release();
    size_key.release();
    size_key_sorted.release();
    ids.release();
    by_size.release();
    counts_by_size.release();
    mapped_f.release();
    mapped_d.release();
    cands.release();
    pairs.release();
    pairs_sorted.release();
    staging.release();
    readback.release();
  }

  std::size_t bytes() const {
    std::size_t b = cub_temp.bytes() + red.bytes() + info.bytes() + counts.bytes() +
                    offsets.bytes() + keys_a.bytes() + keys_b.bytes() + hi_a.bytes() +
                    hi_b.bytes() + vals_a.bytes() + vals_b.bytes() + tri_of.bytes() +
                    head.bytes() + cell_index.bytes() + size_key.bytes() +
                    size_key_sorted.bytes() + ids.bytes() + by_size.bytes() +
                    counts_by_size.bytes() + mapped_f.bytes() + mapped_d.bytes() +
                    cands.bytes() + pairs.bytes() + pairs_sorted.bytes() + pair_count.bytes();
    for (const auto& m : meshes_f) b += m.bytes();
    for (const auto& m : meshes_d) b += m.bytes();
    return b;
  }

  void record(int k) {
    if (profiling) CUDA_TRY(cudaEventRecord(ev[k], stream));
  }
};


/// The process-wide backend state. Deliberately never destroyed: freeing device memory from a
/// static destructor can run after the CUDA runtime has shut down.
Context& context() {
  static Context* ctx = new Context();
  return *ctx;
}

int g_num_sms = 0;

/// Runs a CUB device algorithm: asks for its temporary storage, grows the shared buffer, runs.
template <class F>
void cubCall(Context& ctx, F&& f) {
  std::size_t bytes = 0;
  CUDA_TRY(f(static_cast<void*>(nullptr), bytes));
  ctx.cub_temp.reserve(bytes);
  bytes = ctx.cub_temp.capacity();
  CUDA_TRY(f(static_cast<void*>(ctx.cub_temp.data()), bytes));
}

/// Uploads (vertices, and triangles when `upload_tris`) and rebuilds the hierarchy of one mesh on
/// the device. Reads back the grid and the entry count once (to size the entry arrays and the
/// sort); everything else stays on the device.
template <class S>
void rebuild(Context& ctx, CachedMesh<S>& m, const TriangleMesh<S>& mesh, bool upload_tris) {
  const cudaStream_t s = ctx.stream;
  const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  if (nt > 150000000u)
    throw InvalidInputError("mesh too large for the CUDA backend: " + std::to_string(nt) +
                            " triangles (at most 150,000,000)");
  const std::size_t vbytes = nv * sizeof(Vec3<S>), tbytes = upload_tris ? nt * sizeof(Triangle) : 0;
  ctx.staging.reserve(vbytes + tbytes);
  char* stage = static_cast<char*>(ctx.staging.data());
  if (vbytes) std::memcpy(stage, mesh.vertices.data(), vbytes);
  if (tbytes) std::memcpy(stage + vbytes, mesh.triangles.data(), tbytes);
  m.v.reserve(nv);
  if (vbytes) CUDA_TRY(cudaMemcpyAsync(m.v.data(), stage, vbytes, cudaMemcpyHostToDevice, s));
  if (upload_tris) {
    m.t.reserve(3 * nt);
    if (tbytes)
      CUDA_TRY(cudaMemcpyAsync(m.t.data(), stage + vbytes, tbytes, cudaMemcpyHostToDevice, s));
  }
  m.nv = nv;
  m.nt = nt;
  m.entries = 0;
  m.info = BuildInfo{};
  if (nt == 0) {
    CUDA_TRY(cudaStreamSynchronize(s));  // the staging buffer is free again
    return;
  }
  const auto n = static_cast<std::uint32_t>(nt);
  m.box.reserve(nt);
  m.diam.reserve(nt);
  m.level.reserve(nt);
  ctx.counts.reserve(nt + 1);
  ctx.offsets.reserve(nt + 1);

  CUDA_TRY(cudaMemsetAsync(ctx.red.data(), 0xFF, 4 * sizeof(unsigned long long), s));
  CUDA_TRY(cudaMemsetAsync(reinterpret_cast<char*>(ctx.red.data()) + 4 * sizeof(unsigned long long),
                           0, 4 * sizeof(unsigned long long), s));
  const unsigned int tri_blocks =
      std::min<unsigned int>(blocksFor(nt, kBuildBlock), static_cast<unsigned int>(4 * g_num_sms));
  trianglesKernel<S><<<tri_blocks, kBuildBlock, 0, s>>>(n, m.v.data(), m.t.data(), m.box.data(),
                                                        m.diam.data(), ctx.red.data());
  checkLaunch();
  gridKernel<<<1, 1, 0, s>>>(ctx.red.data(), ctx.info.data());
  checkLaunch();
  ctx.size_key.reserve(nt);
  ctx.size_key_sorted.reserve(nt);
  ctx.ids.reserve(nt);
  ctx.by_size.reserve(nt);
  ctx.counts_by_size.reserve(nt + 1);
  countKernel<S><<<blocksFor(nt + 1, kBuildBlock), kBuildBlock, 0, s>>>(
      n, m.box.data(), m.diam.data(), ctx.info.data(), m.level.data(), ctx.counts.data(),
      ctx.size_key.data(), ctx.ids.data());
  checkLaunch();
  {
    std::uint32_t* sk = ctx.size_key.data();
    std::uint32_t* sks = ctx.size_key_sorted.data();
    std::uint32_t* ids = ctx.ids.data();
    std::uint32_t* by_size = ctx.by_size.data();
    cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
      return cub::DeviceRadixSort::SortPairs(tmp, bytes, sk, sks, ids, by_size,
                                             static_cast<int>(nt), 0, 32, s);
    });
  }
  countsBySizeKernel<<<blocksFor(nt + 1, kBuildBlock), kBuildBlock, 0, s>>>(
      n, ctx.counts.data(), ctx.by_size.data(), ctx.counts_by_size.data());
  checkLaunch();
  std::uint32_t* counts = ctx.counts_by_size.data();
  std::uint32_t* offsets = ctx.offsets.data();
  cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
    return cub::DeviceScan::ExclusiveSum(tmp, bytes, counts, offsets, static_cast<int>(nt + 1), s);
  });
  CUDA_TRY(cudaMemcpyAsync(ctx.hostInfo(), ctx.info.data(), sizeof(BuildInfo),
                           cudaMemcpyDeviceToHost, s));
  *ctx.hostTotal() = 0;
  CUDA_TRY(cudaMemcpyAsync(ctx.hostTotal(), offsets + nt, sizeof(std::uint32_t),
                           cudaMemcpyDeviceToHost, s));
  CUDA_TRY(cudaStreamSynchronize(s));
  m.info = *ctx.hostInfo();
  const std::uint64_t total = *ctx.hostTotal();
  m.entries = total;
  const auto mt = static_cast<std::uint32_t>(total);

  ctx.keys_a.reserve(total);
  ctx.keys_b.reserve(total);
  ctx.vals_a.reserve(total);
  ctx.head.reserve(total);
  ctx.cell_index.reserve(total);
  m.entry_tri.reserve(total);
  m.cell_begin.reserve(total + 1);
  m.cell_key.reserve(total);
  std::size_t slots = 64;
  while (slots < total + total / 2) slots <<= 1;
  m.slots.reserve(slots);
  m.slot_mask = slots - 1;
  CUDA_TRY(cudaMemsetAsync(m.slots.data(), 0xFF, slots * sizeof(unsigned long long), s));

  unsigned long long* keys_a = ctx.keys_a.data();
  unsigned long long* keys_b = ctx.keys_b.data();
  std::uint32_t* vals_a = ctx.vals_a.data();
  const unsigned int eb = blocksFor(total, kBuildBlock);
  const bool compact = m.info.fits64 != 0;
  const unsigned long long* hi_sorted = nullptr;
  if (compact) {
    fillKernel<S, true><<<blocksFor(nt, kBuildBlock), kBuildBlock, 0, s>>>(
        n, m.box.data(), m.level.data(), offsets, ctx.by_size.data(), ctx.info.data(), keys_a,
        nullptr, vals_a, nullptr);
    checkLaunch();
    const int key_bits = m.info.level_bits + 3 * m.info.coord_bits;
    std::uint32_t* entry_tri = m.entry_tri.data();
    cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
      return cub::DeviceRadixSort::SortPairs(tmp, bytes, keys_a, keys_b, vals_a, entry_tri,
                                             static_cast<int>(total), 0, key_bits, s);
    });
  } else {
    // Full 128-bit keys: two stable passes (low word, then high word) sort by (hi, lo).
    ctx.hi_a.reserve(total);
    ctx.hi_b.reserve(total);
    ctx.vals_b.reserve(total);
    ctx.tri_of.reserve(total);
    unsigned long long* hi_a = ctx.hi_a.data();
    unsigned long long* hi_b = ctx.hi_b.data();
    std::uint32_t* vals_b = ctx.vals_b.data();
    fillKernel<S, false><<<blocksFor(nt, kBuildBlock), kBuildBlock, 0, s>>>(
        n, m.box.data(), m.level.data(), offsets, ctx.by_size.data(), ctx.info.data(), keys_a,
        hi_a, vals_a, ctx.tri_of.data());
    checkLaunch();
    cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
      return cub::DeviceRadixSort::SortPairs(tmp, bytes, keys_a, keys_b, vals_a, vals_b,
                                             static_cast<int>(total), 0, 64, s);
    });
    gatherKeysKernel<<<eb, kBuildBlock, 0, s>>>(mt, hi_a, vals_b, hi_b);
    checkLaunch();
    cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
      return cub::DeviceRadixSort::SortPairs(tmp, bytes, hi_b, hi_a, vals_b, vals_a,
                                             static_cast<int>(total), 0, 64, s);
    });
    gatherKeysKernel<<<eb, kBuildBlock, 0, s>>>(mt, keys_a, vals_a, keys_b);
    checkLaunch();
    gatherTrisKernel<<<eb, kBuildBlock, 0, s>>>(mt, ctx.tri_of.data(), vals_a, m.entry_tri.data());
    checkLaunch();
    hi_sorted = hi_a;
  }
  std::uint32_t* head = ctx.head.data();
  std::uint32_t* cell_index = ctx.cell_index.data();
  if (compact)
    headsKernel<true><<<eb, kBuildBlock, 0, s>>>(mt, keys_b, nullptr, head);
  else
    headsKernel<false><<<eb, kBuildBlock, 0, s>>>(mt, keys_b, hi_sorted, head);
  checkLaunch();
  cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
    return cub::DeviceScan::ExclusiveSum(tmp, bytes, head, cell_index, static_cast<int>(total), s);
  });
  if (compact)
    cellsKernel<true><<<eb, kBuildBlock, 0, s>>>(mt, keys_b, nullptr, head, cell_index,
                                                 ctx.info.data(), m.cell_begin.data(),
                                                 m.cell_key.data(), m.slots.data(), m.slot_mask);
  else
    cellsKernel<false><<<eb, kBuildBlock, 0, s>>>(mt, keys_b, hi_sorted, head, cell_index,
                                                  ctx.info.data(), m.cell_begin.data(),
                                                  m.cell_key.data(), m.slots.data(), m.slot_mask);
  checkLaunch();
}

/// The cache entry of `hm`, brought up to date: nothing happens for a mesh whose geometry did not
/// change (rigid motion only changes the pose, which the query uploads); a new version uploads
/// the vertices and re-hashes; changed triangles are uploaded too.
template <class S>
CachedMesh<S>& acquire(Context& ctx, const HashedMesh<S>& hm) {
  auto& list = ctx.meshes(static_cast<S*>(nullptr));
  const TriangleMesh<S>& mesh = hm.mesh();
  const std::uint64_t fp = fingerprintOf(mesh);
  auto it = std::find_if(list.begin(), list.end(),
                         [&](const CachedMesh<S>& c) { return c.owner == &hm; });
  if (it != list.end()) {
    list.splice(list.begin(), list, it);  // most recently used first
  } else {
    list.emplace_front();
    list.front().owner = &hm;
  }
  CachedMesh<S>& m = list.front();
  if (m.valid && !m.force_vertices && m.version == hm.version() && m.fingerprint == fp) return m;
  // markDeformed() with an unchanged version: only the vertices can have moved. Otherwise the
  // triangles are compared on the host (cheaper than uploading them again).
  const bool only_vertices = m.valid && m.force_vertices && m.version == hm.version() &&
                             m.fingerprint == fp;
  const bool same_topology = only_vertices || (m.nt == mesh.triangles.size() &&
                                               m.t.data() != nullptr && m.host_tris == mesh.triangles);
  m.valid = false;
  rebuild(ctx, m, mesh, !same_topology);
  if (!same_topology) m.host_tris = mesh.triangles;
  m.version = hm.version();
  m.fingerprint = fp;
  m.force_vertices = false;
  m.valid = true;
  return m;
}

template <class S>
void evict(Context& ctx) {
  auto& list = ctx.meshes(static_cast<S*>(nullptr));
  while (list.size() > kMaxCachedMeshes) list.pop_back();
}

/// Initial output capacity knob for tests: KDET_FCL_CUDA_PAIR_CAPACITY=k caps the first pass at k
/// pairs (forcing the overflow path). 0 or unset: no cap.
unsigned long long capacityKnob() {
  const char* e = std::getenv("KDET_FCL_CUDA_PAIR_CAPACITY");
  if (e == nullptr || *e == 0) return 0;
  return std::strtoull(e, nullptr, 10);
}

/// Runs `launch(sink)` until every pair fits (overflow: grow, rerun), then sorts the pairs on the
/// device and copies the first max_pairs (or all) of the sorted order into the result.
template <class Launch>
QueryResult runQuery(Context& ctx, Launch&& launch, int a_bits, int b_bits, std::size_t work,
                     const QueryOptions& options) {
  const cudaStream_t s = ctx.stream;
  ctx.cands.reserve(std::max<std::size_t>(std::size_t(1) << 16, 8 * work));
  ctx.pairs.reserve(std::max<std::size_t>(std::size_t(1) << 16, work));
  unsigned long long cand_cap = ctx.cands.capacity(), cap = ctx.pairs.capacity();
  const unsigned long long knob = capacityKnob();
  if (knob > 0) {
    cand_cap = std::min(cand_cap, knob);
    cap = std::min(cap, knob);
  }
  unsigned long long n = 0;
  int passes = 0;
  while (true) {
    ++passes;
    CUDA_TRY(cudaMemsetAsync(ctx.pair_count.data(), 0, 2 * sizeof(unsigned long long), s));
    launch(PairSink{ctx.cands.data(), ctx.pair_count.data(), cand_cap, 32},
           PairSink{ctx.pairs.data(), ctx.pair_count.data() + 1, cap, b_bits});
    checkLaunch();
    CUDA_TRY(cudaMemcpyAsync(ctx.hostCount(), ctx.pair_count.data(), 2 * sizeof(unsigned long long),
                             cudaMemcpyDeviceToHost, s));
    CUDA_TRY(cudaStreamSynchronize(s));
    const unsigned long long nc = ctx.hostCount()[0];
    n = ctx.hostCount()[1];
    ctx.profile.candidates = nc;
    if (nc <= cand_cap && n <= cap) break;
    // The device counted everything it could not store: grow and rerun (no pair is dropped).
    if (nc > 0x7FFFFFFFull || n > 0x7FFFFFFFull)
      throw Error("CUDA backend: more than 2^31-1 candidate pairs (" + std::to_string(nc) + ")");
    if (nc > cand_cap) {
      ctx.cands.reserve(nc);
      cand_cap = ctx.cands.capacity();
    }
    if (n > cap) {
      ctx.pairs.reserve(n);
      cap = ctx.pairs.capacity();
    }
  }
  ctx.record(2);
  QueryResult res;
  std::size_t m = n;
  if (options.max_pairs > 0 && m > options.max_pairs) m = options.max_pairs;
  if (n > 0) {
    ctx.pairs_sorted.reserve(n);
    unsigned long long* in = ctx.pairs.data();
    unsigned long long* out = ctx.pairs_sorted.data();
    const int bits = a_bits + b_bits;
    cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
      return cub::DeviceRadixSort::SortKeys(tmp, bytes, in, out, static_cast<int>(n), 0, bits, s);
    });
    unpackPairsKernel<<<blocksFor(m, 256), 256, 0, s>>>(static_cast<std::uint32_t>(m), out, b_bits,
                                                         reinterpret_cast<uint2*>(in));
    checkLaunch();
    static_assert(sizeof(TrianglePair) == sizeof(uint2), "TrianglePair must be two 32-bit words");
    // Through pinned memory: a pageable device->host copy runs at a fraction of the bus rate.
    ctx.readback.reserve(m * sizeof(TrianglePair));
    CUDA_TRY(cudaMemcpyAsync(ctx.readback.data(), in, m * sizeof(TrianglePair),
                             cudaMemcpyDeviceToHost, s));
    CUDA_TRY(cudaStreamSynchronize(s));
    const auto* staged = static_cast<const TrianglePair*>(ctx.readback.data());
    res.pairs.assign(staged, staged + m);
  }
  ctx.record(3);
  res.complete = options.max_pairs == 0 || res.pairs.size() < options.max_pairs;
  if (ctx.profiling) {
    CUDA_TRY(cudaEventSynchronize(ctx.ev[3]));
    float t01 = 0, t12 = 0, t23 = 0, t03 = 0;
    CUDA_TRY(cudaEventElapsedTime(&t01, ctx.ev[0], ctx.ev[1]));
    CUDA_TRY(cudaEventElapsedTime(&t12, ctx.ev[1], ctx.ev[2]));
    CUDA_TRY(cudaEventElapsedTime(&t23, ctx.ev[2], ctx.ev[3]));
    CUDA_TRY(cudaEventElapsedTime(&t03, ctx.ev[0], ctx.ev[3]));
    ctx.profile.build_ms = t01;
    ctx.profile.query_ms = t12;
    ctx.profile.output_ms = t23;
    ctx.profile.total_ms = t03;
    float t14 = 0;
    CUDA_TRY(cudaEventElapsedTime(&t14, ctx.ev[1], ctx.ev[4]));
    ctx.profile.candidates_ms = t14;
    ctx.profile.passes = passes;
    ctx.profile.pairs = n;
  }
  return res;
}

/// Lanes per query triangle in the candidate search: KDET_FCL_CUDA_TILE = 1, 4, 8, 16 or 32
/// (default 8; read once). Larger tiles suit heavily loaded cells (crumpled cloth), smaller ones
/// lightly loaded cells, where the repeated lookups dominate (benchmarks/RESULTS-gpu.md).
int tileSize() {
  static const int t = [] {
    const char* e = std::getenv("KDET_FCL_CUDA_TILE");
    const int v = (e && *e) ? std::atoi(e) : 8;
    return (v == 1 || v == 4 || v == 8 || v == 16 || v == 32) ? v : 8;
  }();
  return t;
}

/// Register cap of the tile-8 candidate kernels, as blocks per SM in __launch_bounds__:
/// KDET_FCL_CUDA_MINBLOCKS = 1 (no cap), 8 or 12 (default 12: at most 40 registers, about 3x the
/// occupancy of the uncapped ~100-register kernel; measured 5-16% faster phase 1 despite the
/// spills, benchmarks/RESULTS-gpu.md "Optimization round 2"). Read once.
int minBlocksKnob() {
  static const int mb = [] {
    const char* e = std::getenv("KDET_FCL_CUDA_MINBLOCKS");
    const int v = (e && *e) ? std::atoi(e) : 12;
    return (v == 1 || v == 8 || v == 12) ? v : 12;
  }();
  return mb;
}

/// Calls f(G, MB) (integral constants) for the configured tile and register cap.
template <class F>
void withTile(F&& f) {
  using std::integral_constant;
  switch (tileSize()) {
    case 1: f(integral_constant<int, 1>{}, integral_constant<int, 1>{}); break;
    case 4: f(integral_constant<int, 4>{}, integral_constant<int, 1>{}); break;
    case 16: f(integral_constant<int, 16>{}, integral_constant<int, 1>{}); break;
    case 32: f(integral_constant<int, 32>{}, integral_constant<int, 1>{}); break;
    default:
      switch (minBlocksKnob()) {
        case 1: f(integral_constant<int, 8>{}, integral_constant<int, 1>{}); break;
        case 8: f(integral_constant<int, 8>{}, integral_constant<int, 8>{}); break;
        default: f(integral_constant<int, 8>{}, integral_constant<int, 12>{}); break;
      }
      break;
  }
}

/// Calls f.template operator()<K>() with the orientation kernel of the requested predicate.
template <class F>
void withPredicate(Predicate p, F&& f) {
  switch (p) {
    case Predicate::Double:
      f(detail::PlainKernel<double>{});
      break;
    case Predicate::Float:
      f(detail::PlainKernel<float>{});
      break;
    default:
      f(detail::ExactKernel{});
      break;
  }
}

template <class S>
QueryResult interImpl(Context& ctx, const HashedMesh<S>& a, const HashedMesh<S>& b,
                      const QueryOptions& options) {
  const std::size_t na = a.numTriangles(), nb = b.numTriangles();
  ctx.profile = QueryProfile{};
  if (na == 0 || nb == 0) return QueryResult{};
  ctx.record(0);
  CachedMesh<S>& A = acquire(ctx, a);
  CachedMesh<S>& B = acquire(ctx, b);
  ctx.record(1);
  const cudaStream_t s = ctx.stream;
  const detail::RelativePose rp = detail::relativePose(a.pose(), b.pose());
  const Vec3<S>* va = A.v.data();
  if (!rp.identity) {
    auto& mapped = ctx.mapped(static_cast<S*>(nullptr));
    mapped.reserve(A.nv);
    mapVerticesKernel<S><<<blocksFor(A.nv, 256), 256, 0, s>>>(
        static_cast<std::uint32_t>(A.nv), A.v.data(), rp.a_to_b, mapped.data());
    checkLaunch();
    va = mapped.data();
  }
  // The CPU backend's bound on the rounding of B's boxes mapped back into A's frame.
  double eps = 0;
  if (!rp.identity) {
    const Aabb<double>& ba = A.info.bounds;
    const Aabb<double>& bb = B.info.bounds;
    double mag = std::fabs(rp.a_to_b.t.x) + std::fabs(rp.a_to_b.t.y) + std::fabs(rp.a_to_b.t.z);
    for (int k = 0; k < 3; ++k)
      mag += std::max(std::fabs(ba.lo[k]), std::fabs(ba.hi[k])) +
             std::max(std::fabs(bb.lo[k]), std::fabs(bb.hi[k]));
    eps = (16 * rp.orthonormal_defect + 64 * double(std::numeric_limits<S>::epsilon())) * mag +
          std::numeric_limits<double>::min();
  }
  const HashView<S> av = A.view(), bv = B.view();
  const auto una = static_cast<std::uint32_t>(na), unb = static_cast<std::uint32_t>(nb);
  const unsigned int exact_blocks = static_cast<unsigned int>(16 * g_num_sms);
  auto launch = [&](PairSink cand, PairSink out) {
    withTile([&](auto g, auto mb) {
      constexpr int G = decltype(g)::value;
      constexpr int MB = decltype(mb)::value;
      interCandidatesKernel<S, G, MB><<<blocksFor(G * (na + nb), kQueryBlock), kQueryBlock, 0, s>>>(
          av, bv, va, una, unb, rp.identity, rp.b_to_a, eps, cand);
    });
    checkLaunch();
    ctx.record(4);
    withPredicate(options.predicate, [&](auto k) {
      using K = decltype(k);
      interExactKernel<S, K><<<exact_blocks, kQueryBlock, 0, s>>>(
          cand.pairs, cand.count, cand.capacity, va, av.t, bv.v, bv.t, out);
    });
  };
  return runQuery(ctx, launch, bitsFor(na), bitsFor(nb), na + nb, options);
}

template <class S>
QueryResult selfImpl(Context& ctx, const HashedMesh<S>& mesh, const QueryOptions& options) {
  const std::size_t n = mesh.numTriangles();
  ctx.profile = QueryProfile{};
  if (n < 2) return QueryResult{};
  ctx.record(0);
  CachedMesh<S>& M = acquire(ctx, mesh);
  ctx.record(1);
  const cudaStream_t s = ctx.stream;
  const HashView<S> mv = M.view();
  const auto un = static_cast<std::uint32_t>(n);
  const unsigned int exact_blocks = static_cast<unsigned int>(16 * g_num_sms);
  auto launch = [&](PairSink cand, PairSink out) {
    withTile([&](auto g, auto mb) {
      constexpr int G = decltype(g)::value;
      constexpr int MB = decltype(mb)::value;
      selfCandidatesKernel<S, G, MB><<<blocksFor(G * n, kQueryBlock), kQueryBlock, 0, s>>>(mv, un,
                                                                                      cand);
    });
    checkLaunch();
    ctx.record(4);
    withPredicate(options.predicate, [&](auto k) {
      using K = decltype(k);
      selfExactKernel<S, K><<<exact_blocks, kQueryBlock, 0, s>>>(cand.pairs, cand.count,
                                                                  cand.capacity, mv.v, mv.t, out);
    });
  };
  return runQuery(ctx, launch, bitsFor(n), bitsFor(n), n, options);
}

/// Serialises, initialises, and on a CUDA error drops every device buffer before rethrowing.
template <class F>
QueryResult guarded(F&& f) {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  try {
    ctx.init();
    if (g_num_sms == 0) CUDA_TRY(cudaDeviceGetAttribute(&g_num_sms, cudaDevAttrMultiProcessorCount, 0));
    QueryResult r = f(ctx);
    evict<float>(ctx);
    evict<double>(ctx);
    return r;
  } catch (const CudaError&) {
    ctx.releaseAll();
    throw;
  } catch (...) {
    // A non-CUDA failure (bad input, bad_alloc) may have left a half-built entry: drop those.
    ctx.meshes_f.remove_if([](const CachedMesh<float>& m) { return !m.valid; });
    ctx.meshes_d.remove_if([](const CachedMesh<double>& m) { return !m.valid; });
    throw;
  }
}

}  // namespace

template <class S>
QueryResult intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options) {
  return guarded([&](Context& ctx) { return interImpl(ctx, a, b, options); });
}

template <class S>
QueryResult intersectSelf(const HashedMesh<S>& mesh, const QueryOptions& options) {
  return guarded([&](Context& ctx) { return selfImpl(ctx, mesh, options); });
}

void setProfiling(bool on) {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  ctx.profiling = on;
}

QueryProfile lastQueryProfile() {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  return ctx.profile;
}

template <class S>
void markDeformed(const HashedMesh<S>& mesh) {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  for (auto& m : ctx.meshes(static_cast<S*>(nullptr)))
    if (m.owner == &mesh) m.force_vertices = true;
}

std::size_t deviceBytesInUse() {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  return ctx.bytes();
}

void releaseDeviceMemory() {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  ctx.releaseAll();
}

template QueryResult intersectMeshes(const HashedMesh<float>&, const HashedMesh<float>&,
                                     const QueryOptions&);
template QueryResult intersectMeshes(const HashedMesh<double>&, const HashedMesh<double>&,
                                     const QueryOptions&);
template QueryResult intersectSelf(const HashedMesh<float>&, const QueryOptions&);
template QueryResult intersectSelf(const HashedMesh<double>&, const QueryOptions&);
template void markDeformed(const HashedMesh<float>&);
template void markDeformed(const HashedMesh<double>&);

}  // namespace cuda
}  // namespace kdet_fcl
