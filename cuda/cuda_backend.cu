// The CUDA query backend (see cuda_backend.h for the contract).
//
// Per mesh (on a new version only): upload -> per-triangle box/diameter + grid reduction ->
// grid (one thread, the CPU's formulas, into the mesh's device BuildInfo) -> level + cell count
// per triangle -> triangles ordered by decreasing diameter (32-bit radix sort) -> exclusive scan
// -> [first build only: read back the grid and the entry count] -> (cell key, triangle) entries
// (compact 64-bit keys where exact, else 128-bit) -> CUB radix sort by cell key over the entry
// capacity (stable, so each cell lists its triangles by decreasing diameter; padding sorts last)
// -> run heads -> scan -> [first build only: read back the cell count] -> cells (one key per
// cell) + open-addressing table sized by cells. A re-hash reads nothing back (rebuild()).
// Per query: relative pose (host, as on the CPU) -> A's vertices mapped into B's frame ->
// phase 1, the warp-wide scan (P lanes per query triangle, the warp testing the entries of its
// 32 / P queries' cells together; KDET_FCL_CUDA_SCAN=tile: the older tile of G lanes per query):
// cells of its level and every coarser one, size rule, box overlap, canonical cell -> candidate
// pairs -> plane filter (Exact predicate only; one thread per candidate, drops pairs that the
// exact test's first rejection provably rejects, keeps the rest) -> phase 2, one thread per
// surviving candidate: the exact test -> pairs appended with warp-aggregated atomics -> [host
// read-back of the counts, and of the BuildInfo of meshes re-hashed in this query; on overflow
// grow and rerun, on a re-hash that did not fit rebuild it with read-backs and rerun] -> radix
// sort of the pairs -> device->host copy. The meshes' grids reach the candidate kernel through
// constant memory (c_info), copied device to device, so the host never needs a re-hash's grid.
// Memory: the build's sort and count scratch is carved out of the query buffers (candidates,
// pairs, sorted pairs), which are idle during a build; the filter's survivors use the sorted-pair
// buffer, idle until the final sort. A query whose candidates need more than 112 bytes per
// query triangle (14 of 8 bytes) runs phase 1, the filter and phase 2 in rounds over ranges of
// its tasks, which reuse the candidate and survivor buffers (runQuery, RoundPlan), all queued
// before the one read-back; a self query with the cells' pairs runs each of its two phase-1
// kernels in rounds of its own. Where 8-byte candidates would take rounds and their keys fit in
// 40 bits, they are stored in 5 bytes (4 where 32 bits do: PairSink::key_bytes), fewer rounds.
// benchmarks/RESULTS-gpu.md has the measurements behind these choices.

#include <cooperative_groups.h>
#include <cooperative_groups/reduce.h>
#include <cuda_runtime_api.h>

#include <cub/block/block_reduce.cuh>
#include <cub/block/block_scan.cuh>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "cuda_backend.h"
#include "cuda_error.cuh"
#include "device_hash.cuh"
#include "device_scope.h"
#include "staged_upload.h"
#include "kdet_fcl/backend.h"
#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/enclosing_sphere.h"
#include "kdet_fcl/detail/hierarchy.h"
#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "kdet_fcl/errors.h"
#include "kept_self_result.h"
#include "kdet_fcl/detail/knobs.h"

namespace cg = cooperative_groups;

namespace kdet_fcl {
namespace cuda {
namespace {

using detail::Aabb;
using detail::CellKey;
using detail::GridParams;

constexpr int kBuildBlock = 256;
constexpr int kQueryBlock = 128;
constexpr int kFilterBlock = 256;
constexpr std::size_t kMaxCachedMeshes = 32;
// Context::pair_count's words: the counters of one query pass (zeroed before it), see there.
enum PairCountWord : int {
  kCandCount = 0,    // candidates of this round (phase 1)
  kPairCount = 1,    // pairs of all rounds (exact test)
  kSurvCount = 2,    // survivors of the plane filter, this round
  kWarpTasks = 3,    // task counter of the warp-wide candidate kernels, this round
  kCellTasks = 4,    // task counter of the same-level pairs, this round
  kKindCounts = 5,   // two words: the pairs of kinds 1 and 2 of a joint query (deliverPair)
  kMaxCands = 7,     // the most candidates of one round (roundEndKernel)
  kAllCands = 8,     // candidates of all rounds
  kMaxSurv = 9,      // the most survivors of one round
  kAllSurv = 10,     // survivors of all rounds
  kCellCands = 11,   // of all candidates, the cells' (selfCellPairsKernel)
  kBigSegment = 12,  // set when a segment of the pairs' counting order exceeds its limit
  kPairCountWords = 13
};
// The pairs' counting order (runQuery): the pairs are counted per segment (their first index,
// with a joint query's kind, shifted right to at most segmentBits() bits) as the exact kernels
// emit them; a scan, a scatter and a rank within each segment then order them as the radix sort
// does, when there are at least kCountOrderMinPairs pairs (cuda_backend.h) and no segment holds
// more than kSegmentMax (KDET_FCL_CUDA_COUNT_ORDER_SEGMENT: segmentMax()) (else the radix sort
// runs: fewer keys fit its single-tile sort, and a segment's rank reads the whole segment).
constexpr unsigned int kSegmentMax = 1024;
constexpr unsigned int kSegmentMaxLimit = 65536;  // the knob's largest value
constexpr std::size_t kMaxDeviceTriangles = 150000000;  // a cache entry's (entry_tri's index bits)

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

/// The grid, with the CPU's formulas (HierarchicalHash::build), in one thread. Resets the
/// reduction targets for the next build (no memsets per build). `async_key_bits` > 0: a re-hash
/// without read-back whose compact keys are sorted on that many bits; need_sync is set when the
/// new grid's keys do not fit (the host then rebuilds with read-backs).
__global__ void gridKernel(BuildReduce* red, BuildInfo* info, int async_key_bits) {
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
  in.entries = 0;
  in.cells = 0;
  in.need_sync = async_key_bits > 0 &&
                 (!in.fits64 || in.level_bits + 3 * in.coord_bits > async_key_bits);
  in.inserted = 0;
  in.group_axis = kNoCellGroups;  // (a counting build sets its own: countFillKernel)
  *info = in;
  for (int a = 0; a < 3; ++a) red->lo[a] = ~0ull, red->hi[a] = 0;
  red->dmin_pos = ~0ull;
  red->dmax = 0;
}

/// The high 32 bits of a diameter's ordered bit pattern: monotone in the diameter, so entries
/// listed by decreasing sizeKey let a scan stop at the first entry with sizeKey(d_j) <
/// sizeKey(d_query), since every later one is strictly smaller than the query too.
__device__ __forceinline__ std::uint32_t sizeKey(double d) {
  return static_cast<std::uint32_t>(orderedBits(d) >> 32);
}

/// Level and number of covered cells of each triangle; counts[n] = 0 closes the scan. With
/// size_key, also the keys and ids of the sort by decreasing diameter.
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
    const Aabb<double> bd = toDoubleBox(b);
    level[i] = static_cast<std::uint8_t>(l);
    counts[i] = static_cast<std::uint32_t>(detail::cellRange(bd, l, g).count());
    if (size_key != nullptr) {  // (only when the cells are laid out by size)
      size_key[i] = ~sizeKey(diam[i]);  // ascending sort = decreasing diameter
      ids[i] = i;
    }
    atomicOr(&mask, 1ull << l);
  }
  if (i == n) counts[n] = 0;
  __syncthreads();
  if (threadIdx.x == 0 && mask != 0) atomicOr(&info->level_mask, mask);
}

/// (cell, triangle) entries; a triangle is stored with its first-cell bits (entryValue). kCompact:
/// key = compact 64-bit key (exact, bijective), value = triangle. Otherwise: key = low word of the
/// 128-bit key, hi[] = high word, value = entry index, tri_of[entry] = triangle (sorted in two
/// stable passes). Entries at or past `cap` are counted
/// (info->entries = offsets[n]) but not written; the unwritten keys keep their padding (all
/// ones), so they sort after every real key. Nothing is written when info->need_sync.
template <class S, bool kCompact>
__global__ void __launch_bounds__(kBuildBlock)
    fillKernel(std::uint32_t n, const Aabb<S>* __restrict__ box,
               const std::uint8_t* __restrict__ level, const std::uint32_t* __restrict__ offsets,
               const std::uint32_t* __restrict__ by_size, const BuildInfo* info,
               unsigned long long* __restrict__ keys, unsigned long long* __restrict__ hi,
               std::uint32_t* __restrict__ vals, std::uint32_t* __restrict__ tri_of,
               std::uint32_t cap, BuildInfo* winfo) {
  // With by_size, triangles are laid out by decreasing diameter (rank r holds triangle
  // by_size[r]), else in index order; the stable sort by cell key keeps that order inside each
  // cell.
  const std::uint32_t rank = blockIdx.x * blockDim.x + threadIdx.x;
  if (rank == 0) winfo->entries = offsets[n];
  if (rank >= n || info->need_sync) return;
  const std::uint32_t i = by_size != nullptr ? by_size[rank] : rank;
  const GridParams g = info->grid;
  const int cb = info->coord_bits;
  const int l = level[i];
  const Aabb<S> b = box[i];
  const Aabb<double> bd = toDoubleBox(b);
  const detail::CellRange r = detail::cellRange(bd, l, g);
  std::uint32_t e = offsets[rank];
  for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
    for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
      for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z, ++e) {
        if (e >= cap) return;
        const std::uint32_t first =
            (x == r.lo[0] ? 1u : 0u) | (y == r.lo[1] ? 2u : 0u) | (z == r.lo[2] ? 4u : 0u);
        const std::uint32_t v = entryValue(i, first);
        if (kCompact) {
          keys[e] = compactKey(l, x, y, z, cb);
          vals[e] = v;
        } else {
          const CellKey k = detail::makeCellKey(l, x, y, z);
          keys[e] = k.lo;
          hi[e] = k.hi;
          vals[e] = e;
          tri_of[e] = v;
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

/// The entries of this build that were written: min(entries, cap), or none after need_sync.
__device__ __forceinline__ std::uint32_t writtenEntries(const BuildInfo* info, std::uint32_t cap) {
  if (info->need_sync) return 0;
  const std::uint32_t e = info->entries;
  return e < cap ? e : cap;
}

/// The resident entries in cell order (HashView::entry_tri, entry_span): the sorted entry values
/// and the sub-cell span of each entry's triangle box in its cell (so a lookup can skip most
/// non-overlapping entries before it loads their diameter or box). `vals` may be `entry_tri`
/// itself (no __restrict__ on either: each thread reads and writes only its own entry). kCompact:
/// the k-th sorted value is vals[k] and its cell the compact key[k]; otherwise the k-th value is
/// vals[perm[k]] (the 128-bit sort moves entry indices) and its cell {hi[k], key[k]}.
template <class S, bool kCompact>
__global__ void __launch_bounds__(kBuildBlock)
    entriesKernel(std::uint32_t cap, const BuildInfo* info,
                  const unsigned long long* __restrict__ key,
                  const unsigned long long* __restrict__ hi, const std::uint32_t* vals,
                  const std::uint32_t* __restrict__ perm, const Aabb<S>* __restrict__ box,
                  std::uint32_t* entry_tri, std::uint32_t* __restrict__ entry_span) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= writtenEntries(info, cap)) return;
  const std::uint32_t v = kCompact ? vals[k] : vals[perm[k]];
  const detail::CellId c = kCompact ? compactKeyCell(key[k], info->coord_bits)
                                    : detail::cellOfKey(CellKey{hi[k], key[k]});
  const Aabb<S> b = box[v & kEntryTriMask];
  const Aabb<double> bd = toDoubleBox(b);
  entry_tri[k] = v;
  entry_span[k] = detail::subcellSpan(bd, c.level, c.x, c.y, c.z, info->grid);
}

/// head[k] = 1 where a new cell starts in the sorted entries (full-key comparison), 0 past the
/// written entries (the scan runs over the whole capacity, whose size the host knows). When
/// `slots` is given (a re-hash: the table keeps its size), also empties the table (grid-stride),
/// in place of a memset.
template <bool kCompact>
__global__ void headsKernel(std::uint32_t cap, const BuildInfo* info,
                            const unsigned long long* __restrict__ key,
                            const unsigned long long* __restrict__ hi,
                            std::uint32_t* __restrict__ head, unsigned long long* slots,
                            std::uint32_t slot_count) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (slots != nullptr)
    for (std::uint32_t i = k; i < slot_count; i += gridDim.x * blockDim.x) slots[i] = kEmptySlot;
  if (k >= cap) return;
  const std::uint32_t m = writtenEntries(info, cap);
  if (k >= m) {
    head[k] = 0;
    return;
  }
  bool h = k == 0 || key[k] != key[k - 1];
  if (!kCompact && k > 0) h = h || hi[k] != hi[k - 1];
  head[k] = h ? 1u : 0u;
}

/// One thread per run head: the cell's first entry, its full key (1 word when compact, else
/// {hi, lo}), and its slot in the table. Cells at or past `cell_cap` are counted
/// (info->cells) but not stored, so the host can see that the arrays were too small. Also, for
/// every 32nd entry k, the cell that holds it: block_cell[k / 32] (selfCellPairsKernel's tasks).
template <bool kCompact>
__global__ void cellsKernel(std::uint32_t cap, const unsigned long long* __restrict__ key,
                            const unsigned long long* __restrict__ hi,
                            const std::uint32_t* __restrict__ head,
                            const std::uint32_t* __restrict__ cell_index, BuildInfo* info,
                            std::uint32_t cell_cap, std::uint32_t* __restrict__ cell_begin,
                            unsigned long long* __restrict__ cell_key, unsigned long long* slots,
                            std::uint32_t slot_count, std::uint32_t* __restrict__ block_cell) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  const std::uint32_t m = writtenEntries(info, cap);
  if (k >= m) return;
  // cell_index is the exclusive scan of the heads: entry k lies in cell cell_index[k] + head[k] - 1.
  if ((k & 31u) == 0) block_cell[k >> 5] = cell_index[k] + head[k] - 1;
  if (k == m - 1) {  // sentinel after the last cell
    const std::uint32_t cells = cell_index[k] + head[k];
    info->cells = cells;
    if (cells <= cell_cap) cell_begin[cells] = m;
  }
  if (!head[k]) return;
  const std::uint32_t c = cell_index[k];
  if (c <= cell_cap) cell_begin[c] = k;
  if (c >= cell_cap) return;
  CellKey ck;
  if (kCompact) {
    const unsigned long long u = key[k];
    const detail::CellId id = compactKeyCell(u, info->coord_bits);
    ck = detail::makeCellKey(id.level, id.x, id.y, id.z);
    cell_key[c] = u;
  } else {
    ck = CellKey{hi[k], key[k]};
    cell_key[2 * std::size_t(c)] = ck.hi;
    cell_key[2 * std::size_t(c) + 1] = ck.lo;
  }
  const unsigned long long h = detail::hashCellKey(ck);
  const unsigned long long val = slotValue(h, c);
  std::uint32_t s = homeSlot(h, slot_count);
  // Keys are unique (one thread per cell), so the first empty slot is ours; slot_count exceeds
  // cell_cap, so there always is one.
  while (atomicCAS(&slots[s], kEmptySlot, val) != kEmptySlot) s = nextSlot(s, slot_count);
}

/// Adds one per thread of `g` (threads calling together) to *counter with a single atomic, and
/// returns each thread's own old value: distinct values, as a per-thread atomicAdd(counter, 1)
/// would give (in another order), with 1/g.size() of the atomics on one address.
template <class T, class Group>
__device__ __forceinline__ T groupIncrement(T* counter, const Group& g) {
  T base = 0;
  if (g.thread_rank() == 0) base = atomicAdd(counter, static_cast<T>(g.size()));
  return g.shfl(base, 0) + static_cast<T>(g.thread_rank());
}

// ---- The counting build: the cells of a re-hash without a sort ------------------------------
// A re-hash without read-back (compact keys, cells not laid out by size) can group its entries
// by cell with the mesh's own lookup table instead of a radix sort of the entries: each entry
// finds or claims its cell's slot (countFillKernel), counts itself there and keeps its rank; the
// claimed slots get cell indices and counts (countCellsKernel), a scan of the counts gives the
// cells' first entries, and each entry goes to first + rank (scatterKernel). The slots first
// hold the cells' compact keys (never kEmptySlot: a key of all ones is treated as overflow) and
// are then rewritten in place to the lookup form ((hash >> 32) << 32 | cell), where findCell
// finds them: a key claims the slot of its probe sequence, as a lookup walks it. The order of
// the cells, and of the entries inside a cell, follows the atomics and changes from run to run;
// the cells, their entries and every candidate and pair are the same as the sort's (the output
// is sorted). Meshes of more than kCountBuildMaxTriangles keep the sort (KDET_FCL_CUDA_COUNT_BUILD
// forces either, KDET_FCL_CUDA_COUNT_BUILD_MAX moves the limit).

/// Empties the table and zeroes the per-slot counts of the three groups (cellGroupOf; group g's
/// count of slot s at slot_cnt[g * group_stride + s]) and the per-cell counts [0, cells_n).
__global__ void countClearKernel(unsigned long long* __restrict__ slots, std::uint32_t slot_count,
                                 std::uint32_t* __restrict__ slot_cnt, std::size_t group_stride,
                                 std::uint32_t* __restrict__ cell_count, std::uint32_t cells_n) {
  const std::uint32_t stride = gridDim.x * blockDim.x;
  for (std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < slot_count; k += stride) {
    slots[k] = kEmptySlot;
    for (int g = 0; g < 3; ++g) slot_cnt[g * group_stride + k] = 0;
  }
  for (std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < cells_n; k += stride)
    cell_count[k] = 0;
}

/// fillKernel's entries (index order, no size sort), one thread per entry e < cap, each counted
/// in the slot of its cell's compact key (found, or claimed with atomicCAS along the probe
/// sequence that a lookup walks): per entry its slot, its rank among the slot's entries of its
/// group and its value (entryValue). The group (cellGroupOf of the entry's sub-cell span on
/// `axis`; always 1 with axis = kNoCellGroups) picks the slot's counter: group g counts at
/// slot_cnt[g * group_stride + s], and the scatter lists a cell's groups in order. Entry e's
/// triangle is the last i with offsets[i] <= e (warpEntryTriangle: the warp searches the scan of
/// the triangles' cell counts), its cell the (e - offsets[i])-th of the triangle's range in
/// fillKernel's order (x, then y, then z). More distinct cells than
/// `cell_cap`, a probe past the whole table or a key of all ones set need_sync (the query then
/// rebuilds with read-backs and reruns). need_sync is read once per thread, not per entry:
/// polling it shares the sector of the counters' atomics, and work done after it is set is
/// thrown away by the fallback anyway. ncu, H100, 1M cloth: 308 us with a thread per triangle
/// looping over its cells and polling need_sync per cell; 147-152 us without the poll; 143-145
/// us with a thread per entry, whose lanes no longer wait for a triangle of many cells.
template <class S>
__global__ void __launch_bounds__(kBuildBlock)
    countFillKernel(std::uint32_t n, const Aabb<S>* __restrict__ box,
                    const std::uint8_t* __restrict__ level, const std::uint32_t* __restrict__ offsets,
                    BuildInfo* info, unsigned long long* slots, std::uint32_t slot_count,
                    std::uint32_t* __restrict__ slot_cnt, std::size_t group_stride, int axis,
                    std::uint32_t* __restrict__ ent_slot, std::uint32_t* __restrict__ ent_rank,
                    std::uint32_t* __restrict__ ent_val, std::uint32_t cap,
                    std::uint32_t cell_cap) {
  const std::uint32_t e = blockIdx.x * blockDim.x + threadIdx.x;
  const std::uint32_t e0 = e - (threadIdx.x & 31u);  // the warp's first entry
  const std::uint32_t total = __ldg(offsets + n);
  if (e == 0) {
    info->entries = total;
    info->group_axis = axis;
  }
  if (e0 >= cap || e0 >= total) return;  // (the whole warp)
  const std::uint32_t i = warpEntryTriangle(offsets, n, e0, e);
  if (e >= cap || e >= total || info->need_sync) return;
  const int l = level[i];
  const Aabb<double> bd = toDoubleBox(box[i]);
  const detail::CellRange r = detail::cellRange(bd, l, info->grid);
  const std::uint64_t ny = static_cast<std::uint64_t>(r.hi[1] - r.lo[1] + 1);
  const std::uint64_t nz = static_cast<std::uint64_t>(r.hi[2] - r.lo[2] + 1);
  const std::uint64_t local = e - __ldg(offsets + i);
  const std::uint64_t xy = local / nz;
  const std::int64_t x = r.lo[0] + static_cast<std::int64_t>(xy / ny);
  const std::int64_t y = r.lo[1] + static_cast<std::int64_t>(xy % ny);
  const std::int64_t z = r.lo[2] + static_cast<std::int64_t>(local - xy * nz);
  const unsigned long long key = compactKey(l, x, y, z, info->coord_bits);
  const unsigned long long h = detail::hashCellKey(detail::makeCellKey(l, x, y, z));
  std::uint32_t s = homeSlot(h, slot_count);
  bool found = false;
  if (key != kEmptySlot) {
    for (std::uint32_t probe = 0; probe < slot_count; ++probe) {
      unsigned long long cur = __ldcg(slots + s);
      if (cur == kEmptySlot) {
        cur = atomicCAS(slots + s, kEmptySlot, key);
        if (cur == kEmptySlot) {  // claimed: a new cell
          // (one atomic per group of threads inserting together; ncu, H100, 1M cloth:
          // the kernel took 357 us with one atomic per thread for its two counters, 308)
          if (groupIncrement(&info->inserted, cg::coalesced_threads()) >= cell_cap)
            info->need_sync = 1;
          found = true;
          break;
        }
      }
      if (cur == key) {
        found = true;
        break;
      }
      s = nextSlot(s, slot_count);
    }
  }
  if (!found) {
    info->need_sync = 1;
    return;
  }
  const std::uint32_t first =
      (x == r.lo[0] ? 1u : 0u) | (y == r.lo[1] ? 2u : 0u) | (z == r.lo[2] ? 4u : 0u);
  const unsigned int group =
      axis < kNoCellGroups
          ? cellGroupOf(detail::subcellSpan(bd, l, x, y, z, info->grid), axis)
          : 1u;
  ent_slot[e] = s;
  // The threads of a warp counting in the same slot and group take one atomic together.
  const unsigned long long label = (static_cast<unsigned long long>(s) << 2) | group;
  ent_rank[e] = groupIncrement(slot_cnt + group * group_stride + s,
                               cg::labeled_partition(cg::coalesced_threads(), label));
  ent_val[e] = entryValue(i, first);
}

/// One thread per slot: a claimed slot becomes a cell (the next index of info->cells), with its
/// count (the sum of its groups' counts, slot_words[g * group_stride + s]; slot_words[s] then
/// holds the cell: ~0u for one not stored), its groups' ends (cell_split: groups 0 and 1, from
/// its first entry), its compact key in cell_key and the slot rewritten to the lookup form.
/// Cells at or past `cell_cap` are counted but not stored (countFillKernel has set need_sync
/// then), and their slots are emptied. After need_sync every slot is emptied and nothing else is
/// written: the queries that run before the fallback then find no cell and read nothing past the
/// arrays.
__global__ void countCellsKernel(BuildInfo* info, unsigned long long* slots,
                                 std::uint32_t slot_count, std::uint32_t* __restrict__ slot_words,
                                 std::size_t group_stride, std::uint32_t* __restrict__ cell_count,
                                 uint2* __restrict__ cell_split,
                                 unsigned long long* __restrict__ cell_key, std::uint32_t cell_cap) {
  const std::uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= slot_count) return;
  if (info->need_sync) {
    slots[s] = kEmptySlot;
    return;
  }
  const unsigned long long key = slots[s];
  if (key == kEmptySlot) return;
  const std::uint32_t c = groupIncrement(&info->cells, cg::coalesced_threads());
  if (c >= cell_cap) {
    slot_words[s] = ~0u;
    slots[s] = kEmptySlot;
    return;
  }
  const detail::CellId id = compactKeyCell(key, info->coord_bits);
  const unsigned long long h = detail::hashCellKey(detail::makeCellKey(id.level, id.x, id.y, id.z));
  const std::uint32_t n0 = slot_words[s], n1 = slot_words[group_stride + s];
  cell_count[c] = n0 + n1 + slot_words[2 * group_stride + s];
  cell_split[c] = make_uint2(n0, n0 + n1);
  slot_words[s] = c;
  cell_key[c] = key;
  slots[s] = slotValue(h, c);
}

/// One thread per entry of countFillKernel: its place (its cell's first entry, from the scan of
/// the counts, plus the start of its group in the cell, cell_split, plus its rank in the group),
/// its value and sub-cell span there, and, for every 32nd place, the cell (block_cell, as
/// cellsKernel). `axis` as countFillKernel's. Nothing after need_sync.
template <class S>
__global__ void __launch_bounds__(kBuildBlock)
    scatterKernel(std::uint32_t cap, const BuildInfo* info,
                  const std::uint32_t* __restrict__ ent_slot,
                  const std::uint32_t* __restrict__ ent_rank,
                  const std::uint32_t* __restrict__ ent_val,
                  const std::uint32_t* __restrict__ slot_cell,
                  const std::uint32_t* __restrict__ cell_begin,
                  const uint2* __restrict__ cell_split, int axis,
                  const unsigned long long* __restrict__ cell_key, const Aabb<S>* __restrict__ box,
                  std::uint32_t* __restrict__ entry_tri, std::uint32_t* __restrict__ entry_span,
                  std::uint32_t* __restrict__ block_cell) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= writtenEntries(info, cap)) return;
  const std::uint32_t c = slot_cell[ent_slot[k]];
  if (c == ~0u) return;
  const std::uint32_t v = ent_val[k];
  const detail::CellId id = compactKeyCell(cell_key[c], info->coord_bits);
  const Aabb<double> bd = toDoubleBox(box[v & kEntryTriMask]);
  const std::uint32_t span = detail::subcellSpan(bd, id.level, id.x, id.y, id.z, info->grid);
  // (The same span as countFillKernel's for this entry, so the same group.)
  const unsigned int group = axis < kNoCellGroups ? cellGroupOf(span, axis) : 1u;
  const uint2 split = cell_split[c];
  const std::uint32_t pos =
      cell_begin[c] + (group == 0 ? 0u : (group == 1 ? split.x : split.y)) + ent_rank[k];
  entry_tri[pos] = v;
  entry_span[pos] = span;
  if ((pos & 31u) == 0) block_cell[pos >> 5] = c;
}

/// A tile of G lanes per stored cell: which of the kUpperLevels levels above the cell's own hold
/// the cell's ancestor there (the cell containing it: coordinates shifted right by the
/// difference, see selfQueryLevels; lane r looks up levels own + r + 1, own + r + 1 + G, ...),
/// ORed by the lanes into HashView::upper of every triangle stored in the cell, with the valid
/// bit. `upper` must be zero before. Every triangle of the cell lies on the cell's level, and its
/// cells there are its cell range, so a triangle's bits end up as the levels above its own that
/// hold a cell of its range. Nothing is written unless the whole build was stored (not after
/// need_sync, nor when the entries or cells exceed `entry_cap` or `cell_cap`): a triangle with
/// some cells missing must keep its valid bit clear (such a build's query is rerun anyway).
/// G = kUpperTile (ncu, H100: 8 lanes took 18-22 us on the UNC cloth ball and 23-43 us on the
/// 1M cloth's frames; one lane per cell 33-40 and 30-44 us, 4 lanes 24-26 and 25-41, 32 lanes
/// 13-15 and 41-91: crowded cells want more lanes, light ones fewer).
constexpr int kUpperTile = 8;
template <class S, int G>
__global__ void upperLevelsKernel(HashView<S> M, const BuildInfo* __restrict__ info_p,
                                  std::uint32_t entry_cap, std::uint32_t cell_cap,
                                  std::uint32_t* __restrict__ upper) {
  const auto tile = cg::tiled_partition<G>(cg::this_thread_block());
  const unsigned long long c =
      (static_cast<unsigned long long>(blockIdx.x) * blockDim.x + threadIdx.x) / G;
  const unsigned int lane = tile.thread_rank();
  const BuildInfo& info = *info_p;
  if (info.need_sync || info.entries > entry_cap || info.cells > cell_cap || c >= info.cells)
    return;  // tile-uniform
  const detail::CellId id =
      M.key_words == 1
          ? compactKeyCell(__ldg(M.cell_key + c), info.coord_bits)
          : detail::cellOfKey(CellKey{__ldg(M.cell_key + 2 * c), __ldg(M.cell_key + 2 * c + 1)});
  std::uint32_t bits = kUpperValid;
  for (int k = static_cast<int>(lane) + 1; k <= kUpperLevels && id.level + k <= info.top_level;
       k += G) {
    const int L = id.level + k;
    if (((info.level_mask >> L) & 1ull) && findCell(M, info, L, id.x >> k, id.y >> k, id.z >> k) >= 0)
      bits |= 1u << k;
  }
  if (G > 1) bits = cg::reduce(tile, bits, cg::bit_or<std::uint32_t>());
  const std::uint32_t end = __ldg(M.cell_begin + c + 1);
  for (std::uint32_t e = __ldg(M.cell_begin + c) + lane; e < end; e += G) {
    const std::uint32_t tri = __ldg(M.entry_tri + e) & kEntryTriMask;
    atomicOr(upper + (tri >> 1), bits << (16u * (tri & 1u)));
  }
}

// ---------------------------------------------------------------------------------------------
// Query kernels
// ---------------------------------------------------------------------------------------------

/// The BuildInfo of the query's meshes (A in 0, B in 1; a self query uses 0), copied there on the
/// device (cudaMemcpyToSymbolAsync, device to device) before the candidate kernel: the grid of a
/// re-hash never passes through the host, and uniform reads of constant memory are as cheap as
/// kernel parameters.
/// (Raw bytes: BuildInfo's members have default initialisers, which __constant__ does not allow.)
__constant__ __align__(16) unsigned char c_info[2 * sizeof(BuildInfo)];
__device__ __forceinline__ const BuildInfo& cInfo(int k) {
  return reinterpret_cast<const BuildInfo*>(c_info)[k];
}

/// Where pairs go: key (a << b_bits) | b (so a radix sort on b_bits + a_bits bits sorts (a, b)),
/// appended at an atomic counter; slots past `capacity` are counted but not written, so the host
/// sees count > capacity, grows the buffer and reruns: no pair is ever dropped.
struct PairSink {
  unsigned long long* pairs;
  unsigned long long* count;
  unsigned long long capacity;
  int b_bits;
  // The pairs' sink of a query whose pairs are ordered by counting (runQuery): the count of each
  // segment (a >> seg_shift), and the word set when one exceeds seg_max. Null otherwise.
  unsigned int* seg = nullptr;
  int seg_shift = 0;
  unsigned long long* big = nullptr;
  unsigned int seg_max = kSegmentMax;
  /// A candidate sink of the warp-wide phase 1 (the warp scans, the cells' pairs): its kernels
  /// stage their pairs in shared memory (stagePair; KDET_FCL_CUDA_STAGE_PAIRS).
  bool staged = false;
  /// The bytes of a stored key: 8 (`pairs` holds 64-bit keys), or, for candidates whose key fits
  /// in 40 bits (candidateKeyBytes), 5 or 4: `pairs` then holds `capacity` 32-bit words (the
  /// keys' low bits), followed, for 5, by `hi`, the keys' bits 32 to 39, one byte per key.
  int key_bytes = 8;
  unsigned char* hi = nullptr;
};

/// Stores key `key` at place idx (< out.capacity) of the sink, in its layout (key_bytes).
__device__ __forceinline__ void storeKey(const PairSink& out, unsigned long long idx,
                                         unsigned long long key) {
  if (out.key_bytes == 8) {
    out.pairs[idx] = key;
    return;
  }
  reinterpret_cast<std::uint32_t*>(out.pairs)[idx] = static_cast<std::uint32_t>(key);
  if (out.key_bytes == 5) out.hi[idx] = static_cast<unsigned char>(key >> 32);
}

