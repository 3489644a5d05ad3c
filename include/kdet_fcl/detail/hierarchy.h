#pragma once
/// \file
/// The level rule and the cell keys of kDet's hierarchical grid, shared by both backends.
///
/// Level l has cubic cells of edge cell0 * 2^l. A triangle of enclosing diameter d lives on the
/// finest level whose cells are at least d wide, l = ceil(log2(d / cell0)), so its box (extent
/// <= d per axis) overlaps at most 2 cells per axis: at most 8 cells. cell0 is the smallest
/// positive diameter, but never below extent * 2^-kCellBits (so cell coordinates fit in
/// kCellBits bits; triangles smaller than that just share level 0).

#include <cmath>
#include <cstdint>
#include <cstring>

#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/host_device.h"

namespace kdet_fcl {
namespace detail {

/// Bits per cell coordinate in a key. Cell coordinates are measured from the hierarchy's
/// origin and clamped to [0, 2^kCellBits - 1].
constexpr int kCellBits = 40;
/// cell0 >= extent * 2^-kCellRange keeps every coordinate well inside kCellBits bits.
constexpr int kCellRange = 38;
/// Most levels a hierarchy may have (the key stores the level in 8 bits).
constexpr int kMaxLevels = 64;

/// The geometry of one hierarchy: where cell (0,0,0) starts and how big level-0 cells are.
struct GridParams {
  double origin[3] = {0, 0, 0};
  double cell0 = 1;      ///< edge of a level-0 cell
  double inv_cell0 = 1;  ///< 1 / cell0
  int num_levels = 1;    ///< levels 0 .. num_levels-1
};

/// Level of a triangle of diameter d: the smallest l >= 0 with cell0 * 2^l >= d, clamped to the
/// top level. Monotone in d (so "larger triangles live on the same or coarser levels").
KDET_HD_INLINE int levelFor(double d, const GridParams& g) {
  const double r = d * g.inv_cell0;
  if (!(r > 1)) return 0;
  int e = 0;
  const double m = ::frexp(r, &e);  // r = m * 2^e, m in [0.5, 1)
  const int l = (m == 0.5) ? e - 1 : e;
  return l < g.num_levels - 1 ? l : g.num_levels - 1;
}

/// 2^e for -1022 <= e <= 1023, built from its bit pattern (exact, and cheaper than ldexp).
KDET_HD_INLINE double pow2(int e) {
  const std::uint64_t bits = std::uint64_t(1023 + e) << 52;
  double d;
  memcpy(&d, &bits, sizeof d);
  return d;
}

/// 2^-level: the exact factor that turns level-0 cell units into level-`level` units.
KDET_HD_INLINE double levelScale(int level) { return pow2(-level); }

/// Cell coordinate of x along `axis` for a level whose levelScale() is `scale`. Built from
/// monotone rounded operations (the scaling by a power of two is exact), so x <= y implies
/// cellCoord(x) <= cellCoord(y): two overlapping boxes always share a cell, and the cell of a
/// canonical point of their overlap lies in both boxes' cell ranges.
KDET_HD_INLINE std::int64_t cellCoordScaled(double x, int axis, double scale, const GridParams& g) {
  const double v = ((x - g.origin[axis]) * g.inv_cell0) * scale;
  const double maxc = double((std::int64_t(1) << kCellBits) - 1);
  if (!(v > 0)) return 0;  // also maps NaN to 0 (inputs are validated; this is belt and braces)
  if (v >= maxc) return std::int64_t(maxc);
  return std::int64_t(v);  // v > 0: truncation == floor
}

/// Cell coordinate of x along `axis` on `level` (see cellCoordScaled).
KDET_HD_INLINE std::int64_t cellCoord(double x, int axis, int level, const GridParams& g) {
  return cellCoordScaled(x, axis, levelScale(level), g);
}

/// A full 128-bit cell key: (level, cx, cy, cz). Keys are compared in full, so hash-bucket
/// collisions never merge two cells.
struct CellKey {
  std::uint64_t hi, lo;
  KDET_HD_INLINE bool operator==(const CellKey& o) const { return hi == o.hi && lo == o.lo; }
};

KDET_HD_INLINE CellKey makeCellKey(int level, std::int64_t cx, std::int64_t cy, std::int64_t cz) {
  const std::uint64_t x = std::uint64_t(cx), y = std::uint64_t(cy), z = std::uint64_t(cz);
  return {(std::uint64_t(level) << 56) | (x << 16) | (y >> 24), ((y & 0xFFFFFFull) << 40) | z};
}

/// A cell: its level and coordinates.
struct CellId {
  int level;
  std::int64_t x, y, z;
};

/// The cell a key names (the inverse of makeCellKey for coordinates below 2^kCellBits).
KDET_HD_INLINE CellId cellOfKey(const CellKey& k) {
  constexpr std::uint64_t m = (std::uint64_t(1) << kCellBits) - 1;
  return {static_cast<int>(k.hi >> 56), static_cast<std::int64_t>((k.hi >> 16) & m),
          static_cast<std::int64_t>(((k.hi & 0xFFFFull) << 24) | (k.lo >> 40)),
          static_cast<std::int64_t>(k.lo & m)};
}

/// 64-bit hash of a key (a splitmix-style finalizer over both words).
KDET_HD_INLINE std::uint64_t hashCellKey(const CellKey& k) {
  std::uint64_t h = k.hi * 0x9E3779B97F4A7C15ull ^ (k.lo + 0x632BE59BD9B4E019ull + (k.hi << 6));
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 31;
  return h;
}

/// The inclusive range of cells a box covers on one level.
struct CellRange {
  std::int64_t lo[3], hi[3];
  KDET_HD_INLINE std::int64_t count() const {
    return (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
  }
};

KDET_HD_INLINE CellRange cellRange(const Aabb<double>& b, int level, const GridParams& g) {
  const double scale = levelScale(level);
  CellRange r;
  for (int a = 0; a < 3; ++a) {
    r.lo[a] = cellCoordScaled(b.lo[a], a, scale, g);
    r.hi[a] = cellCoordScaled(b.hi[a], a, scale, g);
  }
  return r;
}

/// Whether the cell (cx, cy, cz) is the canonical cell of the overlap of boxes p and q: the
/// cell holding the overlap's minimum corner. Exactly one cell of the common range satisfies
/// this, so each candidate pair is examined once without a de-duplication set.
KDET_HD_INLINE bool isCanonicalCell(const Aabb<double>& p, const Aabb<double>& q, double scale,
                                    const GridParams& g, std::int64_t cx, std::int64_t cy,
                                    std::int64_t cz) {
  const double x = p.lo.x > q.lo.x ? p.lo.x : q.lo.x;
  const double y = p.lo.y > q.lo.y ? p.lo.y : q.lo.y;
  const double z = p.lo.z > q.lo.z ? p.lo.z : q.lo.z;
  return cellCoordScaled(x, 0, scale, g) == cx && cellCoordScaled(y, 1, scale, g) == cy &&
         cellCoordScaled(z, 2, scale, g) == cz;
}

/// Sub-cell spans: a cheap, conservative box test inside one cell. The cell is cut into
/// 2^kSubcellBits slabs per axis, and a box is reduced to the first and last slab it touches per
/// axis, clamped to the cell: six 4-bit numbers, packed as (lo_x, lo_y, lo_z) in bits 0..14 and
/// (hi_x, hi_y, hi_z) in bits 15..29, five bits per number (the fifth is the guard bit of
/// subcellSpansOverlap). A slab index is cellCoordScaled on a 2^kSubcellBits times finer grid
/// minus the cell's first slab, clamped to [0, 15]: a monotone function of the coordinate (for
/// any rounding), so two boxes that overlap (closed intervals: lo <= hi' on every axis) always
/// have overlapping spans in any cell. The converse fails (a span is up to 1/16 of a cell too
/// wide per side), so a passing span test is followed by the exact box test.
constexpr int kSubcellBits = 4;

/// The query side's span for every cell of its range r on `level` at once: the lo fields as in
/// r's first cell, the hi fields as in r's last cell (subcellSpanInCell makes a cell's span).
KDET_HD_INLINE std::uint32_t subcellSpanCorners(const Aabb<double>& b, int level,
                                                const CellRange& r, const GridParams& g) {
  const double scale = pow2(kSubcellBits - level);
  constexpr std::int64_t kLast = (std::int64_t(1) << kSubcellBits) - 1;
  std::uint32_t span = 0;
  for (int a = 0; a < 3; ++a) {
    std::int64_t lo = cellCoordScaled(b.lo[a], a, scale, g) - r.lo[a] * (kLast + 1);
    std::int64_t hi = cellCoordScaled(b.hi[a], a, scale, g) - r.hi[a] * (kLast + 1);
    lo = lo < 0 ? 0 : (lo > kLast ? kLast : lo);
    hi = hi < 0 ? 0 : (hi > kLast ? kLast : hi);
    span |= (static_cast<std::uint32_t>(lo) << (5 * a)) |
            (static_cast<std::uint32_t>(hi) << (15 + 5 * a));
  }
  return span;
}

/// The span of box b in cell (cx, cy, cz) of `level`: the corners of a one-cell range.
KDET_HD_INLINE std::uint32_t subcellSpan(const Aabb<double>& b, int level, std::int64_t cx,
                                         std::int64_t cy, std::int64_t cz, const GridParams& g) {
  const CellRange one{{cx, cy, cz}, {cx, cy, cz}};
  return subcellSpanCorners(b, level, one, g);
}

/// The span of a whole cell (lo 0 and hi 15 on every axis).
constexpr std::uint32_t kWholeCellSpan = (15u << 15) | (15u << 20) | (15u << 25);

/// The query's span in one cell of its range, from subcellSpanCorners and `ends`: bit a (0..2)
/// set when the cell is the range's first on axis a, bit 3 + a when it is the last. On an axis
/// where the cell is not the first, lo = 0; where it is not the last, hi = 15. That is
/// subcellSpan's value or a wider span (on such an axis subcellSpan's lo is 0 and hi 15 unless
/// the coarse and fine coordinates round inconsistently, where the wider span is still
/// conservative).
KDET_HD_INLINE std::uint32_t subcellSpanInCell(std::uint32_t corners, unsigned int ends) {
  std::uint32_t span = corners;
  for (int a = 0; a < 3; ++a) {
    if (!((ends >> a) & 1u)) span &= ~(15u << (5 * a));
    if (!((ends >> (3 + a)) & 1u)) span |= 15u << (15 + 5 * a);
  }
  return span;
}

/// Whether two spans of the same cell overlap on every axis (hi_p >= lo_q and hi_q >= lo_p per
/// axis), in a few integer operations: with the guard bit set above each 4-bit field, the
/// subtraction of a field leaves the guard set iff no borrow, and never borrows across fields.
KDET_HD_INLINE bool subcellSpansOverlap(std::uint32_t p, std::uint32_t q) {
  constexpr std::uint32_t kGuard = (1u << 4) | (1u << 9) | (1u << 14);
  const std::uint32_t p_lo = p & 0x7FFFu, p_hi = p >> 15, q_lo = q & 0x7FFFu, q_hi = q >> 15;
  return ((((p_hi | kGuard) - q_lo) & ((q_hi | kGuard) - p_lo)) & kGuard) == kGuard;
}

}  // namespace detail
}  // namespace kdet_fcl
