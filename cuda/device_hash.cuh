#pragma once
// The device-side pieces of kDet's hierarchical hash: owning buffers, the copyable views that
// kernels take by value, and the device functions of the lookup. The geometry (levels, cell keys,
// boxes, diameters, canonical cells, exact test) comes from include/kdet_fcl/detail, the same
// KDET_HD functions the CPU backend runs, so both backends decide on bit-identical numbers.

#include <cuda_runtime_api.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "cuda_error.cuh"
#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/hierarchy.h"
#include "kdet_fcl/vec3.h"

namespace kdet_fcl {
namespace cuda {

/// Allocations made by every DeviceBuffer of the process (QueryProfile::device_allocations).
inline std::atomic<unsigned long long> g_device_allocations{0};

/// A grow-only device allocation (global memory). reserve() never shrinks and does not keep the
/// contents when it grows; release() is noexcept (used on error paths and at destruction).
template <class T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& o) noexcept : p_(o.p_), cap_(o.cap_) { o.p_ = nullptr, o.cap_ = 0; }
  DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(cap_, o.cap_);
    return *this;
  }
  ~DeviceBuffer() { release(); }

  /// Makes room for n elements (with 1/8 slack when it must grow and `slack`, so slowly growing
  /// inputs do not reallocate every time; arrays whose size is fixed by the topology pass false).
  void reserve(std::size_t n, bool slack = true) {
    if (n <= cap_ && p_ != nullptr) return;
    release();
    const std::size_t want = (n == 0 ? 1 : (slack ? n + n / 8 : n));
    void* p = nullptr;
    CUDA_TRY(cudaMalloc(&p, want * sizeof(T)));
    g_device_allocations.fetch_add(1, std::memory_order_relaxed);
    p_ = static_cast<T*>(p);
    cap_ = want;
  }
  /// Waits for the device first: with the re-hash free of host round-trips, kernels of the
  /// current query may still use a scratch buffer that grows.
  void release() noexcept {
    if (p_ != nullptr) {
      (void)cudaDeviceSynchronize();
      (void)cudaFree(p_);
    }
    p_ = nullptr;
    cap_ = 0;
  }
  T* data() const { return p_; }
  std::size_t capacity() const { return cap_; }
  std::size_t bytes() const { return cap_ * sizeof(T); }

 private:
  T* p_ = nullptr;
  std::size_t cap_ = 0;
};

/// What one build of a hierarchy found: the grid (identical to the CPU's, see
/// HierarchicalHash::build) and the sizes. Written on the device; each mesh keeps its own copy
/// there, which the query kernels read through constant memory (c_info in cuda_backend.cu), so a
/// re-hash needs no read-back. The host reads it once after a first build (to size the arrays)
/// and, after a re-hash, together with the query's pair counts (to check the capacities).
struct BuildInfo {
  detail::GridParams grid;
  detail::Aabb<double> bounds;
  double d_min, d_max;
  unsigned long long level_mask;  ///< bit l: level l holds triangles
  int top_level;
  int coord_bits;  ///< bits of a level-0 cell coordinate (every level's coordinates fit)
  int level_bits;  ///< bits of a level index
  int fits64;      ///< level_bits + 3 * coord_bits <= 64: the compact 64-bit key is exact
  unsigned int entries;  ///< (cell, triangle) entries of this build (may exceed the capacity)
  unsigned int cells;    ///< occupied cells of this build (may exceed the capacity)
  int need_sync;   ///< re-hash without read-back only: the keys no longer fit the host's plan,
                   ///< or (counting build) its cells outgrew the table
  unsigned int inserted;  ///< counting build (countFillKernel): distinct cells inserted so far
  /// The axis (0, 1, 2) on which this build grouped each cell's entries by their sub-cell spans
  /// (cellGroupOf; HashView::cell_split gives the groups' bounds), or kNoCellGroups: the entries
  /// of a cell are in no such order (the sort build, or the groups' knob off).
  int group_axis;
};

/// BuildInfo::group_axis of a build whose cells are not grouped.
constexpr int kNoCellGroups = 3;

/// The group of an entry whose sub-cell span in its cell is `span` (detail::subcellSpan), on axis
/// `axis`: 0 when its high slab lies in the cell's lower half (below 8 of the 16 sub-cells), 2
/// when its low slab lies in the upper half, else 1 (it crosses the middle). A counting build
/// with group_axis < kNoCellGroups lists each cell's entries by group, so that a query whose span
/// lies in one half of the cell skips the other half's group in one contiguous run (their spans
/// cannot overlap: cellGroupRun).
__host__ __device__ __forceinline__ unsigned int cellGroupOf(std::uint32_t span, int axis) {
  const unsigned int lo = (span >> (5 * axis)) & 15u, hi = (span >> (15 + 5 * axis)) & 15u;
  return hi < 8 ? 0u : (lo >= 8 ? 2u : 1u);
}

/// The compact cell key: level and coordinates packed into cb bits per axis (exact and one-to-one
/// when BuildInfo::fits64, for coordinates in [0, 2^cb), which every cell inside the bounds has).
__host__ __device__ __forceinline__ unsigned long long compactKey(int level, std::int64_t x,
                                                                  std::int64_t y, std::int64_t z,
                                                                  int cb) {
  return (static_cast<unsigned long long>(level) << (3 * cb)) |
         (static_cast<unsigned long long>(x) << (2 * cb)) |
         (static_cast<unsigned long long>(y) << cb) | static_cast<unsigned long long>(z);
}

/// An entry's value: the triangle (below 2^29) and, in the top three bits, whether the entry's
/// cell is the triangle's first cell along x, y, z (bit 0, 1, 2). With them the canonical-cell
/// test of a lookup needs no box (as the CPU's Entry::lo_mask).
constexpr std::uint32_t kEntryTriMask = (1u << 29) - 1;
__host__ __device__ __forceinline__ std::uint32_t entryValue(std::uint32_t tri,
                                                             std::uint32_t lo_mask) {
  return tri | (lo_mask << 29);
}

/// The cell of a compact key (see compactKey).
__host__ __device__ __forceinline__ detail::CellId compactKeyCell(unsigned long long u, int cb) {
  const unsigned long long m = (1ull << cb) - 1;
  return {static_cast<int>(u >> (3 * cb)), static_cast<std::int64_t>((u >> (2 * cb)) & m),
          static_cast<std::int64_t>((u >> cb) & m), static_cast<std::int64_t>(u & m)};
}