/// The keys a sink received, as the plane filter and the exact kernels read them: the first
/// min(*count, capacity), each as (a << 32) | b whatever the sink's layout and b_bits.
struct PairKeys {
  const unsigned long long* pairs;
  const unsigned long long* count;
  unsigned long long capacity;
  const unsigned char* hi;
  int key_bytes;
  int b_bits;

  __host__ static PairKeys of(const PairSink& s) {
    return PairKeys{s.pairs, s.count, s.capacity, s.hi, s.key_bytes, s.b_bits};
  }
  __device__ __forceinline__ unsigned long long size() const {
    return *count < capacity ? *count : capacity;
  }
  __device__ __forceinline__ unsigned long long at(unsigned long long k) const {
    unsigned long long key;
    if (key_bytes == 8) {
      key = __ldg(pairs + k);
      if (b_bits == 32) return key;
    } else {
      key = __ldg(reinterpret_cast<const std::uint32_t*>(pairs) + k);
      if (key_bytes == 5) key |= static_cast<unsigned long long>(__ldg(hi + k)) << 32;
    }
    return (key >> b_bits) << 32 | (key & ((1ull << b_bits) - 1));
  }
};

/// Counts pair (a, .) in its segment when the sink's pairs are ordered by counting.
__device__ __forceinline__ void countSegment(const PairSink& out, std::uint32_t a) {
  if (out.seg != nullptr && atomicAdd(out.seg + (a >> out.seg_shift), 1u) == out.seg_max)
    *out.big = 1;  // the segment's pair seg_max + 1: the radix sort orders this query
}

__device__ __forceinline__ void emitPair(const PairSink& out, std::uint32_t a, std::uint32_t b) {
  // One atomic per group of threads emitting together (they are usually a warp's worth).
  const unsigned long long idx = groupIncrement(out.count, cg::coalesced_threads());
  if (idx < out.capacity)
    storeKey(out, idx, (static_cast<unsigned long long>(a) << out.b_bits) | b);
  countSegment(out, a);
}

/// A warp's staging area for the pairs it emits (stagePair): 64 keys in shared memory and their
/// count, `fill` (warp-uniform, below 32 between calls). The warp writes its pairs there and
/// moves them to the sink 32 at a time, with one atomic on the sink's counter per 32 pairs, where
/// emitPair takes one per call of a group of lanes. The wait for that atomic's old value, which
/// the lanes need before they can write, is what the candidate kernels' warps stalled on most
/// (benchmarks/RESULTS-gpu.md: the cells' pairs, ncu's source counters).
struct PairStage {
  unsigned long long* keys;  ///< 64 slots of this warp's shared memory
  unsigned int fill;
};

/// Moves the first n (1..32) staged keys to the sink (counted always, written below capacity).
/// Every lane of the warp must call.
__device__ __forceinline__ void moveStaged(const PairSink& out, const PairStage& st,
                                           unsigned int n) {
  const unsigned int lane = threadIdx.x & 31u;
  unsigned long long base = 0;
  if (lane == 0) base = atomicAdd(out.count, static_cast<unsigned long long>(n));
  base = __shfl_sync(0xFFFFFFFFu, base, 0);
  if (lane < n && base + lane < out.capacity) storeKey(out, base + lane, st.keys[lane]);
}

/// Emits (a, b) from each lane whose `hit` is set, as emitPair does, through the warp's stage.
/// Every lane of the warp must call (the same call), with warp-uniform st.
__device__ __forceinline__ void stagePair(const PairSink& out, PairStage& st, bool hit,
                                          std::uint32_t a, std::uint32_t b) {
  const unsigned int lane = threadIdx.x & 31u;
  const unsigned int m = __ballot_sync(0xFFFFFFFFu, hit);
  if (m == 0) return;
  if (hit) {
    st.keys[st.fill + __popc(m & ((1u << lane) - 1u))] =
        (static_cast<unsigned long long>(a) << out.b_bits) | b;
    countSegment(out, a);
  }
  st.fill += __popc(m);
  if (st.fill < 32) return;
  __syncwarp();
  moveStaged(out, st, 32);
  __syncwarp();
  const unsigned long long rest = st.keys[32 + lane];
  __syncwarp();
  st.keys[lane] = rest;  // (slots past the new fill hold garbage, never read)
  st.fill -= 32;
  __syncwarp();
}

/// Moves what is left in the warp's stage to the sink. Every lane of the warp must call.
__device__ __forceinline__ void flushStage(const PairSink& out, PairStage& st) {
  __syncwarp();
  if (st.fill > 0) moveStaged(out, st, st.fill);
  __syncwarp();
  st.fill = 0;
}

/// A warp's emission of its lanes' pairs (a, b) where `hit`: through the warp's stage when the
/// sink says so (PairSink::staged), else by emitPair. Every lane of the warp must call.
__device__ __forceinline__ void emitFromWarp(const PairSink& out, PairStage& st, bool hit,
                                             std::uint32_t a, std::uint32_t b) {
  if (out.staged) stagePair(out, st, hit, a, b);
  else if (hit) emitPair(out, a, b);
}

/// The end of a kernel's emissions by emitFromWarp. Every lane of the warp must call.
__device__ __forceinline__ void finishWarp(const PairSink& out, PairStage& st) {
  if (out.staged) flushStage(out, st);
}

/// One round of a query pass: phase 1, filter and exact tests of one contiguous range of the
/// candidate search's tasks (runQuery: a query whose candidates would not fit in the candidate
/// buffer's limit runs in several rounds, each reusing the buffer; the pairs add up across
/// rounds). The ranges partition the tasks in order. `stage` 0: the range applies to each
/// phase-1 kernel of the query; a self query that takes its same-level pairs from the cells may
/// instead run its stages in rounds of their own: stage 1 runs only the cells' kernel, stage 2
/// only the scan, each over its range (index of count) of that kernel's tasks, so that a kernel
/// is split only when its own candidates exceed the limit. (Strided shares, round r taking the
/// tasks r, r + count, ..., were measured slower: benchmarks/RESULTS-gpu.md.)
struct Round {
  std::uint32_t index;
  std::uint32_t count;
  std::uint32_t stage;
  std::uint32_t serial;  // the round's place in its pass (Context::markRound)
};

/// How many of `tasks` tasks fall to the round (host and device agree).
__host__ __device__ __forceinline__ unsigned long long roundTasks(unsigned long long tasks,
                                                                  Round r) {
  return tasks * (r.index + 1) / r.count - tasks * r.index / r.count;
}

/// The task of the k-th of the round's tasks (k < roundTasks(tasks, r)).
__device__ __forceinline__ unsigned long long roundTask(unsigned long long k,
                                                        unsigned long long tasks, Round r) {
  return tasks * r.index / r.count + k;
}

/// Between rounds: keeps the round's candidate and survivor counts (the most of one round, and
/// the sum of all) and zeroes the per-round counters; the pair count goes on. One thread.
__global__ void roundEndKernel(unsigned long long* w) {
  w[kMaxCands] = max(w[kMaxCands], w[kCandCount]);
  w[kAllCands] += w[kCandCount];
  w[kMaxSurv] = max(w[kMaxSurv], w[kSurvCount]);
  w[kAllSurv] += w[kSurvCount];
  w[kCandCount] = w[kSurvCount] = w[kWarpTasks] = w[kCellTasks] = 0;
}

template <class S>
__global__ void mapVerticesKernel(std::uint32_t n, const Vec3<S>* __restrict__ v,
                                  Transform<double> a_to_b, Vec3<S>* __restrict__ out) {
  const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) out[i] = detail::mapPoint(a_to_b, v[i]);
}


/// The self query's adjacency rule, applied before a candidate is emitted: pairs sharing a vertex
/// index or coordinates never reach phase 2 (on a connected mesh they are most of the
/// box-overlapping pairs). Triangle i's indices and vertices are loaded here, where they are
/// needed (cache hits), instead of being held in registers through the whole scan.
template <class S>
__device__ __forceinline__ bool adjacentTriangles(const HashView<S>& M, std::uint32_t i,
                                                  std::uint32_t j) {
  const TriIndices ti = loadTri(M.t, i), tj = loadTri(M.t, j);
  if (shareIndex(ti, tj)) return true;
  const Vec3<S> vi[3] = {M.v[ti.a], M.v[ti.b], M.v[ti.c]};
  const Vec3<S> vj[3] = {M.v[tj.a], M.v[tj.b], M.v[tj.c]};
  bool adjacent = false;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) adjacent = adjacent || vi[a] == vj[b];
  return adjacent;
}

/// Two meshes hashed as one (intersectAll): triangles [0, split) are the first mesh's and
/// [split, n) the second's, and the adjacency rule holds only within a mesh (a pair across the
/// two is an inter-object pair, which counts when it merely touches). split = 0: one mesh.
__device__ __forceinline__ bool sameMesh(std::uint32_t split, std::uint32_t i, std::uint32_t j) {
  return (i < split) == (j < split);
}

/// selfCandidate by index, with both triangles' indices at hand.
__device__ __forceinline__ bool selfCandidateByIndex(std::uint32_t split, std::uint32_t i,
                                                     std::uint32_t j, const TriIndices& ti,
                                                     const TriIndices& tj) {
  return !sameMesh(split, i, j) || !shareIndex(ti, tj);
}

/// The self query's emit rule: a pair of one mesh that shares a vertex is adjacent, not a
/// candidate. by_index (indexAdjacency()): phase 1 drops only the pairs that share a vertex
/// index, so it never waits for the vertices; the pairs that share a vertex by its coordinates
/// alone are then candidates, which the plane filter keeps (their shared vertex lies on the
/// other triangle's plane, which it cannot prove off) and the self exact kernel drops (it tests
/// both kinds of adjacency). Else phase 1 drops both kinds.
template <class S>
__device__ __forceinline__ bool selfCandidate(const HashView<S>& M, std::uint32_t split,
                                              std::uint32_t i, std::uint32_t j, bool by_index) {
  if (by_index) return selfCandidateByIndex(split, i, j, loadTri(M.t, i), loadTri(M.t, j));
  return !sameMesh(split, i, j) || !adjacentTriangles(M, i, j);
}

/// The query box of B's triangle j in A's frame: its own box when the frames coincide, else the
/// box of its vertices mapped back into A's frame, grown by a conservative bound on the rounding
/// of that mapping (from both meshes' bounds, which live on the device: cInfo(0) and cInfo(1)).
template <class S>
__device__ __forceinline__ Aabb<double> boxInA(const HashView<S>& B, std::uint32_t j,
                                               bool identity, const Transform<double>& b_to_a,
                                               double eps_coef, double eps_tmag) {
  if (identity) return boxOf(B, j);
  Vec3<double> p[3];
  for (int k = 0; k < 3; ++k) {
    const Vec3<S> w = B.v[B.t[3 * j + k]];
    p[k] = b_to_a.apply(Vec3<double>{double(w.x), double(w.y), double(w.z)});
  }
  double mag = eps_tmag;
  for (int k = 0; k < 3; ++k)
    mag += fmax(fabs(cInfo(0).bounds.lo[k]), fabs(cInfo(0).bounds.hi[k])) +
           fmax(fabs(cInfo(1).bounds.lo[k]), fabs(cInfo(1).bounds.hi[k]));
  const double eps = eps_coef * mag + 2.2250738585072014e-308;
  return detail::inflate(detail::triangleBox<double>(p[0], p[1], p[2]), eps);
}

/// Phase 1 of an inter-object query: candidate pairs (i of A, j of B) that pass the size rule,
/// the box test and the canonical-cell test, appended to `cand` as (i << 32) | j. Threads
/// [0, na): A's triangle i against B's triangles with d_j >= d_i (looked up in B's frame with A's
/// mapped box). Threads [na, na + nb): B's triangle j against A's triangles with d_i > d_j (looked
/// up in A's frame with B's box mapped back and grown by eps). The exact tests run in phase 2,
/// one thread per candidate, so a warp does not serialise them behind its busiest thread.
template <class S, int G, int MB, bool kSpans>
__global__ void __launch_bounds__(kQueryBlock, MB)
    interCandidatesKernel(HashView<S> A, HashView<S> B, const Vec3<S>* __restrict__ va,
                          std::uint32_t na, std::uint32_t nb, bool identity,
                          Transform<double> b_to_a, double eps_coef, double eps_tmag,
                          bool a_ordered, bool b_ordered, Round round, PairSink cand) {
  // One tile of G lanes per query triangle (tile-uniform index), from the round's first.
  const auto tile = cg::tiled_partition<G>(cg::this_thread_block());
  const unsigned long long k =
      (static_cast<unsigned long long>(blockIdx.x) * blockDim.x + threadIdx.x) / G;
  if (k >= roundTasks(na + nb, round)) return;
  const auto idx = static_cast<std::uint32_t>(roundTask(k, na + nb, round));
  if (idx < na) {
    const std::uint32_t i = idx;
    const double di = A.diam[i];
    if (di > cInfo(1).d_max) return;  // nothing in B is as large
    const Aabb<double> q =
        detail::triangleBox<double>(va[A.t[3 * i]], va[A.t[3 * i + 1]], va[A.t[3 * i + 2]]);
    scanCandidatesGroup<kSpans>(
        B, cInfo(1), q, di, b_ordered,
        levelsFrom(cInfo(1).level_mask, detail::levelFor(di, cInfo(1).grid)), tile,
        [&](std::uint32_t, double dj) { return dj >= di; },
        [&](std::uint32_t j) { emitPair(cand, i, j); });
  } else {
    const std::uint32_t j = idx - na;
    const double dj = B.diam[j];
    if (dj >= cInfo(0).d_max) return;  // nothing in A is strictly larger
    const Aabb<double> q = boxInA(B, j, identity, b_to_a, eps_coef, eps_tmag);
    scanCandidatesGroup<kSpans>(
        A, cInfo(0), q, dj, a_ordered,
        levelsFrom(cInfo(0).level_mask, detail::levelFor(dj, cInfo(0).grid)), tile,
        [&](std::uint32_t, double di) { return di > dj; },
        [&](std::uint32_t i) { emitPair(cand, i, j); });
  }
}

/// Phase 1 of a self query: triangle i against the triangles j with (d_j, j) > (d_i, i), on its
/// own level and every coarser one, or (level_skip = 1, after selfCellPairsKernel) only on the
/// coarser ones; of those, only the levels that hold a cell of its range (selfQueryLevels).
template <class S, int G, int MB, bool kSpans>
__global__ void __launch_bounds__(kQueryBlock, MB)
    selfCandidatesKernel(HashView<S> M, std::uint32_t n, bool ordered, int level_skip,
                         bool by_index, std::uint32_t split, Round round, PairSink cand) {
  const auto tile = cg::tiled_partition<G>(cg::this_thread_block());
  const unsigned long long k =
      (static_cast<unsigned long long>(blockIdx.x) * blockDim.x + threadIdx.x) / G;
  if (k >= roundTasks(n, round)) return;
  const auto i = static_cast<std::uint32_t>(roundTask(k, n, round));
  const double di = M.diam[i];
  scanCandidatesGroup<kSpans>(
      M, cInfo(0), boxOf(M, i), di, ordered,
      selfQueryLevels(M, cInfo(0), i, detail::levelFor(di, cInfo(0).grid), level_skip), tile,
      [&](std::uint32_t j, double dj) { return dj > di || (dj == di && j > i); },
      [&](std::uint32_t j) {
        if (selfCandidate(M, split, i, j, by_index)) emitPair(cand, i, j);
      });
}

/// The next task of a warp-wide candidate kernel: a task is the queries of one warp (32 / P of
/// them). Lane 0 takes it from the launch's counter and hands it to the warp, so warps that
/// finish early take more work and no SM idles while another still has a long queue (the grid
/// is sized to the resident warps: warpScanBlocks). Warp-uniform; every lane must call.
__device__ __forceinline__ unsigned long long nextWarpTask(unsigned long long* tasks) {
  unsigned long long t = 0;
  if ((threadIdx.x & 31u) == 0) t = atomicAdd(tasks, 1ull);
  return __shfl_sync(0xFFFFFFFFu, t, 0);
}

/// Whether the warp-wide candidate kernels of S hashes loop over tasks from a counter. Float only:
/// the loop's state pushed the double kernels past their 64 registers (stack frames of 24-80
/// bytes against 0-16; double queries measured 2 % slower), so a double kernel runs one task per
/// warp, as before (the host passes it no counter: warpScanLaunch).
template <class S>
constexpr bool kWarpTaskLoop = std::is_same<S, float>::value;

/// Calls run(task) for each task of the round's share of [0, count) (roundTask) that this warp
/// takes: from the counter `tasks` until they run out, or, with tasks == nullptr (one warp per
/// task, the grid covering the round's tasks), the one task of the warp's index in the grid.
/// Warp-uniform; every lane must call.
template <class S, class Run>
__device__ __forceinline__ void forEachWarpTask(unsigned long long* tasks,
                                                unsigned long long count, Round round, Run&& run) {
  const bool loop = kWarpTaskLoop<S> && tasks != nullptr;
  const unsigned long long mine = roundTasks(count, round);
  unsigned long long k =
      loop ? nextWarpTask(tasks)
           : (static_cast<unsigned long long>(blockIdx.x) * blockDim.x + threadIdx.x) >> 5;
  for (; k < mine; k = nextWarpTask(tasks)) {
    run(roundTask(k, count, round));
    if (!loop) break;
  }
}

/// This warp's 32 / 2^log_p query slots (scanCandidatesWarp's q) in the block's dynamic shared
/// memory, which the host sizes for 2^log_p lanes per query (warpSlotBytes), for the warp scans
/// that test spans (crowded meshes, 8 lanes per query by default): 2.2 KB per block against the
/// 17.4 KB of 32 slots per warp, which leaves the SM more L1 cache (H100, the cloth ball's scan:
/// shared-memory configuration 196 -> 132 KB, L1 hits 50 -> 57 %, 112.8 -> 109.5 us;
/// benchmarks/RESULTS-gpu.md). The scans without spans keep 32 static slots per warp: the
/// dynamic slots' addressing cost them 1-2 % there.
__device__ __forceinline__ WarpQuery* warpSlots(unsigned int log_p) {
  extern __shared__ __align__(16) unsigned char warp_slot_memory[];
  return reinterpret_cast<WarpQuery*>(warp_slot_memory) + (threadIdx.x >> 5) * (32u >> log_p);
}

/// The dynamic shared memory of a warp-wide scan's block for 2^log_p lanes per query: its query
/// slots where it tests spans (warpSlots), else none.
constexpr std::size_t warpSlotBytes(bool spans, unsigned int log_p) {
  return spans ? std::size_t(kQueryBlock / 32) * (32u >> log_p) * sizeof(WarpQuery) : 0;
}

/// Phase 1 of a self query with the warp-wide scan (scanCandidatesWarp): 2^log_p lanes per query
/// triangle, the same candidates as selfCandidatesKernel (level_skip likewise). Each task is the
/// 32 / 2^log_p queries starting at task * (32 >> log_p) (forEachWarpTask).
template <class S, int MB, bool kSpans>
__global__ void __launch_bounds__(kQueryBlock, MB)
    selfCandidatesWarpKernel(HashView<S> M, std::uint32_t n, unsigned int log_p,
                             std::uint32_t max_visit, int level_skip, bool size_by_level,
                             bool by_index, bool fixed_cells, std::uint32_t split, Round round,
                             PairSink cand, unsigned long long* tasks) {
  __shared__ WarpQuery slots[kSpans ? 1 : kQueryBlock];  // (with spans: warpSlots)
  __shared__ unsigned long long stage_keys[kQueryBlock / 32][64];  // (cand.staged)
  WarpQuery* q = kSpans ? warpSlots(log_p) : slots + (threadIdx.x & ~31u);
  PairStage stage{stage_keys[threadIdx.x >> 5], 0};
  const std::uint32_t lane = threadIdx.x & 31u;
  const std::uint32_t per_warp = 32u >> log_p;
  const unsigned long long count = (n + per_warp - 1) / per_warp;
  forEachWarpTask<S>(tasks, count, round, [&](unsigned long long task) {
    const std::uint32_t i = static_cast<std::uint32_t>(task) * per_warp + (lane >> log_p);
    WarpQuery mine;
    mine.id = i;
    mine.d = 0;
    mine.levels = 0;
    mine.live = 0;
    mine.size_level = detail::kMaxLevels;
    if (i < n) {
      mine.d = M.diam[i];
      mine.box = detail::intersectBoxes(boxOf(M, i), cInfo(0).bounds);
      const int own = detail::levelFor(mine.d, cInfo(0).grid);
      mine.levels = selfQueryLevels(M, cInfo(0), i, own, level_skip);
      if (size_by_level) mine.size_level = static_cast<std::int16_t>(own);
      if (by_index) mine.tri = loadTri(M.t, i);
      mine.live = detail::isEmpty(mine.box) ? 0u : 1u;
    }
    scanCandidatesWarp<kSpans>(
        M, cInfo(0), q, mine, log_p, max_visit, by_index, fixed_cells,
        warpRing<kSpans, kQueryBlock / 32>(),
        [&](const WarpQuery& o, std::uint32_t j, double dj) {
          return dj > o.d || (dj == o.d && j > o.id);
        },
        [&](const WarpQuery& o, std::uint32_t j, const TriIndices& tj, std::uint32_t& a,
            std::uint32_t& b) {
          a = o.id, b = j;
          return by_index ? selfCandidateByIndex(split, o.id, j, o.tri, tj)
                          : selfCandidate(M, split, o.id, j, false);
        },
        [&](bool hit, std::uint32_t a, std::uint32_t b) {
          emitFromWarp(cand, stage, hit, a, b);
        });
  });
  finishWarp(cand, stage);
}

/// A triangle's box, its coordinates loaded at once for float (loadBox), plainly for double.
template <class S>
__device__ __forceinline__ Aabb<S> loadBoxOf(const Aabb<S>* p) {
  if constexpr (std::is_same<S, float>::value) return loadBox(p);
  else return *p;
}


/// Phase 1 of a self query, its pairs of triangles on one level; the query scans then start one
/// level above each query's own (level_skip = 1). Two triangles of one level meet only in the
/// cells of that level where both are stored, and a query's cell range on its own level is the
/// set of cells where its triangle is stored (the build's level, box and cellRange), so the
/// same-level candidates of the query scans are the pairs of entries of one cell that pass their
/// rules: the canonical cell (on every axis the first cell of one of the two: their first-cell
/// bits), the box test and the adjacency rule; the size rule only picks which of the two queries
/// found the pair. Here each such pair is tested once, from its cell, with no lookup, against
/// twice (once from each triangle) in the query scans. Emitted as (min, max) of the indices (the
/// filter and exact kernels do not depend on the order).
/// A warp task is `rows` (1, 2, 4, 8, 16 or 32: a divisor of 32) consecutive entries (block_cell gives the cell of the entry
/// 32 * floor(first row / 32)); a task's work is about rows * m / 2 pairs in a cell of m entries,
/// so crowded cells want few rows per task (short tasks, a short tail of busy warps) and sparse
/// ones many (less per-task overhead): cellRows(). In a cell of m entries, row a (its position in the cell) pairs with
/// the h = (m - 1) / 2 entries after it, cyclically, and, when m is even and a < m / 2, also with
/// a + m / 2: every unordered pair once, and every row about m / 2 partners, so no task holds
/// the long first rows of a crowded cell. The warp tests the partners of its rows 32 at a time
/// whatever row they belong to (prefix sum and owner search, as scanCandidatesWarp), each row in
/// visits of at most max_visit partners. kSpans: a pair whose sub-cell spans in the cell do not
/// overlap (both entries' spans: subcellSpan is monotone, so boxes that overlap have overlapping
/// spans) is dropped before the partner's box is loaded, and the partners that pass (few per
/// round in crowded cells) wait on the warp's EntryRing until 32 are there, or the task ends, to
/// be tested together (kQueueSeen, as in scanCandidatesWarp). The round's share of the tasks
/// (roundTask) comes from the counter `tasks`; the grid is the resident blocks. Only the cells
/// this build stored are read (info.cells against cell_cap; none after need_sync): a re-hash that
/// did not fit reruns the query anyway (checkPending). Each warp adds the candidates it emitted
/// to *cell_count once, at its end (the cells' share of the candidates, QueryProfile's
/// cell_candidates and the stages' rounds), so that the share is known also when the scan of the
/// coarser levels runs at the same time (selfOverlap()).
template <class S, bool kSpans>
__global__ void __launch_bounds__(kQueryBlock, 8)
    selfCellPairsKernel(HashView<S> M, const std::uint32_t* __restrict__ block_cell,
                        std::uint32_t cell_cap, std::uint32_t rows, std::uint32_t max_visit,
                        bool by_index, std::uint32_t split, Round round, PairSink cand,
                        unsigned long long* tasks, unsigned long long* cell_count) {
  constexpr unsigned int kFull = 0xFFFFFFFFu;
  __shared__ Aabb<S> row_boxes[kQueryBlock / 32][32];
  __shared__ TriIndices row_tris[kQueryBlock / 32][32];  // (by_index)
  __shared__ unsigned long long stage_keys[kQueryBlock / 32][64];  // (cand.staged)
  EntryRing ring = warpRing<kSpans, kQueryBlock / 32>();
  Aabb<S>* const row_box = row_boxes[threadIdx.x >> 5];
  TriIndices* const row_tri = row_tris[threadIdx.x >> 5];
  PairStage stage{stage_keys[threadIdx.x >> 5], 0};
  const unsigned int lane = threadIdx.x & 31u;
  const BuildInfo& info = cInfo(0);
  const std::uint32_t cells = info.need_sync ? 0u : (info.cells < cell_cap ? info.cells : cell_cap);
  if (cells == 0) return;
  const std::uint32_t entries = __ldg(M.cell_begin + cells);  // the stored cells' entries
  const unsigned long long count = (entries + rows - 1ull) / rows;
  const unsigned long long mine = roundTasks(count, round);
  unsigned long long found = 0;  // the warp's candidates (warp-uniform)
  for (unsigned long long t = nextWarpTask(tasks); t < mine; t = nextWarpTask(tasks)) {
    const unsigned long long task = roundTask(t, count, round);
    const std::uint32_t first = static_cast<std::uint32_t>(task) * rows;
    const std::uint32_t k = first + lane;  // the row of lanes < rows
    // Entries [32 * (first / 32), first + rows) lie in at most 32 consecutive cells from c0
    // (a cell has at least one entry): lane l holds the end of cell c0 + l, and row k's cell is
    // c0 plus the number of those ends at or before k.
    const std::uint32_t c0 = __ldg(block_cell + first / 32);
    const std::uint32_t cl = c0 + lane + 1;
    const std::uint32_t cell_end = __ldg(M.cell_begin + (cl < cells ? cl : cells));
    const int o = warpOwnerOf(cell_end, k);
    const std::uint32_t end = __shfl_sync(kFull, cell_end, o);
    const std::uint32_t prev_end = __shfl_sync(kFull, cell_end, o > 0 ? o - 1 : 0);
    const std::uint32_t begin = o > 0 ? prev_end : __ldg(M.cell_begin + c0);
    // Row k's partners: positions [next, stop) of its cyclic list.
    std::uint32_t next = 0, stop = 0, v = 0, span = 0;
    __syncwarp();  // the lanes are done with the previous task's row boxes
    if (lane < rows && k < entries) {
      const std::uint32_t m = end - begin, a = k - begin;
      stop = (m - 1) / 2 + ((m % 2 == 0 && a < m / 2) ? 1u : 0u);
      v = __ldg(M.entry_tri + k);
      if (kSpans) span = __ldg(M.entry_span + k);
      row_box[lane] = loadBoxOf(M.box + (v & kEntryTriMask));
      if (by_index) row_tri[lane] = loadTri(M.t, v & kEntryTriMask);
    }
    __syncwarp();
    // A partner's last tests (have: the lane holds one; i, j: the row's and the partner's
    // triangles; row: the row's lane): the box test and the adjacency rule; then the emission
    // as (min, max), in every lane.
    const auto test = [&](bool have, std::uint32_t i, std::uint32_t j, std::uint8_t row) {
      bool hit = false;
      if (have) {
        const Aabb<S> e = loadBoxOf(M.box + j);
        // (by_index: the partner's vertex indices come in the same round trip as its box. The
        // adjacency rule by index before the box, sparing the neighbours' boxes, measured level:
        // benchmarks/RESULTS-gpu.md, "The cells' own span filter".)
        const TriIndices tj = by_index ? loadTri(M.t, j) : TriIndices{0, 0, 0};
        bool overlap;
        if constexpr (std::is_same<S, float>::value) overlap = boxesInFloat(row_box[row], e);
        else overlap = detail::boxesOverlap(row_box[row], e);
        hit = overlap && (by_index ? selfCandidateByIndex(split, i, j, row_tri[row], tj)
                                   : selfCandidate(M, split, i, j, false));
      }
      found += __popc(__ballot_sync(kFull, hit));
      emitFromWarp(cand, stage, hit, i < j ? i : j, i < j ? j : i);
    };
    // The same for a partner off the warp's EntryRing (kQueueSeen), tagged with its row: the
    // row's entry comes from the row's lane.
    const auto test_queued = [&](bool have, std::uint32_t j, std::uint8_t row) {
      test(have, __shfl_sync(kFull, v, row) & kEntryTriMask, j, row);
    };
    while (true) {
      const std::uint32_t cnt = stop - next < max_visit ? stop - next : max_visit;
      const std::uint32_t incl = warpInclusiveSum(cnt);
      const std::uint32_t total = __shfl_sync(kFull, incl, 31);
      if (total == 0) break;
      for (std::uint32_t base = 0; base < total; base += 32) {
        const std::uint32_t t = base + lane;
        const int owner = warpOwnerOf(incl, t);
        const std::uint32_t o_first =
            __shfl_sync(kFull, incl, owner) - __shfl_sync(kFull, cnt, owner);
        const std::uint32_t o_next = __shfl_sync(kFull, next, owner);
        const std::uint32_t o_begin = __shfl_sync(kFull, begin, owner);
        const std::uint32_t o_end = __shfl_sync(kFull, end, owner);
        const std::uint32_t o_v = __shfl_sync(kFull, v, owner);
        const std::uint32_t o_span = kSpans ? __shfl_sync(kFull, span, owner) : 0u;
        bool seen = false;
        std::uint32_t w = 0;
        if (t < total) {
          // The partner at position q of row a's cyclic list.
          const std::uint32_t m = o_end - o_begin, a = first + owner - o_begin;
          const std::uint32_t q = o_next + (t - o_first);
          std::uint32_t bpos = q < (m - 1) / 2 ? a + 1 + q : a + m / 2;
          if (bpos >= m) bpos -= m;
          const std::uint32_t b = o_begin + bpos;
          w = __ldg(M.entry_tri + b);
          // This cell is the pair's canonical cell, and (kSpans) their spans overlap in it.
          seen = ((o_v | w) >> 29) == 7u &&
                 (!kSpans || detail::subcellSpansOverlap(o_span, __ldg(M.entry_span + b)));
        }
        if constexpr (kQueueSeen<kSpans>) {
          pushRing(ring, seen, w & kEntryTriMask, static_cast<std::uint8_t>(owner));
          if (ring.count >= 32) popRing(ring, 32, test_queued);
        } else {
          test(seen, o_v & kEntryTriMask, w & kEntryTriMask, static_cast<std::uint8_t>(owner));
        }
      }
      next += cnt;
    }
    if constexpr (kQueueSeen<kSpans>)
      popRing(ring, ring.count, test_queued);  // (the rows change with the task)
  }
  finishWarp(cand, stage);
  if (lane == 0 && found > 0) atomicAdd(cell_count, found);
}

