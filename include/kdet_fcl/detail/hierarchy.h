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

}  // namespace detail
}  // namespace kdet_fcl