/// Slot value of an empty open-addressing slot.
constexpr unsigned long long kEmptySlot = ~0ull;

/// A hierarchy on the device, as kernels see it (all pointers: device global memory). The grid,
/// bounds and level range are not here: they are computed on the device and read from the
/// mesh's BuildInfo (passed separately, from constant memory).
template <class S>
struct HashView {
  const Vec3<S>* v;           ///< vertices, local frame
  const std::uint32_t* t;     ///< 3 vertex indices per triangle
  const detail::Aabb<S>* box; ///< per triangle, local frame (exact min/max of S coordinates)
  const double* diam;         ///< per triangle: enclosing diameter
  /// Each (cell, triangle) entry, grouped by cell: the triangle and its first-cell bits
  /// (entryValue).
  const std::uint32_t* entry_tri;
  /// Per entry: the sub-cell span of the triangle's box in the entry's cell (detail::subcellSpan).
  const std::uint32_t* entry_span;
  const std::uint32_t* cell_begin;  ///< first entry of each cell; cell_begin[cells] = entries
  /// Per cell of a build with grouped cells (BuildInfo::group_axis < kNoCellGroups): the ends of
  /// its groups 0 and 1 (cellGroupOf), as offsets from its first entry. Unread otherwise.
  const uint2* cell_split;
  /// Full key of each cell: key_words = 1: the compact 64-bit key; 2: the 128-bit CellKey as
  /// {hi, lo}. Either way a lookup compares the whole key.
  const unsigned long long* cell_key;
  const unsigned long long* slots;  ///< open addressing: (hash >> 32) << 32 | cell, or empty
  /// Per triangle, 16 bits (triangle i in bits 16 * (i & 1) of word i / 2): the levels above its
  /// own that hold a cell of its cell range (upperLevelsKernel in cuda_backend.cu). nullptr, or a
  /// triangle's valid bit clear: not known, every level is scanned.
  const std::uint32_t* upper;
  unsigned int slot_count;          ///< slots (any size; index = (low 32 hash bits * count) >> 32)
  int key_words;
};

/// A triangle's 16 bits in HashView::upper. Bit 0: valid; bit k (1..kUpperLevels): level own + k
/// holds a cell of the triangle's cell range. Levels above own + kUpperLevels are not recorded.
constexpr std::uint32_t kUpperValid = 1u;
constexpr int kUpperLevels = 15;

/// The levels of a hierarchy's level_mask at or above `from` (none when from > 63).
__host__ __device__ __forceinline__ unsigned long long levelsFrom(unsigned long long level_mask,
                                                                  int from) {
  return from > 63 ? 0ull : level_mask & (~0ull << from);
}

#if defined(__CUDACC__)

/// The levels that triangle i of level `own` must scan in a self query of its own hierarchy:
/// from own + level_skip up, less the levels within kUpperLevels above its own whose cells in its
/// range are all empty (HashView::upper). A triangle's cell range on a level L above its own is
/// the set of the level-L cells that contain a cell of its own range (cell coordinates come from
/// one rounded value scaled by a power of two per level, so each level's coordinate is the one
/// below shifted right by a bit), so those ancestors, looked up once per cell of the build, tell
/// which levels a query can skip without a lookup.
template <class S>
__device__ __forceinline__ unsigned long long selfQueryLevels(const HashView<S>& h,
                                                              const BuildInfo& info,
                                                              std::uint32_t i, int own,
                                                              int level_skip) {
  unsigned long long levels = levelsFrom(info.level_mask, own + level_skip);
  if (h.upper == nullptr || own >= 63) return levels;
  const std::uint32_t u = (__ldg(h.upper + (i >> 1)) >> (16u * (i & 1u))) & 0xFFFFu;
  if (!(u & kUpperValid)) return levels;
  // Bits own+1 .. own+kUpperLevels (those that fit in 64) are known; keep the occupied ones.
  const unsigned long long known = ((1ull << kUpperLevels) - 1) << (own + 1);
  const unsigned long long occupied = static_cast<unsigned long long>(u >> 1) << (own + 1);
  return levels & (~known | occupied);
}

/// The slot where the probe sequence of a cell with hash `hash` starts, in a table of
/// `slot_count` slots (open addressing, linear probing: see nextSlot).
__host__ __device__ __forceinline__ std::uint32_t homeSlot(unsigned long long hash,
                                                           std::uint32_t slot_count) {
  return static_cast<std::uint32_t>(
      (static_cast<unsigned long long>(static_cast<std::uint32_t>(hash)) * slot_count) >> 32);
}

/// The slot after `s` in a probe sequence (wrapping at the table's end).
__host__ __device__ __forceinline__ std::uint32_t nextSlot(std::uint32_t s,
                                                           std::uint32_t slot_count) {
  return s + 1 == slot_count ? 0u : s + 1;
}

/// A slot's lookup form for cell `c` with hash `hash`: the hash's 32 high bits (the fingerprint
/// findCell compares first) and the cell index.
__host__ __device__ __forceinline__ unsigned long long slotValue(unsigned long long hash,
                                                                 std::uint32_t c) {
  return ((hash >> 32) << 32) | c;
}

/// The cell index of cell (L, x, y, z), or -1 when no triangle occupies that cell. The 32 high
/// hash bits in the slot only skip most mismatches cheaply; a match is confirmed on the full key
/// (the compact 64-bit key, exact for coordinates inside the bounds, or the 128-bit one), so a
/// bucket or fingerprint collision can neither invent nor lose a candidate.
template <class S>
__device__ __forceinline__ int findCell(const HashView<S>& h, const BuildInfo& info, int L,
                                        std::int64_t x, std::int64_t y, std::int64_t z) {
  const detail::CellKey key = detail::makeCellKey(L, x, y, z);
  const unsigned long long hash = detail::hashCellKey(key);
  const unsigned int fp = static_cast<unsigned int>(hash >> 32);
  unsigned int i = homeSlot(hash, h.slot_count);
  const bool compact = h.key_words == 1;
  const unsigned long long ck = compact ? compactKey(L, x, y, z, info.coord_bits) : 0ull;
  while (true) {
    const unsigned long long s = __ldg(h.slots + i);
    if (s == kEmptySlot) return -1;
    if (static_cast<unsigned int>(s >> 32) == fp) {
      const unsigned int c = static_cast<unsigned int>(s);
      if (compact) {
        if (__ldg(h.cell_key + c) == ck) return static_cast<int>(c);
      } else if (__ldg(h.cell_key + 2 * std::size_t(c)) == key.hi &&
                 __ldg(h.cell_key + 2 * std::size_t(c) + 1) == key.lo) {
        return static_cast<int>(c);
      }
    }
    i = nextSlot(i, h.slot_count);
  }
}