/// Phase 1 of an inter-object query with the warp-wide scan: the same candidates as
/// interCandidatesKernel, 2^log_p lanes per query triangle. The first wa = ceil(na / (32 >> log_p))
/// tasks query A's triangles in B's hash, the next ones B's triangles in A's hash (so no warp
/// mixes the two); tasks as in selfCandidatesWarpKernel.
template <class S, int MB, bool kSpans>
__global__ void __launch_bounds__(kQueryBlock, MB)
    interCandidatesWarpKernel(HashView<S> A, HashView<S> B, const Vec3<S>* __restrict__ va,
                              std::uint32_t na, std::uint32_t nb, bool identity,
                              Transform<double> b_to_a, double eps_coef, double eps_tmag,
                              unsigned int log_p, std::uint32_t max_visit, bool size_by_level,
                              bool fixed_cells, Round round, PairSink cand,
                              unsigned long long* tasks) {
  __shared__ WarpQuery slots[kSpans ? 1 : kQueryBlock];  // (with spans: warpSlots)
  __shared__ unsigned long long stage_keys[kQueryBlock / 32][64];  // (cand.staged)
  WarpQuery* q = kSpans ? warpSlots(log_p) : slots + (threadIdx.x & ~31u);
  PairStage stage{stage_keys[threadIdx.x >> 5], 0};
  const std::uint32_t lane = threadIdx.x & 31u;
  const std::uint32_t per_warp = 32u >> log_p;
  const unsigned long long wa = (na + per_warp - 1) / per_warp;
  const unsigned long long count = wa + (nb + per_warp - 1) / per_warp;
  forEachWarpTask<S>(tasks, count, round, [&](unsigned long long task) {
    const bool a_side = task < wa;
    const std::uint32_t idx =
        static_cast<std::uint32_t>(a_side ? task : task - wa) * per_warp + (lane >> log_p);
    const std::uint32_t nq = a_side ? na : nb;
    WarpQuery mine;
    mine.id = idx;
    mine.d = 0;
    mine.levels = 0;
    mine.live = 0;
    mine.size_level = detail::kMaxLevels;
    const BuildInfo& target = cInfo(a_side ? 1 : 0);
    if (idx < nq) {
      Aabb<double> box;
      if (a_side) {
        mine.d = A.diam[idx];
        box = detail::triangleBox<double>(va[A.t[3 * idx]], va[A.t[3 * idx + 1]],
                                          va[A.t[3 * idx + 2]]);
      } else {
        mine.d = B.diam[idx];
        box = boxInA(B, idx, identity, b_to_a, eps_coef, eps_tmag);
      }
      // Nothing in the other mesh is large enough (A: d_j >= d_i; B: d_i > d_j).
      const bool none = a_side ? mine.d > cInfo(1).d_max : mine.d >= cInfo(0).d_max;
      mine.box = detail::intersectBoxes(box, target.bounds);
      const int own = detail::levelFor(mine.d, target.grid);
      mine.levels = levelsFrom(target.level_mask, own);
      if (size_by_level) mine.size_level = static_cast<std::int16_t>(own);
      mine.live = (none || detail::isEmpty(mine.box)) ? 0u : 1u;
    }
    const auto emit = [&](bool hit, std::uint32_t a, std::uint32_t b) {
      emitFromWarp(cand, stage, hit, a, b);
    };
    if (a_side)
      scanCandidatesWarp<kSpans>(
          B, target, q, mine, log_p, max_visit, false, fixed_cells,
          warpRing<kSpans, kQueryBlock / 32>(),
          [](const WarpQuery& o, std::uint32_t, double dj) { return dj >= o.d; },
          [](const WarpQuery& o, std::uint32_t j, const TriIndices&, std::uint32_t& a,
             std::uint32_t& b) {
            a = o.id, b = j;
            return true;
          },
          emit);
    else
      scanCandidatesWarp<kSpans>(
          A, target, q, mine, log_p, max_visit, false, fixed_cells,
          warpRing<kSpans, kQueryBlock / 32>(),
          [](const WarpQuery& o, std::uint32_t, double di) { return di > o.d; },
          [](const WarpQuery& o, std::uint32_t i, const TriIndices&, std::uint32_t& a,
             std::uint32_t& b) {
            a = i, b = o.id;
            return true;
          },
          emit);
  });
  finishWarp(cand, stage);
}

/// Phase 2: the exact test of each candidate (grid-stride over the device-side count, so the
/// host needs no read-back between the phases; items spread over the warps, spreadIndex). Every
/// test uses A's vertices mapped into B's frame (`va`) and B's own vertices, as on the CPU.
template <class S, class K>
__global__ void __launch_bounds__(kQueryBlock)
    interExactKernel(PairKeys cand, const Vec3<S>* __restrict__ va,
                     const std::uint32_t* __restrict__ ta, const Vec3<S>* __restrict__ vb,
                     const std::uint32_t* __restrict__ tb, PairSink out) {
  const unsigned long long m = cand.size();
  const SpreadIndex at = spreadIndex();
  for (unsigned long long k = at.first; k < m; k += at.stride) {
    const unsigned long long c = cand.at(k);
    const auto i = static_cast<std::uint32_t>(c >> 32), j = static_cast<std::uint32_t>(c);
    if (detail::trianglesIntersectWith<K>(va[ta[3 * i]], va[ta[3 * i + 1]], va[ta[3 * i + 2]],
                                          vb[tb[3 * j]], vb[tb[3 * j + 1]], vb[tb[3 * j + 2]]))
      emitPair(out, i, j);
  }
}

/// Emits a self query's colliding pair (i, j) as (min, max); with two meshes hashed as one
/// (split > 0), in its own mesh's indices, with its kind in the two bits above the first index
/// (bit cat_shift: 0 the first mesh's self pair, 1 the second's, 2 across).
__device__ __forceinline__ void emitSelfPair(const PairSink& out, std::uint32_t split,
                                             int cat_shift, std::uint32_t i, std::uint32_t j) {
  std::uint32_t a = i < j ? i : j, b = i < j ? j : i;
  if (split > 0 && b >= split) {  // the second mesh's own pair, or one across
    const std::uint32_t cat = a >= split ? 1u : 2u;
    a = (cat << cat_shift) | (cat == 1u ? a - split : a);
    b -= split;
  }
  emitPair(out, a, b);
}

/// Phase 2 of a self query: pairs sharing a vertex (index or coordinates) are adjacent, not
/// colliding; the others get the exact test. Emits (min, max). With two meshes hashed as one
/// (split > 0), a pair across them is never adjacent, and its test takes the first mesh's
/// triangle first, as intersectMeshes does (the inexact predicates may depend on the order);
/// each pair is emitted in its own mesh's indices, with its kind in the two bits above the
/// first index (bit cat_shift: 0 the first mesh's self pair, 1 the second's, 2 across), so
/// that the sort puts the three lists one after the other (runQuery deals them out).
template <class S, class K>
__global__ void __launch_bounds__(kQueryBlock)
    selfExactKernel(PairKeys cand, const Vec3<S>* __restrict__ v,
                    const std::uint32_t* __restrict__ t, std::uint32_t split, int cat_shift,
                    PairSink out) {
  const unsigned long long m = cand.size();
  const SpreadIndex at = spreadIndex();
  for (unsigned long long k = at.first; k < m; k += at.stride) {
    const unsigned long long c = cand.at(k);
    auto i = static_cast<std::uint32_t>(c >> 32), j = static_cast<std::uint32_t>(c);
    const bool same = sameMesh(split, i, j);
    if (!same && i > j) {
      const std::uint32_t x = i;
      i = j;
      j = x;
    }
    const std::uint32_t ti[3] = {t[3 * i], t[3 * i + 1], t[3 * i + 2]};
    const std::uint32_t tj[3] = {t[3 * j], t[3 * j + 1], t[3 * j + 2]};
    const Vec3<S> vi[3] = {v[ti[0]], v[ti[1]], v[ti[2]]};
    const Vec3<S> vj[3] = {v[tj[0]], v[tj[1]], v[tj[2]]};
    bool adjacent = false;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) adjacent = adjacent || ti[a] == tj[b] || vi[a] == vj[b];
    adjacent = adjacent && same;
    if (!adjacent &&
        detail::trianglesIntersectWith<K>(vi[0], vi[1], vi[2], vj[0], vj[1], vj[2]))
      emitSelfPair(out, split, cat_shift, i, j);
  }
}

/// True when the filter proves all three vertices of triangle p strictly on one side of the
/// plane of triangle q (orient3d(q0, q1, q2, p_k) all +1 or all -1, by detail::orient3dFilterSign
/// on the plane prepared once, on the coordinates converted to double exactly, as
/// trianglesIntersectWith does): then trianglesIntersectWith<ExactKernel>, whose first test is
/// these exact signs, rejects the pair. A sign the filter cannot prove (0) keeps the pair. The
/// vertices are loaded where they are used, so few stay live in registers.
template <class S>
__device__ __forceinline__ bool strictlyOneSide(const Vec3<S>* __restrict__ qv,
                                                const std::uint32_t* __restrict__ qt,
                                                const Vec3<S>* __restrict__ pv,
                                                const std::uint32_t* __restrict__ pt) {
  const detail::OrientPlane plane = detail::orientPlane(
      detail::toDouble(qv[qt[0]]), detail::toDouble(qv[qt[1]]), detail::toDouble(qv[qt[2]]));
  const int s = detail::orient3dFilterSign(plane, detail::toDouble(pv[pt[0]]));
  if (s == 0) return false;
  if (detail::orient3dFilterSign(plane, detail::toDouble(pv[pt[1]])) != s) return false;
  return detail::orient3dFilterSign(plane, detail::toDouble(pv[pt[2]])) == s;
}

/// Calls f(i, j, p0, p1, p2, q0, q1, q2) for candidate c = (i << 32) | j: A's triangle i
/// (vertices va, indices ta) and B's triangle j (vb, tb), their vertices loaded here.
template <class S, class F>
__device__ __forceinline__ void withPairVertices(unsigned long long c,
                                                 const Vec3<S>* __restrict__ va,
                                                 const std::uint32_t* __restrict__ ta,
                                                 const Vec3<S>* __restrict__ vb,
                                                 const std::uint32_t* __restrict__ tb, F&& f) {
  const auto i = static_cast<std::uint32_t>(c >> 32), j = static_cast<std::uint32_t>(c);
  const std::uint32_t* const p = ta + 3 * std::size_t(i);
  const std::uint32_t* const q = tb + 3 * std::size_t(j);
  f(i, j, va[p[0]], va[p[1]], va[p[2]], vb[q[0]], vb[q[1]], vb[q[2]]);
}

/// The deciding filter's verdict v on candidate (i, j): a colliding pair to `out` as the exact
/// kernel would emit it (self: emitSelfPair), an undecided one to `surv` for the exact kernel,
/// nothing for a disjoint one.
__device__ __forceinline__ void emitVerdict(detail::FilterVerdict v, std::uint32_t i,
                                            std::uint32_t j, const PairSink& surv,
                                            const PairSink& out, bool self, std::uint32_t split,
                                            int cat_shift) {
  if (v == detail::FilterVerdict::Intersect) {
    if (self) emitSelfPair(out, split, cat_shift, i, j);
    else emitPair(out, i, j);
  } else if (v == detail::FilterVerdict::Undecided) {
    emitPair(surv, i, j);
  }
}

/// Between phases 1 and 2 (Predicate::Exact only): one thread per candidate drops the pair when
/// either triangle lies, provably, strictly on one side of the other's plane; the survivors are
/// appended to `surv` (the same (i << 32) | j keys) for the exact kernel. Every dropped pair is one
/// the exact test rejects, so the result set cannot change; the exact kernel (128 registers, low
/// occupancy) then runs on several times fewer pairs. kDecide (KDET_FCL_CUDA_FILTER_DECIDES):
/// the filter also finishes the test wherever its filters decide it
/// (detail::trianglesFilterVerdict, the exact test's own answer there), emits the colliding
/// pairs to `out` as the exact kernel would (self: emitSelfPair), and passes on only the
/// undecided ones: among them every pair that shares a vertex, so the exact kernel still decides
/// adjacency. Inter queries pass A's mapped vertices as (va, ta) and B's as (vb, tb); self
/// queries pass the mesh twice, `self` set. MB: blocks per SM in __launch_bounds__ (6: at most 40
/// registers, a few spills; 1: uncapped, ~80 registers; 3: the deciding filter's default).
template <class S, int MB, bool kDecide>
__global__ void __launch_bounds__(kFilterBlock, MB)
    planeFilterKernel(PairKeys cand, const Vec3<S>* __restrict__ va,
                      const std::uint32_t* __restrict__ ta,
                      const Vec3<S>* __restrict__ vb, const std::uint32_t* __restrict__ tb,
                      PairSink surv, PairSink out, bool self, std::uint32_t split,
                      int cat_shift) {
  const unsigned long long m = cand.size();
  for (unsigned long long k = blockIdx.x * blockDim.x + threadIdx.x; k < m;
       k += gridDim.x * blockDim.x) {
    const unsigned long long c = cand.at(k);
    if constexpr (kDecide) {
      withPairVertices(c, va, ta, vb, tb, [&](std::uint32_t i, std::uint32_t j, const auto&... v) {
        emitVerdict(detail::trianglesFilterVerdict(v...), i, j, surv, out, self, split,
                    cat_shift);
      });
    } else {
      const auto i = static_cast<std::uint32_t>(c >> 32), j = static_cast<std::uint32_t>(c);
      const bool drop =
          strictlyOneSide(vb, tb + 3 * std::size_t(j), va, ta + 3 * std::size_t(i)) ||
          strictlyOneSide(va, ta + 3 * std::size_t(i), vb, tb + 3 * std::size_t(j));
      if (!drop) emitPair(surv, i, j);
    }
  }
}

/// The deciding plane filter (planeFilterKernel<S, MB, true>: the same pairs to `out` and `surv`)
/// with its last step in full warps. A lane's first steps (detail::planeFilterSigns: the two
/// planes' signs) decide most pairs; the rest, about one in five on the cloth ball, take
/// detail::transversalFilterVerdict's two orientations. In the one-thread-per-pair kernel those
/// run with a few lanes of each warp busy (ncu, cloth ball: 7 of 32 on average there). Here each
/// warp queues those pairs in shared memory, with their six signs (non-zero: one bit each), and
/// finishes them 32 at a time, reloading their vertices (cached), and the few left at its end.
/// Warp-uniform loop: every lane of a warp takes the pairs base + lane of the same bases. The
/// grid is the resident blocks (launchPlaneFilter), so that a warp takes many pairs.
template <class S, int MB>
__global__ void __launch_bounds__(kFilterBlock, MB)
    planeFilterQueuedKernel(PairKeys cand, const Vec3<S>* __restrict__ va,
                            const std::uint32_t* __restrict__ ta,
                            const Vec3<S>* __restrict__ vb, const std::uint32_t* __restrict__ tb,
                            PairSink surv, PairSink out, bool self, std::uint32_t split,
                            int cat_shift) {
  constexpr unsigned int kFull = 0xFFFFFFFFu;
  __shared__ unsigned long long queue_keys[kFilterBlock / 32][64];
  __shared__ unsigned char queue_signs[kFilterBlock / 32][64];
  unsigned long long* const qk = queue_keys[threadIdx.x >> 5];
  unsigned char* const qs = queue_signs[threadIdx.x >> 5];
  const unsigned int lane = threadIdx.x & 31u;
  const unsigned long long m = cand.size();
  // The last step of pair c whose signs are `bits` (bit k: sp[k] > 0, bit 3 + k: sq[k] > 0).
  const auto finish = [&](unsigned long long c, unsigned int bits) {
    int sp[3], sq[3];
    for (int k = 0; k < 3; ++k) {
      sp[k] = (bits >> k) & 1u ? 1 : -1;
      sq[k] = (bits >> (3 + k)) & 1u ? 1 : -1;
    }
    withPairVertices(c, va, ta, vb, tb, [&](std::uint32_t i, std::uint32_t j, const auto&... v) {
      emitVerdict(detail::transversalFilterVerdict(sp, sq, v...), i, j, surv, out, self, split,
                  cat_shift);
    });
  };
  unsigned int fill = 0;  // the warp's queued pairs (warp-uniform, below 32 between steps)
  const unsigned long long stride = static_cast<unsigned long long>(gridDim.x) * blockDim.x;
  for (unsigned long long base = static_cast<unsigned long long>(blockIdx.x) * blockDim.x +
                                 (threadIdx.x & ~31u);
       base < m; base += stride) {
    const unsigned long long k = base + lane;
    bool queue = false;
    unsigned int bits = 0;
    unsigned long long c = 0;
    if (k < m) {
      c = cand.at(k);
      withPairVertices(c, va, ta, vb, tb, [&](std::uint32_t i, std::uint32_t j, const auto&... v) {
        int sp[3], sq[3];
        detail::FilterVerdict verdict;
        if (detail::planeFilterSigns(v..., sp, sq, verdict)) {
          queue = true;
          for (int e = 0; e < 3; ++e)
            bits |= (sp[e] > 0 ? 1u : 0u) << e | (sq[e] > 0 ? 1u : 0u) << (3 + e);
        } else if (verdict == detail::FilterVerdict::Undecided) {
          emitPair(surv, i, j);
        }
      });
    }
    const unsigned int mask = __ballot_sync(kFull, queue);
    if (queue) {
      const unsigned int at = fill + __popc(mask & ((1u << lane) - 1u));
      qk[at] = c;
      qs[at] = static_cast<unsigned char>(bits);
    }
    fill += __popc(mask);
    __syncwarp();
    if (fill >= 32) {  // the last 32 queued, one per lane
      fill -= 32;
      const unsigned long long qc = qk[fill + lane];
      const unsigned int qb = qs[fill + lane];
      __syncwarp();  // read before the next pushes overwrite them
      finish(qc, qb);
    }
  }
  if (lane < fill) finish(qk[lane], qs[lane]);
}

/// Adds `by` to n vertex indices: the second mesh's triangles of two meshes hashed as one.
__global__ void shiftIndicesKernel(std::uint32_t n, std::uint32_t by, std::uint32_t* t) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < n) t[k] += by;
}

/// Delivers the pair with key `u` at place k of the sorted order (k below the m delivered):
/// written to out[k] in TrianglePair layout {a, b} when k < limit (out: the key buffer the order
/// no longer needs, or the caller's device buffer), or to copy[k] instead where copy is set (the
/// host's mapped stage: orderPairsKernel). With `kinds` (two meshes hashed as one: the
/// pair's kind in the bits of a from a_bits up, selfExactKernel), also counts the pairs of kinds
/// 1 and 2 into kinds[0] and kinds[1] and clears the kind from a: the host knows where each
/// kind's run starts from the counts.
__device__ __forceinline__ void deliverPair(std::uint32_t k, unsigned long long u,
                                            std::uint32_t limit, int b_bits,
                                            uint2* __restrict__ out, int a_bits,
                                            unsigned long long* kinds,
                                            uint2* __restrict__ copy = nullptr) {
  const auto a = static_cast<unsigned int>(u >> b_bits);
  const unsigned int a_mask = kinds != nullptr ? (1u << a_bits) - 1 : ~0u;
  if (k < limit) {
    const uint2 p = make_uint2(a & a_mask, static_cast<unsigned int>(u & ((1ull << b_bits) - 1)));
    (copy != nullptr ? copy : out)[k] = p;
  }
  if (kinds != nullptr) {
    // The keys are in order (or in segments of one kind), so a warp's lanes mostly share one
    // kind: one atomic per kind among the lanes that arrive together (lanes that arrive apart,
    // after the rank's loops of different lengths, are each counted once by their own group).
    const unsigned int kind = a >> a_bits;
    const unsigned int peers = __match_any_sync(__activemask(), kind);
    if (kind != 0 && (threadIdx.x & 31u) == static_cast<unsigned int>(__ffs(peers) - 1))
      atomicAdd(kinds + (kind - 1), static_cast<unsigned long long>(__popc(peers)));
  }
}

/// The radix-sorted keys delivered (deliverPair): the first m, of which the first `limit` are
/// written.
__global__ void unpackPairsKernel(std::uint32_t m, std::uint32_t limit,
                                  const unsigned long long* __restrict__ keys, int b_bits,
                                  uint2* __restrict__ out, int a_bits, unsigned long long* kinds) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k >= m) return;
  deliverPair(k, keys[k], limit, b_bits, out, a_bits, kinds);
}

/// The sizes of the counting order's steps (scatterPairsKernel, rankPairsKernel,
/// copyPairsOutKernel): n pairs to order, the first `unpack` places delivered, of which the
/// first `give` written. From the host after it has read the pass's counts back (w null), or,
/// queued before that read-back (one trip, runQuery), from the pass's counters `w` on the device:
/// then every step does nothing unless the pass stored everything it found (the host's own test
/// before it takes the pairs: passFits) and no segment went over its limit, so a pass that must
/// rerun or sort leaves its keys as they were; the host, reading the same counters, comes to the
/// same answer (resolve runs on both).
struct OrderSizes {
  std::uint32_t n = 0, unpack = 0, give = 0;
  const unsigned long long* w = nullptr;
  unsigned long long cand_cap = 0, surv_cap = 0, cap = 0;  // passFits
  unsigned long long sorted_cap = 0;  // the grouped keys' buffer (pairs_sorted)
  unsigned long long max_pairs = 0;   // QueryOptions::max_pairs (0: all)
  unsigned long long give_cap = 0;    // the pairs to write at most (a caller's device buffer)
  bool rounds = false;  // the pass ran in several rounds (roundEndKernel's counters)
  bool filtered = false;  // the plane filter ran
  bool kinds = false;  // two meshes hashed as one: every pair is delivered, to count its kind
};

/// Whether a pass's counters `w` show everything it found stored (runQuery grows and reruns
/// otherwise).
__host__ __device__ __forceinline__ bool passFits(const unsigned long long* w,
                                                  const OrderSizes& z) {
  const unsigned long long nc = z.rounds ? w[kMaxCands] : w[kCandCount];
  const unsigned long long ns = z.filtered ? (z.rounds ? w[kMaxSurv] : w[kSurvCount]) : nc;
  return nc <= z.cand_cap && w[kPairCount] <= z.cap && (!z.filtered || ns <= z.surv_cap);
}

/// Fills n, unpack and give from the counters when z.w is set; false when the counting order
/// must not run from them (see OrderSizes).
__host__ __device__ __forceinline__ bool resolve(OrderSizes& z) {
  if (z.w == nullptr) return true;
  const unsigned long long* w = z.w;
  if (!passFits(w, z) || w[kBigSegment] != 0 || w[kPairCount] > z.sorted_cap) return false;
  const unsigned long long n = w[kPairCount];
  const unsigned long long m = z.max_pairs > 0 && n > z.max_pairs ? z.max_pairs : n;
  const unsigned long long give = m < z.give_cap ? m : z.give_cap;
  z.n = static_cast<std::uint32_t>(n);
  z.give = static_cast<std::uint32_t>(give);
  z.unpack = static_cast<std::uint32_t>(z.kinds ? m : give);
  return true;
}

/// Key u to its segment's next free place in `grouped` (seg: the segments' next free places).
__device__ __forceinline__ void scatterKey(unsigned long long u, int shift,
                                           unsigned int* __restrict__ seg,
                                           unsigned long long* __restrict__ grouped) {
  grouped[atomicAdd(seg + (u >> shift), 1u)] = u;
}

/// The place in the order of key u, at place k of `grouped` (seg[g]: the end of segment g): its
/// segment's start plus the number of the segment's keys below it (equal keys, which a query
/// never emits, by their places in `grouped`, so no place is taken twice).
__device__ __forceinline__ std::uint32_t placeInOrder(const unsigned long long* __restrict__ grouped,
                                                      std::uint32_t k, unsigned long long u,
                                                      int shift,
                                                      const unsigned int* __restrict__ seg) {
  const auto g = static_cast<std::uint32_t>(u >> shift);
  const std::uint32_t first = g > 0 ? seg[g - 1] : 0, end = seg[g];
  std::uint32_t place = first;
  for (std::uint32_t j = first; j < end; ++j) {
    const unsigned long long v = grouped[j];
    place += (v < u || (v == u && j < k)) ? 1u : 0u;
  }
  return place;
}

/// The keys' scatter over the threads of a launch (grid-stride): each of the n keys to its
/// segment's next free place (scatterKey). Shared by scatterPairsKernel and orderPairsKernel.
__device__ __forceinline__ void scatterKeys(std::uint32_t n,
                                            const unsigned long long* __restrict__ keys, int shift,
                                            unsigned int* __restrict__ seg,
                                            unsigned long long* __restrict__ grouped) {
  for (std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < n;
       k += gridDim.x * blockDim.x)
    scatterKey(keys[k], shift, seg, grouped);
}

/// The keys' ranks over the threads of a launch (grid-stride): each key's place
/// (placeInOrder), and the first z.unpack places delivered (deliverPair: the first z.give
/// written, to `copy` instead of `out` where copy is set). Shared by rankPairsKernel and
/// orderPairsKernel.
__device__ __forceinline__ void rankKeys(const OrderSizes& z,
                                         const unsigned long long* __restrict__ grouped,
                                         int shift, const unsigned int* __restrict__ seg,
                                         int b_bits, uint2* __restrict__ out, int a_bits,
                                         unsigned long long* kinds, uint2* __restrict__ copy) {
  for (std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < z.n;
       k += gridDim.x * blockDim.x) {
    const unsigned long long u = grouped[k];
    const std::uint32_t place = placeInOrder(grouped, k, u, shift, seg);
    if (place < z.unpack) deliverPair(place, u, z.give, b_bits, out, a_bits, kinds, copy);
  }
}

/// The counting order, step 2 (after the exclusive scan of the segments' counts, `seg`): each
/// of the n keys goes to its segment's next free place in `grouped`; `seg[g]` ends as the end of
/// segment g (the start of g + 1).
__global__ void scatterPairsKernel(OrderSizes z, const unsigned long long* __restrict__ keys,
                                   int shift, unsigned int* __restrict__ seg,
                                   unsigned long long* __restrict__ grouped) {
  if (resolve(z)) scatterKeys(z.n, keys, shift, seg, grouped);
}

/// The counting order, step 3: each key's place (placeInOrder: a segment holds at most
/// segmentMax() keys); the first `unpack` places are delivered (deliverPair), the first `give`
/// of them written.
__global__ void rankPairsKernel(OrderSizes z, const unsigned long long* __restrict__ grouped,
                                int shift, const unsigned int* __restrict__ seg, int b_bits,
                                uint2* __restrict__ out, int a_bits, unsigned long long* kinds) {
  if (resolve(z)) rankKeys(z, grouped, shift, seg, b_bits, out, a_bits, kinds, nullptr);
}

/// One trip, the last step: the `give` pairs delivered, straight into the page-locked stage of
/// the host (mapped: the kernel's writes cross the bus), when they are at most `most`; else the
/// host reads them back in chunks after the counts (runQuery).
__global__ void copyPairsOutKernel(OrderSizes z, const uint2* __restrict__ from,
                                   uint2* __restrict__ stage, std::uint32_t most) {
  if (!resolve(z) || z.give > most) return;
  for (std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < z.give;
       k += gridDim.x * blockDim.x)
    stage[k] = from[k];
}

/// The block size of orderPairsKernel.
constexpr int kOrderBlock = 256;

/// The counting order in one cooperative launch (KDET_FCL_CUDA_FUSED_ORDER; every block
/// resident, so that the grid can wait for itself): the exclusive scan of the `segments`
/// counts in `seg` (each block sums its share into sums[block], the grid meets, each block scans
/// its share from the sums before it), the scatter (as scatterPairsKernel), the rank and the
/// delivery (as rankPairsKernel), with the grid meeting between the steps; and, where `stage` is
/// set and the `give` pairs are at most `most`, each delivered pair written there instead (where
/// copyPairsOutKernel copies them after the rank). One launch instead of five (the scan's two, the
/// scatter, the rank, the copy), each of which costs a few microseconds on its own. Sized as
/// the steps it replaces (z: OrderSizes, resolved on the device in every block alike, so that no
/// block waits at a meeting the others skip).
__global__ void __launch_bounds__(kOrderBlock)
    orderPairsKernel(OrderSizes z, const unsigned long long* __restrict__ keys, int shift,
                     unsigned int* __restrict__ seg, std::uint32_t segments,
                     unsigned int* __restrict__ sums, unsigned long long* __restrict__ grouped,
                     int b_bits, uint2* __restrict__ out, int a_bits,
                     unsigned long long* kinds, uint2* __restrict__ stage, std::uint32_t most) {
  if (!resolve(z) || z.n == 0) return;
  const cg::grid_group grid = cg::this_grid();
  using Reduce = cub::BlockReduce<unsigned int, kOrderBlock>;
  using Scan = cub::BlockScan<unsigned int, kOrderBlock>;
  __shared__ union {
    typename Reduce::TempStorage reduce;
    typename Scan::TempStorage scan;
  } tmp;
  __shared__ unsigned int base;
  // 1. This block's share of the segments, summed.
  const std::uint32_t per = (segments + gridDim.x - 1) / gridDim.x;
  const std::uint32_t lo = min(segments, blockIdx.x * per), hi = min(segments, lo + per);
  unsigned int sum = 0;
  for (std::uint32_t g = lo + threadIdx.x; g < hi; g += kOrderBlock) sum += seg[g];
  sum = Reduce(tmp.reduce).Sum(sum);
  if (threadIdx.x == 0) sums[blockIdx.x] = sum;
  grid.sync();
  // 2. Its start (the shares before it), then its share scanned in place.
  unsigned int before = 0;
  for (unsigned int b = threadIdx.x; b < blockIdx.x; b += kOrderBlock) before += sums[b];
  __syncthreads();  // (tmp reused)
  before = Reduce(tmp.reduce).Sum(before);
  if (threadIdx.x == 0) base = before;
  __syncthreads();
  unsigned int running = base;
  for (std::uint32_t g0 = lo; g0 < hi; g0 += kOrderBlock) {
    const std::uint32_t g = g0 + threadIdx.x;
    const unsigned int c = g < hi ? seg[g] : 0u;
    unsigned int start = 0, all = 0;
    Scan(tmp.scan).ExclusiveSum(c, start, all);
    if (g < hi) seg[g] = running + start;
    running += all;
    __syncthreads();  // (tmp reused)
  }
  grid.sync();
  // 3. Each key to its segment's next free place.
  scatterKeys(z.n, keys, shift, seg, grouped);
  grid.sync();
  // 4. Each key's rank within its segment, and its delivery (into the stage alone where the
  // pairs fit it: the host reads them from there, runQuery's from_stage).
  rankKeys(z, grouped, shift, seg, b_bits, out, a_bits, kinds,
           stage != nullptr && z.give <= most ? stage : nullptr);
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
    // Page-locked memory is mapped into the device's address space where the device addresses
    // memory as one space with the host (every 64-bit platform CUDA 13 supports); else kernels
    // cannot write here (deviceData() null).
    if (cudaHostGetDevicePointer(&d_, p_, 0) != cudaSuccess) {
      (void)cudaGetLastError();
      d_ = nullptr;
    }
  }
  void release() noexcept {
    if (p_ != nullptr) (void)cudaFreeHost(p_);
    p_ = d_ = nullptr;
    cap_ = 0;
  }
  void* data() const { return p_; }
  /// The same memory as kernels address it, or null where they cannot.
  void* deviceData() const { return d_; }

 private:
  void* p_ = nullptr;
  void* d_ = nullptr;
  std::size_t cap_ = 0;
};

/// What a cache entry holds on the device: one mesh, or two hashed as one (intersectAll): the
/// second's vertices follow the first's, its triangles follow the first's with their vertex
/// indices shifted by the first's vertex count.
template <class S>
struct MeshSource {
  const TriangleMesh<S>* part[2] = {nullptr, nullptr};
  const HashedMesh<S>* owner[2] = {nullptr, nullptr};  // whose mesh() each part is
  std::size_t nv() const {
    return (part[0] ? part[0]->vertices.size() : 0) + (part[1] ? part[1]->vertices.size() : 0);
  }
  std::size_t nt() const {
    return (part[0] ? part[0]->triangles.size() : 0) + (part[1] ? part[1]->triangles.size() : 0);
  }
};
template <class S>
MeshSource<S> sourceOf(const HashedMesh<S>* first, const HashedMesh<S>* second = nullptr) {
  MeshSource<S> src;
  src.owner[0] = first;
  src.owner[1] = second;
  src.part[0] = first ? &first->mesh() : nullptr;
  src.part[1] = second ? &second->mesh() : nullptr;
  return src;
}

/// The knob that turns the kept self results of the CUDA backend off (detail::KeptSelfResult).
constexpr const char* kSelfCacheKnob = "KDET_FCL_CUDA_SELF_CACHE";

