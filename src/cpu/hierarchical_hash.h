#pragma once
// The CPU hierarchical spatial hash of one mesh, built in the mesh's own frame.

#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/hierarchy.h"
#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/triangle_mesh.h"

namespace kdet_fcl {
namespace detail {

/// For x >= 0 (not NaN): a float no larger (floatDown) or no smaller (floatUp) than x, at most
/// two float steps from it: x rounded to nearest (within half a step), then one step toward the
/// bound, always, which keeps the conversion free of data-dependent branches. Beyond float's
/// range: the step below the largest float, or infinity.
inline float floatStep(double x, bool up) {
  const float f = static_cast<float>(x < double(std::numeric_limits<float>::max())
                                         ? x
                                         : double(std::numeric_limits<float>::max()));
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  u = up ? u + 1 : u - (u != 0);  // the largest float steps up to infinity; 0 stays 0 (x >= 0)
  float r;
  std::memcpy(&r, &u, sizeof r);
  return r;
}
inline float floatDown(double x) { return floatStep(x, false); }
inline float floatUp(double x) { return floatStep(x, true); }

/// A box in a hash entry: float offsets from the grid origin (the low corner of the hash's
/// bounds, so offsets of boxes inside the bounds are >= 0), rounded outward. The offsets are
/// computed in double (rounded to nearest, which is monotone) and then rounded outward, so for
/// any double boxes q and e inside the bounds, q overlapping e implies entryBox(q) overlapping
/// entryBox(e): the compact test never drops a pair, it only admits a few more within float
/// rounding of the extent (the exact triangle test decides them). 24 bytes instead of 48.
struct EntryBox {
  float lo[3], hi[3];
};
inline EntryBox entryBox(const Aabb<double>& b, const double origin[3]) {
  EntryBox r;
  for (int a = 0; a < 3; ++a) {
    r.lo[a] = floatDown(b.lo[a] - origin[a]);
    r.hi[a] = floatUp(b.hi[a] - origin[a]);
  }
  return r;
}
/// Closed overlap, as boxesOverlap.
inline bool entryBoxesOverlap(const EntryBox& p, const EntryBox& q) {
  return p.lo[0] <= q.hi[0] && q.lo[0] <= p.hi[0] && p.lo[1] <= q.hi[1] && q.lo[1] <= p.hi[1] &&
         p.lo[2] <= q.hi[2] && q.lo[2] <= p.hi[2];
}

/// Owning CPU structure. Per triangle: box, enclosing diameter, level. Cells: an open-addressing
/// table of full 128-bit keys, each slot pointing at a contiguous run of `entries`, sorted by
/// decreasing diameter (ties: increasing id) inside a cell. Memory is linear in the triangle count.
/// The layout (slots, entries) is a function of the mesh alone, never of the thread count.
template <class S>
class HierarchicalHash {
 public:
  /// One (cell, triangle) entry. The triangle's box (compact: entryBox) and diameter are copied
  /// next to its id so that scanning a cell reads memory sequentially; 40 bytes.
  struct Entry {
    EntryBox box;
    double diameter;
    std::uint32_t id;
    /// Bit a set: this cell is the first of the triangle's cells along axis a. Then the
    /// canonical-cell test of a lookup (see scan.h) is three integer comparisons.
    std::uint8_t lo_mask;
  };

  struct Slot {
    CellKey key;
    std::uint32_t begin;
    std::uint32_t count;  // 0: empty slot (an occupied cell always holds a triangle)
  };

  /// Builds from a mesh's local coordinates (validated by the caller), on up to `threads` threads
  /// (0: all). On an exception (only std::bad_alloc, or InvalidInputError for a mesh too large for
  /// 32-bit entry indices) the object is left empty (and keeps its scratch buffers).
  void build(const std::vector<Vec3<S>>& vertices, const std::vector<Triangle>& triangles,
             int threads);
  void build(const TriangleMesh<S>& mesh, int threads) { build(mesh.vertices, mesh.triangles, threads); }

  /// The slot of a cell, or nullptr when the cell is empty. A cell's home slot is given by the
  /// high bits of hashCellKey(); the table is laid out by linear probing in increasing home order
  /// and ends in an overflow tail plus an empty sentinel slot, so probing runs forward without
  /// wrapping and always stops at an empty slot.
  const Slot* find(const CellKey& key) const {
    if (slots_.empty()) return nullptr;
    const Slot* s = slots_.data() + (hashCellKey(key) >> shift_);
    for (;; ++s) {
      if (s->count == 0) return nullptr;
      if (s->key == key) return s;
    }
  }

  std::size_t numTriangles() const { return diameter.size(); }
  bool empty() const { return diameter.empty(); }
  bool levelOccupied(int l) const { return (level_mask >> l) & 1u; }
  HierarchyStats stats() const;
  /// Bytes allocated by this structure.
  std::size_t memoryBytes() const;

  // Per triangle (local frame).
  std::vector<Aabb<double>> boxes;
  std::vector<double> diameter;
  std::vector<std::uint8_t> level;
  // The hierarchy.
  GridParams grid;
  Aabb<double> bounds{};   // box of all triangles
  std::uint64_t level_mask = 0;
  int top_level = 0;
  double d_min = 0, d_max = 0;
  std::vector<Entry> entries;

 private:
  /// One (cell, triangle) record of the build: the full key, the top 32 bits of its hash (the
  /// home slot is a prefix of them), the triangle and the bits of its diameter (a non-negative
  /// double: the bits order like the values).
  struct Rec {
    CellKey key;
    std::uint32_t h32;
    std::uint32_t tri;
    std::uint64_t dbits;
  };
  /// Per hash bucket (a fixed range of home slots): occupied cells, and the slot after the last
  /// one when the bucket starts empty (no overflow from the previous bucket).
  struct BucketInfo {
    std::uint32_t begin;  // first record of the bucket
    std::uint32_t cells;
    std::uint64_t end0;
    std::uint64_t write_begin;  // first slot this bucket writes (its start plus the overflow in)
  };
  void buildImpl(const std::vector<Vec3<S>>& vertices, const std::vector<Triangle>& triangles,
                 int threads);
  void clear();

  std::vector<Slot> slots_;  // capacity home slots, the overflow tail, one empty sentinel
  // Build scratch, kept so that rebuilding a deforming mesh reuses its memory.
  std::vector<Rec> scratch_rec_;
  std::vector<std::uint32_t> scratch_hist_, scratch_cell_;
  std::vector<BucketInfo> scratch_bucket_;
  unsigned shift_ = 64;  // home slot = hashCellKey(key) >> shift_ (capacity = 2^(64 - shift_))
  std::size_t cells_ = 0;
};

}  // namespace detail
}  // namespace kdet_fcl