/// The high 32 bits of a non-negative diameter's bit pattern: monotone in the diameter (the same
/// order as sizeKey() in cuda_backend.cu, which maps through the ordered bit pattern).
__device__ __forceinline__ unsigned int sizeKeyOf(double d) {
  const unsigned long long b = static_cast<unsigned long long>(__double_as_longlong(d));
  const unsigned long long o = (b >> 63) ? ~b : (b | 0x8000000000000000ull);
  return static_cast<unsigned int>(o >> 32);
}

/// A box in double (exact: S -> double never rounds).
template <class S>
__host__ __device__ __forceinline__ detail::Aabb<double> toDoubleBox(const detail::Aabb<S>& b) {
  return {{double(b.lo.x), double(b.lo.y), double(b.lo.z)},
          {double(b.hi.x), double(b.hi.y), double(b.hi.z)}};
}

/// The box of triangle j in double.
template <class S>
__device__ __forceinline__ detail::Aabb<double> boxOf(const HashView<S>& h, std::uint32_t j) {
  return toDoubleBox(h.box[j]);
}

/// Per axis, whether the cell at offsets (dx, dy, dz) of a query's cell range with extents
/// (n0, n1, n2) is the range's first (bits 0..2) and last (bits 3..5).
__device__ __forceinline__ unsigned int cellEnds(int dx, int dy, int dz, int n0, int n1, int n2) {
  return (dx == 0 ? 1u : 0u) | (dy == 0 ? 2u : 0u) | (dz == 0 ? 4u : 0u) | (dx == n0 ? 8u : 0u) |
         (dy == n1 ? 16u : 0u) | (dz == n2 ? 32u : 0u);
}

/// The load-free part of an entry's test, seen from a query cell with `ends` (cellEnds): the
/// canonical cell holds the overlap's minimum corner, per axis the later of the two first cells
/// (cellCoord is monotone), so, this cell lying in both ranges, it is this cell iff on every axis
/// it is the entry's first cell (its value's top bits) or the query's. kSpans: also the sub-cell
/// spans (entry's, query's in this cell) must overlap. An entry that fails costs neither its
/// diameter nor its box.
template <bool kSpans>
__device__ __forceinline__ bool entrySeenHere(std::uint32_t v, unsigned int ends,
                                              std::uint32_t espan, std::uint32_t qspan) {
  // (No short circuit: the span's load issues with the entry's, not after its test.)
  return ((((v >> 29) | ends | 0x38u) & 0x3Fu) == 0x3Fu) &
         (!kSpans || detail::subcellSpansOverlap(espan, qspan));
}

/// The device twin of cpu::scanCandidates (src/cpu/scan.h), run by a tile of G lanes (a
/// cooperative-groups tile: 4, 8, 16 or 32) for one query triangle: every triangle j of `h` on
/// the query's level or a coarser one, in a cell the (clipped) query box covers, accepted by the
/// size rule accept(j, d_j), whose box overlaps the query box, seen only from the canonical cell
/// of that overlap; calls emit(j) for each. The lanes stride through each cell's entries, so a
/// heavily loaded cell costs a few rounds of one tile instead of hundreds of iterations of one
/// thread that its warp would wait for; the cell lookups are repeated in every lane, so smaller
/// tiles suit lightly loaded cells. kSpans: entries whose sub-cell span misses the query's are
/// skipped before their diameter and box are loaded (a saving where cells are crowded with
/// near-misses; elsewhere the filter's setup costs more than it saves, so the host chooses:
/// spansFor() in cuda_backend.cu). `size_ordered`: the cells of `h` list their triangles by
/// decreasing diameter, so the scan of a cell ends at its first entry smaller than the query (else
/// every entry is tested; smaller ones fail the size rule). `levels`: the levels to scan, a subset
/// of info.level_mask at or above the query's own level (levelsFrom() of it for every such
/// level; a self query whose same-level pairs come from selfCellPairsKernel in cuda_backend.cu
/// leaves out its own; selfQueryLevels() also leaves out the levels known to be empty around the
/// query). All arguments must be tile-uniform; every lane of the tile must call.
template <bool kSpans, class S, class Tile, class Accept, class Emit>
__device__ __forceinline__ void scanCandidatesGroup(const HashView<S>& h, const BuildInfo& info,
                                                    const detail::Aabb<double>& qbox, double dq,
                                                    bool size_ordered, unsigned long long levels,
                                                    const Tile& tile, Accept&& accept,
                                                    Emit&& emit) {
  constexpr unsigned int G = Tile::num_threads();
  const unsigned int lane = tile.thread_rank();
  // Only the clipped box stays live through the scan: every entry's box lies inside info.bounds
  // (the exact union of the triangles' boxes), so against an entry box e the clipped box gives the
  // same overlap test (q ∩ e = q ∩ bounds ∩ e) and the same canonical cell (max(q.lo, e.lo) =
  // max(q.lo, bounds.lo, e.lo) per axis), and twelve fewer registers are held under the cap.
  const detail::Aabb<double> clipped = detail::intersectBoxes(qbox, info.bounds);
  if (detail::isEmpty(clipped)) return;
  // Cells built in size order list their triangles by decreasing sizeKey (cuda_backend.cu); every
  // size rule needs d_j >= d_query, so the scan of such a cell stops at the first entry of a
  // smaller sizeKey.
  const unsigned int qkey = sizeKeyOf(dq);
  for (; levels != 0; levels &= levels - 1) {
    const int L = __ffsll(static_cast<long long>(levels)) - 1;
    const detail::CellRange r = detail::cellRange(clipped, L, info.grid);
    const std::uint32_t corners =
        kSpans ? detail::subcellSpanCorners(clipped, L, r, info.grid) : detail::kWholeCellSpan;
    // The loops run over offsets from the range's first cell (a range spans a few cells): fewer
    // registers than full coordinates, and the register cap is what limits this kernel.
    const int n[3] = {static_cast<int>(r.hi[0] - r.lo[0]), static_cast<int>(r.hi[1] - r.lo[1]),
                      static_cast<int>(r.hi[2] - r.lo[2])};
    // Every lane computes the same lookups (cheap next to the entry scans; a variant in which
    // the lanes probed different cells of the range and shuffled the hits was measured slower).
    for (int dx = 0; dx <= n[0]; ++dx)
      for (int dy = 0; dy <= n[1]; ++dy)
        for (int dz = 0; dz <= n[2]; ++dz) {
          const int c = findCell(h, info, L, r.lo[0] + dx, r.lo[1] + dy, r.lo[2] + dz);
          if (c < 0) continue;  // (the same in every lane)
          const std::uint32_t begin = __ldg(h.cell_begin + c), end = __ldg(h.cell_begin + c + 1);
          const unsigned int ends = cellEnds(dx, dy, dz, n[0], n[1], n[2]);
          const std::uint32_t qspan =
              kSpans ? detail::subcellSpanInCell(corners, ends) : detail::kWholeCellSpan;
          for (std::uint32_t base = begin; base < end; base += G) {
            const std::uint32_t k = base + lane;
            bool smaller = false;
            if (k < end) {
              const std::uint32_t v = __ldg(h.entry_tri + k);
              const std::uint32_t espan = kSpans ? __ldg(h.entry_span + k) : 0u;
              if (entrySeenHere<kSpans>(v, ends, espan, qspan)) {
                const std::uint32_t j = v & kEntryTriMask;
                const double dj = __ldg(h.diam + j);
                smaller = sizeKeyOf(dj) < qkey;
                if (!smaller && accept(j, dj) && detail::boxesOverlap(clipped, boxOf(h, j)))
                  emit(j);
              }
            }
            // Entries by size: once one lane saw a smaller one, all later rounds are smaller.
            if (size_ordered && tile.any(smaller)) break;
          }
        }
  }
}