/// One HashedMesh's device state (or that of two hashed as one).
template <class S>
struct CachedMesh {
  const void* owner = nullptr;
  const void* owner2 = nullptr;  // the second mesh of two hashed as one (else nullptr)
  // The owners' HashedMesh::identity() (0: none yet; identity2 0: no second mesh) whose queries
  // set the forecasts below. A new mesh at a freed owner's address has another identity (acquire:
  // takeFor), and a partner's forecast names the partner's identity, not its entry.
  std::uint64_t identity = 0, identity2 = 0;
  std::uint64_t version = 0, version2 = 0;
  std::uint64_t topology = 0, topology2 = 0;  // the meshes' topologyVersion() of the device's
                                              // triangles (with `valid`)
  std::uint64_t fingerprint = 0;
  std::size_t nv = 0, nt = 0;
  bool valid = false;  // false: the next use rebuilds
  bool force_vertices = false;
  // The owner's version() whose positions commitVertices or updateVertices copied into `v`
  // (startCommitCopy; the entry of one mesh alone), 0: none. The next rebuild skips their upload.
  std::uint64_t commit_version = 0;
  std::vector<Triangle> host_tris;  // what the device triangles hold, unshifted (topology check)

  DeviceBuffer<Vec3<S>> v;
  DeviceBuffer<std::uint32_t> t;
  DeviceBuffer<Aabb<S>> box;
  DeviceBuffer<double> diam;
  DeviceBuffer<std::uint8_t> level;
  DeviceBuffer<std::uint32_t> entry_tri, entry_span, cell_begin;
  DeviceBuffer<uint2> cell_split;  // HashView::cell_split (counting builds), as many as cell_begin
  DeviceBuffer<std::uint32_t> block_cell;     // the cell of every 32nd entry (cellsKernel)
  DeviceBuffer<unsigned long long> cell_key;  // key_words per cell
  DeviceBuffer<unsigned long long> slots;
  DeviceBuffer<std::uint32_t> upper;  // HashView::upper (upperLevelsKernel), 2 bytes per triangle
  bool upper_ready = false;           // the last build wrote `upper` (else queries scan all levels)
  bool count_build = false;  // the last build grouped its entries by counting (countFillKernel)
  int group_axis = kNoCellGroups;  // a counting build's group axis (cellGroupAxis, at its build)
  DeviceBuffer<BuildInfo> dinfo;  // this mesh's grid and sizes, on the device
  PinnedBuffer staging;  // vertex/triangle uploads (per mesh: two uploads can be in flight)
  std::uint32_t slot_count = 0;
  int key_words = 0;          // 1: compact 64-bit cell keys, 2: 128-bit
  std::uint32_t entry_cap = 0, cell_cap = 0;  // what the entry / cell arrays can hold
  int sort_bits = 0;          // compact keys: the bits the entry sort covers
  /// Whether each cell lists its triangles by decreasing diameter (the tile scan's early exit
  /// needs it; the warp scan does not, and a build for it skips the size sort: rebuild()).
  bool size_ordered = true;
  bool pending = false;       // re-hashed without read-back: check the sizes at the query's
  std::uint32_t pending_entry_cap = 0, pending_cell_cap = 0;  // what that re-hash could store
  // A re-hash without read-back found more entries or cells than its arrays held (checkPending):
  // the build with read-backs after it leaves more room in both (withRoom, buildOnDevice).
  bool outgrown = false;
  BuildInfo info{};           // the host's copy (after a read-back; stale while pending)
  cudaGraphExec_t graph = nullptr;  // the re-hash without read-back (rehashFromGraph)
  std::vector<std::uintptr_t> graph_key;  // the sizes and buffers it was captured with
  // The forecasts, all of the owners' (identity, identity2) and dropped when the entry passes to
  // other meshes (takeFor). Candidates per query triangle of the last self query of this
  // mesh and of the last inter query it took part in (spansFor()).
  double self_density = 0, inter_density = 0;
  // Of the last self query's candidates, the share that the cells' pairs gave (runQuery's
  // stages).
  double self_cell_share = 0;
  // runQuery's forecasts: the pairs the last self query of this entry (two meshes hashed as one
  // included) delivered into a host result, and those of its last inter query with the mesh of
  // identity `inter_partner` as its second mesh (another partner, or a new mesh at the partner's
  // address, starts without one; 0: none).
  std::size_t self_host_pairs = 0, inter_host_pairs = 0;
  std::uint64_t inter_partner = 0;
  // `builds` counts the geometries this entry has held (rebuild()): the geometry of the kept
  // self result (detail::KeptSelfResult's rule: a rigid mesh's self query runs on the device
  // twice, then never again; a mesh with new geometry at every self query never keeps one).
  std::uint64_t builds = 0;
  detail::KeptSelfResult kept_self{kSelfCacheKnob};

  CachedMesh() = default;
  CachedMesh(const CachedMesh&) = delete;
  CachedMesh& operator=(const CachedMesh&) = delete;
  ~CachedMesh() { dropGraph(); }
  void dropGraph() noexcept {
    if (graph != nullptr) (void)cudaGraphExecDestroy(graph);
    graph = nullptr;
    graph_key.clear();
  }
  /// Makes the entry that of the meshes of identities (id, id2), with no forecast, unless it is
  /// already theirs. (Their geometry is rebuilt anyway: a new mesh has a new version.)
  void takeFor(std::uint64_t id, std::uint64_t id2) {
    if (id == identity && id2 == identity2) return;
    identity = id;
    identity2 = id2;
    self_density = inter_density = self_cell_share = 0;
    self_host_pairs = inter_host_pairs = 0;
    inter_partner = 0;
  }

  HashView<S> view() const {
    HashView<S> h;
    h.v = v.data();
    h.t = t.data();
    h.box = box.data();
    h.diam = diam.data();
    h.entry_tri = entry_tri.data();
    h.entry_span = entry_span.data();
    h.cell_begin = cell_begin.data();
    h.cell_split = cell_split.data();
    h.cell_key = cell_key.data();
    h.slots = slots.data();
    h.upper = upper_ready ? upper.data() : nullptr;
    h.slot_count = slot_count;
    h.key_words = key_words;
    return h;
  }
  std::size_t bytes() const {
    return v.bytes() + t.bytes() + box.bytes() + diam.bytes() + level.bytes() +
           entry_tri.bytes() + entry_span.bytes() + cell_begin.bytes() + cell_split.bytes() +
           block_cell.bytes() + cell_key.bytes() + slots.bytes() + upper.bytes() + dinfo.bytes();
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

/// The CUDA device the backend uses unless setDevice() chose one: KDET_FCL_CUDA_DEVICE (an
/// ordinal, 0 to 1023; whether that device exists is checked where it is used), else 0.
int deviceKnob() { return static_cast<int>(detail::numberKnob("KDET_FCL_CUDA_DEVICE", 0, 1023, 0)); }

/// Throws InvalidInputError unless CUDA device `d` exists (`what` names where d came from).
void checkDeviceOrdinal(int d, const std::string& what) {
  const int count = kdet_fcl::cudaDeviceCount();  // (asked of the runtime once per process)
  if (d < 0 || d >= count)
    throw InvalidInputError(what + " names CUDA device " + std::to_string(d) + ", but this machine has " +
                            std::to_string(count) + (count == 1 ? " device (0)" : " devices") +
                            (count > 1 ? " (0.." + std::to_string(count - 1) + ")" : ""));
}

struct Context {
  std::mutex mutex;
  bool ready = false;
  /// The CUDA device of every stream, event and buffer below (-1: not chosen yet: chosen()).
  int device = -1;
  cudaStream_t stream = nullptr;
  // A second stream for work that runs beside the stream's own (selfOverlap): forkSide() makes it
  // wait for everything queued on `stream` so far, joinSide() makes `stream` wait for it.
  cudaStream_t side = nullptr;  // (of the least priority, `stream` of the greatest)
  cudaEvent_t fork = nullptr, join = nullptr;
  cudaEvent_t counted = nullptr;  // a pass's counts are back (runQuery, with a forecast)
  cudaEvent_t ev[4] = {};
  // While profiling, three events per round of a query pass (markRound): before its phase 1
  // (round 0: ev[1]), after its phase 1 and after its plane filter. Created as needed.
  std::vector<cudaEvent_t> round_ev;
  bool profiling = false;
  QueryProfile profile;
  unsigned long long allocations_at_start = 0;  // g_device_allocations when the query began
  /// A query's profile starts empty.
  void startProfile() {
    profile = QueryProfile{};
    allocations_at_start = g_device_allocations.load(std::memory_order_relaxed);
  }

  // Scratch shared by all builds and queries (serialised by the mutex).
  DeviceBuffer<unsigned char> cub_temp;
  DeviceBuffer<BuildReduce> red;  // reset by gridKernel after each use
  bool red_ready = false;
  // The build's sort and count scratch is carved out of cands / pairs / pairs_sorted (rebuild()).
  DeviceBuffer<Vec3<float>> mapped_f;
  DeviceBuffer<Vec3<double>> mapped_d;
  // pair_count: the counters of a query pass (PairCountWord), zeroed before every pass: the
  // round's candidate and survivor counts, the pair count, the task counters of the warp-wide
  // candidate kernels (warpTasks()) and of the same-level pairs (cellTasks()), the pair counts of
  // two kinds of a joint query (kindCounts()), and the rounds' totals (roundEndKernel).
  DeviceBuffer<unsigned long long> cands, pairs, pairs_sorted, pair_count;
  DeviceBuffer<unsigned int> segs;  // the pairs' counting order: the counts of the segments
  PinnedBuffer host_small;  // 3 BuildInfo + entry total + cell total + 2 kind counts + the
                            // kPairCountWords counters of the last pass
  PinnedBuffer readback;    // sorted pairs on their way into the result
  std::size_t last_host_pairs = 0;  // the pairs of the last query into a host result (runQuery)
  // orderPairsKernel's resident blocks per SM (0: the device has no cooperative launch), -1:
  // not asked yet (orderBlocksPerSm).
  int order_blocks_per_sm = -1;
  staging::CopyPool copy_pool;  // the threads of pooled read-backs (results kept by the caller)

  std::list<CachedMesh<float>> meshes_f;
  std::list<CachedMesh<double>> meshes_d;

  std::list<CachedMesh<float>>& meshes(float*) { return meshes_f; }
  std::list<CachedMesh<double>>& meshes(double*) { return meshes_d; }
  DeviceBuffer<Vec3<float>>& mapped(float*) { return mapped_f; }
  DeviceBuffer<Vec3<double>>& mapped(double*) { return mapped_d; }

  /// The backend's device: setDevice()'s choice, else deviceKnob()'s, which must exist. Called
  /// under the mutex, before the DeviceScope of a call.
  int chosen() {
    if (device < 0) {
      const int d = deviceKnob();
      checkDeviceOrdinal(d, "KDET_FCL_CUDA_DEVICE=" + std::to_string(d));
      device = d;
    }
    return device;
  }

  /// Creates the streams, events and fixed buffers on `device`, the thread's current device
  /// (inside the call's DeviceScope).
  void init() {
    if (ready) return;
    int least = 0, greatest = 0;
    CUDA_TRY(cudaDeviceGetStreamPriorityRange(&least, &greatest));
    CUDA_TRY(cudaStreamCreateWithPriority(&stream, cudaStreamNonBlocking, greatest));
    CUDA_TRY(cudaStreamCreateWithPriority(&side, cudaStreamNonBlocking, least));
    for (cudaEvent_t& e : ev) CUDA_TRY(cudaEventCreate(&e));
    CUDA_TRY(cudaEventCreateWithFlags(&fork, cudaEventDisableTiming));
    CUDA_TRY(cudaEventCreateWithFlags(&join, cudaEventDisableTiming));
    CUDA_TRY(cudaEventCreateWithFlags(&counted, cudaEventDisableTiming));
    red.reserve(1);
    pair_count.reserve(kPairCountWords);
    host_small.reserve(3 * sizeof(BuildInfo) + (4 + kPairCountWords) * sizeof(unsigned long long));
    ready = true;
  }

  BuildInfo* hostInfo(int k = 0) { return static_cast<BuildInfo*>(host_small.data()) + k; }
  unsigned long long* hostTotal() {
    return reinterpret_cast<unsigned long long*>(static_cast<char*>(host_small.data()) +
                                                 3 * sizeof(BuildInfo));
  }
  unsigned long long* hostCells() { return hostTotal() + 1; }
  unsigned long long* hostKinds() { return hostTotal() + 2; }  // 2 words (deliverPair)
  unsigned long long* hostCount() { return hostTotal() + 4; }  // kPairCountWords words
  cudaStream_t forkSide() {
    CUDA_TRY(cudaEventRecord(fork, stream));
    CUDA_TRY(cudaStreamWaitEvent(side, fork, 0));
    return side;
  }
  void joinSide() {
    CUDA_TRY(cudaEventRecord(join, side));
    CUDA_TRY(cudaStreamWaitEvent(stream, join, 0));
  }
  unsigned long long* warpTasks() { return pair_count.data() + kWarpTasks; }
  unsigned long long* cellTasks() { return pair_count.data() + kCellTasks; }
  unsigned long long* kindCounts() { return pair_count.data() + kKindCounts; }  // 2 words

  /// Drops all device memory without throwing (after a CUDA error, or on request): the next
  /// call re-uploads what it needs.
  void releaseAll() noexcept {
    meshes_f.clear();
    meshes_d.clear();
    cub_temp.release();
    mapped_f.release();
    mapped_d.release();
    cands.release();
    pairs.release();
    pairs_sorted.release();
    segs.release();
    readback.release();
    red_ready = false;
  }

  /// Drops everything made on `device` (its caller holds the mutex and a DeviceScope of that
  /// device), so that the next call initialises on another: every buffer and mesh, the streams,
  /// the events and the pinned buffers, and what was asked of the device once. Never throws.
  void teardown() noexcept {
    if (ready) {
      (void)cudaStreamSynchronize(stream);
      (void)cudaStreamSynchronize(side);
    }
    releaseAll();
    red.release();
    pair_count.release();
    host_small.release();
    for (cudaEvent_t& e : ev) {
      if (e != nullptr) (void)cudaEventDestroy(e);
      e = nullptr;
    }
    for (cudaEvent_t e : round_ev) (void)cudaEventDestroy(e);
    round_ev.clear();
    for (cudaEvent_t* e : {&fork, &join, &counted}) {
      if (*e != nullptr) (void)cudaEventDestroy(*e);
      *e = nullptr;
    }
    for (cudaStream_t* st : {&stream, &side}) {
      if (*st != nullptr) (void)cudaStreamDestroy(*st);
      *st = nullptr;
    }
    (void)cudaGetLastError();
    order_blocks_per_sm = -1;
    last_host_pairs = 0;
    ready = false;
  }

  std::size_t bytes() const {
    std::size_t b = cub_temp.bytes() + red.bytes() + mapped_f.bytes() +
                    mapped_d.bytes() + cands.bytes() + pairs.bytes() + pairs_sorted.bytes() +
                    pair_count.bytes() + segs.bytes();
    for (const auto& m : meshes_f) b += m.bytes();
    for (const auto& m : meshes_d) b += m.bytes();
    return b;
  }

  void record(int k) {
    if (profiling) CUDA_TRY(cudaEventRecord(ev[k], stream));
  }
  /// While profiling: event k (0 before phase 1, 1 after it, 2 after the plane filter) of round r.
  void markRound(std::uint32_t r, int k) {
    if (!profiling) return;
    while (round_ev.size() < 3 * (std::size_t(r) + 1)) {
      cudaEvent_t e = nullptr;
      CUDA_TRY(cudaEventCreate(&e));
      round_ev.push_back(e);
    }
    CUDA_TRY(cudaEventRecord(round_ev[3 * r + k], stream));
  }
};


/// The process-wide backend state. Deliberately never destroyed: freeing device memory from a
/// static destructor can run after the CUDA runtime has shut down.
Context& context() {
  static Context* ctx = new Context();
  return *ctx;
}

int g_num_sms = 0;  // of the context's device (0: not asked yet; guarded())

/// Runs a CUB device algorithm: asks for its temporary storage, grows the shared buffer, runs.
template <class F>
void cubCall(Context& ctx, F&& f) {
  std::size_t bytes = 0;
  CUDA_TRY(f(static_cast<void*>(nullptr), bytes));
  ctx.cub_temp.reserve(bytes);
  bytes = ctx.cub_temp.capacity();
  CUDA_TRY(f(static_cast<void*>(ctx.cub_temp.data()), bytes));
}

/// KDET_FCL_CUDA_SYNC_REHASH=1: every re-hash reads the sizes back (the round-3 behaviour, for
/// comparisons). Read at every build.
bool syncRehash() { return detail::switchKnob("KDET_FCL_CUDA_SYNC_REHASH", false); }

/// KDET_FCL_CUDA_FULL_KEYS=1: 128-bit cell keys even where the compact 64-bit key is exact
/// (tests). Read at every build.
bool fullKeys() { return detail::switchKnob("KDET_FCL_CUDA_FULL_KEYS", false); }

/// Candidates per query triangle of a mesh's last query above which its cells count as crowded
/// (the UNC cloth ball 8.4, the two frames 21; smooth cloths 1.6-3.4, the n-body 1.1): the rule
/// of spansFor, warpLanesLog2, cellRows and upperLevelsFor.
constexpr double kCrowdedDensity = 4.0;

/// The 32-bit words of HashView::upper for nt triangles (two per word).
inline std::size_t upperWords(std::size_t nt) { return (nt + 1) / 2; }

inline std::size_t roundUp(std::size_t x, std::size_t a) { return (x + a - 1) / a * a; }

/// Host milliseconds since `t0` (QueryProfile's host times: graph captures, registrations).
inline double hostMsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// The room a build with read-backs leaves in a mesh's entry and cell arrays after a re-hash
/// without read-back outgrew them (CachedMesh::outgrown), as a share of what the build holds, on
/// top of DeviceBuffer's 1/8: a mesh that outgrew its arrays by more than 1/8 in one frame is
/// growing (kdet_bench's 90k cloth draping over its sphere: 10-20 % more cells every frame), and
/// with 1/8 alone its next frames fell back again. Only such meshes pay the memory.
constexpr std::size_t kOutgrownRoomDiv = 2;  // n / 2 more

std::size_t withRoom(std::size_t n, bool outgrown) {
  return outgrown ? n + n / kOutgrownRoomDiv : n;
}

/// KDET_FCL_CUDA_REHASH_CAP=k (tests): a re-hash without read-back uses at most k entries and k
/// cells, so that it overflows and takes the fallback. 0 or unset: the arrays' capacities.
std::uint32_t rehashCap(std::uint32_t cap) {
  const std::uint64_t k = detail::numberKnob("KDET_FCL_CUDA_REHASH_CAP", 0, 0xFFFFFFFFull, 0);
  return k > 0 && k < cap ? static_cast<std::uint32_t>(k) : cap;
}

/// KDET_FCL_CUDA_REHASH_GRAPH=0 turns the re-hash graph off (read at every build).
bool rehashGraphOn() { return detail::switchKnob("KDET_FCL_CUDA_REHASH_GRAPH", true); }

/// Triangles up to which a re-hash without read-back groups its entries by counting. H100,
/// gpu_bench, the counting build (one thread per entry) against the sort in alternating rounds in
/// one run (benchmarks/RESULTS-gpu.md), ms of build and of frame. 2026-11-23: the UNC cloth ball
/// (92k) 0.15-0.16 against 0.20-0.21 and 0.82-0.83 against 0.86-0.88; the 1M cloth even; the
/// 10M cloth 5.7 against 4.6 of build, 15.4 against 12.9 of frame. 2026-11-24 (the code of that
/// day, three rounds each): the 200k and 250k cloths 0.14-0.16 against 0.18-0.20 of build and
/// 0.452-0.534 against 0.502-0.555 of frame; the joint two cloth-ball frames (184k) 0.14 against
/// 0.20 and 1.38-1.39 against 1.42-1.48 (slower per frame the day before); the joint two n-body
/// frames (293k) 0.20 against 0.23-0.29 and 0.64-0.67 against 0.69-0.87; the 1M cloth level
/// again (1.34-1.48 against 1.32-1.45). So the rule covers the sizes where the count was
/// measured faster, up to 300k.
constexpr std::size_t kCountBuildMaxTriangles = 300000;

/// Whether a re-hash without read-back of `nt` triangles groups its entries by counting instead
/// of sorting them (countFillKernel): KDET_FCL_CUDA_COUNT_BUILD = 0 (never), 1 (always), unset
/// (up to KDET_FCL_CUDA_COUNT_BUILD_MAX triangles, by default kCountBuildMaxTriangles). Read at
/// every build.
bool countBuildOn(std::size_t nt) {
  const std::uint64_t most = detail::numberKnob("KDET_FCL_CUDA_COUNT_BUILD_MAX", 0, 0xFFFFFFFFull,
                                                kCountBuildMaxTriangles);
  return detail::switchKnob("KDET_FCL_CUDA_COUNT_BUILD", nt <= most);
}

/// The axis on which a counting build groups each cell's entries (cellGroupOf, so that the
/// warp-wide scans visit one run of a cell: cellGroupRun): KDET_FCL_CUDA_CELL_GROUPS = 0 (none,
/// kNoCellGroups), 1, 2 or 3 (x, y or z); unset: y. Read at every counting build (a graph's
/// key holds it). The choice changes the work, never the pairs.
int cellGroupAxis() {
  const std::uint64_t v = detail::numberKnob("KDET_FCL_CUDA_CELL_GROUPS", 0, 3, 2);
  return v == 0 ? kNoCellGroups : static_cast<int>(v) - 1;
}

/// Whether a re-hash without read-back of `m` (`nt` triangles) is a counting build: its cells
/// need no size order, and countBuildOn.
template <class S>
bool countsOnRehash(const CachedMesh<S>& m, std::size_t nt) {
  return !m.size_ordered && countBuildOn(nt);
}

/// 8-byte words for `k` 64-bit values in the build's scratch, rounded up to 256 bytes (each
/// scratch array starts on a 256-byte boundary).
std::size_t wordsFor64(std::size_t k) { return (k + 31) & ~std::size_t(31); }
/// The same for `k` 32-bit values.
std::size_t wordsFor32(std::size_t k) { return wordsFor64((k + 1) / 2); }

/// 8-byte words of scratch a counting build of up to `cap` entries, `slot_count` slots and
/// `cell_cap` cells reserves (buildOnDevice's layout: per entry its slot, rank and value; per
/// slot its count, then its cell; per cell its count; at least the compact sort's arena).
std::size_t countBuildWords(std::uint32_t cap, std::uint32_t slot_count, std::uint32_t cell_cap) {
  const std::size_t e8 = wordsFor64(cap), e4 = wordsFor32(cap);
  return std::max(2 * e8 + e4,
                  3 * e4 + 3 * wordsFor32(slot_count) + wordsFor32(std::size_t(cell_cap) + 1));
}

/// Copies one part's vertices to the device. From staging::kPinMinBytes up (unless
/// KDET_FCL_CUDA_PIN_VERTICES=0) the mesh's vertex buffer is registered as page-locked memory
/// on its second upload (its whole pages; a buffer uploaded once, as a new mesh per frame, never
/// pays the registration), the registration kept with the mesh (detail::HostPin, which the mesh
/// drops before that buffer can go; updateVertices writes into the same buffer), and every later
/// upload of it is one DMA from it, with no copy into the staging buffer but for the partial
/// pages at its ends (staging::pinnedUpload). A buffer that cannot be registered is
/// recorded as such and takes the staged path from then on. The registration's host time goes
/// into QueryProfile::host_register_ms. Returns whether the DMA path ran.
/// (The query synchronises its stream before it returns, so the buffer is not read after.)
template <class S>
bool uploadVertices(Context& ctx, Vec3<S>* dst, const HashedMesh<S>* owner,
                    const TriangleMesh<S>& part, char* stage) {
  const std::size_t bytes = part.vertices.size() * sizeof(Vec3<S>);
  const void* src = part.vertices.data();
  if (owner != nullptr && bytes >= staging::kPinMinBytes && staging::pinVerticesOn()) {
    detail::HostPin& pin = owner->hostPin();
    if (pin.at() != src) {
      pin.see(src);  // a first upload is staged: a buffer uploaded once is never registered
    } else if (!pin.tried()) {
      const auto t0 = std::chrono::steady_clock::now();
      pin.set(src, staging::pinHostMemory(src, bytes));
      ++ctx.profile.host_registrations;
      ctx.profile.host_register_ms += hostMsSince(t0);
    }
    if (pin.pinned()) {
      CUDA_TRY(staging::pinnedUpload(dst, src, bytes, stage, ctx.stream));
      return true;
    }
  }
  CUDA_TRY(staging::stagedUpload(dst, src, bytes, stage, ctx.stream));
  return false;
}

/// Whether a build of `m` records, per triangle, the levels above its own that hold a cell of its
/// range (upperLevelsKernel): KDET_FCL_CUDA_UPPER_LEVELS = 0 (never), 1 (always), unset (while
/// the mesh's last self query found at most 4 candidates per triangle, as spansFor; a mesh not
/// queried yet records them). Measured on an H100 (benchmarks/RESULTS-gpu.md): phase 1 of the
/// self queries fell 3-16 % on the UNC and cloth scenes, for 0.01-0.06 ms more build; per frame
/// the sparse scenes (cloths, funnel, n-body: most lookups of the levels above miss) gained up to
/// 0.1 ms or stayed level, the cloth ball (8.4 candidates per triangle; half of those lookups on
/// levels with a cell in range) stayed level, and the joint two cloth-ball frames (21) lost
/// 0.01-0.08 ms in every call. The choice changes the work, never the pairs.
bool upperLevelsFor(double self_density) {
  return detail::switchKnob("KDET_FCL_CUDA_UPPER_LEVELS", self_density <= kCrowdedDensity);
}

/// The device part of rebuild() after the uploads: everything a re-hash without read-back
/// enqueues (and, for a build with read-backs, the read-backs too). Allocates only where a
/// buffer must grow; a re-hash replayed from a graph has all of them reserved beforehand
/// (reserveRehash()).
template <class S>
void buildOnDevice(Context& ctx, CachedMesh<S>& m, std::size_t nt, bool async) {
  const cudaStream_t s = ctx.stream;
  const auto n = static_cast<std::uint32_t>(nt);
  m.box.reserve(nt, false);
  m.diam.reserve(nt, false);
  m.level.reserve(nt, false);
  BuildInfo* const dinfo = m.dinfo.data();
  // The per-triangle scratch of the build (counts, offsets, the size sort) lives in the output
  // buffers of the queries (`pairs`, `pairs_sorted`), idle during a build: 256-byte aligned
  // arrays of n4 words. Nothing reallocates those two buffers before the build's last use.
  const std::size_t n4 = (nt + 1 + 63) & ~std::size_t(63);
  ctx.pairs_sorted.reserve(2 * n4);  // 4 arrays of n4 words
  ctx.pairs.reserve(3 * n4 / 2);     // 3 arrays of n4 words
  std::uint32_t* const sort_arena = reinterpret_cast<std::uint32_t*>(ctx.pairs_sorted.data());
  std::uint32_t* const count_arena = reinterpret_cast<std::uint32_t*>(ctx.pairs.data());
  std::uint32_t* const tri_counts = count_arena;
  std::uint32_t* const offsets = count_arena + n4;
  std::uint32_t* const counts = count_arena + 2 * n4;  // in size order

  if (!ctx.red_ready) {  // afterwards gridKernel leaves them reset
    CUDA_TRY(cudaMemsetAsync(ctx.red.data(), 0xFF, 4 * sizeof(unsigned long long), s));
    CUDA_TRY(cudaMemsetAsync(reinterpret_cast<char*>(ctx.red.data()) + 4 * sizeof(unsigned long long),
                             0, 4 * sizeof(unsigned long long), s));
    ctx.red_ready = true;
  }
  const unsigned int tri_blocks =
      std::min<unsigned int>(blocksFor(nt, kBuildBlock), static_cast<unsigned int>(4 * g_num_sms));
  trianglesKernel<S><<<tri_blocks, kBuildBlock, 0, s>>>(n, m.v.data(), m.t.data(), m.box.data(),
                                                        m.diam.data(), ctx.red.data());
  checkLaunch();
  // A re-hash without read-back whose cells need no size order groups its entries by counting
  // (countFillKernel), not by a sort; its compact keys then need only fit in 64 bits, not in the
  // sort's bits.
  const bool count_build = async && countsOnRehash(m, nt);
  m.count_build = count_build;
  if (count_build) m.group_axis = cellGroupAxis();
  if (count_build) ++ctx.profile.count_builds;
  gridKernel<<<1, 1, 0, s>>>(ctx.red.data(), dinfo, async ? (count_build ? 64 : m.sort_bits) : 0);
  checkLaunch();
  countKernel<S><<<blocksFor(nt + 1, kBuildBlock), kBuildBlock, 0, s>>>(
      n, m.box.data(), m.diam.data(), dinfo, m.level.data(), tri_counts,
      m.size_ordered ? sort_arena : nullptr, m.size_ordered ? sort_arena + 2 * n4 : nullptr);
  checkLaunch();
  // Double-buffered sorts (here and below): CUB then needs no temporary copy of the keys and
  // values, only its histograms, which keeps the shared temporary storage small.
  std::uint32_t* by_size = nullptr;
  if (m.size_ordered) {
    {
      cub::DoubleBuffer<std::uint32_t> sk(sort_arena, sort_arena + n4);
      cub::DoubleBuffer<std::uint32_t> ids(sort_arena + 2 * n4, sort_arena + 3 * n4);
      cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
        return cub::DeviceRadixSort::SortPairs(tmp, bytes, sk, ids, static_cast<int>(nt), 0, 32,
                                               s);
      });
      by_size = ids.Current();
    }
    countsBySizeKernel<<<blocksFor(nt + 1, kBuildBlock), kBuildBlock, 0, s>>>(
        n, tri_counts, by_size, counts);
    checkLaunch();
  }
  cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
    return cub::DeviceScan::ExclusiveSum(tmp, bytes, m.size_ordered ? counts : tri_counts, offsets,
                                         static_cast<int>(nt + 1), s);
  });
  bool compact = true;
  if (!async) {
    CUDA_TRY(cudaMemcpyAsync(ctx.hostInfo(), dinfo, sizeof(BuildInfo), cudaMemcpyDeviceToHost, s));
    *ctx.hostTotal() = 0;
    CUDA_TRY(cudaMemcpyAsync(ctx.hostTotal(), offsets + nt, sizeof(std::uint32_t),
                             cudaMemcpyDeviceToHost, s));
    CUDA_TRY(cudaStreamSynchronize(s));
    m.info = *ctx.hostInfo();
    const std::uint64_t total = *ctx.hostTotal();
    if (total > 0xF0000000ull)
      throw InvalidInputError("mesh too large for the CUDA backend: " + std::to_string(total) +
                              " cell entries");
    // The device writes the entry count with the fill, after this read-back; the host's copy
    // takes it here, so that the rules that read a mesh's entry count (selfCellPairs, cellRows,
    // cellSpans) see it from the first query on, not only after a re-hash without read-back.
    m.info.entries = static_cast<unsigned int>(total);
    compact = m.info.fits64 != 0 && !fullKeys();
    // 1/8 slack: room for the next re-hash without read-back; more after the mesh outgrew its
    // arrays (withRoom).
    m.entry_tri.reserve(withRoom(total, m.outgrown));
    m.entry_span.reserve(m.entry_tri.capacity(), false);
    m.block_cell.reserve(m.entry_tri.capacity() / 32 + 1, false);
    m.entry_cap = static_cast<std::uint32_t>(std::min<std::size_t>(m.entry_tri.capacity(), 0xF0000000ull));
    m.key_words = compact ? 1 : 2;
    // The compact sort covers whole 8-bit digits (CUB's radix passes): the bits up to the next
    // digit boundary are free room for a re-hash whose grid grows; beyond them it falls back.
    // (Three bits of guaranteed room cost one more pass in call 1: slower, not kept.)
    const int key_bits = m.info.level_bits + 3 * m.info.coord_bits;
    m.sort_bits = static_cast<int>(std::min<std::size_t>(64, roundUp(key_bits, 8)));
  }
  const std::uint32_t cap = async ? rehashCap(m.entry_cap) : m.entry_cap;
  const std::uint32_t cell_cap = async ? rehashCap(m.cell_cap) : 0;  // sync: set below
  const unsigned int eb = blocksFor(cap, kBuildBlock);

  // The entry-sized scratch of the sort lives in the candidate buffer of the queries, which is
  // idle during a build (same stream, and the context's mutex serialises the calls): no separate
  // memory for it. Each array starts on a 256-byte boundary.
  const std::size_t e8 = wordsFor64(cap), e4 = wordsFor32(cap);
  if (count_build) {
    // The counting build (countFillKernel): its scratch in the same idle buffer, in 32-bit
    // arrays: per entry its slot, rank and value; per slot its three groups' counts (the first
    // then holds its cell); per cell its count.
    const std::size_t s4 = wordsFor32(m.slot_count);
    ctx.cands.reserve(countBuildWords(cap, m.slot_count, cell_cap));
    std::uint32_t* const at = reinterpret_cast<std::uint32_t*>(ctx.cands.data());
    std::uint32_t* const ent_slot = at;
    std::uint32_t* const ent_rank = at + 2 * e4;
    std::uint32_t* const ent_val = at + 4 * e4;
    std::uint32_t* const slot_cnt = at + 6 * e4;  // the slot's cell after countCellsKernel
    const std::size_t group_stride = 2 * s4;
    std::uint32_t* const cell_count = slot_cnt + 3 * group_stride;
    const int axis = m.group_axis;
    countClearKernel<<<std::min<unsigned int>(blocksFor(std::max<std::size_t>(m.slot_count,
                                                                                cell_cap + 1ull),
                                                        kBuildBlock),
                                              static_cast<unsigned int>(8 * g_num_sms)),
                       kBuildBlock, 0, s>>>(m.slots.data(), m.slot_count, slot_cnt, group_stride,
                                            cell_count, cell_cap + 1);
    checkLaunch();
    countFillKernel<S><<<eb, kBuildBlock, 0, s>>>(n, m.box.data(), m.level.data(), offsets,
                                                  dinfo, m.slots.data(), m.slot_count, slot_cnt,
                                                  group_stride, axis, ent_slot, ent_rank, ent_val,
                                                  cap, cell_cap);
    checkLaunch();
    countCellsKernel<<<blocksFor(m.slot_count, kBuildBlock), kBuildBlock, 0, s>>>(
        dinfo, m.slots.data(), m.slot_count, slot_cnt, group_stride, cell_count,
        m.cell_split.data(), m.cell_key.data(), cell_cap);
    checkLaunch();
    cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
      return cub::DeviceScan::ExclusiveSum(tmp, bytes, cell_count, m.cell_begin.data(),
                                           static_cast<int>(cell_cap + 1), s);
    });
    scatterKernel<S><<<eb, kBuildBlock, 0, s>>>(cap, dinfo, ent_slot, ent_rank, ent_val,
                                                slot_cnt, m.cell_begin.data(),
                                                m.cell_split.data(), axis, m.cell_key.data(),
                                                m.box.data(), m.entry_tri.data(),
                                                m.entry_span.data(),
                                                m.block_cell.data());
    checkLaunch();
  } else {
    ctx.cands.reserve(compact ? 2 * e8 + e4 : 4 * e8 + 3 * e4);
    unsigned long long* const arena = ctx.cands.data();
    unsigned long long* keys_a = arena;
    unsigned long long* keys_b = arena + e8;
    std::uint32_t* vals_a = reinterpret_cast<std::uint32_t*>(arena + (compact ? 2 : 4) * e8);
    const unsigned long long* hi_sorted = nullptr;
    const unsigned long long* keys_sorted = keys_b;
    // Padding: the entries past the real ones (the host may not know how many there are) keep
    // all-one keys, which sort after every real key (stably, so real entries come first).
    CUDA_TRY(cudaMemsetAsync(keys_a, 0xFF, cap * sizeof(unsigned long long), s));
    // After the sorts, a free key-sized buffer holds the run heads and their scan (2 x 4 bytes per
    // entry in 8 bytes per entry), instead of two more entry-sized arrays.
    unsigned long long* spare = keys_a;
    if (compact) {
      fillKernel<S, true><<<blocksFor(nt, kBuildBlock), kBuildBlock, 0, s>>>(
          n, m.box.data(), m.level.data(), offsets, by_size, dinfo, keys_a, nullptr, vals_a,
          nullptr, cap, dinfo);
      checkLaunch();
      // The resident entry array is the sort's second value buffer; entriesKernel rewrites each
      // sorted value in place (thread k reads and writes only entry k).
      cub::DoubleBuffer<unsigned long long> kb(keys_a, keys_b);
      cub::DoubleBuffer<std::uint32_t> vb(vals_a, m.entry_tri.data());
      cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
        return cub::DeviceRadixSort::SortPairs(tmp, bytes, kb, vb, static_cast<int>(cap), 0,
                                               m.sort_bits, s);
      });
      keys_sorted = kb.Current();
      spare = kb.Alternate();
      entriesKernel<S, true><<<eb, kBuildBlock, 0, s>>>(cap, dinfo, keys_sorted, nullptr,
                                                        vb.Current(), nullptr, m.box.data(),
                                                        m.entry_tri.data(), m.entry_span.data());
      checkLaunch();
    } else {
      // Full 128-bit keys (never re-hashed without read-back, so cap >= entries): two stable
      // passes (low word, then high word) sort by (hi, lo).
      unsigned long long* hi_a = arena + 2 * e8;
      unsigned long long* hi_b = arena + 3 * e8;
      std::uint32_t* vals_b = reinterpret_cast<std::uint32_t*>(arena + 4 * e8 + e4);
      std::uint32_t* tri_of = reinterpret_cast<std::uint32_t*>(arena + 4 * e8 + 2 * e4);
      CUDA_TRY(cudaMemsetAsync(hi_a, 0xFF, cap * sizeof(unsigned long long), s));
      fillKernel<S, false><<<blocksFor(nt, kBuildBlock), kBuildBlock, 0, s>>>(
          n, m.box.data(), m.level.data(), offsets, by_size, dinfo, keys_a, hi_a, vals_a, tri_of,
          cap, dinfo);
      checkLaunch();
      const std::uint32_t mt = static_cast<std::uint32_t>(*ctx.hostTotal());  // read back above
      cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
        return cub::DeviceRadixSort::SortPairs(tmp, bytes, keys_a, keys_b, vals_a, vals_b,
                                               static_cast<int>(mt), 0, 64, s);
      });
      const unsigned int mb = blocksFor(mt, kBuildBlock);
      gatherKeysKernel<<<mb, kBuildBlock, 0, s>>>(mt, hi_a, vals_b, hi_b);
      checkLaunch();
      cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
        return cub::DeviceRadixSort::SortPairs(tmp, bytes, hi_b, hi_a, vals_b, vals_a,
                                               static_cast<int>(mt), 0, 64, s);
      });
      gatherKeysKernel<<<mb, kBuildBlock, 0, s>>>(mt, keys_a, vals_a, keys_b);
      checkLaunch();
      hi_sorted = hi_a;
      entriesKernel<S, false><<<mb, kBuildBlock, 0, s>>>(mt, dinfo, keys_b, hi_sorted, tri_of,
                                                         vals_a, m.box.data(), m.entry_tri.data(),
                                                         m.entry_span.data());
      checkLaunch();
    }
    std::uint32_t* head = reinterpret_cast<std::uint32_t*>(spare);
    std::uint32_t* cell_index = head + cap;
    // A re-hash keeps the table's size, so the heads kernel empties it; a build with read-backs
    // sizes it after the cell count and clears it with a memset.
    unsigned long long* const clear = async ? m.slots.data() : nullptr;
    if (compact)
      headsKernel<true><<<eb, kBuildBlock, 0, s>>>(cap, dinfo, keys_sorted, nullptr, head, clear,
                                                   m.slot_count);
    else
      headsKernel<false><<<eb, kBuildBlock, 0, s>>>(cap, dinfo, keys_sorted, hi_sorted, head, clear,
                                                    m.slot_count);
    checkLaunch();
    cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
      return cub::DeviceScan::ExclusiveSum(tmp, bytes, head, cell_index, static_cast<int>(cap), s);
    });
    if (!async) {
      // The cell count (heads past the entries are 0): size the cell arrays and the table by cells.
      *ctx.hostCells() = 0;
      std::uint32_t* hc = reinterpret_cast<std::uint32_t*>(ctx.hostCells());
      CUDA_TRY(cudaMemcpyAsync(hc, cell_index + (cap - 1), sizeof(std::uint32_t),
                               cudaMemcpyDeviceToHost, s));
      CUDA_TRY(cudaMemcpyAsync(hc + 1, head + (cap - 1), sizeof(std::uint32_t),
                               cudaMemcpyDeviceToHost, s));
      CUDA_TRY(cudaStreamSynchronize(s));
      const std::size_t cells = withRoom(std::size_t(hc[0]) + hc[1], m.outgrown);
      m.outgrown = false;
      m.cell_key.reserve(cells * m.key_words);
      m.cell_begin.reserve(cells + cells / 8 + 1, false);
      m.cell_split.reserve(m.cell_begin.capacity(), false);
      m.cell_cap = static_cast<std::uint32_t>(
          std::min(m.cell_key.capacity() / m.key_words, m.cell_begin.capacity() - 1));
      // Linear probing: most lookups are misses (empty cells of the query's range), which scan to
      // the next empty slot, so the load stays low: 8 slots per cell where that is no more than
      // one slot per entry (crowded cells, as in cloth: ~17 entries per cell on the UNC ball),
      // and never fewer than 2 per cell. (A load of up to 2/3 cost 3-5% of phase 1 in call 1.)
      const std::size_t c = m.cell_cap;
      const std::size_t slots = std::max<std::size_t>(
          64, std::max(2 * c, std::min<std::size_t>(8 * c, m.entry_cap)) + 1);
      m.slots.reserve(slots, false);
      m.slot_count = static_cast<std::uint32_t>(slots);
      CUDA_TRY(cudaMemsetAsync(m.slots.data(), 0xFF, slots * sizeof(unsigned long long), s));
    }
    if (compact)
      cellsKernel<true><<<eb, kBuildBlock, 0, s>>>(cap, keys_sorted, nullptr, head, cell_index,
                                                   dinfo, async ? cell_cap : m.cell_cap,
                                                   m.cell_begin.data(), m.cell_key.data(),
                                                   m.slots.data(), m.slot_count,
                                                   m.block_cell.data());
    else
      cellsKernel<false><<<eb, kBuildBlock, 0, s>>>(cap, keys_sorted, hi_sorted, head, cell_index,
                                                    dinfo, m.cell_cap, m.cell_begin.data(),
                                                    m.cell_key.data(), m.slots.data(), m.slot_count,
                                                    m.block_cell.data());
  }
  checkLaunch();
  // The levels above each triangle's own that hold a cell of its range (self queries skip the
  // others without a lookup), where they pay (upperLevelsFor).
  m.upper_ready = upperLevelsFor(m.self_density);
  if (m.upper_ready) {
    m.upper.reserve(upperWords(nt), false);
    CUDA_TRY(cudaMemsetAsync(m.upper.data(), 0, upperWords(nt) * sizeof(std::uint32_t), s));
    const std::uint32_t ccap = async ? cell_cap : m.cell_cap;
    upperLevelsKernel<S, kUpperTile><<<blocksFor(std::max<std::uint32_t>(ccap, 1),
                                                 kBuildBlock / kUpperTile),
                                       kBuildBlock, 0, s>>>(m.view(), dinfo, cap, ccap,
                                                            m.upper.data());
    checkLaunch();
  }
  m.pending = async;
  m.pending_entry_cap = cap;
  m.pending_cell_cap = async ? cell_cap : m.cell_cap;
  if (async) ++ctx.profile.rehashes_async;
  else ++ctx.profile.builds_with_readback;
}

