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

/// Owning CPU structure. Per triangle: box, enclosing diameter, level. Cells: open-addressing
/// tables of full 128-bit keys, each slot pointing at a contiguous run of entries, sorted by
/// decreasing diameter (ties: increasing id) inside a cell. Memory is linear in the triangle count.
/// The layout (slots, entries) is a function of the mesh and the levels built, never of the
/// thread count.
///
/// The cell tables are built only for the levels that lookups will visit ("pay for what a query
/// asks"): a lookup by a triangle of diameter d visits levelFor(d) and the coarser levels, so a
/// query whose lookups all come from triangles at least d_lookup wide needs the cells of levels
/// >= levelFor(d_lookup) only (an inter-object query against a mesh of larger triangles: the
/// draped cloth against the sphere needs 1-8 % of the cloth's entries). At most two tables: the
/// first one built covers levels [split, top]; a later request below `split` adds the second,
/// levels [0, split), without touching the first, so readers of the first are undisturbed.
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
    /// canonical-cell test of a lookup (see scan.h) is one mask test.
    std::uint8_t lo_mask;
  };

  struct Slot {
    CellKey key;
    std::uint32_t begin;  // first entry of the cell in its table's entries
    std::uint32_t count;  // 0: empty slot (an occupied cell always holds a triangle)
  };

  /// One open-addressing table: a cell's home slot is given by the high bits of hashCellKey();
  /// the table is laid out by linear probing in increasing home order and ends in an overflow
  /// tail plus an empty sentinel slot, so probing runs forward without wrapping and always stops
  /// at an empty slot.
  struct Table {
    std::vector<Slot> slots;  // home slots, the overflow tail, one empty sentinel
    std::vector<Entry> entries;
    unsigned shift = 64;  // home slot = hashCellKey(key) >> shift (capacity = 2^(64 - shift))
    std::size_t cells = 0;
    const Slot* find(const CellKey& key) const {
      if (slots.empty()) return nullptr;
      const Slot* s = slots.data() + (hashCellKey(key) >> shift);
      for (;; ++s) {
        if (s->count == 0) return nullptr;
        if (s->key == key) return s;
      }
    }
    void clear() {
      slots.clear();
      entries.clear();
      shift = 64;
      cells = 0;
    }
  };

  /// "No level": what coveredFrom() returns while no cell table is built.
  static constexpr int kNoTable = kMaxLevels;

  /// Builds from a mesh's local coordinates (validated by the caller), on up to `threads` threads
  /// (0: all): the per-triangle data and the cell tables of levels >= from_level (every level:
  /// 0; none: kNoTable). On an exception (only std::bad_alloc, or InvalidInputError for a mesh
  /// too large for 32-bit entry indices) the object is left empty (and keeps its scratch
  /// buffers).
  void build(const std::vector<Vec3<S>>& vertices, const std::vector<Triangle>& triangles,
             int threads, int from_level = 0);
  void build(const TriangleMesh<S>& mesh, int threads) { build(mesh.vertices, mesh.triangles, threads); }

  /// Adds the cell tables that levels >= from_level still lack (nothing if coveredFrom() <=
  /// from_level). Same mesh as the last build; the tables built before are not modified, so
  /// lookups on the levels they cover may run concurrently. Same exceptions as build(); on one,
  /// the structure is left as it was.
  void cover(int from_level, int threads);

  /// The lowest level whose cells are in a table (levels above it are too); kNoTable if none.
  int coveredFrom() const { return covered_from_; }

  /// The table holding level `level`'s cells (the level must be covered). A lookup takes it
  /// once per level.
  const Table& table(int level) const { return level >= split_ ? upper_ : lower_; }
  /// The slot of a cell, or nullptr when the cell is empty. The cell's level must be covered.
  const Slot* find(const CellKey& key) const { return table(levelOfKey(key)).find(key); }
  /// The entries a slot of a level-`level` cell points into.
  const Entry* entriesOf(int level) const { return table(level).entries.data(); }

  std::size_t numTriangles() const { return diameter.size(); }
  bool empty() const { return diameter.empty(); }
  bool levelOccupied(int l) const { return (level_mask >> l) & 1u; }
  /// Entries in the tables built so far.
  std::size_t numEntries() const { return upper_.entries.size() + lower_.entries.size(); }
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
  std::uint64_t level_mask = 0;  // bit l: level l holds triangles (its table built or not)
  int top_level = 0;
  double d_min = 0, d_max = 0;  // smallest positive and largest diameter
  double d_smallest = 0;        // smallest diameter (0 when a triangle is a point)

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
  static int levelOfKey(const CellKey& key) { return int(key.hi >> 56); }
  void perTriangle(const std::vector<Vec3<S>>& vertices, const std::vector<Triangle>& triangles,
                   int threads);
  /// The table of the triangles on levels [lo, hi].
  void buildTable(Table& out, int lo, int hi, int threads);
  void clear();

  Table upper_;  // levels [split_, top]
  Table lower_;  // levels [0, split_), built after upper_ when a lookup needs them
  int split_ = 0;
  int covered_from_ = kNoTable;
  // Build scratch, kept so that rebuilding a deforming mesh reuses its memory.
  std::vector<Rec> scratch_rec_;
  std::vector<std::uint32_t> scratch_hist_, scratch_cell_;
  std::vector<BucketInfo> scratch_bucket_;
};

}  // namespace detail
}  // namespace kdet_fcl