/// A triangle's three vertex indices.
struct TriIndices {
  std::uint32_t a, b, c;
};

__device__ __forceinline__ TriIndices loadTri(const std::uint32_t* __restrict__ t, std::uint32_t j) {
  return {__ldg(t + 3 * j), __ldg(t + 3 * j + 1), __ldg(t + 3 * j + 2)};
}

/// Whether two triangles share a vertex index (every comparison made, no short circuit).
__device__ __forceinline__ bool shareIndex(const TriIndices& x, const TriIndices& y) {
  return (x.a == y.a) | (x.a == y.b) | (x.a == y.c) | (x.b == y.a) | (x.b == y.b) |
         (x.b == y.c) | (x.c == y.a) | (x.c == y.b) | (x.c == y.c);
}

/// One lane's query in the warp-wide scan (scanCandidatesWarp), in shared memory so that every
/// lane can test entries of every other lane's query.
struct WarpQuery {
  detail::Aabb<double> box;  ///< the query box clipped to the hash's bounds
  /// Float hashes only: the clipped box for the entries' box test in float (testBoxOf; set by
  /// scanCandidatesWarp).
  detail::Aabb<float> test;
  double d;                  ///< the query triangle's diameter
  /// The levels to scan (as scanCandidatesGroup's `levels`).
  unsigned long long levels;
  std::uint32_t id;          ///< the caller's index of the query triangle
  /// Self queries whose scan loads each entry's vertex indices (scanCandidatesWarp's load_tri):
  /// the query triangle's own, for the adjacency rule by index.
  TriIndices tri;
  std::uint16_t live;        ///< 1: the lane has a query (0: idle lane, or an empty clipped box)
  /// The query's own level in the hash (levelFor of d in its grid): the entries of the levels
  /// above it pass the size rule with no load of their diameter (a triangle stored above it is
  /// strictly larger than the query, levelFor being monotone). kMaxLevels: every entry's
  /// diameter is loaded and tested (KDET_FCL_CUDA_SIZE_BY_LEVEL=0).
  std::int16_t size_level;
  /// The box's fixed-point coordinates (fixedCoord; lo x, y, z, then hi x, y, z), from which
  /// the scan takes every level's cell range and sub-cell corners with shifts (levelRange). Set
  /// by scanCandidatesWarp when it runs fixed (fixedCells).
  std::uint32_t fine[6];
};

/// The most bits of a hash's level-0 cell coordinates (BuildInfo::coord_bits) for which the
/// warp-wide scan takes its cell ranges from fixed-point coordinates (fixedCoord): below that,
/// every fixed-point coordinate of a box inside the hash's bounds fits in 32 bits.
constexpr int kFixedCoordBits = 32 - detail::kSubcellBits;

/// Whether the warp-wide scan of a hash with this build info takes its cell ranges from
/// fixed-point coordinates: asked for (KDET_FCL_CUDA_FIXED_CELLS, `fixed`) and the hash's
/// coordinates small enough (kFixedCoordBits). Else each level's range is computed from the
/// box in double (detail::cellRange), as the other scans do. Both give the same ranges.
/// (The host applies it to its copy of the build info for QueryProfile::fixed_cells.)
__host__ __device__ __forceinline__ bool fixedCells(bool fixed, const BuildInfo& info) {
  return fixed && info.coord_bits <= kFixedCoordBits;
}

/// The fixed-point coordinate of x along `axis`: its cell coordinate on the grid of level-0
/// sub-cells (detail::cellCoordScaled at scale 2^kSubcellBits). For x inside the bounds of a
/// hash whose level-0 coordinates have coord_bits <= kFixedCoordBits bits (fixedCells), it is
/// floor(2^kSubcellBits w) for w = (x - origin) * inv_cell0 rounded once (0 for w <= 0), below
/// 2^32: w is at most w of the bounds' max corner (rounding is monotone), whose floor is below
/// 2^coord_bits, so no clamp of cellCoordScaled binds. Since the scaling by a power of two is
/// exact and floor(floor(y) / 2^k) = floor(y / 2^k), on every level L the coordinate shifted
/// right by L + kSubcellBits is detail::cellCoord(x, L), and shifted right by L it is the
/// sub-cell coordinate from which subcellSpanCorners takes its 4 bits (the low 4 bits, which
/// need no clamp): levelRange.
__device__ __forceinline__ std::uint32_t fixedCoord(double x, int axis,
                                                    const detail::GridParams& g) {
  return static_cast<std::uint32_t>(
      detail::cellCoordScaled(x, axis, double(1 << detail::kSubcellBits), g));
}

/// u >> s for any s >= 0 (0 from s = 32 on).
__device__ __forceinline__ std::uint32_t shiftRight(std::uint32_t u, int s) {
  return s < 32 ? u >> s : 0u;
}

/// Bit of a visit's `ends` (cellEnds' six bits below it) in the warp-wide scan: the visited cell
/// lies on a level above the query's size_level, so its entries pass the size rule unloaded.
constexpr unsigned int kAboveQueryLevel = 1u << 6;