/// Grows, before a graph capture, every buffer that buildOnDevice(async) could grow (the same
/// sizes it asks for), so that nothing allocates while the stream is captured.
template <class S>
void reserveRehash(Context& ctx, CachedMesh<S>& m, std::size_t nt) {
  const cudaStream_t s = ctx.stream;
  m.box.reserve(nt, false);
  m.diam.reserve(nt, false);
  m.level.reserve(nt, false);
  if (upperLevelsFor(m.self_density)) m.upper.reserve(upperWords(nt), false);
  const std::size_t n4 = (nt + 1 + 63) & ~std::size_t(63);
  ctx.pairs_sorted.reserve(2 * n4);
  ctx.pairs.reserve(3 * n4 / 2);
  const std::uint32_t cap = rehashCap(m.entry_cap);
  ctx.cands.reserve(2 * wordsFor64(cap) + wordsFor32(cap));  // the compact sort's arena
  std::size_t need = 0, b = 0;
  {
    cub::DoubleBuffer<std::uint32_t> sk(nullptr, nullptr), ids(nullptr, nullptr);
    CUDA_TRY(cub::DeviceRadixSort::SortPairs(nullptr, b, sk, ids, static_cast<int>(nt), 0, 32, s));
    need = std::max(need, b);
    std::uint32_t* p = nullptr;
    CUDA_TRY(cub::DeviceScan::ExclusiveSum(nullptr, b, p, p, static_cast<int>(nt + 1), s));
    need = std::max(need, b);
    cub::DoubleBuffer<unsigned long long> kb(nullptr, nullptr);
    cub::DoubleBuffer<std::uint32_t> vb(nullptr, nullptr);
    CUDA_TRY(cub::DeviceRadixSort::SortPairs(nullptr, b, kb, vb, static_cast<int>(cap), 0,
                                             m.sort_bits, s));
    need = std::max(need, b);
    CUDA_TRY(cub::DeviceScan::ExclusiveSum(nullptr, b, p, p, static_cast<int>(cap), s));
    need = std::max(need, b);
    if (countsOnRehash(m, nt)) {  // the counting build's scratch and scan
      const std::uint32_t cell_cap = rehashCap(m.cell_cap);
      ctx.cands.reserve(countBuildWords(cap, m.slot_count, cell_cap));
      CUDA_TRY(cub::DeviceScan::ExclusiveSum(nullptr, b, p, p, static_cast<int>(cell_cap + 1), s));
      need = std::max(need, b);
    }
  }
  ctx.cub_temp.reserve(need);
}

/// A re-hash without read-back as one CUDA graph: its ~20 operations are the same for every
/// re-hash of a mesh while its sizes and buffers stay the same, so the graph is captured once
/// (on the first such re-hash, which it also runs) and replayed (one launch) afterwards; any
/// change of a buffer address or size captures it again.
template <class S>
void rehashFromGraph(Context& ctx, CachedMesh<S>& m, std::size_t nt) {
  const cudaStream_t s = ctx.stream;
  reserveRehash(ctx, m, nt);
  const std::uint32_t cap = rehashCap(m.entry_cap), cell_cap = rehashCap(m.cell_cap);
  m.group_axis = cellGroupAxis();  // (a counting build's; the key holds it)
  const std::vector<std::uintptr_t> key = {
      nt, cap, cell_cap, m.slot_count, std::uintptr_t(m.sort_bits), std::uintptr_t(g_num_sms),
      std::uintptr_t(m.size_ordered), std::uintptr_t(countsOnRehash(m, nt)),
      std::uintptr_t(ctx.red_ready), std::uintptr_t(upperLevelsFor(m.self_density)),
      reinterpret_cast<std::uintptr_t>(m.upper.data()),
      reinterpret_cast<std::uintptr_t>(m.v.data()), reinterpret_cast<std::uintptr_t>(m.t.data()),
      reinterpret_cast<std::uintptr_t>(m.box.data()),
      reinterpret_cast<std::uintptr_t>(m.diam.data()),
      reinterpret_cast<std::uintptr_t>(m.level.data()),
      reinterpret_cast<std::uintptr_t>(m.entry_tri.data()),
      reinterpret_cast<std::uintptr_t>(m.entry_span.data()),
      reinterpret_cast<std::uintptr_t>(m.cell_begin.data()),
      reinterpret_cast<std::uintptr_t>(m.cell_split.data()), std::uintptr_t(m.group_axis),
      reinterpret_cast<std::uintptr_t>(m.block_cell.data()),
      reinterpret_cast<std::uintptr_t>(m.cell_key.data()),
      reinterpret_cast<std::uintptr_t>(m.slots.data()),
      reinterpret_cast<std::uintptr_t>(m.dinfo.data()),
      reinterpret_cast<std::uintptr_t>(ctx.red.data()),
      reinterpret_cast<std::uintptr_t>(ctx.cands.data()),
      reinterpret_cast<std::uintptr_t>(ctx.pairs.data()),
      reinterpret_cast<std::uintptr_t>(ctx.pairs_sorted.data()),
      reinterpret_cast<std::uintptr_t>(ctx.cub_temp.data()), ctx.cub_temp.capacity()};
  if (m.graph == nullptr || m.graph_key != key) {
    const auto t0 = std::chrono::steady_clock::now();
    cudaGraph_t g = nullptr;
    CUDA_TRY(cudaStreamBeginCapture(s, cudaStreamCaptureModeRelaxed));
    try {
      buildOnDevice(ctx, m, nt, true);
    } catch (...) {
      (void)cudaStreamEndCapture(s, &g);
      if (g != nullptr) (void)cudaGraphDestroy(g);
      throw;
    }
    CUDA_TRY(cudaStreamEndCapture(s, &g));
    // (Writing the new capture into the old executable graph, cudaGraphExecUpdate, took 0.06-0.08
    // ms of host time against 0.13-0.36 for an instantiation on an H200, but the runtime refuses
    // it where the shape changed, and memcheck reports each refusal as an API error; session 49,
    // benchmarks/RESULTS-gpu.md. Captures are rare: 2 in 20 new frames of the 90k cloth.)
    m.dropGraph();
    const cudaError_t e = cudaGraphInstantiate(&m.graph, g, 0);
    (void)cudaGraphDestroy(g);
    if (e != cudaSuccess) {
      m.graph = nullptr;
      CUDA_TRY(e);
    }
    m.graph_key = key;
    ++ctx.profile.rehash_captures;
    ctx.profile.rehash_capture_ms += hostMsSince(t0);
  } else {
    // What buildOnDevice() records on the host besides the enqueued work.
    m.pending = true;
    m.pending_entry_cap = cap;
    m.pending_cell_cap = cell_cap;
    ++ctx.profile.rehashes_async;
    m.count_build = countsOnRehash(m, nt);  // as captured (the graph's key)
    if (m.count_build) ++ctx.profile.count_builds;
  }
  ++ctx.profile.rehash_graphs;
  CUDA_TRY(cudaGraphLaunch(m.graph, s));
}

bool warpScan();

/// Uploads (vertices, and triangles when `upload_tris`) and rebuilds the hierarchy of one mesh on
/// the device.
/// - First build, new topology, 128-bit keys, or a failed re-hash: reads back the grid and the
///   entry count, then the cell count, and sizes every array (with 1/8 slack) to them.
/// - Re-hash of a mesh whose last build used compact keys (`try_async`): no read-back. The
///   arrays keep their capacities; kernels read the sizes through pointers, sorts and scans run
///   over the whole capacity (padding sorts last), and whatever does not fit is counted but not
///   stored. The query reads this BuildInfo back with its pair counts (checkPending) and, if
///   anything did not fit, rebuilds this way with read-backs and reruns. Such a re-hash runs
///   as a CUDA graph (rehashFromGraph), unless KDET_FCL_CUDA_REHASH_GRAPH=0.
template <class S>
void rebuild(Context& ctx, CachedMesh<S>& m, const MeshSource<S>& mesh, bool upload_tris,
             bool try_async, bool committed = false) {
  const cudaStream_t s = ctx.stream;
  const std::size_t nv = mesh.nv(), nt = mesh.nt();
  static_assert(kMaxDeviceTriangles <= kEntryTriMask,
                "triangle indices must fit beside the first-cell bits");
  if (nt > kMaxDeviceTriangles)
    throw InvalidInputError("mesh too large for the CUDA backend: " + std::to_string(nt) +
                            " triangles (at most 150,000,000)");
  const bool async = try_async && !upload_tris && m.key_words == 1 && m.nt == nt &&
                     m.nv == nv && m.entry_cap > 0 && !syncRehash();
  const std::size_t vbytes = nv * sizeof(Vec3<S>), tbytes = upload_tris ? nt * sizeof(Triangle) : 0;
  m.staging.reserve(vbytes + tbytes);
  char* stage = static_cast<char*>(m.staging.data());
  m.v.reserve(nv, false);
  if (upload_tris) m.t.reserve(3 * nt, false);
  // Each part's vertices (and triangles) go to their place in the arrays, through their own part
  // of the stage; the second part's vertex indices are then shifted past the first's vertices.
  // (`committed`: the first part's positions are on the device already, copied there by
  // commitVertices or updateVertices; startCommitCopy.)
  m.commit_version = 0;
  std::size_t v_at = 0, t_at = 0;
  for (int k = 0; k < 2; ++k) {
    const TriangleMesh<S>* part = mesh.part[k];
    if (part == nullptr) continue;
    const std::size_t pv = part->vertices.size(), pt = part->triangles.size();
    if (k == 0 && committed)
      ++ctx.profile.commit_uploads;
    else if (uploadVertices(ctx, m.v.data() + v_at, mesh.owner[k], *part,
                            stage + v_at * sizeof(Vec3<S>)))
      ++ctx.profile.pinned_uploads;
    if (upload_tris) {
      CUDA_TRY(staging::stagedUpload(m.t.data() + 3 * t_at, part->triangles.data(),
                                     pt * sizeof(Triangle),
                                     stage + vbytes + t_at * sizeof(Triangle), s));
      if (v_at > 0 && pt > 0) {
        shiftIndicesKernel<<<blocksFor(3 * pt, 256), 256, 0, s>>>(
            static_cast<std::uint32_t>(3 * pt), static_cast<std::uint32_t>(v_at),
            m.t.data() + 3 * t_at);
        checkLaunch();
      }
    }
    v_at += pv;
    t_at += pt;
  }
  m.nv = nv;
  m.nt = nt;
  m.pending = false;
  // Cells in size order only for the tile scan (its early exit); the warp scan tests every entry
  // of a cell anyway, so its builds skip the size sort. A tile scan over cells built for the warp
  // scan tests them all (no early exit): the same candidates.
  m.size_ordered = !warpScan();
  ++m.builds;             // new geometry: a kept self result is of the old one
  m.kept_self.drop();
  m.dinfo.reserve(1, false);
  if (nt == 0) {
    m.info = BuildInfo{};
    m.key_words = 0;
    m.entry_cap = 0;
    CUDA_TRY(cudaMemcpyAsync(m.dinfo.data(), &m.info, sizeof(BuildInfo), cudaMemcpyHostToDevice, s));
    CUDA_TRY(cudaStreamSynchronize(s));  // the staging buffer and m.info are free again
    return;
  }
  if (async && rehashGraphOn()) {
    rehashFromGraph(ctx, m, nt);
    return;
  }
  buildOnDevice(ctx, m, nt, async);
}

/// Whether a re-hash without read-back of `m` stored everything (its BuildInfo `host`, copied
/// back with the pass's counts): nothing too large for its arrays, keys within the compact sort.
template <class S>
bool builtInCaps(const CachedMesh<S>& m, const BuildInfo& host) {
  return !host.need_sync && host.entries <= m.pending_entry_cap &&
         host.cells <= m.pending_cell_cap;
}

/// After a query pass: a mesh re-hashed without read-back (pending) whose BuildInfo, copied to
/// `host` with the pass's counts, shows that an array was too small or the keys outgrew the
/// compact sort is rebuilt with read-backs. Returns true when it was (the query must rerun).
template <class S>
bool checkPending(Context& ctx, CachedMesh<S>& m, const MeshSource<S>& mesh,
                  const BuildInfo& host) {
  if (!m.pending) return false;
  m.pending = false;
  m.info = host;
  if (builtInCaps(m, host)) return false;
  ++ctx.profile.rehash_fallbacks;
  // Too many entries, or too many cells (the counting build stops inserting at its cap, the
  // sort build counts them all): the mesh is growing, so its next arrays get more room.
  m.outgrown = host.entries > m.pending_entry_cap || host.cells > m.pending_cell_cap ||
               host.inserted >= m.pending_cell_cap;
  ctx.profile.rehash_outgrown += m.outgrown ? 1 : 0;
  rebuild(ctx, m, mesh, false, false);
  return true;
}

/// The cache entry of `hm` (or of `hm` and `hm2` hashed as one), brought up to date: nothing
/// happens for meshes whose geometry did not change (rigid motion only changes the pose, which
/// the query uploads); a new version uploads the vertices and re-hashes; changed triangles are
/// uploaded too.
template <class S>
CachedMesh<S>& acquire(Context& ctx, const HashedMesh<S>& hm, const HashedMesh<S>* hm2 = nullptr) {
  auto& list = ctx.meshes(static_cast<S*>(nullptr));
  const MeshSource<S> src = sourceOf(&hm, hm2);
  std::uint64_t fp = fingerprintOf(hm.mesh());
  if (hm2) fp = fp * 1099511628211ull ^ fingerprintOf(hm2->mesh());
  const std::uint64_t v2 = hm2 ? hm2->version() : 0;
  auto it = std::find_if(list.begin(), list.end(), [&](const CachedMesh<S>& c) {
    return c.owner == &hm && c.owner2 == hm2;
  });
  if (it != list.end()) {
    list.splice(list.begin(), list, it);  // most recently used first
  } else {
    list.emplace_front();
    list.front().owner = &hm;
    list.front().owner2 = hm2;
  }
  CachedMesh<S>& m = list.front();
  m.takeFor(hm.identity(), hm2 ? hm2->identity() : 0);
  const bool same_ids = m.version == hm.version() && m.version2 == v2 && m.fingerprint == fp;
  if (m.valid && !m.force_vertices && same_ids) return m;
  // markDeformed() with unchanged versions: only the vertices can have moved. So too after
  // updateVertices(), which keeps the topology version: the device's triangles are those of the
  // meshes' topology versions (a moved-from mesh keeps its version but not its triangles: the
  // count tells). Otherwise the triangles are compared on the host (cheaper than uploading them
  // again; a comparison of every triangle per frame was most of a 1M-triangle re-hash's host
  // time: benchmarks/RESULTS-gpu.md).
  const std::uint64_t t2 = hm2 ? hm2->topologyVersion() : 0;
  const bool only_vertices =
      m.valid && ((m.force_vertices && same_ids) ||
                  (m.topology == hm.topologyVersion() && m.topology2 == t2 && m.nt == src.nt()));
  auto sameTriangles = [&] {
    ++ctx.profile.topology_compares;
    if (m.nt != src.nt() || m.host_tris.size() != src.nt() || m.t.data() == nullptr) return false;
    const std::vector<Triangle>& t0 = src.part[0]->triangles;
    if (!std::equal(t0.begin(), t0.end(), m.host_tris.begin())) return false;
    return hm2 == nullptr || std::equal(hm2->mesh().triangles.begin(), hm2->mesh().triangles.end(),
                                        m.host_tris.begin() + t0.size());
  };
  const bool same_topology = only_vertices || sameTriangles();
  // commitVertices or updateVertices copied this version's positions into the device's array
  // (startCommitCopy). It marks only a valid entry of one mesh with as many vertices, and any
  // change since would have given the mesh a new version (versions start at 1: 0 never matches).
  const bool committed = m.commit_version == hm.version();
  m.valid = false;
  rebuild(ctx, m, src, !same_topology, same_topology, committed);
  if (!same_topology) {
    m.host_tris = hm.mesh().triangles;
    if (hm2) m.host_tris.insert(m.host_tris.end(), hm2->mesh().triangles.begin(),
                                hm2->mesh().triangles.end());
  }
  m.version = hm.version();
  m.version2 = v2;
  m.topology = hm.topologyVersion();
  m.topology2 = t2;
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
  return detail::numberKnob("KDET_FCL_CUDA_PAIR_CAPACITY", 0, std::uint64_t(1) << 40, 0);
}

/// Whether the warp-wide phase 1 (the warp scans and the cells' pairs) emits its candidates
/// through a warp's stage in shared memory, 32 per atomic (stagePair), or each group of lanes
/// with its own atomic (emitPair): KDET_FCL_CUDA_STAGE_PAIRS unset or 1, or 0 (PairSink::staged,
/// on the candidates' sink). The tile scan, the plane filter and the exact tests take the atomic
/// per group (staging them too measured no faster: benchmarks/RESULTS-gpu.md). Read at every
/// query, so tests and benchmarks can compare the two; both give the same candidates (in
/// another order).
bool stagedPairs() { return detail::switchKnob("KDET_FCL_CUDA_STAGE_PAIRS", true); }

/// The plane filter between the phases (Predicate::Exact only): KDET_FCL_CUDA_PLANE_FILTER=0
/// turns it off (default on; read at every query, so tests and benchmarks can compare both).
bool planeFilterOn() { return detail::switchKnob("KDET_FCL_CUDA_PLANE_FILTER", true); }

/// The pairs' order by counting (runQuery): KDET_FCL_CUDA_COUNT_ORDER = 0 never (the radix sort
/// always), 1 whenever no segment exceeds segmentMax() pairs, unset: also only from
/// kCountOrderMinPairs pairs. Read at every query.
bool countOrderAllowed() { return detail::switchKnob("KDET_FCL_CUDA_COUNT_ORDER", true); }
bool countOrderForced() { return detail::switchKnob("KDET_FCL_CUDA_COUNT_ORDER", false); }

/// Whether a query pass queues the counting order of its pairs (and, for a host result of at
/// most oneTripCopyChunks() read-back chunks, their copy into the page-locked stage) before the
/// host reads the pass's counts back, each step deciding on the device whether the pass allows
/// it (OrderSizes), so that the host waits once per pass, not twice: KDET_FCL_CUDA_ONE_TRIP
/// (default on; needs the counting order, KDET_FCL_CUDA_COUNT_ORDER not 0). Read at every
/// query.
bool oneTripOn() { return detail::switchKnob("KDET_FCL_CUDA_ONE_TRIP", true); }

/// The read-back chunks (KDET_FCL_CUDA_DOWNLOAD_CHUNK) of the largest host result that the one
/// trip writes straight into the page-locked stage: KDET_FCL_CUDA_ONE_TRIP_COPY = k, 0 (never) to
/// kOneTripMaxChunks (the default); larger ones are read back in chunks after the counts. H100,
/// gpu_bench: from 1 chunk to 4, the cloth ball's output (61,530 pairs, 1.9 chunks) took 0.073
/// against 0.099 ms, the two n-body frames' (70,169, 2.1 chunks) 0.095 against 0.140 ms
/// (benchmarks/RESULTS-gpu.md). Read at every query.
std::size_t oneTripCopyChunks() {
  return static_cast<std::size_t>(
      detail::numberKnob("KDET_FCL_CUDA_ONE_TRIP_COPY", 0, kOneTripMaxChunks, kOneTripMaxChunks));
}

/// Whether a host query whose last host result (these meshes, this kind: runQuery's forecast)
/// held one to kOneTripMaxChunks read-back chunks of pairs (KDET_FCL_CUDA_DOWNLOAD_CHUNK; 32,768
/// to 131,072 pairs by default) has them delivered into device memory in its one trip and read
/// back by DMA, sized from that forecast and queued right behind the pass's counts
/// (forecastPairs): KDET_FCL_CUDA_ONE_TRIP_FORECAST (default on; needs the one trip). The pairs
/// then cross the bus by DMA instead of as the order kernel's writes into mapped memory
/// (oneTripCopyChunks; ncu, H100, the cloth ball's 61,530 pairs: that kernel took 39.7 us with
/// them, 15.8 without). H100, gpu_bench, three rounds each way (benchmarks/RESULTS-gpu.md): the
/// output of the two funnel frames (48,538 pairs) 0.077-0.085 -> 0.059-0.073 ms, of the two
/// n-body frames (70,169) 0.106-0.166 -> 0.096-0.128, the cloth ball's (61,530) level. Not
/// below one chunk: results of a few thousand pairs took 0.004-0.009 ms more that way (a DMA's
/// and its event's fixed costs against a kernel's few KB of writes). Not above kOneTripMaxChunks:
/// the two cloth-ball frames' 445,614 pairs took 0.007-0.021 ms more than with their order and
/// read-back queued after the counts (the host's queueing then runs while the order does). A
/// query with more pairs than the forecast's read-back holds reads them all back after the counts
/// (drained first). Read at every query.
bool oneTripForecastOn() { return detail::switchKnob("KDET_FCL_CUDA_ONE_TRIP_FORECAST", true); }