/// The query box b as a float box for the test against entry boxes of float coordinates: lo
/// rounded up and hi rounded down to float. For any float e and any double x, x <= e iff
/// roundUp(x) <= e (roundUp(x) is the least float not below x), and e <= x iff e <= roundDown(x),
/// so boxesInFloat(testBoxOf(b), e) decides exactly what detail::boxesOverlap(b, e) decides, in
/// float comparisons with no conversion of e.
__device__ __forceinline__ detail::Aabb<float> testBoxOf(const detail::Aabb<double>& b) {
  return {{__double2float_ru(b.lo.x), __double2float_ru(b.lo.y), __double2float_ru(b.lo.z)},
          {__double2float_rd(b.hi.x), __double2float_rd(b.hi.y), __double2float_rd(b.hi.z)}};
}

/// Triangle j's box, its six coordinates loaded at once (three 8-byte loads: an Aabb<float> of 24
/// bytes is 8-byte aligned in a cudaMalloc'd array), so a test that needs all six waits for one
/// round trip, not one per coordinate.
__device__ __forceinline__ detail::Aabb<float> loadBox(const detail::Aabb<float>* p) {
  static_assert(sizeof(detail::Aabb<float>) == 6 * sizeof(float), "packed box");
  const float2* f = reinterpret_cast<const float2*>(p);
  const float2 a = __ldg(f), b = __ldg(f + 1), c = __ldg(f + 2);
  return {{a.x, a.y, b.x}, {b.y, c.x, c.y}};
}

/// detail::boxesOverlap of two float boxes, every comparison made (no short circuit: the caller's
/// loads all issue before the first comparison).
__device__ __forceinline__ bool boxesInFloat(const detail::Aabb<float>& p,
                                             const detail::Aabb<float>& q) {
  return (p.lo.x <= q.hi.x) & (q.lo.x <= p.hi.x) & (p.lo.y <= q.hi.y) & (q.lo.y <= p.hi.y) &
         (p.lo.z <= q.hi.z) & (q.lo.z <= p.hi.z);
}

/// A lane's position in its query's lookups: level L (past top_level: done), the level's cell
/// range as a first cell and extents, the lane's next position in the level's walk (the cells in
/// x-major order: position p is offset (p / (ny nz), p / nz mod ny, p mod nz) for ny = n[1] + 1,
/// nz = n[2] + 1), and what is left of a cell that was cut into chunks (max_visit).
struct LookupCursor {
  std::int64_t lo[3];
  int n[3];
  int L;
  std::uint32_t p;        ///< the lane's next position in the level's walk
  std::uint32_t corners;  ///< sub-cell span corners of the level (kSpans only)
  std::uint32_t rest_begin, rest_end, rest_ends;
};

/// The most entries of one cell handed to the warp in one visit: a larger cell is visited in
/// chunks, so the 32 lanes' entry counts always sum to less than 2^31. (The backend passes a
/// smaller bound only for tests: KDET_FCL_CUDA_WARP_VISIT.)
constexpr std::uint32_t kMaxWarpVisit = 1u << 25;

/// The cells of the cursor's level range.
__device__ __forceinline__ std::uint32_t rangeCells(const LookupCursor& c) {
  return static_cast<std::uint32_t>(c.n[0] + 1) * static_cast<std::uint32_t>(c.n[1] + 1) *
         static_cast<std::uint32_t>(c.n[2] + 1);
}

/// The cursor's level range and sub-cell corners on level L, from the query's fixed-point
/// coordinates (`fixed`, see fixedCoord: a shift per coordinate) or from its box in double
/// (detail::cellRange and subcellSpanCorners). The same numbers either way.
template <bool kSpans>
__device__ __forceinline__ void levelRange(LookupCursor& c, const WarpQuery& q,
                                           const BuildInfo& info, bool fixed, int L) {
  if (fixed) {
    const int s = L + detail::kSubcellBits;
    std::uint32_t corners = 0;
    for (int a = 0; a < 3; ++a) {
      const std::uint32_t lo = shiftRight(q.fine[a], s), hi = shiftRight(q.fine[3 + a], s);
      c.lo[a] = lo;
      c.n[a] = static_cast<int>(hi - lo);
      if (kSpans)
        corners |= ((shiftRight(q.fine[a], L) & 15u) << (5 * a)) |
                   ((shiftRight(q.fine[3 + a], L) & 15u) << (15 + 5 * a));
    }
    c.corners = kSpans ? corners : detail::kWholeCellSpan;
  } else {
    const detail::CellRange r = detail::cellRange(q.box, L, info.grid);
    for (int a = 0; a < 3; ++a) {
      c.lo[a] = r.lo[a];
      c.n[a] = static_cast<int>(r.hi[a] - r.lo[a]);
    }
    c.corners =
        kSpans ? detail::subcellSpanCorners(q.box, L, r, info.grid) : detail::kWholeCellSpan;
  }
  c.L = L;
}

/// Moves the cursor to the first level >= L0 of the query's levels whose walk reaches the lane's
/// position c.p (the positions of the levels passed on the way are taken off it, so each lane
/// keeps its share of the query's whole walk); past top_level if none.
template <bool kSpans>
__device__ __forceinline__ void startLevel(LookupCursor& c, const WarpQuery& q,
                                           const BuildInfo& info, bool fixed, int L0) {
  for (unsigned long long left = levelsFrom(q.levels, L0); left != 0; left &= left - 1) {
    levelRange<kSpans>(c, q, info, fixed, __ffsll(static_cast<long long>(left)) - 1);
    const std::uint32_t cells = rangeCells(c);
    if (c.p < cells) return;
    c.p -= cells;
  }
  c.L = info.top_level + 1;
}

/// Narrows a grouped cell's entries [begin, end) (BuildInfo::group_axis, cellGroupOf) to the run
/// that a query of sub-cell span `qspan` in the cell must visit: with its span in the lower half
/// on that axis (high slab below 8), groups 0 and 1; in the upper half (low slab 8 or more),
/// groups 1 and 2; else all. The entries left out are those whose span lies wholly in the other
/// half, so their spans miss the query's (subcellSpansOverlap would reject each of them), and so
/// do their boxes (subcellSpan is monotone): the same candidates, fewer visits. The run can be
/// empty (nextVisit then looks on to the lane's next cell).
__device__ __forceinline__ void cellGroupRun(uint2 split, std::uint32_t qspan, int axis,
                                             std::uint32_t& begin, std::uint32_t& end) {
  const unsigned int q_lo = (qspan >> (5 * axis)) & 15u, q_hi = (qspan >> (15 + 5 * axis)) & 15u;
  if (q_hi < 8) end = begin + split.y;
  else if (q_lo >= 8) begin += split.x;
}