/// The pairs a forecast's read-back covers: the forecast `f` and a sixteenth more, plus 512
/// (frame-to-frame growth; the extra chunks' transfers are the cost of a larger margin), at most
/// `most` (what the delivery buffer holds).
std::size_t forecastPairs(std::size_t f, unsigned long long most) {
  const unsigned long long want = static_cast<unsigned long long>(f) + f / 16 + 512;
  return static_cast<std::size_t>(std::min(want, most));
}

/// The counting order in one cooperative launch (orderPairsKernel), or in its five launches (0):
/// KDET_FCL_CUDA_FUSED_ORDER = k, 0 to 32 (default 2), the launch's blocks per SM in one trip,
/// where the pairs are not known yet (at most as many as fit at once; after the counts, as many
/// as the pairs fill). Read at every query.
int fusedOrderBlocks() {
  return static_cast<int>(detail::numberKnob("KDET_FCL_CUDA_FUSED_ORDER", 0, 32, 2));
}

/// orderPairsKernel's blocks that fit on one SM at once, 0 where the device has no cooperative
/// launch (then the order takes its five launches). Asked once.
int orderBlocksPerSm(Context& ctx) {
  if (ctx.order_blocks_per_sm < 0) {
    int coop = 0, per_sm = 0;
    CUDA_TRY(cudaDeviceGetAttribute(&coop, cudaDevAttrCooperativeLaunch, ctx.device));
    if (coop != 0)
      CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, orderPairsKernel,
                                                             kOrderBlock, 0));
    ctx.order_blocks_per_sm = per_sm;
  }
  return ctx.order_blocks_per_sm;
}

/// The bits of the counting order's segment index (a segment holds the pairs whose first index,
/// with a joint query's kind above it, agrees in its top that many bits): kCountOrderSegmentBits
/// (cuda_backend.h), or KDET_FCL_CUDA_COUNT_ORDER_BITS (12 .. 20). More bits: smaller segments,
/// so fewer keys for each key's rank to read, against a larger scan and more memory for the
/// segments' counts (4 bytes each). Read at every query.
int segmentBits() {
  return static_cast<int>(
      detail::numberKnob("KDET_FCL_CUDA_COUNT_ORDER_BITS", 12, 20, kCountOrderSegmentBits));
}

/// The most pairs of one segment that the counting order ranks (each pair of a segment reads the
/// whole segment): kSegmentMax, or KDET_FCL_CUDA_COUNT_ORDER_SEGMENT (1 .. kSegmentMaxLimit).
/// Read at every query.
unsigned int segmentMax() {
  return static_cast<unsigned int>(detail::numberKnob("KDET_FCL_CUDA_COUNT_ORDER_SEGMENT", 1,
                                                      kSegmentMaxLimit, kSegmentMax));
}

/// When a query stores its candidates in fewer than 8 bytes where their key fits
/// (candidateKeyBytes): KDET_FCL_CUDA_PACKED_CANDIDATES = 1 (the default) only when its
/// candidates, forecast from the last query of its kind on its meshes, would take more than one
/// round at 8 bytes each (runQuery); 2 always (tests); 0 never. Read at every query, so tests and
/// benchmarks can compare them; all give the same candidates. H100: the two cloth-ball frames
/// hashed as one then take one round instead of two, 0.11 ms faster; queries of one round at 8
/// bytes gained nothing from fewer bytes (benchmarks/RESULTS-gpu.md).
int packedCandidates() {
  return static_cast<int>(detail::numberKnob("KDET_FCL_CUDA_PACKED_CANDIDATES", 0, 2, 1));
}

/// The bytes of a stored candidate of a query whose keys (a << b_bits) | b take a_bits + b_bits
/// bits: 4 up to 32 bits (meshes of up to 65,536 triangles), 5 up to 40 (up to 1,048,576), else
/// 8. Fewer bytes let one round hold more candidates in the same memory (roundCandidateLimit).
constexpr int candidateKeyBytes(int a_bits, int b_bits) {
  return a_bits + b_bits > 40 ? 8 : a_bits + b_bits > 32 ? 5 : 4;
}

/// The candidates of key_bytes bytes that `words` 64-bit words hold (PairSink's layouts), and
/// the words that hold n of them.
constexpr std::size_t candidatesIn(std::size_t words, int key_bytes) {
  return words * 8 / static_cast<std::size_t>(key_bytes);
}
constexpr std::size_t candidateWords(std::size_t n, int key_bytes) {
  return (n * static_cast<std::size_t>(key_bytes) + 7) / 8;
}

/// The candidates one round of a query may hold (KDET_FCL_CUDA_ROUND_CANDIDATES = k from 0 to
/// 2^20 per query triangle, read at every query; 0: no limit). A query whose phase 1 gives more
/// runs its tasks in rounds that reuse the candidate buffer, so that the buffer holds about the
/// limit, not all of them (runQuery). Each extra round costs time (on an H100, 0.13 ms on two
/// near-coincident cloth frames hashed as one: benchmarks/RESULTS-gpu.md). By default the
/// buffer may take 112 bytes per query triangle (at least 2^19 bytes): 14 candidates of 8 bytes,
/// 22 of 5 (those two frames' 21 in one round), 28 of 4; that keeps every scene of the
/// benchmark under 256 bytes per triangle. With the knob, exactly k candidates per triangle,
/// whatever their bytes (tests force many rounds on small meshes).
std::size_t roundCandidateLimit(std::size_t work, int key_bytes) {
  constexpr std::uint64_t kUnset = ~std::uint64_t(0);
  const std::uint64_t k =
      detail::numberKnob("KDET_FCL_CUDA_ROUND_CANDIDATES", 0, 1u << 20, kUnset);
  if (k == kUnset)
    return candidatesIn(std::max<std::size_t>(std::size_t(1) << 16, 14 * work), key_bytes);
  return static_cast<std::size_t>(k) * work;
}

/// Rounds for `candidates` candidates under the limit: one while they fit in it, else each round
/// planned at 4/5 of it, as the rounds' ranges of tasks are only near-equal in candidates (at
/// most kMaxRounds).
constexpr std::uint32_t kMaxRounds = 256;
std::uint32_t roundsFor(double candidates, std::size_t limit) {
  if (limit == 0 || !(candidates > double(limit))) return 1;
  const double r = std::ceil(candidates / (0.8 * double(limit)));
  return r >= kMaxRounds ? kMaxRounds : static_cast<std::uint32_t>(r);
}

/// The rounds of a query pass (runQuery): `rounds` rounds of stage 0, or, `staged`, first_rounds
/// of stage 1 (the cells' pairs) then second_rounds of stage 2 (the scan).
struct RoundPlan {
  bool staged = false;
  std::uint32_t rounds = 1, first_rounds = 0, second_rounds = 0;
  std::uint32_t total() const { return staged ? first_rounds + second_rounds : rounds; }
  Round at(std::uint32_t r) const {
    if (!staged) return Round{r, rounds, 0, r};
    return r < first_rounds ? Round{r, first_rounds, 1, r}
                            : Round{r - first_rounds, second_rounds, 2, r};
  }
  /// The plan for `all` candidates of which `first` come from the first stage (stages: the query
  /// has two): one round while they fit in the limit; else, with stages, each stage in its own
  /// rounds (two rounds, no kernel split, while each stage fits), else ranges of every kernel.
  static RoundPlan make(double all, double first, bool stages, std::size_t limit) {
    RoundPlan p;
    p.rounds = roundsFor(all, limit);
    if (p.rounds > 1 && stages) {
      p.staged = true;
      p.first_rounds = roundsFor(first, limit);
      p.second_rounds = roundsFor(all - first, limit);
    }
    return p;
  }
};

/// Where a query's pairs go when the caller keeps them on the device (intersect*OnDevice): at
/// most `capacity` of them to `ptr` (device memory, checked by checkDevicePairs), and `count`
/// receives how many the query found.
struct DeviceOut {
  TrianglePair* ptr = nullptr;
  std::size_t capacity = 0;
  std::size_t count = 0;
  std::size_t kinds[2] = {0, 0};  // two meshes hashed as one: the pairs of kinds 1 and 2
};

/// Runs `launch(cand, survivors, out, round)` (it returns whether the plane filter ran) for each
/// round of a pass, until every pair fits (overflow: grow, or more rounds; rerun), then puts the
/// pairs in key order on the device (by counting them per segment, or by the radix sort: see
/// segmentBits()) and copies the first max_pairs (or all) of that order into the result. The
/// rounds (roundsFor: from `density`, the candidates per unit of `work` of the last query of
/// this kind on these meshes, and from the counts of a pass that overflowed) split the candidate
/// search's tasks into contiguous ranges (Round); each round's candidates and survivors reuse
/// their buffers, its pairs add to the others'. All rounds of a pass are queued at once: the host
/// reads the counts back once per pass, as with one round. With `parts` (two meshes hashed as
/// one, the first's triangles below `split`; max_pairs 0), the pairs carry their kind in the two
/// bits above the first index's a_bits (selfExactKernel), the order covers those bits too, so the
/// three kinds come as three runs, whose lengths the delivery (deliverPair) counts; the runs are
/// dealt out as they arrive: parts[0] gets the first mesh's own pairs, parts[1] the second's and
/// parts[2] those across, each in its own mesh's indices and in (a, b) order, as the three
/// separate queries give them. With `dev` (instead of `parts`), the ordered pairs are delivered
/// straight into the caller's device buffer, as many as fit, dev->count gets how many there were
/// (and dev->kinds, with split, the pairs of kinds 1 and 2), nothing else is read back, and the
/// call returns once the stream is done. With `keep` (a result the caller keeps across frames:
/// its storage, moved into the returned result's pairs), or with `parts` that hold pairs, the
/// pairs are read back into that storage: by several threads where staging::pooledThreads allows
/// (enough pairs, and at least half as many there already; staging::downloadInto,
/// pooledDownload). `forecast`: the pairs this query (these meshes, this kind) delivered into a
/// host result last time (0: none yet), updated here after each host result; with one trip, a
/// forecast queues the read-back of that many pairs and a margin before the counts come back
/// (forecastPairs, oneTripForecastOn).
template <class Launch, class Pending>
QueryResult runQuery(Context& ctx, Launch&& launch, Pending&& pending, int a_bits, int b_bits,
                     std::size_t work, double density, double first_share, bool stages,
                     const QueryOptions& options, std::size_t* forecast, std::uint32_t split = 0,
                     QueryResult* parts = nullptr, DeviceOut* dev = nullptr,
                     std::vector<TrianglePair>* keep = nullptr) {
  const cudaStream_t s = ctx.stream;
  ctx.profile.density_forecast = density;
  ctx.profile.pairs_forecast = forecast != nullptr ? *forecast : 0;
  // The candidates' layout (PairSink::key_bytes; packedCandidates): their keys carry b_bits for
  // b, or 32 in 8 bytes.
  const int packing = packedCandidates();
  const bool packed =
      packing == 2 || (packing == 1 && roundsFor(density * double(work),
                                                 roundCandidateLimit(work, 8)) > 1);
  const int key_bytes = packed ? candidateKeyBytes(a_bits, b_bits) : 8;
  const int cand_b_bits = key_bytes == 8 ? 32 : b_bits;
  ctx.profile.candidate_key_bytes = key_bytes;
  ctx.cands.reserve(std::max<std::size_t>(std::size_t(1) << 16, 8 * work));
  ctx.pairs.reserve(std::max<std::size_t>(std::size_t(1) << 16, work));
  // The survivors of the plane filter live in the buffer that later receives the sorted pairs
  // (they are dead by then, and there are never fewer survivors than pairs).
  ctx.pairs_sorted.reserve(std::max<std::size_t>(std::size_t(1) << 16, 2 * work));
  unsigned long long cand_cap = candidatesIn(ctx.cands.capacity(), key_bytes);
  unsigned long long cap = ctx.pairs.capacity();
  unsigned long long surv_cap = ctx.pairs_sorted.capacity();
  const unsigned long long knob = capacityKnob();
  if (knob > 0) {
    cand_cap = std::min(cand_cap, knob);
    cap = std::min(cap, knob);
    surv_cap = std::min(surv_cap, knob);
  }
  const std::size_t limit = roundCandidateLimit(work, key_bytes);
  RoundPlan plan =
      RoundPlan::make(density * double(work), first_share * density * double(work), stages, limit);
  unsigned long long n = 0;
  int passes = 0;
  unsigned long long* const w = ctx.pair_count.data();
  const unsigned long long* const h = ctx.hostCount();
  // The counting order's segments: a pair's first index (with a joint query's kind above it),
  // shifted right to at most segmentBits() bits.
  const bool kinds = split > 0;
  const int upper_bits = a_bits + (kinds ? 2 : 0);
  const int seg_shift = std::max(0, upper_bits - segmentBits());
  const std::size_t segments = std::size_t(1) << (upper_bits - seg_shift);
  const bool counting = countOrderAllowed();
  const unsigned int seg_max = segmentMax();
  const bool staged = stagedPairs();
  ctx.profile.staged_pairs = staged;
  // The fused order's grid in one trip (0: five launches), and the most blocks it may have
  // after the counts (all that fit at once); its blocks' sums follow the segments' counts.
  unsigned int order_grid = 0, order_most = 0;
  if (counting) {
    const int fit = orderBlocksPerSm(ctx);
    const int per_sm = std::min(fusedOrderBlocks(), fit);
    if (per_sm > 0) {
      order_grid = static_cast<unsigned int>(per_sm * g_num_sms);
      order_most = static_cast<unsigned int>(fit * g_num_sms);
    }
    ctx.segs.reserve(segments + order_most);
  }
  unsigned long long* const kind_counts = kinds ? ctx.kindCounts() : nullptr;
  // Where the order delivers the pairs: the caller's device buffer, or `spare`, a key buffer
  // the order no longer needs (the counting order's: ctx.pairs, read at each use, as it may
  // have grown; the sort's: its alternate buffer).
  auto delivery = [&](void* spare) {
    return reinterpret_cast<uint2*>(dev != nullptr ? static_cast<void*>(dev->ptr) : spare);
  };
  // The counting order: the segments' starts (in place), each key into its segment, its rank
  // there (the order of the sort, in light steps instead of the sort's passes: one cooperative
  // launch, orderPairsKernel, or the scan's two launches and three kernels), sized by z
  // (OrderSizes: from the host, or from the pass's counters).
  const int order_shift = b_bits + seg_shift;
  // With `stage` (a host result in one trip), the pairs also go to the mapped stage when they
  // are at most `most`.
  auto countingOrder = [&](const OrderSizes& z, unsigned int blocks, uint2* stage,
                           std::uint32_t most) {
    unsigned int* const seg = ctx.segs.data();
    if (order_grid > 0) {
      cudaLaunchConfig_t cfg = {};
      // In one trip (z.w set) the pairs are not known yet: k blocks per SM at most
      // (KDET_FCL_CUDA_FUSED_ORDER); after the counts, as many as the pairs fill (`blocks`), at
      // least one per SM (the scan's shares) and at most all that fit.
      cfg.gridDim = dim3(z.w != nullptr
                             ? std::max(1u, std::min(order_grid, blocks))
                             : std::min(order_most,
                                        std::max(blocks, static_cast<unsigned int>(g_num_sms))));
      ctx.profile.order_blocks = cfg.gridDim.x;
      cfg.blockDim = dim3(kOrderBlock);
      cfg.stream = s;
      cudaLaunchAttribute coop = {};
      coop.id = cudaLaunchAttributeCooperative;
      coop.val.cooperative = 1;
      cfg.attrs = &coop;
      cfg.numAttrs = 1;
      CUDA_TRY(cudaLaunchKernelEx(&cfg, orderPairsKernel, z,
                                  static_cast<const unsigned long long*>(ctx.pairs.data()),
                                  order_shift, seg, static_cast<std::uint32_t>(segments),
                                  seg + segments, ctx.pairs_sorted.data(), b_bits,
                                  delivery(ctx.pairs.data()), a_bits, kind_counts, stage, most));
      return;
    }
    cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
      return cub::DeviceScan::ExclusiveSum(tmp, bytes, seg, seg, static_cast<int>(segments), s);
    });
    scatterPairsKernel<<<blocks, 256, 0, s>>>(z, ctx.pairs.data(), order_shift, seg,
                                              ctx.pairs_sorted.data());
    checkLaunch();
    rankPairsKernel<<<blocks, 256, 0, s>>>(z, ctx.pairs_sorted.data(), order_shift, seg, b_bits,
                                           delivery(ctx.pairs.data()), a_bits, kind_counts);
    checkLaunch();
    if (stage != nullptr) {
      copyPairsOutKernel<<<std::min<unsigned int>(blocksFor(most, 256),
                                                  static_cast<unsigned int>(2 * g_num_sms)),
                           256, 0, s>>>(z, delivery(ctx.pairs.data()), stage, most);
      checkLaunch();
    }
  };
  // One trip (oneTripOn): each pass queues the counting order behind its exact tests, and a
  // host result of at most oneTripCopyChunks() read-back chunks (copy_most pairs) its copy into
  // the stage, all sized on the device from the pass's counters (trip), before the counts come
  // back. Not for a host result when the last one took more than kOneTripMaxChunks chunks: the
  // host then enqueues a copy and an event per chunk (a few us each) after the counts, which the
  // order's kernels cover when they are queued after the counts instead.
  // With a forecast (a host result of this query before, of one to kOneTripMaxChunks read-back
  // chunks: oneTripForecastOn), the one trip instead delivers the pairs into device memory and
  // queues their read-back by DMA, sized from the forecast, right behind the counts; the host
  // waits for the counts alone and copies the chunks out of the stage as they arrive.
  const std::size_t chunk_pairs =
      std::min<std::size_t>(staging::downloadChunkElements(sizeof(TrianglePair)), 0x7FFFFFFF);
  const bool trip_on = counting && oneTripOn();
  // (A forecast is only taken in one trip: forecast_pairs > 0 implies one_trip.)
  const std::size_t forecast_pairs =
      trip_on && dev == nullptr && forecast != nullptr && *forecast >= chunk_pairs &&
              *forecast <= kOneTripMaxChunks * chunk_pairs && oneTripForecastOn()
          ? *forecast
          : 0;
  const bool one_trip = trip_on && (dev != nullptr || forecast_pairs > 0 ||
                                    ctx.last_host_pairs <= kOneTripMaxChunks * chunk_pairs);
  std::uint32_t copy_most = 0;
  if (one_trip && dev == nullptr && forecast_pairs == 0) {
    copy_most = static_cast<std::uint32_t>(
        std::min<std::size_t>(oneTripCopyChunks() * chunk_pairs, 0x7FFFFFFF));
    ctx.readback.reserve(std::size_t(copy_most) * sizeof(TrianglePair));
    if (ctx.readback.deviceData() == nullptr) copy_most = 0;  // kernels cannot write there
  }
  OrderSizes trip;  // the last pass's capacities and counters (passFits; one_trip's sizes)
  // The read-back queued before the counts (forecast_pairs > 0): the first `ahead_pairs` places
  // of the delivered order, in chunks, into the stage. Drained (reset: the stream synchronised)
  // before anything may write the stage or the delivery buffer again.
  std::optional<staging::ChunkEvents> ahead;
  std::size_t ahead_pairs = 0;
  while (true) {
    ++passes;
    // One trip: the grouped keys' buffer (the survivors') holds every pair the pass can store,
    // so that no pass that stored all it found skips the order on the device for want of room
    // there (the host could not count them after it: the pass's scan has run on the counts).
    if (one_trip && ctx.pairs_sorted.capacity() < cap) {
      ctx.pairs_sorted.reserve(cap);
      surv_cap = ctx.pairs_sorted.capacity();
      if (knob > 0) surv_cap = std::min(surv_cap, knob);
    }
    CUDA_TRY(cudaMemsetAsync(w, 0, kPairCountWords * sizeof(unsigned long long), s));
    if (counting)
      CUDA_TRY(cudaMemsetAsync(ctx.segs.data(), 0, segments * sizeof(unsigned int), s));
    bool filtered = false;
    const std::uint32_t rounds = plan.total();
    for (std::uint32_t r = 0; r < rounds; ++r) {
      if (r > 0) ctx.markRound(r, 0);
      // (Key layouts of 4 and 5 bytes: cand_cap low words, then, for 5, cand_cap high bytes.)
      unsigned char* const cand_hi =
          key_bytes == 5 ? reinterpret_cast<unsigned char*>(ctx.cands.data()) + 4 * cand_cap
                         : nullptr;
      filtered = launch(PairSink{ctx.cands.data(), w + kCandCount, cand_cap, cand_b_bits, nullptr,
                                 0, nullptr, kSegmentMax, staged, key_bytes, cand_hi},
                        PairSink{ctx.pairs_sorted.data(), w + kSurvCount, surv_cap, 32},
                        PairSink{ctx.pairs.data(), w + kPairCount, cap, b_bits,
                                 counting ? ctx.segs.data() : nullptr, seg_shift,
                                 w + kBigSegment, seg_max},
                        plan.at(r));
      checkLaunch();
      if (rounds > 1) {
        roundEndKernel<<<1, 1, 0, s>>>(w);
        checkLaunch();
      }
    }
    trip = OrderSizes{};
    trip.w = w;
    trip.cand_cap = cand_cap;
    trip.surv_cap = surv_cap;
    trip.cap = cap;
    trip.sorted_cap = ctx.pairs_sorted.capacity();
    trip.max_pairs = options.max_pairs;
    trip.give_cap = dev != nullptr ? dev->capacity : ~0ull;
    trip.rounds = rounds > 1;
    trip.filtered = filtered;
    trip.kinds = kinds;
    if (one_trip) {
      ctx.record(2);
      // A grid for the most keys the pass can have stored; its threads loop over the n there.
      countingOrder(trip,
                    std::min<unsigned int>(blocksFor(std::min(cap, trip.sorted_cap), 256),
                                           static_cast<unsigned int>(8 * g_num_sms)),
                    copy_most > 0 ? static_cast<uint2*>(ctx.readback.deviceData()) : nullptr,
                    copy_most);
    }
    CUDA_TRY(cudaMemcpyAsync(ctx.hostCount(), w, kPairCountWords * sizeof(unsigned long long),
                             cudaMemcpyDeviceToHost, s));
    pending.enqueue();  // the BuildInfo of meshes re-hashed without read-back, same sync
    if (forecast_pairs > 0) {
      // The forecast's read-back behind the counts (a pass that must rerun, or whose pairs are
      // more, drains it below); the host waits for the counts alone.
      ahead_pairs = forecastPairs(forecast_pairs, cap);
      ctx.readback.reserve(ahead_pairs * sizeof(TrianglePair));
      CUDA_TRY(cudaEventRecord(ctx.counted, s));
      ahead.emplace();
      CUDA_TRY(staging::downloadChunks(reinterpret_cast<const TrianglePair*>(
                                           delivery(ctx.pairs.data())),
                                       ahead_pairs,
                                       static_cast<TrianglePair*>(ctx.readback.data()), s, *ahead));
      CUDA_TRY(cudaEventSynchronize(ctx.counted));
      if (pending.rebuilds() || !passFits(h, trip)) ahead.reset();
    } else {
      CUDA_TRY(cudaStreamSynchronize(s));
    }
    if (pending.check()) continue;  // a re-hash did not fit: rebuilt with read-backs, rerun
    // The most candidates of one round, and of all rounds (one round: its own counters).
    const unsigned long long nc = rounds > 1 ? h[kMaxCands] : h[kCandCount];
    const unsigned long long nc_all = rounds > 1 ? h[kAllCands] : h[kCandCount];
    n = h[kPairCount];
    // Without the filter the exact kernel reads the candidates directly.
    const unsigned long long ns = filtered ? (rounds > 1 ? h[kMaxSurv] : h[kSurvCount]) : nc;
    const unsigned long long ns_all =
        filtered ? (rounds > 1 ? h[kAllSurv] : h[kSurvCount]) : nc_all;
    ctx.profile.candidates = nc_all;
    ctx.profile.exact_tests = ns_all;
    ctx.profile.rounds = static_cast<int>(rounds);
    ctx.profile.cell_rounds = static_cast<int>(plan.staged ? plan.first_rounds : 0);
    ctx.profile.cell_candidates = h[kCellCands];
    if (passFits(h, trip)) break;
    // The device counted everything it could not store: grow and rerun (no pair is dropped).
    if (nc > 0x7FFFFFFFull || n > 0x7FFFFFFFull)
      throw Error("CUDA backend: more than 2^31-1 candidate pairs (" + std::to_string(nc) + ")");
    if (filtered && ns > surv_cap) {
      ctx.pairs_sorted.reserve(ns);
      surv_cap = ctx.pairs_sorted.capacity();
    }
    if (nc > cand_cap) {
      // More rounds, each within the limit; or, when more rounds would not help (a round's
      // share was crowded, or the rounds are at their maximum), a larger buffer.
      RoundPlan more = RoundPlan::make(double(nc_all), double(h[kCellCands]), stages, limit);
      if (more.staged ? (!plan.staged || more.first_rounds > plan.first_rounds ||
                         more.second_rounds > plan.second_rounds)
                      : more.rounds > rounds) {
        if (more.staged && plan.staged) {  // never fewer rounds for a stage than before
          more.first_rounds = std::max(more.first_rounds, plan.first_rounds);
          more.second_rounds = std::max(more.second_rounds, plan.second_rounds);
        }
        plan = more;
        ctx.cands.reserve(candidateWords(limit, key_bytes), false);
      } else {
        // With 1/8 slack, but no more than the limit when they fit in it (one round stays
        // within the limit's memory).
        const std::size_t words = candidateWords(nc, key_bytes);
        const std::size_t most = candidateWords(limit, key_bytes);
        const std::size_t slack = words + words / 8;
        ctx.cands.reserve(limit > 0 && words <= most ? std::min(slack, most) : slack, false);
      }
      cand_cap = candidatesIn(ctx.cands.capacity(), key_bytes);
    }
    if (n > cap) {
      ctx.pairs.reserve(n);
      cap = ctx.pairs.capacity();
    }
  }
  // Whether the last pass's one trip ordered the pairs (and the device saw what the host sees).
  OrderSizes got = trip;
  got.w = h;
  const bool tripped = one_trip && resolve(got);
  if (!tripped) ctx.record(2);
  QueryResult res;
  if (keep != nullptr) res.pairs = std::move(*keep);  // (its old pairs: replaced below)
  std::size_t m = n;
  if (options.max_pairs > 0 && m > options.max_pairs) m = options.max_pairs;
  // The pairs to deliver: all m to the host, or to the caller's device buffer as many as fit.
  // Two meshes hashed as one (split > 0) carry their kinds, which are counted over all m.
  const std::size_t give = dev != nullptr ? std::min(m, dev->capacity) : m;
  if (dev != nullptr) dev->count = m;
  // Ordered by counting when no segment holds more than segmentMax() pairs and there are enough
  // pairs (or KDET_FCL_CUDA_COUNT_ORDER=1), else sorted; with one trip, counted on the device
  // or (a segment too large: the counts are scanned already) sorted.
  const bool counted =
      one_trip ? tripped
               : counting && h[kBigSegment] == 0 &&
                     (n >= kCountOrderMinPairs || countOrderForced());
  // The one trip copied the pairs into the stage already.
  const bool from_stage = tripped && dev == nullptr && copy_most > 0 && m <= copy_most;
  // The forecast's read-back holds them all (else it is drained and they come as without it).
  if (ahead && !(tripped && m <= ahead_pairs)) ahead.reset();
  staging::ChunkEvents* const ahead_chunks = ahead ? &*ahead : nullptr;
  unsigned long long* in = ctx.pairs.data();  // receives the pairs in TrianglePair layout
  const bool delivers = give > 0 || (kinds && m > 0);
  if (!(counted && delivers)) ctx.profile.order_blocks = 0;  // (as pairs_counted)
  if (delivers) {
    ctx.profile.pairs_counted = counted;
    ctx.profile.one_trip = tripped;
    ctx.profile.one_trip_copy = from_stage;
    ctx.profile.forecast_copy = ahead_chunks != nullptr;
    static_assert(sizeof(TrianglePair) == sizeof(uint2), "TrianglePair must be two 32-bit words");
    // Into the caller's device buffer, or the key buffer the order no longer needs (`in`); the
    // kinds are counted over all m, and their counts come back before the first chunk of a host
    // result's pairs (same stream), so that the three results are sized exactly, as a single
    // query's is.
    const std::size_t unpack = kinds ? m : give;
    if (tripped) {
      if (kinds) {  // (counted on the device before the counters came back)
        ctx.hostKinds()[0] = h[kKindCounts];
        ctx.hostKinds()[1] = h[kKindCounts + 1];
      }
    } else {
      ctx.pairs_sorted.reserve(n);
      if (counted) {
        OrderSizes z;
        z.n = static_cast<std::uint32_t>(n);
        z.unpack = static_cast<std::uint32_t>(unpack);
        z.give = static_cast<std::uint32_t>(give);
        countingOrder(z, blocksFor(n, 256), nullptr, 0);
      } else {
        cub::DoubleBuffer<unsigned long long> keys(ctx.pairs.data(), ctx.pairs_sorted.data());
        const int bits = a_bits + b_bits + (kinds ? 2 : 0);
        cubCall(ctx, [&](void* tmp, std::size_t& bytes) {
          return cub::DeviceRadixSort::SortKeys(tmp, bytes, keys, static_cast<int>(n), 0, bits,
                                                s);
        });
        in = keys.Alternate();  // the sorted keys are in Current()
        unpackPairsKernel<<<blocksFor(unpack, 256), 256, 0, s>>>(
            static_cast<std::uint32_t>(unpack), static_cast<std::uint32_t>(give),
            keys.Current(), b_bits, delivery(in), a_bits, kind_counts);
        checkLaunch();
      }
      if (kinds)
        CUDA_TRY(cudaMemcpyAsync(ctx.hostKinds(), ctx.kindCounts(),
                                 2 * sizeof(unsigned long long), cudaMemcpyDeviceToHost, s));
    }
    if (dev == nullptr) {
      // Through pinned memory (a pageable device->host copy runs at a fraction of the bus rate),
      // in chunks, each appended to the result as soon as it has arrived (staged_upload.h), or,
      // into storage the caller keeps, copied by several threads where that pays (a new
      // result's empty vector always goes by the one thread: staging::downloadInto); or, after
      // the one trip's copy, out of the stage that holds them all already.
      // (The forecast's read-back reserved the stage before its chunks were queued.)
      if (!from_stage && ahead_chunks == nullptr) ctx.readback.reserve(m * sizeof(TrianglePair));
      auto* const from = reinterpret_cast<const TrianglePair*>(in);
      auto* const stage = static_cast<TrianglePair*>(ctx.readback.data());
      if (parts == nullptr) {
        if (from_stage) res.pairs.assign(stage, stage + m);
        else
          CUDA_TRY(
              staging::downloadInto(from, m, stage, s, ctx.copy_pool, res.pairs, ahead_chunks));
      } else {
        // The three runs' ends (the kind counts arrived before the first chunk).
        std::size_t end0 = 0, end1 = 0;
        auto runs = [&] {
          const std::size_t k1 = ctx.hostKinds()[0], k2 = ctx.hostKinds()[1];
          end1 = m - std::min<std::size_t>(m, k2);
          end0 = end1 - std::min<std::size_t>(end1, k1);
        };
        // Pairs [at, at + k) of the runs, at `first`, to their parts by `put(kind, offset in
        // the part, first, count)`.
        auto deal = [&](std::size_t at, const TrianglePair* first, std::size_t k, auto&& put) {
          for (std::size_t e = 0; e < k;) {
            const std::size_t i = at + e;
            const int kind = i < end0 ? 0 : i < end1 ? 1 : 2;
            const std::size_t stop =
                std::min(k, (kind == 0 ? end0 : kind == 1 ? end1 : m) - at);
            put(kind, i - (kind == 0 ? 0 : kind == 1 ? end0 : end1), first + e, stop - e);
            e = stop;
          }
        };
        // Pairs [at, at + k) appended to their parts (the first call clears and sizes them).
        auto append = [&](std::size_t at, const TrianglePair* first, std::size_t k) {
          if (at == 0) {
            runs();
            for (int kind = 0; kind < 3; ++kind) parts[kind].pairs.clear();
            parts[0].pairs.reserve(end0);
            parts[1].pairs.reserve(end1 - end0);
            parts[2].pairs.reserve(m - end1);
          }
          deal(at, first, k, [&](int kind, std::size_t, const TrianglePair* p, std::size_t c) {
            parts[kind].pairs.insert(parts[kind].pairs.end(), p, p + c);
          });
        };
        const int threads =
            from_stage ? 0
                       : staging::pooledThreads(m, parts[0].pairs.size() + parts[1].pairs.size() +
                                                       parts[2].pairs.size());
        if (from_stage) {
          append(0, stage, m);
        } else if (threads > 0) {
          CUDA_TRY(staging::pooledDownload(
              from, m, stage, s, ctx.copy_pool, threads,
              [&] {
                runs();
                parts[0].pairs.resize(end0);
                parts[1].pairs.resize(end1 - end0);
                parts[2].pairs.resize(m - end1);
              },
              [&](std::size_t at, const TrianglePair* first, std::size_t k) {
                deal(at, first, k,
                     [&](int kind, std::size_t off, const TrianglePair* p, std::size_t c) {
                       std::memcpy(static_cast<void*>(parts[kind].pairs.data() + off), p,
                                   c * sizeof(TrianglePair));
                     });
              },
              ahead_chunks));
        } else {
          std::size_t at = 0;  // the next pair's index
          CUDA_TRY(staging::stagedDownload(
              from, m, stage, s,
              [&](const TrianglePair* first, std::size_t k) {
                append(at, first, k);
                at += k;
              },
              ahead_chunks));
        }
      }
    }
  }
  if (dev == nullptr && m == 0) {  // (kept storage: no old pair stays)
    res.pairs.clear();
    if (parts != nullptr)
      for (int kind = 0; kind < 3; ++kind) parts[kind].pairs.clear();
  }
  ctx.record(3);
  // The caller's device buffer is filled when the call returns (its reader may use any stream).
  if (dev != nullptr) {
    CUDA_TRY(cudaStreamSynchronize(s));
    if (kinds && m > 0) {
      dev->kinds[0] = ctx.hostKinds()[0];
      dev->kinds[1] = ctx.hostKinds()[1];
    }
  }
  if (dev == nullptr) {
    ctx.last_host_pairs = m;
    if (forecast != nullptr) *forecast = m;
  }
  res.complete = options.max_pairs == 0 || m < options.max_pairs;
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
    // Phase 1 and the filter of every round of the last pass (round 0 from event 1).
    for (std::uint32_t r = 0; r < plan.total(); ++r) {
      float tc = 0, tf = 0;
      CUDA_TRY(cudaEventElapsedTime(&tc, r == 0 ? ctx.ev[1] : ctx.round_ev[3 * r],
                                    ctx.round_ev[3 * r + 1]));
      CUDA_TRY(cudaEventElapsedTime(&tf, ctx.round_ev[3 * r + 1], ctx.round_ev[3 * r + 2]));
      ctx.profile.candidates_ms += tc;
      ctx.profile.filter_ms += tf;
    }
    ctx.profile.passes = passes;
    ctx.profile.pairs = n;
    ctx.profile.device_allocations = static_cast<int>(
        g_device_allocations.load(std::memory_order_relaxed) - ctx.allocations_at_start);
  }
  return res;
}

/// Lanes per query triangle in the candidate search: KDET_FCL_CUDA_TILE = 1, 4, 8, 16 or 32
/// (default 8; read at every query). Larger tiles suit heavily loaded cells (crumpled cloth),
/// smaller ones lightly loaded cells, where the repeated lookups dominate
/// (benchmarks/RESULTS-gpu.md).
int tileSize() {
  return static_cast<int>(detail::choiceKnob("KDET_FCL_CUDA_TILE", {1, 4, 8, 16, 32}, 8));
}

/// Whether the candidate search tests sub-cell spans (kSpans of scanCandidatesWarp and
/// scanCandidatesGroup), given the scan (`warp`: the warp-wide scan, warpScan()) and the
/// candidates per query triangle of the last query of the same kind on the same meshes:
/// KDET_FCL_CUDA_SPANS = 0 (never), 1 (always), unset (the warp-wide scan always; the tile scan
/// when that density exceeds 4). Read at every query, so tests and benchmarks can compare the
/// ways; the choice changes the work, never the pairs.
/// The warp-wide scan with spans queues the entries that pass them and tests 32 at a time
/// (EntryRing): measured on an H200 in kdet_bench's frames (benchmarks/RESULTS-gpu.md, "The knob
/// check's cost, and the scan's spans everywhere"), phase 1 of the sparse scenes (n-body,
/// smooth cloth 20k-1M, funnel) 3-29 % shorter and their frames -17 to +5 % (two calls; a
/// placebo knob moved them by up to 6.5 %), the crowded ones (cloth ball, two frames: spans
/// already) unchanged. The tile scan tests each entry as it comes: there the test pays only in
/// crowded cells full of near-misses (cloth ball 8.4 candidates per triangle, two frames 21:
/// phase 1 -3 and -11 %) and cost +10 to +25 % on sparse scenes (n-body 1.1, smooth cloth
/// 1.6-3.4), measured on an H100 before the warp-wide scan existed, where the density rule leaves
/// it off.
bool spansFor(double density, bool warp) {
  return detail::switchKnob("KDET_FCL_CUDA_SPANS", warp || density > kCrowdedDensity);
}

/// Whether phase 1 runs the warp-wide scan (scanCandidatesWarp: 1-8 lanes per query triangle, the
/// warp testing the entries of its 4-32 queries' cells together) or the tile scan
/// (scanCandidatesGroup: a tile of tileSize() lanes per query triangle):
/// KDET_FCL_CUDA_SCAN = warp or tile (default warp; read at every query, so tests and benchmarks
/// can compare the two). Both find the same candidates; benchmarks/RESULTS-gpu.md has the A/B.
bool warpScan() { return detail::wordKnob("KDET_FCL_CUDA_SCAN", {"warp", "tile"}, 0) == 0; }

/// Lanes per query triangle of the warp-wide scan, as log2, from the number of queries and the
/// candidates per query triangle of the last query of the same kind on the same meshes (as
/// spansFor). More lanes per query cut the work into more, smaller warps: that pays until the
/// warps fill the device several times over (a finer grain leaves a shorter tail of busy warps),
/// and always where cells are crowded. So: 8 lanes when the density exceeds 4; else the fewest
/// lanes (1, 2, 4, 8) that give at least 4 x 32 lanes per resident warp of the 64-register kernel
/// (32 warps per SM). Measured on an H100 (benchmarks/RESULTS-gpu.md): the cloth ball and two
/// frames want 8, the 1M cloth 1, the n-body pair and the 200k-250k cloths 2-4, the 90k cloth 4
/// (the rule gives it 8, 5 % slower than the tile scan there).
/// KDET_FCL_CUDA_WARP_LANES = 1, 2, 4, 8, 16 or 32 forces it (read at every query).
unsigned int warpLanesLog2(unsigned long long queries, double density) {
  const std::uint64_t forced =
      detail::choiceKnob("KDET_FCL_CUDA_WARP_LANES", {1, 2, 4, 8, 16, 32}, 0);
  for (unsigned int l = 0; l <= 5; ++l)
    if (forced == (1u << l)) return l;
  if (density > kCrowdedDensity) return 3;
  const unsigned long long fill = 4ull * 32ull * 32ull * static_cast<unsigned long long>(g_num_sms);
  unsigned int l = 0;
  while (l < 3 && (queries << l) < fill) ++l;
  return l;
}

/// The most entries of one cell that the warp-wide scan takes in one visit (larger cells are cut
/// into chunks): kMaxWarpVisit, or KDET_FCL_CUDA_WARP_VISIT (1 .. kMaxWarpVisit) so that tests
/// can cut every cell.
std::uint32_t warpVisit() {
  return static_cast<std::uint32_t>(
      detail::numberKnob("KDET_FCL_CUDA_WARP_VISIT", 1, kMaxWarpVisit, kMaxWarpVisit));
}

/// Whether the warp-wide candidate kernels take their tasks from a counter, on a grid of the
/// resident blocks (KDET_FCL_CUDA_WARP_TASKS unset or 1), or run one warp per task on a grid
/// that covers them all (0). Read at every query, so tests and benchmarks can compare the two.
/// Both give the same candidates; benchmarks/RESULTS-gpu.md has the A/B.
bool dynamicWarpTasks() { return detail::switchKnob("KDET_FCL_CUDA_WARP_TASKS", true); }

/// Whether the warp-wide scan passes the entries of the levels above a query's own by the size
/// rule without loading their diameters (WarpQuery::size_level): KDET_FCL_CUDA_SIZE_BY_LEVEL
/// unset or 1; 0 loads and tests every entry's diameter. Read at every query, so tests and
/// benchmarks can compare the two; both give the same candidates.
bool sizeByLevel() { return detail::switchKnob("KDET_FCL_CUDA_SIZE_BY_LEVEL", true); }

/// Whether the warp-wide scan takes each level's cell range from the query's fixed-point
/// coordinates (fixedCells in device_hash.cuh; hashes of coordinates up to kFixedCoordBits bits):
/// KDET_FCL_CUDA_FIXED_CELLS unset or 1; 0 computes every level's range from the box in double.
/// Read at every query, so tests and benchmarks can compare the two; both give the same ranges.
bool fixedCellsKnob() { return detail::switchKnob("KDET_FCL_CUDA_FIXED_CELLS", true); }

/// Whether a self query's phase 1 applies the adjacency rule by vertex index only
/// (selfCandidate's by_index: the entry's indices come with its box, and the pairs that share a
/// vertex by coordinates alone are dropped by the exact kernel), for a mesh (or two hashed as
/// one) of nv vertices and nt triangles: KDET_FCL_CUDA_INDEX_ADJACENCY = 0 (never), 1 (always),
/// unset (when nv <= 1.5 nt: a mesh whose triangles share their vertices, about nt / 2 of them,
/// where few pairs share a vertex by coordinates alone; a soup of unshared vertices, 3 nt of
/// them, would pass every neighbour pair to the exact kernel). Read at every query; the pairs are
/// the same either way.
bool indexAdjacency(std::size_t nv, std::size_t nt) {
  return detail::switchKnob("KDET_FCL_CUDA_INDEX_ADJACENCY", 2 * nv <= 3 * nt);
}

/// The grid and task counter of a warp-wide candidate kernel with `tasks` warp tasks. With the
/// counter (kWarpTaskLoop<S> and dynamicWarpTasks()): no more blocks of kQueryBlock threads than
/// the device holds at once, as the occupancy calculator gives for that kernel (cached per
/// kernel; the context's mutex serialises the callers). Without: one warp per task, no counter.
/// Records the choice in the query's profile.
struct WarpScanLaunch {
  unsigned int blocks;
  unsigned long long* tasks;
};

/// At most `all` blocks of `block` threads (kQueryBlock unless given; one size per kernel): no more
/// than the device holds at once, as the occupancy calculator gives for `kernel` (cached per
/// kernel; the context's mutex serialises the callers).
template <class Kernel>
unsigned int residentBlocks(Kernel* kernel, unsigned int all, int block = kQueryBlock,
                            std::size_t dynamic_smem = 0) {
  static std::map<std::pair<int, const void*>, int> per_sm;  // (device, kernel)
  const std::pair<int, const void*> key(context().device, reinterpret_cast<const void*>(kernel));
  auto it = per_sm.find(key);
  if (it == per_sm.end()) {
    int b = 0;
    CUDA_TRY(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&b, kernel, block, dynamic_smem));
    it = per_sm.emplace(key, std::max(b, 1)).first;
  }
  return static_cast<unsigned int>(std::min<unsigned long long>(
      all, static_cast<unsigned long long>(it->second) * g_num_sms));
}

/// The grid of an exact kernel (interExactKernel, selfExactKernel: grid-stride over the
/// device-side count of the pairs the filter left): the blocks the device holds at once, at most
/// 16 per SM. More only queue behind them; with the short sums of the exact orientations in
/// registers (exact::orient3dSignShort: 192-216 per thread) the device holds 2 per SM.
template <class Kernel>
unsigned int exactBlocks(Kernel* kernel) {
  return residentBlocks(kernel, static_cast<unsigned int>(16 * g_num_sms));
}

template <class S, class Kernel>
WarpScanLaunch warpScanLaunch(Context& ctx, Kernel* kernel, unsigned long long tasks,
                              bool spans) {
  const bool dynamic = kWarpTaskLoop<S> && dynamicWarpTasks();
  ctx.profile.warp_tasks = dynamic;
  // (At least one block: a round may have no tasks.)
  const unsigned int all = std::max(1u, blocksFor(32 * tasks, kQueryBlock));
  if (!dynamic) return {all, nullptr};
  // (The slots for one lane per query: the most dynamic shared memory a launch asks for.)
  return {residentBlocks(kernel, all, kQueryBlock, warpSlotBytes(spans, 0)), ctx.warpTasks()};
}

/// Whether a self query that takes its same-level pairs from the cells runs the cells' kernel and
/// the scan of the coarser levels at the same time, so that neither kernel's tail leaves SMs idle
/// (both are grids of the resident blocks that take their tasks from a counter, so each alone
/// ends in a tail, and the second one's blocks take the SMs as the first one's leave). Only in a
/// round that runs both (Round::stage 0; the stages' rounds run one kernel each). Which kernel
/// takes the SMs first matters: measured on an H100 (benchmarks/RESULTS-gpu.md, "The cells'
/// kernel beside the scan"), phase 1 of the cloth ball took 0.172 ms with the scan first and
/// 0.212 ms with the cells' kernel first (0.225 ms one after the other), and a second stream of
/// the same priority gave either, process by process; so did a scan on a second stream of a
/// higher priority, queued first, in 2 processes of 12 (the second stream's wait for the fork
/// is not instant). So the scan runs on the query's stream, of the greatest priority, and the
/// cells' kernel on a second one of the least (Context::side), which waits for an event recorded
/// on the query's stream just before the scan, and is waited for before the plane filter. Phase 1
/// of the n-body and the 200k-1M cloths: 0.016-0.053 ms less.
/// KDET_FCL_CUDA_SELF_OVERLAP=0 runs the cells' kernel first, then the scan, on the query's
/// stream (default 1; read at every query).
bool selfOverlap() { return detail::switchKnob("KDET_FCL_CUDA_SELF_OVERLAP", true); }

/// Whether a self query takes its same-level pairs from the cells (selfCellPairsKernel) and scans
/// only the coarser levels, or scans every level from each triangle's own. With the two kernels
/// at the same time (selfOverlap(), the default), the cells are used for every mesh: measured on
/// an H100 (benchmarks/RESULTS-gpu.md, "The cells' kernel beside the scan"), the frames of the
/// funnel and its two frames took 0.010-0.041 ms less with the cells, those of the 2k-40k cloths
/// were level or less.
/// One after the other (KDET_FCL_CUDA_SELF_OVERLAP=0), only for meshes of at least 48 x 32
/// entries per SM (203k on an H100): measured so, phase 1 gained 3-16 % from the n-body (399k
/// entries) and the cloth ball (268k) up, was level on the 90k cloth (240k) and lost 2-7 % on the
/// funnel, the 20k and the 40k cloths (49k-111k), where the extra kernel and its tail cost more
/// than the lookups it saves. KDET_FCL_CUDA_SELF_CELLS = 1 or 0 forces it on or off (read at
/// every query, so tests and benchmarks can compare the two). Both give the same candidates.
/// `overlap`: the query's selfOverlap().
bool selfCellPairs(std::size_t entries, bool overlap) {
  const std::size_t large = 48 * 32 * static_cast<std::size_t>(g_num_sms);
  return detail::switchKnob("KDET_FCL_CUDA_SELF_CELLS", overlap || entries >= large);
}

/// Whether a self query's cells are many and sparse: not crowded (the candidates per triangle of
/// the mesh's last self query, as spansFor, at most 4) and 32-row tasks of selfCellPairsKernel at
/// least as many as the warps an H100-class SM holds (64 per SM): from about 270k entries on an
/// H100 or H200 (the 200k-1M cloths and the n-body scenes, not the cloth ball, the funnel or the
/// 20k-90k cloths). Such meshes take 32 rows per task (cellRows) and the spans in the cells
/// (cellSpans).
bool manySparseCells(std::size_t entries, double density) {
  const std::size_t fill = 64 * static_cast<std::size_t>(g_num_sms);
  return density <= kCrowdedDensity && entries / 32 >= fill;
}

/// Whether selfCellPairsKernel tests the sub-cell spans of a cell's pairs before their boxes
/// (and queues the pairs that pass, kQueueSeen): where the scan does (`spans`, spansFor: always
/// under the warp-wide scan, the default) and on meshes of many sparse cells (manySparseCells,
/// which matters under the tile scan or KDET_FCL_CUDA_SPANS=0). In a cell the spans are 4 bytes
/// per entry read in the cell's order, against a 24- or 48-byte box gathered per pair; on the
/// sparse cloths they pass 33-36 % of the canonical pairs, barely more than the boxes
/// (benchmarks/results/gpu-session41/cell_pairs_orders.cpp). Measured on an H200 (the first self
/// query of a frame, benchmarks/RESULTS-gpu.md, "The cells' own span filter"): phase 1 of the
/// 200k, 250k and 1M cloths 12-17 % shorter, the UNC n-body's -10 to +2 %; on the 20k-90k cloths
/// -9 to +3 % (the two funnel frames' kdet_bench frame was measured 0.04 ms longer then, but with
/// a knob set, whose check cost every query 8-34 us until it was skipped for an unchanged
/// setting: readEveryKnob). KDET_FCL_CUDA_CELL_SPANS = 1 or 0 forces it (read at every query).
bool cellSpans(bool spans, std::size_t entries, double density) {
  return detail::switchKnob("KDET_FCL_CUDA_CELL_SPANS",
                            spans || manySparseCells(entries, density));
}

/// Rows per task of selfCellPairsKernel: 32 where the 32-row tasks are at least as many as the
/// warps an H100-class SM holds (64 per SM) and the cells are not crowded (the candidates per
/// triangle of the mesh's last self query, as spansFor, at most 4), else 8. Measured on an H100
/// (benchmarks/RESULTS-gpu.md): 8 rows took the cloth ball's cell pass from 356 to 159 us (its
/// 32-row tasks in crowded cells, up to 361 entries, left a tail at 24 % occupancy) and phase 1
/// of the funnel and the 20k cloth down by 6-15 %, but the 1M cloth's cell pass (cells of at most
/// 161) from 497 to 626 us; the n-body (400k entries) and the 200k-1M cloths run faster with 32.
/// KDET_FCL_CUDA_CELL_ROWS = 1, 2, 4, 8, 16 or 32 forces it (read at every query; a divisor of
/// 32, so that a task's entries lie in the 32 cells from its block_cell).
std::uint32_t cellRows(std::size_t entries, double density) {
  const std::uint64_t forced =
      detail::choiceKnob("KDET_FCL_CUDA_CELL_ROWS", {1, 2, 4, 8, 16, 32}, 0);
  if (forced != 0) return static_cast<std::uint32_t>(forced);
  return manySparseCells(entries, density) ? 32u : 8u;
}