/// The lane's next visit: the entries [begin, begin + count) of the next occupied cell of its
/// share of the lookups (the cells whose position in the query's walk over all its levels is
/// `sub` modulo P, a power of two: the lane steps P positions at a time), or the next chunk of a
/// cut cell, with the cell's `ends` bits (as in scanCandidatesGroup) and the query's sub-cell
/// span there; count 0 when the lookups are done.
template <bool kSpans, class S>
__device__ __forceinline__ std::uint32_t nextVisit(const HashView<S>& h, const BuildInfo& info,
                                                   const WarpQuery& mine, bool fixed,
                                                   std::uint32_t max_visit, unsigned int P,
                                                   LookupCursor& c, std::uint32_t& begin,
                                                   unsigned int& ends, std::uint32_t& qspan) {
  std::uint32_t end = 0;
  if (c.rest_begin < c.rest_end) {
    begin = c.rest_begin;
    end = c.rest_end;
    ends = c.rest_ends;
  } else {
    // A found cell whose groups the query skips whole (cellGroupRun) leaves nothing to visit:
    // the lane looks on for its next cell (an empty visit would read as the end of its
    // lookups, and a warp whose live lanes all had one would stop early).
    do {
      int cell = -1;
      while (cell < 0 && c.L <= info.top_level) {
        // The lane's position p in the level's walk (p < its cells: startLevel).
        const std::uint32_t nz = static_cast<std::uint32_t>(c.n[2] + 1);
        const std::uint32_t nyz = static_cast<std::uint32_t>(c.n[1] + 1) * nz;
        const std::uint32_t dx = c.p / nyz, r = c.p - dx * nyz, dy = r / nz, dz = r - dy * nz;
        cell = findCell(h, info, c.L, c.lo[0] + dx, c.lo[1] + dy, c.lo[2] + dz);
        if (cell >= 0) {
          ends = cellEnds(static_cast<int>(dx), static_cast<int>(dy), static_cast<int>(dz),
                          c.n[0], c.n[1], c.n[2]);
          if (kSpans) qspan = detail::subcellSpanInCell(c.corners, ends);
          if (c.L > mine.size_level) ends |= kAboveQueryLevel;
        }
        c.p += P;
        const std::uint32_t cells = rangeCells(c);
        if (c.p >= cells) {
          c.p -= cells;
          startLevel<kSpans>(c, mine, info, fixed, c.L + 1);
        }
      }
      if (cell < 0) return 0;
      begin = __ldg(h.cell_begin + cell);
      end = __ldg(h.cell_begin + cell + 1);
      if (kSpans && info.group_axis < kNoCellGroups)
        cellGroupRun(__ldg(h.cell_split + cell), qspan, info.group_axis, begin, end);
    } while (begin == end);
  }
  const std::uint32_t count = end - begin < max_visit ? end - begin : max_visit;
  c.rest_begin = begin + count;
  c.rest_end = end;
  c.rest_ends = ends;
  return count;
}

/// A grid-stride loop's first item for this thread and its stride, with the items spread over the
/// warps: item k goes to warp k mod W (W: the grid's warps), lane k / W mod 32, so that fewer than
/// W items take one lane of as many warps, each on its own path, where consecutive items would
/// fill whole warps whose lanes take different branches one after the other (the exact kernels:
/// the exact test's branches; ncu, benchmarks/RESULTS-gpu.md: the 90k cloth's self exact kernel
/// 14.3 -> 9.8 us). Every item k below any count is taken exactly once. Blocks of a multiple of
/// 32 threads.
struct SpreadIndex {
  unsigned long long first, stride;
};
__device__ __forceinline__ SpreadIndex spreadIndex() {
  const unsigned long long warps = static_cast<unsigned long long>(gridDim.x) * (blockDim.x >> 5);
  const unsigned long long warp =
      static_cast<unsigned long long>(blockIdx.x) * (blockDim.x >> 5) + (threadIdx.x >> 5);
  return {warp + warps * (threadIdx.x & 31u), warps * 32};
}

/// The inclusive prefix sum of the lanes' counts across the warp: lane o then owns the warp's
/// items [incl_o - count_o, incl_o). Every lane must call.
__device__ __forceinline__ std::uint32_t warpInclusiveSum(std::uint32_t count) {
  const unsigned int lane = threadIdx.x & 31u;
  std::uint32_t incl = count;
  for (int o = 1; o < 32; o <<= 1) {
    const std::uint32_t y = __shfl_up_sync(0xFFFFFFFFu, incl, o);
    if (lane >= static_cast<unsigned int>(o)) incl += y;
  }
  return incl;
}

/// The first lane whose value of `incl` (non-decreasing across the lanes) exceeds t; 31 when
/// none does. With warpInclusiveSum: the lane that owns item t. Every lane must call.
__device__ __forceinline__ int warpOwnerOf(std::uint32_t incl, std::uint32_t t) {
  int owner = 0;
  for (int step = 16; step > 0; step >>= 1)
    if (__shfl_sync(0xFFFFFFFFu, incl, owner + step - 1) <= t) owner += step;
  return owner;
}

/// The triangle of entry e: the last i < n with offsets[i] <= e, where offsets (n + 1 words,
/// non-decreasing, offsets[n] the entries' total) is the exclusive scan of the triangles' entry
/// counts, for a warp whose lanes hold consecutive entries e = e0 + lane (e0: the warp's first,
/// below offsets[n]). A lane's own binary search is a chain of log2(n) dependent loads (17 on
/// the cloth ball; the counting build's fill kernel, which ran one per entry, waits on its loads:
/// long scoreboard, 41 of its 53 cycles per instruction on the cloth ball, ncu). Here the warp
/// searches e0's triangle i0 with 32 probes at once (log32(n) loads, 4 on the cloth ball), and
/// one coalesced load brings the first entries of triangles i0 + 1 .. i0 + 32: as a triangle
/// holds at least one entry, each lane's lies among them. Where some hold none (not a mesh of
/// finite coordinates), a lane whose entry lies past them searches the rest alone. Every lane
/// must call, with the same e0.
__device__ __forceinline__ std::uint32_t warpEntryTriangle(
    const std::uint32_t* __restrict__ offsets, std::uint32_t n, std::uint32_t e0,
    std::uint32_t e) {
  constexpr unsigned int kFull = 0xFFFFFFFFu;
  const unsigned int lane = threadIdx.x & 31u;
  // offsets[lo] <= e0, and hi == n or offsets[hi] > e0. Lane k probes lo + floor(k (hi - lo)
  // / 32): non-decreasing in k, so the lanes whose probe is at most e0 are a prefix (lane 0's,
  // lo, is one), and each step leaves at most ceil((hi - lo) / 32) of the range.
  std::uint32_t lo = 0, hi = n;
  while (hi - lo > 1) {
    const std::uint32_t p =
        lo + static_cast<std::uint32_t>((static_cast<std::uint64_t>(hi - lo) * lane) >> 5);
    const int m = __popc(__ballot_sync(kFull, __ldg(offsets + p) <= e0));
    const std::uint32_t last = __shfl_sync(kFull, p, m - 1);
    const std::uint32_t next = __shfl_sync(kFull, p, m & 31);  // (lane m's; m < 32)
    lo = last;
    if (m < 32) hi = next;
  }
  // Lane k: the first entry of triangle lo + 1 + k (offsets[n] closes the last triangle).
  const std::uint32_t t = lo + 1 + lane;
  const std::uint32_t start = t <= n ? __ldg(offsets + t) : 0xFFFFFFFFu;
  const int k = warpOwnerOf(start, e);  // the first lane whose triangle starts past e
  if (__shfl_sync(kFull, start, 31) > e) return lo + static_cast<std::uint32_t>(k);
  std::uint32_t i = lo + 32, past = n;  // triangles without entries: offsets[i] <= e
  while (past - i > 1) {
    const std::uint32_t mid = i + (past - i) / 2;
    if (__ldg(offsets + mid) <= e) i = mid;
    else past = mid;
  }
  return i;
}

/// A warp's queue of the entries that passed the canonical-cell and span tests
/// (entrySeenHere), in its shared memory: 64 slots, each the entry's triangle and a tag (its
/// query's slot in the warp, and kRingAbove where the size rule holds unloaded). The warp-wide
/// scans test 32 queued entries at once (their diameters, boxes and the caller's last rules),
/// so that the loads and tests of a surviving entry run in full warps: in the rounds of 32
/// entries only about 4 pass those tests on the cloth ball (ncu, benchmarks/RESULTS-gpu.md).
struct EntryRing {
  std::uint32_t* tri;  ///< 64 slots
  std::uint8_t* tag;   ///< 64 slots
  unsigned int head;   ///< first queued slot (warp-uniform)
  unsigned int count;  ///< queued entries, at most 63 after a push (warp-uniform)
};

/// Whether the warp-wide scans queue their seen entries in an EntryRing: where they test sub-cell
/// spans (kSpans, chosen for crowded meshes), few entries of a round are seen and the queue
/// fills the warp; without spans most are, and the queue's own work costs more than it saves
/// (H100, benchmarks/RESULTS-gpu.md: with spans, the cloth ball's scan 130 -> 112 us and its
/// cells' pairs 95 -> 86 us; without, the sparse scenes' scans up to 10 % slower and the 1M
/// cloth's candidate search 0.45 -> 0.51 ms). Else each round tests its own seen entries.
template <bool kSpans>
constexpr bool kQueueSeen = kSpans;

/// This warp's EntryRing, empty, in its block's shared memory (64 + 64 slots for each of the
/// block's kWarps warps) where the kernel queues (kQueueSeen<kSpans>), else none.
template <bool kSpans, int kWarps>
__device__ __forceinline__ EntryRing warpRing() {
  if constexpr (kQueueSeen<kSpans>) {
    __shared__ std::uint32_t tris[kWarps][64];
    __shared__ std::uint8_t tags[kWarps][64];
    return {tris[threadIdx.x >> 5], tags[threadIdx.x >> 5], 0u, 0u};
  } else {
    return {nullptr, nullptr, 0u, 0u};
  }
}

/// EntryRing tag bit: the entry passes the size rule without its diameter (kAboveQueryLevel).
constexpr std::uint8_t kRingAbove = 0x80u;

/// Queues the lanes' entries whose `keep` is set (tri, tag) behind those queued, in lane order.
/// The caller pops 32 whenever 32 or more are queued, so at most 31 wait before a push. Every
/// lane of the warp must call.
__device__ __forceinline__ void pushRing(EntryRing& r, bool keep, std::uint32_t tri,
                                         std::uint8_t tag) {
  const unsigned int lane = threadIdx.x & 31u;
  const unsigned int kept = __ballot_sync(0xFFFFFFFFu, keep);
  if (keep) {
    const unsigned int at = (r.head + r.count + __popc(kept & ((1u << lane) - 1u))) & 63u;
    r.tri[at] = tri;
    r.tag[at] = tag;
  }
  r.count += static_cast<unsigned int>(__popc(kept));
  __syncwarp();
}

/// Calls test(have, tri, tag) once in every lane for the first n (0..32) queued entries (lane l
/// the l-th; have = l < n, else tri and tag are 0) and takes them off the queue. Every lane of
/// the warp must call, with the same n.
template <class Test>
__device__ __forceinline__ void popRing(EntryRing& r, unsigned int n, Test&& test) {
  const unsigned int lane = threadIdx.x & 31u;
  const bool have = lane < n;
  const unsigned int at = (r.head + lane) & 63u;
  test(have, have ? r.tri[at] : 0u, have ? r.tag[at] : std::uint8_t{0});
  __syncwarp();  // every lane has read its slot before a push reuses it
  r.head = (r.head + n) & 63u;
  r.count -= n;
}