/// Register cap of the tile-8 candidate kernels, as blocks per SM in __launch_bounds__:
/// KDET_FCL_CUDA_MINBLOCKS = 1 (no cap, ~100 registers), 8 (default: at most 64 registers) or 12
/// (at most 40). The 40-register kernel has twice the occupancy of the 64-register one but spills
/// its loop state to local memory on every cell (ncu: 30M local requests on the cloth ball), so
/// the 64-register kernel's phase 1 was measured 15-23% faster on every scene
/// (benchmarks/RESULTS-gpu.md, "Register cap of the candidate search"); both beat the uncapped
/// kernel ("Optimization round 2"). Read at every query.
int minBlocksKnob() {
  return static_cast<int>(detail::choiceKnob("KDET_FCL_CUDA_MINBLOCKS", {1, 8, 12}, 8));
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

/// Whether the plane filter runs between the phases. Only under Predicate::Exact: its signs are
/// those of ExactKernel (filtered orient3dSign). The Float and Double kernels evaluate their
/// determinants in their own rounding, which near a plane can disagree with the certified sign,
/// and the filter must only drop pairs that the chosen kernel itself rejects.
bool usePlaneFilter(const QueryOptions& options) {
  return options.predicate == Predicate::Exact && planeFilterOn();
}

/// Register cap of the plane filter: KDET_FCL_CUDA_FILTER_MINBLOCKS = 6 (at most 40 registers,
/// ~150 B of spills) or 1 (default: uncapped, ~80 registers; the deciding filter at most 80, 3
/// blocks per SM). Read at every query. The uncapped kernel was measured faster
/// (benchmarks/RESULTS-gpu.md, "Optimization round 3").
int filterMinBlocks() {
  return static_cast<int>(detail::choiceKnob("KDET_FCL_CUDA_FILTER_MINBLOCKS", {1, 6}, 1));
}

/// KDET_FCL_CUDA_FILTER_DECIDES=0: the plane filter only drops pairs, and every other candidate
/// takes the exact kernel (default 1: the filter also finishes the pairs its filters decide).
/// Read at every query.
bool filterDecides() { return detail::switchKnob("KDET_FCL_CUDA_FILTER_DECIDES", true); }

/// KDET_FCL_CUDA_FILTER_QUEUE=0: the deciding filter finishes each pair in its own thread
/// (planeFilterKernel) instead of in full warps (default 1: planeFilterQueuedKernel). Read at
/// every query.
bool filterQueue() { return detail::switchKnob("KDET_FCL_CUDA_FILTER_QUEUE", true); }

/// Launches the plane filter (grid-stride over the device-side candidate count: 8 blocks of 256
/// threads per SM, or the queued kernel's resident blocks); a self query's pairs (self) go to
/// `out` as selfExactKernel emits them.
template <class S>
void launchPlaneFilter(cudaStream_t s, const PairSink& cand, const Vec3<S>* va,
                       const std::uint32_t* ta, const Vec3<S>* vb, const std::uint32_t* tb,
                       const PairSink& surv, const PairSink& out, bool self, std::uint32_t split,
                       int cat_shift, bool decides) {
  const auto blocks = static_cast<unsigned int>(8 * g_num_sms);
  const auto run = [&](auto kernel, unsigned int grid) {
    kernel<<<grid, kFilterBlock, 0, s>>>(PairKeys::of(cand), va, ta, vb, tb, surv, out, self,
                                         split, cat_shift);
  };
  const bool capped = filterMinBlocks() != 1;
  // The deciding filter, uncapped, took 107 registers (float); at 3 blocks per SM, 80 and no
  // spills (ptxas -v, sm_90): the dropping-only filter's occupancy.
  if (decides && filterQueue()) {
    // The resident blocks only (80 registers: 3 per SM), so that each warp takes many pairs and
    // finishes its queued ones 32 at a time (8 per SM, a warp's queue rarely filled: 43.6 µs
    // against 36.5 on the cloth ball, call 3 of results/gpu-h100-session31).
    const auto kernel = capped ? planeFilterQueuedKernel<S, 6> : planeFilterQueuedKernel<S, 3>;
    run(kernel, residentBlocks(kernel, blocks, kFilterBlock));
  } else if (decides) {
    run(capped ? planeFilterKernel<S, 6, true> : planeFilterKernel<S, 3, true>, blocks);
  } else {
    run(capped ? planeFilterKernel<S, 6, false> : planeFilterKernel<S, 1, false>, blocks);
  }
  checkLaunch();
}

/// Copies the meshes' device BuildInfo into c_info (A in 0, B in 1): stream-ordered, device to
/// device, so the candidate kernel sees the grids of re-hashes the host has not read.
template <class S>
void bindInfo(cudaStream_t s, const CachedMesh<S>& a, const CachedMesh<S>* b) {
  CUDA_TRY(cudaMemcpyToSymbolAsync(c_info, a.dinfo.data(), sizeof(BuildInfo), 0,
                                   cudaMemcpyDeviceToDevice, s));
  if (b != nullptr)
    CUDA_TRY(cudaMemcpyToSymbolAsync(c_info, b->dinfo.data(), sizeof(BuildInfo), sizeof(BuildInfo),
                                     cudaMemcpyDeviceToDevice, s));
}

/// The pending re-hashes of a query (at most two meshes): their BuildInfo rides on the pass's
/// read-back (enqueue), and check() rebuilds those that did not fit.
template <class S>
struct PendingBuilds {
  Context& ctx;
  CachedMesh<S>* m[2];
  MeshSource<S> mesh[2];
  void enqueue() {
    for (int k = 0; k < 2; ++k)
      if (m[k] != nullptr && m[k]->pending)
        CUDA_TRY(cudaMemcpyAsync(ctx.hostInfo(1 + k), m[k]->dinfo.data(), sizeof(BuildInfo),
                                 cudaMemcpyDeviceToHost, ctx.stream));
  }
  bool check() {
    bool again = false;
    for (int k = 0; k < 2; ++k)
      if (m[k] != nullptr && m[k]->pending)
        again = checkPending(ctx, *m[k], mesh[k], *ctx.hostInfo(1 + k)) || again;
    return again;
  }
  /// Whether check() will rebuild a mesh (after the infos have come back; changes nothing).
  bool rebuilds() const {
    for (int k = 0; k < 2; ++k)
      if (m[k] != nullptr && m[k]->pending && !builtInCaps(*m[k], *ctx.hostInfo(1 + k)))
        return true;
    return false;
  }
};

template <class S>
QueryResult interImpl(Context& ctx, const HashedMesh<S>& a, const HashedMesh<S>& b,
                      const QueryOptions& options, DeviceOut* dev = nullptr,
                      std::vector<TrianglePair>* keep = nullptr) {
  const std::size_t na = a.numTriangles(), nb = b.numTriangles();
  ctx.startProfile();
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
  // The rounding bound of B's boxes mapped back into A's frame is finished on the device (it
  // needs both meshes' bounds): eps = coef * (|t| + sum of both bounds' magnitudes) + DBL_MIN.
  const double eps_coef =
      rp.identity ? 0.0
                  : 16 * rp.orthonormal_defect + 64 * double(std::numeric_limits<S>::epsilon());
  const double eps_tmag =
      std::fabs(rp.a_to_b.t.x) + std::fabs(rp.a_to_b.t.y) + std::fabs(rp.a_to_b.t.z);
  const auto una = static_cast<std::uint32_t>(na), unb = static_cast<std::uint32_t>(nb);
  const bool filter = usePlaneFilter(options);
  const bool decides = filter && filterDecides();
  ctx.profile.filter_decides = decides;
  const bool warp = warpScan();
  const bool spans = spansFor(std::max(A.inter_density, B.inter_density), warp);
  const bool size_by_level = warp && sizeByLevel();
  const bool fixed_cells = warp && fixedCellsKnob();
  ctx.profile.spans = spans;
  ctx.profile.warp_scan = warp;
  ctx.profile.size_by_level = size_by_level;
  ctx.profile.fixed_cells = fixedCells(fixed_cells, A.info) && fixedCells(fixed_cells, B.info);
  auto launch = [&](PairSink cand, PairSink surv, PairSink out, Round round) {
    // Views and grids are taken at every pass: a failed re-hash rebuilds between passes.
    const HashView<S> av = A.view(), bv = B.view();
    ctx.profile.cells_by_size = A.size_ordered && B.size_ordered;
    bindInfo(s, A, &B);
    if (warp) {
      const unsigned int log_p =
          warpLanesLog2(na + nb, std::max(A.inter_density, B.inter_density));
      ctx.profile.warp_lanes = 1 << log_p;
      const unsigned long long per_warp = 32u >> log_p;
      const unsigned long long warps =
          (na + per_warp - 1) / per_warp + (nb + per_warp - 1) / per_warp;
      const auto kernel = spans ? interCandidatesWarpKernel<S, 8, true>
                                : interCandidatesWarpKernel<S, 8, false>;
      const WarpScanLaunch wl =
          warpScanLaunch<S>(ctx, kernel, roundTasks(warps, round), spans);
      kernel<<<wl.blocks, kQueryBlock, warpSlotBytes(spans, log_p), s>>>(
          av, bv, va, una, unb, rp.identity, rp.b_to_a, eps_coef, eps_tmag, log_p, warpVisit(),
          size_by_level, fixed_cells, round, cand, wl.tasks);
    } else {
      withTile([&](auto g, auto mb) {
        constexpr int G = decltype(g)::value;
        constexpr int MB = decltype(mb)::value;
        const auto kernel = spans ? interCandidatesKernel<S, G, MB, true>
                                  : interCandidatesKernel<S, G, MB, false>;
        kernel<<<std::max(1u, blocksFor(G * roundTasks(na + nb, round), kQueryBlock)),
                 kQueryBlock, 0, s>>>(
            av, bv, va, una, unb, rp.identity, rp.b_to_a, eps_coef, eps_tmag, A.size_ordered,
            B.size_ordered, round, cand);
      });
    }
    checkLaunch();
    ctx.markRound(round.serial, 1);
    PairSink in = cand;
    if (filter) {
      launchPlaneFilter<S>(s, cand, va, av.t, bv.v, bv.t, surv, out, false, 0, 0, decides);
      in = surv;
    }
    ctx.markRound(round.serial, 2);
    withPredicate(options.predicate, [&](auto k) {
      using K = decltype(k);
      interExactKernel<S, K><<<exactBlocks(interExactKernel<S, K>), kQueryBlock, 0, s>>>(
          PairKeys::of(in), va, av.t, bv.v, bv.t, out);
    });
    return filter;
  };
  PendingBuilds<S> pending{ctx, {&A, &B == &A ? nullptr : &B},
                           {sourceOf(&a), sourceOf(&b)}};
  if (A.inter_partner != B.identity) {
    A.inter_partner = B.identity;
    A.inter_host_pairs = 0;
  }
  QueryResult res = runQuery(ctx, launch, pending, bitsFor(na), bitsFor(nb), na + nb,
                             std::max(A.inter_density, B.inter_density), 0.0, false, options,
                             &A.inter_host_pairs, 0, nullptr, dev, keep);
  A.inter_density = B.inter_density = double(ctx.profile.candidates) / double(na + nb);
  return res;
}

/// The self query of the cache entry M (its event 0 recorded before M was acquired): the pairs of
/// one mesh, or (split > 0, `parts`) of two meshes hashed as one, dealt out by runQuery.
template <class S>
QueryResult selfQuery(Context& ctx, CachedMesh<S>& M, const MeshSource<S>& src,
                      std::uint32_t split, QueryResult* parts, const QueryOptions& options,
                      DeviceOut* dev = nullptr, std::vector<TrianglePair>* keep = nullptr) {
  const std::size_t n = M.nt;
  ctx.record(1);
  const cudaStream_t s = ctx.stream;
  const auto un = static_cast<std::uint32_t>(n);
  const bool filter = usePlaneFilter(options);
  const bool decides = filter && filterDecides();
  ctx.profile.filter_decides = decides;
  const bool warp = warpScan();
  const bool spans = spansFor(M.self_density, warp);
  // (The entry count of the last build that read it back: an estimate after a re-hash.)
  const bool beside = selfOverlap();
  const bool cell_pairs = selfCellPairs(M.info.entries, beside);
  const int level_skip = cell_pairs ? 1 : 0;
  const bool size_by_level = warp && sizeByLevel();
  const bool fixed_cells = warp && fixedCellsKnob();
  const bool by_index = indexAdjacency(M.nv, n);
  const bool cell_spans = cell_pairs && cellSpans(spans, M.info.entries, M.self_density);
  ctx.profile.cell_spans = cell_spans;
  ctx.profile.spans = spans;
  ctx.profile.warp_scan = warp;
  ctx.profile.size_by_level = size_by_level;
  ctx.profile.fixed_cells = fixedCells(fixed_cells, M.info);
  ctx.profile.index_adjacency = by_index;
  ctx.profile.self_cell_pairs = cell_pairs;
  const bool overlap = cell_pairs && beside;
  auto launch = [&](PairSink cand, PairSink surv, PairSink out, Round round) {
    const HashView<S> mv = M.view();
    ctx.profile.cells_by_size = M.size_ordered;
    bindInfo<S>(s, M, nullptr);
    // The pairs within a level, from the cells, on stream `on`.
    auto cells = [&](cudaStream_t on) {
      const auto kernel =
          cell_spans ? selfCellPairsKernel<S, true> : selfCellPairsKernel<S, false>;
      const std::uint32_t rows = cellRows(M.info.entries, M.self_density);
      ctx.profile.cell_rows = static_cast<int>(rows);
      const unsigned int blocks = residentBlocks(
          kernel, blocksFor(32 * ((std::size_t(M.entry_cap) + rows - 1) / rows), kQueryBlock));
      kernel<<<blocks, kQueryBlock, 0, on>>>(mv, M.block_cell.data(),
                                             M.pending ? M.pending_cell_cap : M.cell_cap, rows,
                                             warpVisit(), by_index, split, round, cand,
                                             ctx.cellTasks(), ctx.pair_count.data() + kCellCands);
      checkLaunch();
    };
    // The scan from each triangle's level (level_skip), on stream `on`.
    auto scan = [&](cudaStream_t on) {
      if (warp) {
        const auto kernel =
            spans ? selfCandidatesWarpKernel<S, 8, true> : selfCandidatesWarpKernel<S, 8, false>;
        const unsigned int log_p = warpLanesLog2(n, M.self_density);
        ctx.profile.warp_lanes = 1 << log_p;
        const unsigned long long warps = (n + (32u >> log_p) - 1) / (32u >> log_p);
        const WarpScanLaunch wl =
            warpScanLaunch<S>(ctx, kernel, roundTasks(warps, round), spans);
        kernel<<<wl.blocks, kQueryBlock, warpSlotBytes(spans, log_p), on>>>(
            mv, un, log_p, warpVisit(), level_skip, size_by_level, by_index, fixed_cells, split,
            round, cand, wl.tasks);
      } else {
        withTile([&](auto g, auto mb) {
          constexpr int G = decltype(g)::value;
          constexpr int MB = decltype(mb)::value;
          const auto kernel =
              spans ? selfCandidatesKernel<S, G, MB, true> : selfCandidatesKernel<S, G, MB, false>;
          kernel<<<std::max(1u, blocksFor(G * roundTasks(n, round), kQueryBlock)), kQueryBlock,
                   0, on>>>(mv, un, M.size_ordered, level_skip, by_index, split, round, cand);
        });
      }
      checkLaunch();
    };
    if (overlap && round.stage == 0) {  // both in this round, at the same time (selfOverlap)
      ctx.profile.self_overlap = true;
      const cudaStream_t side = ctx.forkSide();
      scan(s);
      cells(side);
      ctx.joinSide();
    } else {
      if (cell_pairs && round.stage != 2) cells(s);
      if (round.stage != 1) scan(s);  // (stage 1: only the cells' pairs in this round)
    }
    ctx.markRound(round.serial, 1);
    PairSink in = cand;
    if (filter) {
      launchPlaneFilter<S>(s, cand, mv.v, mv.t, mv.v, mv.t, surv, out, true, split, bitsFor(n),
                           decides);
      in = surv;
    }
    ctx.markRound(round.serial, 2);
    withPredicate(options.predicate, [&](auto k) {
      using K = decltype(k);
      selfExactKernel<S, K><<<exactBlocks(selfExactKernel<S, K>), kQueryBlock, 0, s>>>(
          PairKeys::of(in), mv.v, mv.t, split, bitsFor(n), out);
    });
    return filter;
  };
  PendingBuilds<S> pending{ctx, {&M, nullptr}, {src, MeshSource<S>{}}};
  QueryResult res = runQuery(ctx, launch, pending, bitsFor(n), bitsFor(n), n, M.self_density,
                             M.self_cell_share, cell_pairs, options, &M.self_host_pairs, split,
                             parts, dev, keep);
  M.self_density = double(ctx.profile.candidates) / double(n);
  M.self_cell_share = ctx.profile.candidates > 0 ? double(ctx.profile.cell_candidates) /
                                                       double(ctx.profile.candidates)
                                                 : 0.0;
  return res;
}

/// Host pairs into the caller's device buffer (as many as fit), as runQuery leaves a query's
/// own: dev->count is how many there are, and the copy is done when this returns.
void copyToDevice(Context& ctx, const std::vector<TrianglePair>& pairs, DeviceOut* dev) {
  dev->count = pairs.size();
  const std::size_t give = std::min(pairs.size(), dev->capacity);
  if (give == 0) return;
  CUDA_TRY(cudaMemcpyAsync(dev->ptr, pairs.data(), give * sizeof(TrianglePair),
                           cudaMemcpyHostToDevice, ctx.stream));
  CUDA_TRY(cudaStreamSynchronize(ctx.stream));
}

/// The self query (`keep`: storage for the pairs that the caller keeps across frames, as
/// runQuery's).
template <class S>
QueryResult selfImpl(Context& ctx, const HashedMesh<S>& mesh, const QueryOptions& options,
                     DeviceOut* dev = nullptr, std::vector<TrianglePair>* keep = nullptr) {
  const std::size_t n = mesh.numTriangles();
  ctx.startProfile();
  if (n < 2) return QueryResult{};
  ctx.record(0);
  CachedMesh<S>& M = acquire(ctx, mesh);
  // One kept result (host pairs) answers both forms. With `dev`, a kept result is copied into
  // the caller's buffer; the query that keeps one reads its pairs back once and copies them
  // there; any other runs straight into the buffer.
  detail::KeptSelfResult::Ticket ticket;
  QueryResult kept;
  if (keep != nullptr) kept.pairs = std::move(*keep);  // (a kept result is copied into it)
  if (M.kept_self.find(M.builds, options, &kept, &ticket)) {
    ctx.profile = QueryProfile{};  // nothing ran on the device but this copy
    ctx.profile.self_cached = true;
    ctx.profile.pairs = kept.pairs.size();
    if (dev != nullptr) copyToDevice(ctx, kept.pairs, dev);
    return kept;
  }
  if (dev != nullptr && !ticket.keep)
    return selfQuery(ctx, M, sourceOf(&mesh), 0, nullptr, options, dev);
  QueryResult res = selfQuery(ctx, M, sourceOf(&mesh), 0, nullptr, options, nullptr,
                              keep != nullptr ? &kept.pairs : nullptr);
  M.kept_self.offer(ticket, options, res);
  if (dev != nullptr) copyToDevice(ctx, res.pairs, dev);
  return res;
}

/// Both meshes hashed as one (their own cache entry): one build, one self query whose pairs
/// across the two meshes are the inter-object pairs, dealt out to `parts` or left in `dev`
/// (runQuery).
template <class S>
void jointQuery(Context& ctx, const HashedMesh<S>& a, const HashedMesh<S>& b,
                const QueryOptions& options, QueryResult* parts, DeviceOut* dev) {
  ctx.startProfile();
  ctx.record(0);
  CachedMesh<S>& M = acquire(ctx, a, &b);
  selfQuery(ctx, M, sourceOf(&a, &b), static_cast<std::uint32_t>(a.numTriangles()), parts,
            options, dev);
  ctx.profile.joint = true;
}

/// intersectAll with both meshes hashed as one (see cuda::intersectJoint), into `out`, whose
/// pairs' storage is reused (runQuery's parts).
template <class S>
void jointImpl(Context& ctx, const HashedMesh<S>& a, const HashedMesh<S>& b,
               const QueryOptions& options, AllPairsResult* out) {
  QueryResult* const results[3] = {&out->self_a, &out->self_b, &out->inter};
  QueryResult parts[3];
  for (int k = 0; k < 3; ++k) parts[k].pairs = std::move(results[k]->pairs);
  jointQuery(ctx, a, b, options, parts, nullptr);
  for (int k = 0; k < 3; ++k) *results[k] = std::move(parts[k]);
}

/// jointImpl with the pairs left in the caller's device buffer: the first mesh's own pairs, then
/// the second's, then those across, one run after another (as many as fit).
template <class S>
AllDevicePairsResult jointOnDeviceImpl(Context& ctx, const HashedMesh<S>& a,
                                       const HashedMesh<S>& b, const QueryOptions& options,
                                       DeviceOut* dev) {
  jointQuery(ctx, a, b, options, nullptr, dev);
  AllDevicePairsResult r;  // (every pair is asked for: each result is complete)
  r.self_b.count = dev->kinds[0];
  r.inter.count = dev->kinds[1];
  r.self_a.count = dev->count - dev->kinds[0] - dev->kinds[1];
  return r;
}

/// KDET_FCL_CUDA_JOINT=0 runs the three queries of intersectAll instead of one joint query
/// (read at every call).
bool jointOn() { return detail::switchKnob("KDET_FCL_CUDA_JOINT", true); }

/// KDET_FCL_CUDA_COMMIT_COPY=0 turns off commitVertices' copy of the positions while it checks
/// them (startCommitCopy; default on). Read at every commit; any value but 0 or 1 fails the next
/// query (checkKnobs).
bool commitCopyOn() { return detail::switchKnob("KDET_FCL_CUDA_COMMIT_COPY", true); }

/// The batch of commitVertices' copy (CommitCopy::batchBytes): KDET_FCL_CUDA_COMMIT_BATCH=b
/// (4096 bytes to 1 GiB; read at every commit, checked at every query), else
/// detail::kCommitBatchBytes.
std::size_t commitBatch() {
  return static_cast<std::size_t>(detail::numberKnob("KDET_FCL_CUDA_COMMIT_BATCH", 4096,
                                                     std::uint64_t(1) << 30,
                                                     detail::kCommitBatchBytes));
}

/// Reads every knob of the CUDA backend once, so that a value a knob does not accept throws
/// InvalidInputError (naming the variable) before a query enqueues any work, not half-way
/// through it. Each knob is read through the function that the query itself uses. With no
/// KDET_FCL_CUDA_* variable set (a user's usual case) it returns after one pass over the
/// environment (0.14 us here). With some set, it reads them all only when their setting (every
/// KDET_FCL_CUDA_* entry, names and values) differs from the last one it read without an error.
/// Reading them all every time had added 8-34 us to each query's host time on an H200
/// machine's host (benchmarks/results/gpu-session42, call 1), and so had made every knob's A/B
/// in kdet_bench's host-timed frames look that much slower than the defaults; an unchanged
/// setting now costs 0.75 us there (a full read 4.2 us).
void readEveryKnob() {
  if (!detail::someKnobSet("KDET_FCL_CUDA_")) return;
  static std::mutex checked_mutex;
  static std::string checked;  // the setting last read in full without an error
  std::string setting;
  const bool listed = detail::appendKnobEntries("KDET_FCL_CUDA_", setting);
  if (listed) {
    std::lock_guard<std::mutex> lock(checked_mutex);
    if (setting == checked) return;
  }
  (void)deviceKnob();
  (void)syncRehash();
  (void)fullKeys();
  (void)rehashCap(1);
  (void)rehashGraphOn();
  (void)countBuildOn(0);
  (void)cellGroupAxis();
  (void)staging::pinVerticesOn();
  (void)commitCopyOn();
  (void)commitBatch();
  (void)upperLevelsFor(0);
  (void)capacityKnob();
  (void)planeFilterOn();
  (void)filterDecides();
  (void)filterQueue();
  (void)countOrderAllowed();
  (void)oneTripOn();
  (void)oneTripCopyChunks();
  (void)oneTripForecastOn();
  (void)fusedOrderBlocks();
  (void)segmentMax();
  (void)segmentBits();
  (void)roundCandidateLimit(1, 8);
  (void)tileSize();
  (void)spansFor(0, false);
  (void)warpScan();
  (void)warpLanesLog2(1, 0);
  (void)warpVisit();
  (void)dynamicWarpTasks();
  (void)sizeByLevel();
  (void)fixedCellsKnob();
  (void)stagedPairs();
  (void)packedCandidates();
  (void)indexAdjacency(0, 0);
  (void)selfCellPairs(0, false);
  (void)selfOverlap();
  (void)cellRows(0, 0);
  (void)cellSpans(false, 0, 0);
  (void)minBlocksKnob();
  (void)filterMinBlocks();
  (void)jointOn();
  (void)detail::KeptSelfResult::on(kSelfCacheKnob);
  (void)staging::uploadChunk();
  (void)staging::downloadChunk();
  (void)staging::uploadThreads(1);
  (void)staging::downloadThreads(1);
  if (listed) {
    std::lock_guard<std::mutex> lock(checked_mutex);
    checked = std::move(setting);
  }
}

/// Serialises, initialises, and on a CUDA error drops every device buffer before rethrowing.
template <class F>
auto guarded(F&& f) -> decltype(f(std::declval<Context&>())) {
  readEveryKnob();
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  const DeviceScope scope(ctx.chosen());
  try {
    ctx.init();
    if (g_num_sms == 0)
      CUDA_TRY(cudaDeviceGetAttribute(&g_num_sms, cudaDevAttrMultiProcessorCount, ctx.device));
    auto r = f(ctx);
    evict<float>(ctx);
    evict<double>(ctx);
    return r;
  } catch (const CudaError&) {
    // Nothing enqueued may still read a host buffer once the query has thrown (a vertex upload
    // from a mesh's own pinned buffer, or from the stage).
    (void)cudaStreamSynchronize(ctx.stream);
    ctx.releaseAll();
    throw;
  } catch (...) {
    (void)cudaStreamSynchronize(ctx.stream);
    // A non-CUDA failure (bad input, bad_alloc) may have left a half-built entry: drop those.
    ctx.meshes_f.remove_if([](const CachedMesh<float>& m) { return !m.valid; });
    ctx.meshes_d.remove_if([](const CachedMesh<double>& m) { return !m.valid; });
    throw;
  }
}

/// Throws InvalidInputError unless the caller's pair buffer (of `capacity` pairs, > 0) is memory
/// that the query's kernels may write on the backend's device `device`: cudaMalloc'd or managed,
/// and 8-byte aligned (unpackPairsKernel stores each pair as one uint2). Its size cannot be
/// checked: the caller vouches for `capacity`, as for any CUDA copy.
void checkDevicePairs(const TrianglePair* out, std::size_t capacity, int device) {
  if (capacity == 0) return;
  if (reinterpret_cast<std::uintptr_t>(out) % alignof(uint2) != 0)
    throw InvalidInputError("the device pair buffer is not 8-byte aligned (cudaMalloc's is)");
  cudaPointerAttributes at{};
  const cudaError_t e = cudaPointerGetAttributes(&at, out);
  if (e != cudaSuccess) {
    (void)cudaGetLastError();  // not sticky: clear it
    throw InvalidInputError(std::string("the device pair buffer is not a pointer CUDA knows (") +
                            cudaGetErrorString(e) + ")");
  }
  if (at.type != cudaMemoryTypeDevice && at.type != cudaMemoryTypeManaged)
    throw InvalidInputError(
        "the device pair buffer is not device memory (use cudaMalloc or cudaMallocManaged on "
        "CUDA device " + std::to_string(device) + "; host memory takes intersectSelf/intersectMeshes)");
  // (Managed memory is any device's.)
  if (at.type == cudaMemoryTypeDevice && at.device != device)
    throw InvalidInputError("the device pair buffer is memory of CUDA device " +
                            std::to_string(at.device) + ", but the backend runs on device " +
                            std::to_string(device) + " (setCudaDevice, KDET_FCL_CUDA_DEVICE)");
}

/// A query into the caller's device buffer: the buffer checked, then `run(ctx, &dev)`.
template <class Run>
auto intoDevice(TrianglePair* out, std::size_t capacity, Run&& run) {
  return guarded([&](Context& ctx) {
    checkDevicePairs(out, capacity, ctx.device);
    DeviceOut dev{out, capacity, 0, {0, 0}};
    return run(ctx, &dev);
  });
}

/// A single *OnDevice query (intoDevice): its count, completeness and keeping.
template <class Run>
DevicePairsResult onDevice(TrianglePair* out, std::size_t capacity, Run&& run) {
  return intoDevice(out, capacity, [&](Context& ctx, DeviceOut* dev) {
    const QueryResult r = run(ctx, dev);
    DevicePairsResult res;
    res.count = dev->count;
    res.complete = r.complete;
    res.kept = r.kept;
    return res;
  });
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

template <class S>
void intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b,
                     const QueryOptions& options, QueryResult& out) {
  out = guarded([&](Context& ctx) { return interImpl(ctx, a, b, options, nullptr, &out.pairs); });
}

template <class S>
void intersectSelf(const HashedMesh<S>& mesh, const QueryOptions& options, QueryResult& out) {
  out = guarded([&](Context& ctx) { return selfImpl(ctx, mesh, options, nullptr, &out.pairs); });
}

template <class S>
DevicePairsResult intersectSelfOnDevice(const HashedMesh<S>& mesh, const QueryOptions& options,
                                        TrianglePair* out, std::size_t capacity) {
  return onDevice(out, capacity, [&](Context& ctx, DeviceOut* dev) {
    return selfImpl(ctx, mesh, options, dev);
  });
}

template <class S>
DevicePairsResult intersectMeshesOnDevice(const HashedMesh<S>& a, const HashedMesh<S>& b,
                                          const QueryOptions& options, TrianglePair* out,
                                          std::size_t capacity) {
  return onDevice(out, capacity, [&](Context& ctx, DeviceOut* dev) {
    return interImpl(ctx, a, b, options, dev);
  });
}

namespace {
/// Whether one hash for both meshes gives exactly the three queries' pairs: the inter query
/// would decide on both meshes' own coordinates (poses that map one frame onto the other
/// exactly), every pair is asked for, and both meshes have triangles (which fit in one entry
/// together); and KDET_FCL_CUDA_JOINT is not 0.
template <class S>
bool jointApplies(const HashedMesh<S>& a, const HashedMesh<S>& b, const QueryOptions& options) {
  return options.max_pairs == 0 && a.numTriangles() > 0 && b.numTriangles() > 0 &&
         a.numTriangles() + b.numTriangles() <= kMaxDeviceTriangles &&
         detail::relativePose(a.pose(), b.pose()).identity && jointOn();
}
}  // namespace

template <class S>
bool intersectJoint(const HashedMesh<S>& a, const HashedMesh<S>& b, const QueryOptions& options,
                    AllPairsResult* out) {
  if (!jointApplies(a, b, options)) return false;
  guarded([&](Context& ctx) {
    jointImpl(ctx, a, b, options, out);
    return 0;
  });
  return true;
}

template <class S>
bool intersectJointOnDevice(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options, TrianglePair* out, std::size_t capacity,
                            AllDevicePairsResult* result) {
  if (!jointApplies(a, b, options)) return false;
  *result = intoDevice(out, capacity, [&](Context& ctx, DeviceOut* dev) {
    return jointOnDeviceImpl(ctx, a, b, options, dev);
  });
  return true;
}


void checkKnobs() { readEveryKnob(); }

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
    if (m.owner == &mesh || m.owner2 == &mesh) m.force_vertices = true;
}

namespace {
/// startCommitCopy's copy: holds the backend (the context's lock) from the start of the check to
/// finish(), and enqueues each checked range of the buffer on the context's stream into the
/// entry's vertex array (staging::pinnedUploadRange: the registered pages straight, the partial
/// pages at the buffer's ends through the entry's stage).
template <class S>
class DeviceCommitCopy final : public detail::CommitCopy {
 public:
  DeviceCommitCopy(std::unique_lock<std::mutex> lock, Context& ctx, CachedMesh<S>& m,
                   const void* buffer, std::size_t bytes, std::size_t batch)
      : lock_(std::move(lock)), ctx_(ctx), m_(m), src_(buffer), bytes_(bytes), batch_(batch) {}
  DeviceCommitCopy(const DeviceCommitCopy&) = delete;
  DeviceCommitCopy& operator=(const DeviceCommitCopy&) = delete;
  ~DeviceCommitCopy() override { finish(false, 0); }

  void piece(std::size_t offset, std::size_t bytes) noexcept override {
    if (failed_ || offset != copied_ || bytes > bytes_ - offset) {
      failed_ = true;  // not the next range: left to the query
      return;
    }
    // (Called on the committing threads, the caller's among them: their own contexts stay.)
    cudaError_t entered = cudaSuccess;
    const DeviceScope scope(ctx_.device, &entered);
    if (entered != cudaSuccess) {
      failed_ = true;
      return;
    }
    if (staging::pinnedUploadRange(m_.v.data(), src_, bytes_, offset, offset + bytes,
                                   m_.staging.data(), ctx_.stream) != cudaSuccess) {
      (void)cudaGetLastError();
      failed_ = true;
      return;
    }
    copied_ += bytes;
  }

  std::size_t batchBytes() const noexcept override { return batch_; }

  void finish(bool ok, std::uint64_t version) noexcept override {
    if (finished_) return;
    finished_ = true;
    // Every copy enqueued reads the buffer (or the stage): none may run after the commit.
    cudaError_t entered = cudaSuccess;
    const DeviceScope scope(ctx_.device, &entered);
    if (entered != cudaSuccess || cudaStreamSynchronize(ctx_.stream) != cudaSuccess) {
      (void)cudaGetLastError();  // a sticky error fails the next query, which drops everything
      failed_ = true;
    }
    if (ok && !failed_ && copied_ == bytes_) {
      m_.commit_version = version;
    } else {
      m_.commit_version = 0;
      // Positions of neither version: the next query uploads the mesh's own again, even where
      // the refused commit left its version as it was.
      if (copied_ > 0 || failed_) m_.force_vertices = true;
    }
    lock_.unlock();
  }

 private:
  std::unique_lock<std::mutex> lock_;
  Context& ctx_;
  CachedMesh<S>& m_;
  const void* src_;
  std::size_t bytes_;
  std::size_t batch_;
  std::size_t copied_ = 0;  // the bytes enqueued, from offset 0
  bool failed_ = false;
  bool finished_ = false;
};
}  // namespace

template <class S>
std::unique_ptr<detail::CommitCopy> startCommitCopy(const HashedMesh<S>& mesh, const void* buffer,
                                                    std::size_t bytes,
                                                    const detail::HostPin& pin) {
  if (bytes < kCommitCopyMinBytes || !pin.pinned() || pin.at() != buffer) return nullptr;
  std::size_t batch = 0;
  try {
    if (!commitCopyOn()) return nullptr;
    batch = commitBatch();
  } catch (const InvalidInputError&) {
    return nullptr;  // the next query reports the value
  }
  Context& ctx = context();
  std::unique_lock<std::mutex> lock(ctx.mutex, std::try_to_lock);
  if (!lock.owns_lock() || !ctx.ready) return nullptr;
  for (CachedMesh<S>& m : ctx.meshes(static_cast<S*>(nullptr))) {
    if (m.owner != &mesh || m.owner2 != nullptr) continue;
    if (!m.valid || m.pending || m.nv != mesh.numVertices() || m.nv * sizeof(Vec3<S>) != bytes)
      return nullptr;
    try {
      const DeviceScope scope(ctx.device);
      m.staging.reserve(bytes);  // (held already: the entry's uploads went through it)
    } catch (const CudaError&) {
      return nullptr;  // the next query meets the error
    }
    return std::unique_ptr<detail::CommitCopy>(
        new DeviceCommitCopy<S>(std::move(lock), ctx, m, buffer, bytes, batch));
  }
  return nullptr;
}

/// Whether `m` is `mesh`'s own entry (the mesh alone, not an entry another mesh left at its
/// address) with a build whose sizes are known (valid, not pending a check): the entries the
/// test hooks below read.
template <class S>
bool settledEntryOf(const CachedMesh<S>& m, const HashedMesh<S>& mesh) {
  return m.owner == &mesh && m.owner2 == nullptr && m.identity == mesh.identity() && m.valid &&
         !m.pending;
}

template <class S>
std::vector<std::uint16_t> upperLevels(const HashedMesh<S>& mesh) {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  if (!ctx.ready) return {};
  const DeviceScope scope(ctx.device);
  for (auto& m : ctx.meshes(static_cast<S*>(nullptr))) {
    if (!settledEntryOf(m, mesh) || !m.upper_ready) continue;
    std::vector<std::uint32_t> words(upperWords(m.nt));
    CUDA_TRY(cudaMemcpyAsync(words.data(), m.upper.data(), words.size() * sizeof(std::uint32_t),
                             cudaMemcpyDeviceToHost, ctx.stream));
    CUDA_TRY(cudaStreamSynchronize(ctx.stream));
    std::vector<std::uint16_t> bits(m.nt);
    for (std::size_t i = 0; i < m.nt; ++i)
      bits[i] = static_cast<std::uint16_t>(words[i / 2] >> (16 * (i % 2)));
    return bits;
  }
  return {};
}

template <class S>
CellLayout cellLayout(const HashedMesh<S>& mesh) {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  CellLayout out;
  if (!ctx.ready) return out;
  const DeviceScope scope(ctx.device);
  for (auto& m : ctx.meshes(static_cast<S*>(nullptr))) {
    if (!settledEntryOf(m, mesh)) continue;
    BuildInfo info;
    CUDA_TRY(cudaMemcpyAsync(&info, m.dinfo.data(), sizeof(BuildInfo), cudaMemcpyDeviceToHost,
                             ctx.stream));
    CUDA_TRY(cudaStreamSynchronize(ctx.stream));
    if (info.need_sync || info.cells > m.cell_cap || info.entries > m.entry_cap) return out;
    const std::size_t cells = info.cells, entries = info.entries;
    out.cell_begin.resize(cells + 1);
    out.entry_span.resize(entries);
    std::vector<uint2> split(info.group_axis < kNoCellGroups ? cells : 0);
    CUDA_TRY(cudaMemcpyAsync(out.cell_begin.data(), m.cell_begin.data(),
                             (cells + 1) * sizeof(std::uint32_t), cudaMemcpyDeviceToHost,
                             ctx.stream));
    CUDA_TRY(cudaMemcpyAsync(out.entry_span.data(), m.entry_span.data(),
                             entries * sizeof(std::uint32_t), cudaMemcpyDeviceToHost, ctx.stream));
    if (!split.empty())
      CUDA_TRY(cudaMemcpyAsync(split.data(), m.cell_split.data(), cells * sizeof(uint2),
                               cudaMemcpyDeviceToHost, ctx.stream));
    CUDA_TRY(cudaStreamSynchronize(ctx.stream));
    out.axis = info.group_axis;
    for (const uint2& g : split) out.split.emplace_back(g.x, g.y);
    return out;
  }
  return out;
}

std::string deviceMemoryReport() {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  std::string r;
  auto add = [&](const char* name, std::size_t b) {
    if (b == 0) return;
    if (!r.empty()) r += ", ";
    r += std::string(name) + " " + std::to_string(b);
  };
  std::size_t mesh[11] = {};
  auto meshes = [&](const auto& list) {
    for (const auto& m : list) {
      mesh[0] += m.v.bytes();
      mesh[1] += m.t.bytes();
      mesh[2] += m.box.bytes();
      mesh[3] += m.diam.bytes();
      mesh[4] += m.level.bytes();
      mesh[5] += m.entry_tri.bytes() + m.entry_span.bytes() + m.block_cell.bytes();
      mesh[6] += m.cell_begin.bytes() + m.cell_split.bytes();
      mesh[7] += m.cell_key.bytes();
      mesh[8] += m.slots.bytes();
      mesh[9] += m.dinfo.bytes();
      mesh[10] += m.upper.bytes();
    }
  };
  meshes(ctx.meshes_f);
  meshes(ctx.meshes_d);
  const char* mesh_names[11] = {"v", "t", "box", "diam", "level", "entries", "cell_begin",
                                "cell_key", "slots", "info", "upper"};
  for (int k = 0; k < 11; ++k) add(mesh_names[k], mesh[k]);
  add("cub_temp", ctx.cub_temp.bytes());
  add("mapped", ctx.mapped_f.bytes() + ctx.mapped_d.bytes());
  add("cands (+ build sort scratch)", ctx.cands.bytes());
  add("pairs (+ build counts)", ctx.pairs.bytes());
  add("pairs_sorted/survivors (+ build size sort)", ctx.pairs_sorted.bytes());
  add("segs", ctx.segs.bytes());
  return r;
}

std::size_t deviceBytesInUse() {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  return ctx.bytes();
}

void releaseDeviceMemory() {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  if (!ctx.ready) return ctx.releaseAll();  // (holds nothing on a device)
  // Where the device cannot be made current, this thread frees (cudaFree takes any pointer).
  cudaError_t entered = cudaSuccess;
  const DeviceScope scope(ctx.device, &entered);
  ctx.releaseAll();
}

void setDevice(int device) {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  checkDeviceOrdinal(device, "setCudaDevice(" + std::to_string(device) + ")");
  if (ctx.device == device) return;
  if (ctx.ready) {
    // Everything on the old device goes: the next call initialises on the new one, and each
    // mesh is uploaded and hashed there again by its next query (on the old device where it can
    // be made current, else from this thread, as releaseDeviceMemory).
    cudaError_t entered = cudaSuccess;
    const DeviceScope scope(ctx.device, &entered);
    ctx.teardown();
    g_num_sms = 0;
  }
  ctx.device = device;
}

int currentDevice() {
  Context& ctx = context();
  std::lock_guard<std::mutex> lock(ctx.mutex);
  return ctx.chosen();
}

template QueryResult intersectMeshes(const HashedMesh<float>&, const HashedMesh<float>&,
                                     const QueryOptions&);
template QueryResult intersectMeshes(const HashedMesh<double>&, const HashedMesh<double>&,
                                     const QueryOptions&);
template QueryResult intersectSelf(const HashedMesh<float>&, const QueryOptions&);
template QueryResult intersectSelf(const HashedMesh<double>&, const QueryOptions&);
template void intersectMeshes(const HashedMesh<float>&, const HashedMesh<float>&,
                              const QueryOptions&, QueryResult&);
template void intersectMeshes(const HashedMesh<double>&, const HashedMesh<double>&,
                              const QueryOptions&, QueryResult&);
template void intersectSelf(const HashedMesh<float>&, const QueryOptions&, QueryResult&);
template void intersectSelf(const HashedMesh<double>&, const QueryOptions&, QueryResult&);
template DevicePairsResult intersectSelfOnDevice(const HashedMesh<float>&, const QueryOptions&,
                                                 TrianglePair*, std::size_t);
template DevicePairsResult intersectSelfOnDevice(const HashedMesh<double>&, const QueryOptions&,
                                                 TrianglePair*, std::size_t);
template DevicePairsResult intersectMeshesOnDevice(const HashedMesh<float>&,
                                                   const HashedMesh<float>&, const QueryOptions&,
                                                   TrianglePair*, std::size_t);
template DevicePairsResult intersectMeshesOnDevice(const HashedMesh<double>&,
                                                   const HashedMesh<double>&, const QueryOptions&,
                                                   TrianglePair*, std::size_t);
template bool intersectJointOnDevice(const HashedMesh<float>&, const HashedMesh<float>&,
                                     const QueryOptions&, TrianglePair*, std::size_t,
                                     AllDevicePairsResult*);
template bool intersectJointOnDevice(const HashedMesh<double>&, const HashedMesh<double>&,
                                     const QueryOptions&, TrianglePair*, std::size_t,
                                     AllDevicePairsResult*);
template bool intersectJoint(const HashedMesh<float>&, const HashedMesh<float>&,
                             const QueryOptions&, AllPairsResult*);
template bool intersectJoint(const HashedMesh<double>&, const HashedMesh<double>&,
                             const QueryOptions&, AllPairsResult*);
template void markDeformed(const HashedMesh<float>&);
template void markDeformed(const HashedMesh<double>&);
template std::unique_ptr<detail::CommitCopy> startCommitCopy(const HashedMesh<float>&,
                                                             const void*, std::size_t,
                                                             const detail::HostPin&);
template std::unique_ptr<detail::CommitCopy> startCommitCopy(const HashedMesh<double>&,
                                                             const void*, std::size_t,
                                                             const detail::HostPin&);
template std::vector<std::uint16_t> upperLevels(const HashedMesh<float>&);
template std::vector<std::uint16_t> upperLevels(const HashedMesh<double>&);
template CellLayout cellLayout(const HashedMesh<float>&);
template CellLayout cellLayout(const HashedMesh<double>&);

}  // namespace cuda
}  // namespace kdet_fcl