/// The warp-wide form of scanCandidatesGroup: the same candidates (size rule, box overlap,
/// canonical cell), for 32 / P queries at once, P = 2^log_p lanes per query (1, 2, 4, ..., 32; lane
/// l serves the query in slot l / P of q, this warp's slots; `query` is the lane's query, which
/// lanes l with l % P == 0 write there). The P lanes of a query share its lookups (each probes
/// every P-th cell of the walk; no lane repeats another's); at each step every lane contributes the
/// entries of its next occupied cell, and the warp tests all of them together, 32 entries per
/// round, whatever cell and query each belongs to. So no lane idles at the end of a cell, at the
/// price of the size rule's early exit: an entry smaller than its query is rejected by accept()
/// after its diameter is loaded instead of ending the cell. A larger P gives a small query set more
/// warps. candidate(query, j, tj, a, b) decides on an entry j that passed the size rule and the
/// box test (the pair's last rules: a self query's adjacency) and names the pair (a, b); tj is
/// entry j's vertex indices when `load_tri` (loaded beside its box, for a self query's adjacency
/// rule), else zeros. emit(hit, a, b) is then called by every lane of the warp together, once per
/// round of 32 entries (hit: candidate() accepted the lane's entry), so that the caller can
/// collect the round's pairs with warp-wide operations.
/// accept(q_owner, j, d_j) and candidate(q_owner, ...) get the slot of the query that the entry
/// is tested against. max_visit: 1..kMaxWarpVisit. The query's levels (query.levels) as scanCandidatesGroup's.
/// `fixed_cells`: take each level's cell range from the query's fixed-point coordinates where the
/// hash allows (fixedCells; a few shifts against a dozen rounded double operations and their
/// clamps per level). `ring`: the warp's EntryRing, empty (warpRing), where kQueueSeen<kSpans>
/// queues the entries that pass the canonical-cell and span tests and tests them 32 at a time
/// (emit is then called per 32 queued entries, and for the rest before the return). Every lane of the warp must call, with warp-uniform arguments
/// except `query`.
template <bool kSpans, class S, class Accept, class Candidate, class Emit>
__device__ __forceinline__ void scanCandidatesWarp(const HashView<S>& h, const BuildInfo& info,
                                                   WarpQuery* q,
                                                   const WarpQuery& query, unsigned int log_p,
                                                   std::uint32_t max_visit, bool load_tri,
                                                   bool fixed_cells, EntryRing ring,
                                                   Accept&& accept, Candidate&& candidate,
                                                   Emit&& emit) {
  constexpr unsigned int kFull = 0xFFFFFFFFu;
  const unsigned int lane = threadIdx.x & 31u;
  const unsigned int P = 1u << log_p;
  const unsigned int sub = lane & (P - 1);
  const bool fixed = fixedCells(fixed_cells, info);
  __syncwarp();  // the lanes are done with the slots' previous queries
  if (sub == 0) {
    WarpQuery w = query;
    w.test = std::is_same<S, float>::value ? testBoxOf(query.box) : detail::Aabb<float>{};
    if (fixed)
      for (int a = 0; a < 3; ++a) {
        w.fine[a] = fixedCoord(query.box.lo[a], a, info.grid);
        w.fine[3 + a] = fixedCoord(query.box.hi[a], a, info.grid);
      }
    q[lane >> log_p] = w;
  }
  __syncwarp();
  const WarpQuery& mine = q[lane >> log_p];
  LookupCursor c;
  c.rest_begin = c.rest_end = c.rest_ends = 0;
  c.p = sub;  // the lane's first position in the query's walk
  c.L = info.top_level + 1;
  if (mine.live) startLevel<kSpans>(c, mine, info, fixed, 0);
  // A seen entry's last tests (have: the lane holds one; j, tag: its triangle and EntryRing
  // tag): the size rule, the box and candidate(); then emit, in every lane.
  const auto test = [&](bool have, std::uint32_t j, std::uint8_t tag) {
    bool hit = false;
    std::uint32_t pa = 0, pb = 0;
    if (have) {
      const bool above = (tag & kRingAbove) != 0;
      const double dj = above ? 0.0 : __ldg(h.diam + j);
      // (load_tri: the entry's vertex indices come in the same round trip as its box.)
      const TriIndices tj = load_tri ? loadTri(h.t, j) : TriIndices{0, 0, 0};
      const WarpQuery& oq = q[tag & ~kRingAbove];
      if constexpr (std::is_same<S, float>::value) {
        // The diameter and the box are loaded together and tested without a short circuit:
        // one round trip per entry (with the short circuit, each coordinate's load waited for
        // the previous comparison: H100, benchmarks/RESULTS-gpu.md).
        const detail::Aabb<float> e = loadBox(h.box + j);
        if ((above || accept(oq, j, dj)) & boxesInFloat(oq.test, e))
          hit = candidate(oq, j, tj, pa, pb);
      } else {
        if ((above || accept(oq, j, dj)) && detail::boxesOverlap(oq.box, boxOf(h, j)))
          hit = candidate(oq, j, tj, pa, pb);
      }
    }
    emit(hit, pa, pb);
  };
  while (true) {
    std::uint32_t begin = 0, qspan = detail::kWholeCellSpan;
    unsigned int ends = 0;
    const std::uint32_t count =
        nextVisit<kSpans>(h, info, mine, fixed, max_visit, P, c, begin, ends, qspan);
    // Lane o owns the warp's entries [incl_o - count_o, incl_o).
    const std::uint32_t incl = warpInclusiveSum(count);
    const std::uint32_t total = __shfl_sync(kFull, incl, 31);
    if (total == 0) break;  // every lane's lookups are done
    for (std::uint32_t base = 0; base < total; base += 32) {
      const std::uint32_t t = base + lane;
      const int owner = warpOwnerOf(incl, t);
      const std::uint32_t o_first =
          __shfl_sync(kFull, incl, owner) - __shfl_sync(kFull, count, owner);
      const std::uint32_t o_begin = __shfl_sync(kFull, begin, owner);
      const unsigned int o_ends = __shfl_sync(kFull, ends, owner);
      const std::uint32_t o_qspan = kSpans ? __shfl_sync(kFull, qspan, owner) : 0u;
      bool seen = false;
      std::uint32_t v = 0;
      if (t < total) {
        const std::uint32_t k = o_begin + (t - o_first);
        v = __ldg(h.entry_tri + k);
        const std::uint32_t espan = kSpans ? __ldg(h.entry_span + k) : 0u;
        seen = entrySeenHere<kSpans>(v, o_ends, espan, o_qspan);
      }
      // Above the query's own level the size rule holds (WarpQuery::size_level): no load.
      const std::uint32_t j = v & kEntryTriMask;
      const auto tag = static_cast<std::uint8_t>(
          (owner >> log_p) | ((o_ends & kAboveQueryLevel) ? kRingAbove : 0u));
      if constexpr (kQueueSeen<kSpans>) {
        pushRing(ring, seen, j, tag);
        if (ring.count >= 32) popRing(ring, 32, test);
      } else {
        test(seen, j, tag);
      }
    }
  }
  if constexpr (kQueueSeen<kSpans>)
    popRing(ring, ring.count, test);  // (the slots' queries change after the return)
}

#endif  // __CUDACC__

}  // namespace cuda
}  // namespace kdet_fcl
