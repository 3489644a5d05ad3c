/// \file
/// kdet_fcl::CollisionManager: kDet's hierarchical hash over object AABBs (see collision_manager.h).

#include "kdet_fcl/collision_manager.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>
#include <unordered_map>
#include <utility>

#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/hierarchy.h"
#include "kdet_fcl/errors.h"

namespace kdet_fcl {
namespace {

using detail::Aabb;
using detail::CellKey;
using detail::CellRange;
using detail::GridParams;

/// Largest extent of a box over the three axes (the level rule's "size").
double maxExtent(const Aabb<double>& b) {
  return std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z});
}

double axisLo(const Aabb<double>& b, int a) { return a == 0 ? b.lo.x : a == 1 ? b.lo.y : b.lo.z; }
double axisHi(const Aabb<double>& b, int a) { return a == 0 ? b.hi.x : a == 1 ? b.hi.y : b.hi.z; }

/// Cells of a range as a double (a range of a far-away query may exceed 2^63 cells).
double cellCount(const CellRange& r) {
  return double(r.hi[0] - r.lo[0] + 1) * double(r.hi[1] - r.lo[1] + 1) *
         double(r.hi[2] - r.lo[2] + 1);
}

template <class S>
Aabb<double> toBox(const fcl::AABB<S>& a) {
  // float -> double is exact, so the grid and the overlap test see FCL's numbers.
  return {{double(a.min_[0]), double(a.min_[1]), double(a.min_[2])},
          {double(a.max_[0]), double(a.max_[1]), double(a.max_[2])}};
}

/// Whether a box goes into the hash: non-empty, finite and below FCL's "unbounded" sentinel
/// (fcl::Halfspace and fcl::Plane report +-numeric_limits<S>::max()). Others are "loose".
template <class S>
bool isHashable(const Aabb<double>& b) {
  const double huge = double(std::numeric_limits<S>::max()) * 0.5;
  for (int a = 0; a < 3; ++a) {
    const double lo = axisLo(b, a), hi = axisHi(b, a);
    if (!(lo <= hi)) return false;
    if (!(std::fabs(lo) < huge && std::fabs(hi) < huge)) return false;
  }
  return true;
}

template <class S>
const fcl::AABB<S>& checkedAabb(const fcl::CollisionObject<S>* obj, const char* where) {
  if (obj == nullptr)
    throw InvalidInputError(std::string("kdet_fcl::CollisionManager::") + where + ": null object");
  const fcl::AABB<S>& a = obj->getAABB();
  for (int i = 0; i < 3; ++i)
    if (std::isnan(a.min_[i]) || std::isnan(a.max_[i]))
      throw InvalidInputError(std::string("kdet_fcl::CollisionManager::") + where +
                              ": object has a NaN AABB (bad pose or geometry?)");
  return a;
}

/// Throws InvalidInputError for a null callback (FCL's managers call it unchecked and crash).
template <class Callback>
void requireCallback(Callback callback, const char* where) {
  if (callback == nullptr)
    throw InvalidInputError(std::string("kdet_fcl::CollisionManager::") + where +
                            ": null callback");
}

/// One box of a distance sweep.
template <class S>
struct SweepItem {
  S lo, hi;                  // the box's interval on the sweep axis
  const fcl::AABB<S>* box;   // the full box (FCL's AABB distance)
  fcl::CollisionObject<S>* obj;
  std::uint64_t order;       // tie-break and (self) argument order
  int side;                  // 0: this manager, 1: the other one
};

/// Calls cb for every pair of items (of different sides when `bipartite`) whose AABB distance is
/// below the running bound, in sweep order (items hold their interval on the sweep axis).
/// Returns true when cb asked to stop. Argument order: cb(a, b) with a.side == 0 (bipartite) or
/// a.order < b.order (self).
template <class S>
bool sweepDistance(std::vector<SweepItem<S>>& items, bool bipartite, void* cdata,
                   fcl::DistanceCallBack<S> callback, S& min_dist) {
  std::sort(items.begin(), items.end(), [](const SweepItem<S>& p, const SweepItem<S>& q) {
    return p.lo < q.lo || (p.lo == q.lo && (p.side < q.side || (p.side == q.side && p.order < q.order)));
  });
  const std::size_t n = items.size();
  for (std::size_t i = 0; i < n; ++i) {
    const SweepItem<S>& a = items[i];
    for (std::size_t j = i + 1; j < n; ++j) {
      const SweepItem<S>& b = items[j];
      // b.lo >= a.lo, so on this axis the boxes are apart by at least b.lo - a.hi, computed the
      // way fcl::AABB::distance computes it; its square is a term of that distance, so once the
      // gap reaches the bound every later item is out of reach too (unless the square underflows).
      const S gap = b.lo - a.hi;
      if (gap > 0 && gap >= min_dist && gap * gap > 0) break;
      if (bipartite && a.side == b.side) continue;
      const S d = a.box->distance(*b.box);
      if (!(d < min_dist)) continue;
      const bool a_first = bipartite ? a.side == 0 : a.order < b.order;
      const bool stop = a_first ? callback(a.obj, b.obj, cdata, min_dist)
                                : callback(b.obj, a.obj, cdata, min_dist);
      if (stop) return true;
    }
  }
  return false;
}

/// The axis along which the items' lower bounds spread most (the sweep prunes best there).
template <class S>
int widestAxis(const std::vector<const fcl::AABB<S>*>& boxes) {
  double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double hi[3] = {-lo[0], -lo[1], -lo[2]};
  for (const fcl::AABB<S>* b : boxes)
    for (int a = 0; a < 3; ++a) {
      const double v = double(b->min_[a]);
      if (std::isfinite(v)) {
        lo[a] = std::min(lo[a], v);
        hi[a] = std::max(hi[a], v);
      }
    }
  int best = 0;
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[best] - lo[best]) best = a;
  return best;
}

}  // namespace

template <class S>
struct CollisionManager<S>::Impl {
  using Obj = fcl::CollisionObject<S>;
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

  // ---- the objects (the source of truth; the frozen hash below is derived from them) ----

  struct Entry {
    Obj* obj = nullptr;                  ///< nullptr: a free slot
    std::uint64_t seq = 0;               ///< registration number: self-query argument order
    fcl::AABB<S> fbox;                   ///< the stored box, as FCL holds it (distance)
    Aabb<double> box;                    ///< the same box in double (grid, overlap test)
    std::uint32_t pending_pos = kNone;   ///< index in `pending`, or kNone
  };
  /// What a report needs of an object, packed (read once per reported pair).
  struct Meta {
    Obj* obj;
    std::uint64_t seq;
  };

  std::vector<Entry> slots;
  std::vector<Meta> meta;                 ///< per slot
  std::vector<std::uint32_t> free_slots;
  std::unordered_map<const Obj*, std::uint32_t> index;
  std::uint64_t next_seq = 0;

  // ---- the frozen hash: a snapshot of the objects at the last rebuild ----
  //
  // Objects changed since (registered, updated, unregistered) are taken out of it by clearing
  // their `valid` flag (their old entries are skipped) and, while live, kept in `pending`, which
  // every query tests directly. Once pending (plus half the stale objects) exceeds
  // rebuildThreshold(), the next query rebuilds the snapshot in O(n): update(obj) stays O(1) and
  // a burst of updates costs one rebuild.

  /// One (cell, object) entry; the box is copied next to the slot so that a cell scan reads
  /// memory sequentially.
  struct CellEntry {
    Aabb<double> box;
    std::uint32_t slot;
    /// Bit a set: this cell is the object's first cell along axis a. The canonical cell of an
    /// overlap is then found by integer tests (see queryFrozen).
    std::uint32_t lo_mask;
  };
  struct Cell {
    CellKey key;
    std::uint32_t begin;
    std::uint32_t count;  ///< 0: empty slot of the table
  };
  /// One hashed object, grouped by level (level scans and the self query's upward pass).
  struct Member {
    Aabb<double> box;
    std::uint32_t slot;
    std::uint32_t level;
  };

  GridParams grid;
  bool grid_valid = false;
  std::vector<Cell> table;  ///< open addressing, power-of-two capacity, full keys compared
  std::uint64_t table_mask = 0;
  std::vector<CellEntry> entries;         ///< contiguous per cell
  std::vector<Member> members;            ///< hashed objects sorted by level
  std::uint32_t level_begin[detail::kMaxLevels + 1] = {};
  std::uint64_t level_mask = 0;           ///< bit l: level l holds objects
  std::vector<std::uint32_t> frozen_loose;  ///< unbounded or empty boxes: tested against all
  std::vector<std::uint8_t> valid;        ///< per slot: its frozen entries are current
  std::size_t stale = 0;                  ///< frozen objects changed or removed since the build
  std::vector<std::uint32_t> pending;     ///< live objects that are not (validly) frozen
  bool force_rebuild = false;             ///< every box was re-read (update())

  std::atomic<bool> dirty{false};  ///< the next query rebuilds (const queries may run in parallel)
  std::mutex rebuild_mutex;

  std::size_t rebuildThreshold() const { return 16 + index.size() / 64; }

  void refreshDirty() {
    dirty.store(force_rebuild || pending.size() + stale / 2 > rebuildThreshold(),
                std::memory_order_release);
  }
  bool changedSinceBuild() const { return force_rebuild || !pending.empty() || stale > 0; }

  /// Brings the frozen hash up to date when too much changed. Queries are const; concurrent
  /// const queries are safe (the rebuild is locked), a query concurrent with a mutation is not
  /// (as with FCL's managers).
  void ensureFresh() const {
    if (!dirty.load(std::memory_order_acquire)) return;
    Impl& self = const_cast<Impl&>(*this);  // impl_ is never a const object
    std::lock_guard<std::mutex> lock(self.rebuild_mutex);
    if (!dirty.load(std::memory_order_relaxed)) return;
    self.rebuild();
    self.dirty.store(false, std::memory_order_release);
  }

  // ---- changes (O(1)) ----

  void setBox(Entry& e, const fcl::AABB<S>& a) {
    e.fbox = a;
    e.box = toBox(a);
  }

  /// Marks a live slot changed: out of the snapshot, into pending.
  void markChanged(std::uint32_t s) {
    if (valid[s]) {
      valid[s] = 0;
      ++stale;
    }
    Entry& e = slots[s];
    if (e.pending_pos == kNone) {
      e.pending_pos = std::uint32_t(pending.size());
      pending.push_back(s);
    }
  }

  void removePending(std::uint32_t s) {
    Entry& e = slots[s];
    if (e.pending_pos == kNone) return;
    const std::uint32_t last = pending.back();
    pending[e.pending_pos] = last;
    slots[last].pending_pos = e.pending_pos;
    pending.pop_back();
    e.pending_pos = kNone;
  }

  /// Adds an object whose box was validated (pending until the next rebuild).
  std::uint32_t addEntry(Obj* obj, const fcl::AABB<S>& a) {
    std::uint32_t s;
    if (!free_slots.empty()) {
      s = free_slots.back();
      free_slots.pop_back();
    } else {
      s = std::uint32_t(slots.size());
      slots.emplace_back();
      meta.push_back({nullptr, 0});
      valid.push_back(0);
    }
    Entry& e = slots[s];
    e.obj = obj;
    e.seq = next_seq++;
    e.pending_pos = kNone;
    meta[s] = {obj, e.seq};
    setBox(e, a);
    index.emplace(obj, s);
    markChanged(s);  // a reused slot's old entries are invalid already
    return s;
  }

  void removeSlot(std::uint32_t s) {
    if (valid[s]) {
      valid[s] = 0;
      ++stale;
    }
    removePending(s);
    slots[s].obj = nullptr;
    meta[s] = {nullptr, 0};
    free_slots.push_back(s);
  }

  void reset() {
    slots.clear();
    meta.clear();
    free_slots.clear();
    index.clear();
    table.clear();
    table_mask = 0;
    entries.clear();
    members.clear();
    std::fill(std::begin(level_begin), std::end(level_begin), 0u);
    level_mask = 0;
    frozen_loose.clear();
    valid.clear();
    stale = 0;
    pending.clear();
    force_rebuild = false;
    grid_valid = false;
    dirty.store(false, std::memory_order_release);
  }

  // ---- the O(n) rebuild ----

  const Cell* findCell(const CellKey& key) const {
    std::uint64_t i = detail::hashCellKey(key) & table_mask;
    while (true) {
      const Cell& c = table[i];
      if (c.count == 0) return nullptr;
      if (c.key == key) return &c;
      i = (i + 1) & table_mask;
    }
  }

  /// Derives the grid from the current boxes and builds the hash of every live object.
  ///
  /// The level-0 cell is the smallest positive box extent (kDet's rule), but no smaller than
  /// 2^-kCellRange of the scene, so cell coordinates fit the key. Grid parameters matter for speed
  /// only: cell coordinates are monotone (and clamped monotonically), which is all the
  /// canonical-cell rule needs for exactness.
  void rebuild() {
    for (std::uint32_t s : pending) slots[s].pending_pos = kNone;
    pending.clear();
    stale = 0;
    force_rebuild = false;
    std::fill(valid.begin(), valid.end(), std::uint8_t(0));
    members.clear();
    frozen_loose.clear();
    entries.clear();
    level_mask = 0;
    std::fill(std::begin(level_begin), std::end(level_begin), 0u);

    const double inf = std::numeric_limits<double>::infinity();
    double lo[3] = {inf, inf, inf}, hi[3] = {-inf, -inf, -inf};
    double min_ext = inf;
    std::size_t hashable = 0;
    for (std::uint32_t s = 0; s < slots.size(); ++s) {
      const Entry& e = slots[s];
      if (e.obj == nullptr) continue;
      valid[s] = 1;
      if (!isHashable<S>(e.box)) {
        frozen_loose.push_back(s);
        continue;
      }
      ++hashable;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], axisLo(e.box, a));
        hi[a] = std::max(hi[a], axisHi(e.box, a));
      }
      const double ext = maxExtent(e.box);
      if (ext > 0) min_ext = std::min(min_ext, ext);
    }
    grid_valid = hashable > 0;
    if (!grid_valid) {
      table.clear();
      table_mask = 0;
      return;
    }
    double span = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    if (!(span > 0)) {
      double maxabs = 1;
      for (int a = 0; a < 3; ++a) maxabs = std::max({maxabs, std::fabs(lo[a]), std::fabs(hi[a])});
      span = maxabs;
    }
    const double min_cell0 = std::ldexp(span, -detail::kCellRange);
    double cell0 = min_ext < inf ? min_ext : span / 1024;
    cell0 = std::max(cell0, min_cell0);
    grid.num_levels = detail::kMaxLevels;
    grid.cell0 = cell0;
    grid.inv_cell0 = 1 / cell0;
    for (int a = 0; a < 3; ++a) grid.origin[a] = lo[a];

    // Levels, then the objects grouped by level (a counting sort keeps slot order inside one).
    std::uint32_t count[detail::kMaxLevels] = {};
    std::vector<std::uint8_t> level_of(slots.size(), 0);
    for (std::uint32_t s = 0; s < slots.size(); ++s) {
      const Entry& e = slots[s];
      if (e.obj == nullptr || !isHashable<S>(e.box)) continue;
      const int l = levelOf(e.box);
      level_of[s] = std::uint8_t(l);
      ++count[l];
      level_mask |= std::uint64_t(1) << l;
    }
    for (int l = 0; l < detail::kMaxLevels; ++l) level_begin[l + 1] = level_begin[l] + count[l];
    members.resize(hashable);
    {
      std::uint32_t fill[detail::kMaxLevels];
      std::copy(level_begin, level_begin + detail::kMaxLevels, fill);
      for (std::uint32_t s = 0; s < slots.size(); ++s) {
        const Entry& e = slots[s];
        if (e.obj == nullptr || !isHashable<S>(e.box)) continue;
        members[fill[level_of[s]]++] = {e.box, s, level_of[s]};
      }
    }

    // Cells: count the entries, size the table, insert the keys, then place the entries.
    std::uint64_t total = 0;
    for (const Member& m : members) total += std::uint64_t(cellCount(detail::cellRange(m.box, int(m.level), grid)));
    if (total >= std::numeric_limits<std::uint32_t>::max())
      throw InvalidInputError("kdet_fcl::CollisionManager: too many objects for the hash");
    std::uint64_t capacity = 16;
    while (capacity < total + total / 2) capacity <<= 1;
    table.assign(capacity, Cell{{0, 0}, 0, 0});
    table_mask = capacity - 1;
    std::vector<std::uint32_t> entry_cell(total);
    std::vector<std::uint8_t> entry_mask(total);
    std::uint64_t k = 0;
    for (const Member& m : members) {
      const CellRange r = detail::cellRange(m.box, int(m.level), grid);
      for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
        for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
          for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
            const CellKey key = detail::makeCellKey(int(m.level), x, y, z);
            std::uint64_t i = detail::hashCellKey(key) & table_mask;
            while (table[i].count != 0 && !(table[i].key == key)) i = (i + 1) & table_mask;
            table[i].key = key;
            ++table[i].count;
            entry_cell[k] = std::uint32_t(i);
            entry_mask[k++] = std::uint8_t((x == r.lo[0] ? 1 : 0) | (y == r.lo[1] ? 2 : 0) |
                                           (z == r.lo[2] ? 4 : 0));
          }
    }
    std::uint32_t running = 0;
    for (Cell& c : table) {
      c.begin = running;
      running += c.count;
      c.count = 0;  // refilled below
    }
    entries.resize(total);
    k = 0;
    for (const Member& m : members) {
      const CellRange r = detail::cellRange(m.box, int(m.level), grid);
      const std::uint64_t n = std::uint64_t(cellCount(r));
      for (std::uint64_t j = 0; j < n; ++j, ++k) {
        Cell& c = table[entry_cell[k]];
        entries[c.begin + c.count++] = {m.box, m.slot, entry_mask[k]};
      }
    }
  }

  // ---- queries ----

  /// The level of a box: the finest whose cells are at least half its largest extent, so it
  /// covers at most 3 cells per axis there. Half-size cells (rather than kDet's full-size ones)
  /// make a coarse cell hold fewer non-overlapping neighbours: on 10k boxes over two orders of
  /// magnitude, self collide examines about 3x fewer candidates for about 2.5x the entries.
  int levelOf(const Aabb<double>& b) const { return detail::levelFor(maxExtent(b) * 0.5, grid); }

  bool isValid(std::uint32_t s) const { return valid[s] != 0; }

  /// Calls f(slot) for every valid entry on level l whose box overlaps q, seen only from the
  /// canonical cell of the overlap (r: q's cell range on l). The canonical cell holds the
  /// overlap's minimum corner; cell coordinates are monotone, so on each axis it is max(query's
  /// first cell, entry's first cell): this cell iff on every axis it is the entry's first cell or
  /// the query's. Stops and returns true when f does.
  template <class F>
  bool walkCanonical(const Aabb<double>& q, int l, const CellRange& r, bool check, F&& f) const {
    for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
      for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
        for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
          const Cell* c = findCell(detail::makeCellKey(l, x, y, z));
          if (c == nullptr) continue;
          const std::uint32_t need =
              (x == r.lo[0] ? 0u : 1u) | (y == r.lo[1] ? 0u : 2u) | (z == r.lo[2] ? 0u : 4u);
          const CellEntry* ce = entries.data() + c->begin;
          for (std::uint32_t j = 0; j < c->count; ++j) {
            const CellEntry& en = ce[j];
            if ((en.lo_mask & need) != need) continue;
            if (!detail::boxesOverlap(en.box, q)) continue;
            if (check && !isValid(en.slot)) continue;
            if (f(en.slot)) return true;
          }
        }
    return false;
  }

  /// Calls f(slot) once for every frozen, valid object whose box overlaps q (closed); stops and
  /// returns true when f does.
  template <class F>
  bool queryFrozen(const Aabb<double>& q, F&& f) const {
    const bool check = stale > 0;
    if (grid_valid && isHashable<S>(q)) {
      const int lq = levelOf(q);
      for (std::uint64_t lm = level_mask; lm != 0; lm &= lm - 1) {
        const int l = __builtin_ctzll(lm);
        const CellRange r = detail::cellRange(q, l, grid);
        if (l < lq) {
          // On finer levels than its own the query covers many cells: visit whichever is
          // cheaper, the cells (a hash probe each) or the level's objects (a box test each).
          const std::uint32_t b = level_begin[l], e = level_begin[l + 1];
          if (4 * cellCount(r) > double(e - b)) {
            for (std::uint32_t i = b; i < e; ++i) {
              const Member& m = members[i];
              if (detail::boxesOverlap(m.box, q) && (!check || isValid(m.slot)) && f(m.slot))
                return true;
            }
            continue;
          }
        }
        if (walkCanonical(q, l, r, check, f)) return true;
      }
    } else {
      for (const Member& m : members)
        if (detail::boxesOverlap(m.box, q) && (!check || isValid(m.slot)) && f(m.slot))
          return true;
    }
    for (std::uint32_t s : frozen_loose)
      if ((!check || isValid(s)) && detail::boxesOverlap(slots[s].box, q) && f(s)) return true;
    return false;
  }

  /// Calls f(slot) once for every stored object whose box overlaps q (closed).
  template <class F>
  bool queryBox(const Aabb<double>& q, F&& f) const {
    if (queryFrozen(q, f)) return true;
    for (std::uint32_t s : pending)
      if (detail::boxesOverlap(slots[s].box, q) && f(s)) return true;
    return false;
  }

  bool reportSelf(std::uint32_t a, std::uint32_t b, void* cdata,
                  fcl::CollisionCallBack<S> callback) const {
    const Meta& A = meta[a];
    const Meta& B = meta[b];
    return A.seq < B.seq ? callback(A.obj, B.obj, cdata) : callback(B.obj, A.obj, cdata);
  }

  /// All overlapping pairs once. Frozen pairs are examined in the canonical cell of the two boxes'
  /// overlap on the coarser object's level: pairs of one level inside each cell, pairs of
  /// different levels by the finer object probing the coarser occupied levels. Loose objects meet
  /// everything; pending objects query the frozen hash and each other.
  bool selfCollide(void* cdata, fcl::CollisionCallBack<S> callback) const {
    const bool check = stale > 0;
    // Same level: the pairs inside each cell.
    for (const Cell& c : table) {
      if (c.count < 2) continue;
      const CellEntry* ce = entries.data() + c.begin;
      for (std::uint32_t i = 0; i + 1 < c.count; ++i) {
        const CellEntry& A = ce[i];
        if (check && !isValid(A.slot)) continue;
        for (std::uint32_t j = i + 1; j < c.count; ++j) {
          const CellEntry& B = ce[j];
          if (((A.lo_mask | B.lo_mask) & 7u) != 7u) continue;
          if (!detail::boxesOverlap(A.box, B.box)) continue;
          if (check && !isValid(B.slot)) continue;
          if (reportSelf(A.slot, B.slot, cdata, callback)) return true;
        }
      }
    }
    // Different levels: each object probes its cells on every coarser occupied level.
    for (const Member& A : members) {
      const std::uint64_t above = level_mask & ~((std::uint64_t(2) << A.level) - 1);
      if (above == 0) continue;
      if (check && !isValid(A.slot)) continue;
      for (std::uint64_t lm = above; lm != 0; lm &= lm - 1) {
        const int l = __builtin_ctzll(lm);
        const CellRange r = detail::cellRange(A.box, l, grid);
        if (walkCanonical(A.box, l, r, check, [&](std::uint32_t b) {
              return reportSelf(A.slot, b, cdata, callback);
            }))
          return true;
      }
    }
    // Frozen loose objects against every frozen object; two loose ones once.
    for (std::size_t i = 0; i < frozen_loose.size(); ++i) {
      const std::uint32_t u = frozen_loose[i];
      if (check && !isValid(u)) continue;
      const Aabb<double>& U = slots[u].box;
      for (const Member& B : members)
        if (detail::boxesOverlap(U, B.box) && (!check || isValid(B.slot)) &&
            reportSelf(u, B.slot, cdata, callback))
          return true;
      for (std::size_t j = i + 1; j < frozen_loose.size(); ++j) {
        const std::uint32_t v = frozen_loose[j];
        if (detail::boxesOverlap(U, slots[v].box) && (!check || isValid(v)) &&
            reportSelf(u, v, cdata, callback))
          return true;
      }
    }
    // Pending objects against the frozen ones and against each other.
    for (std::size_t i = 0; i < pending.size(); ++i) {
      const std::uint32_t p = pending[i];
      const Aabb<double>& P = slots[p].box;
      if (queryFrozen(P, [&](std::uint32_t b) { return reportSelf(p, b, cdata, callback); }))
        return true;
      for (std::size_t j = i + 1; j < pending.size(); ++j) {
        const std::uint32_t q = pending[j];
        if (detail::boxesOverlap(P, slots[q].box) && reportSelf(p, q, cdata, callback)) return true;
      }
    }
    return false;
  }

  /// Live slots in registration order.
  std::vector<std::uint32_t> liveSlots() const {
    std::vector<std::uint32_t> v;
    v.reserve(index.size());
    for (std::uint32_t s = 0; s < slots.size(); ++s)
      if (slots[s].obj != nullptr) v.push_back(s);
    std::sort(v.begin(), v.end(),
              [this](std::uint32_t p, std::uint32_t q) { return slots[p].seq < slots[q].seq; });
    return v;
  }
};

template <class S>
CollisionManager<S>::CollisionManager() : impl_(new Impl) {}

template <class S>
CollisionManager<S>::~CollisionManager() = default;

template <class S>
void CollisionManager<S>::registerObjects(const std::vector<fcl::CollisionObject<S>*>& other_objs) {
  if (other_objs.empty()) return;
  Impl& m = *impl_;
  for (fcl::CollisionObject<S>* o : other_objs) checkedAabb(o, "registerObjects");
  // An object already managed (or listed twice) just gets a new box. A large batch makes the
  // next query rebuild the hash once.
  for (fcl::CollisionObject<S>* o : other_objs) {
    auto it = m.index.find(o);
    if (it == m.index.end()) {
      m.addEntry(o, o->getAABB());
    } else {
      m.setBox(m.slots[it->second], o->getAABB());
      m.markChanged(it->second);
    }
  }
  m.refreshDirty();
}

template <class S>
void CollisionManager<S>::registerObject(fcl::CollisionObject<S>* obj) {
  const fcl::AABB<S>& a = checkedAabb(obj, "registerObject");
  Impl& m = *impl_;
  auto it = m.index.find(obj);
  if (it != m.index.end()) {
    update(obj);
    return;
  }
  m.addEntry(obj, a);
  m.refreshDirty();
}

template <class S>
void CollisionManager<S>::unregisterObject(fcl::CollisionObject<S>* obj) {
  Impl& m = *impl_;
  auto it = m.index.find(obj);
  if (it == m.index.end()) return;
  m.removeSlot(it->second);
  m.index.erase(it);
  if (m.index.empty())
    m.reset();
  else
    m.refreshDirty();
}

template <class S>
void CollisionManager<S>::setup() {
  Impl& m = *impl_;
  if (!m.index.empty() && m.changedSinceBuild()) {
    m.rebuild();
    m.dirty.store(false, std::memory_order_release);
  }
}

template <class S>
void CollisionManager<S>::update() {
  Impl& m = *impl_;
  for (const auto& e : m.slots)
    if (e.obj != nullptr) checkedAabb(e.obj, "update");
  for (auto& e : m.slots)
    if (e.obj != nullptr) m.setBox(e, e.obj->getAABB());
  if (m.index.empty()) return;
  m.force_rebuild = true;  // the next query rebuilds once
  m.refreshDirty();
}

template <class S>
void CollisionManager<S>::update(fcl::CollisionObject<S>* updated_obj) {
  Impl& m = *impl_;
  auto it = m.index.find(updated_obj);
  if (it == m.index.end()) return;
  const fcl::AABB<S>& a = checkedAabb(updated_obj, "update");
  const std::uint32_t s = it->second;
  typename Impl::Entry& e = m.slots[s];
  if (e.fbox.min_ == a.min_ && e.fbox.max_ == a.max_) return;
  m.setBox(e, a);
  if (!m.force_rebuild) {
    m.markChanged(s);
    m.refreshDirty();
  }
}

template <class S>
void CollisionManager<S>::update(const std::vector<fcl::CollisionObject<S>*>& updated_objs) {
  Impl& m = *impl_;
  for (fcl::CollisionObject<S>* o : updated_objs)
    if (m.index.count(o) != 0) checkedAabb(o, "update");
  for (fcl::CollisionObject<S>* o : updated_objs) update(o);
}

template <class S>
void CollisionManager<S>::clear() {
  impl_->reset();
}

template <class S>
void CollisionManager<S>::getObjects(std::vector<fcl::CollisionObject<S>*>& objs) const {
  const std::vector<std::uint32_t> live = impl_->liveSlots();
  objs.resize(live.size());
  for (std::size_t i = 0; i < live.size(); ++i) objs[i] = impl_->slots[live[i]].obj;
}

template <class S>
void CollisionManager<S>::collide(fcl::CollisionObject<S>* obj, void* cdata,
                                  fcl::CollisionCallBack<S> callback) const {
  requireCallback(callback, "collide");
  const Impl& m = *impl_;
  const Aabb<double> q = toBox(checkedAabb(obj, "collide"));
  if (m.index.empty()) return;
  m.ensureFresh();
  m.queryBox(q, [&](std::uint32_t b) { return callback(m.meta[b].obj, obj, cdata); });
}

template <class S>
void CollisionManager<S>::collide(void* cdata, fcl::CollisionCallBack<S> callback) const {
  requireCallback(callback, "collide");
  if (impl_->index.size() < 2) return;
  impl_->ensureFresh();
  impl_->selfCollide(cdata, callback);
}

template <class S>
void CollisionManager<S>::collide(fcl::BroadPhaseCollisionManager<S>* other_manager, void* cdata,
                                  fcl::CollisionCallBack<S> callback) const {
  requireCallback(callback, "collide");
  const Impl& m = *impl_;
  if (other_manager == nullptr) return;
  if (other_manager == this) {
    collide(cdata, callback);
    return;
  }
  if (const auto* ours = dynamic_cast<const CollisionManager<S>*>(other_manager)) {
    // Fast path: the smaller manager's stored boxes query the larger one's hash.
    const Impl& o = *ours->impl_;
    if (m.index.empty() || o.index.empty()) return;
    if (o.index.size() <= m.index.size()) {
      m.ensureFresh();
      for (std::uint32_t s = 0; s < o.slots.size(); ++s) {
        fcl::CollisionObject<S>* theirs = o.slots[s].obj;
        if (theirs == nullptr) continue;
        if (m.queryBox(o.slots[s].box,
                       [&](std::uint32_t b) { return callback(m.meta[b].obj, theirs, cdata); }))
          return;
      }
    } else {
      o.ensureFresh();
      for (std::uint32_t s = 0; s < m.slots.size(); ++s) {
        fcl::CollisionObject<S>* mine = m.slots[s].obj;
        if (mine == nullptr) continue;
        if (o.queryBox(m.slots[s].box,
                       [&](std::uint32_t b) { return callback(mine, o.meta[b].obj, cdata); }))
          return;
      }
    }
    return;
  }
  std::vector<fcl::CollisionObject<S>*> theirs;
  other_manager->getObjects(theirs);
  for (fcl::CollisionObject<S>* q : theirs) checkedAabb(q, "collide(other manager)");
  if (m.index.empty()) return;
  m.ensureFresh();
  for (fcl::CollisionObject<S>* q : theirs)
    if (m.queryBox(toBox(q->getAABB()),
                   [&](std::uint32_t b) { return callback(m.meta[b].obj, q, cdata); }))
      return;
}

template <class S>
void CollisionManager<S>::distance(fcl::CollisionObject<S>* obj, void* cdata,
                                   fcl::DistanceCallBack<S> callback) const {
  requireCallback(callback, "distance");
  const Impl& m = *impl_;
  const fcl::AABB<S>& q = checkedAabb(obj, "distance");
  if (m.index.empty()) return;
  // Every candidate, nearest box first: a callback that lowers `dist` prunes the rest at once.
  std::vector<std::pair<S, std::uint32_t>> order;
  order.reserve(m.index.size());
  for (std::uint32_t s = 0; s < m.slots.size(); ++s)
    if (m.slots[s].obj != nullptr) order.emplace_back(m.slots[s].fbox.distance(q), s);
  std::sort(order.begin(), order.end(), [&m](const auto& p, const auto& r) {
    return p.first < r.first || (p.first == r.first && m.slots[p.second].seq < m.slots[r.second].seq);
  });
  S min_dist = std::numeric_limits<S>::max();
  for (const auto& [d, s] : order) {
    if (!(d < min_dist)) break;
    if (callback(m.slots[s].obj, obj, cdata, min_dist)) return;
  }
}

template <class S>
void CollisionManager<S>::distance(void* cdata, fcl::DistanceCallBack<S> callback) const {
  requireCallback(callback, "distance");
  const Impl& m = *impl_;
  if (m.index.size() < 2) return;
  std::vector<const fcl::AABB<S>*> boxes;
  for (const auto& e : m.slots)
    if (e.obj != nullptr) boxes.push_back(&e.fbox);
  const int axis = widestAxis<S>(boxes);
  std::vector<SweepItem<S>> items;
  items.reserve(boxes.size());
  for (const auto& e : m.slots)
    if (e.obj != nullptr)
      items.push_back({e.fbox.min_[axis], e.fbox.max_[axis], &e.fbox, e.obj, e.seq, 0});
  S min_dist = std::numeric_limits<S>::max();
  sweepDistance<S>(items, false, cdata, callback, min_dist);
}

template <class S>
void CollisionManager<S>::distance(fcl::BroadPhaseCollisionManager<S>* other_manager, void* cdata,
                                   fcl::DistanceCallBack<S> callback) const {
  requireCallback(callback, "distance");
  const Impl& m = *impl_;
  if (other_manager == nullptr) return;
  if (other_manager == this) {
    distance(cdata, callback);
    return;
  }
  std::vector<fcl::CollisionObject<S>*> theirs;
  other_manager->getObjects(theirs);
  for (fcl::CollisionObject<S>* q : theirs) checkedAabb(q, "distance(other manager)");
  if (m.index.empty() || theirs.empty()) return;
  std::vector<const fcl::AABB<S>*> boxes;
  for (const auto& e : m.slots)
    if (e.obj != nullptr) boxes.push_back(&e.fbox);
  for (fcl::CollisionObject<S>* q : theirs) boxes.push_back(&q->getAABB());
  const int axis = widestAxis<S>(boxes);
  std::vector<SweepItem<S>> items;
  items.reserve(boxes.size());
  for (const auto& e : m.slots)
    if (e.obj != nullptr)
      items.push_back({e.fbox.min_[axis], e.fbox.max_[axis], &e.fbox, e.obj, e.seq, 0});
  for (std::size_t i = 0; i < theirs.size(); ++i) {
    const fcl::AABB<S>& b = theirs[i]->getAABB();
    items.push_back({b.min_[axis], b.max_[axis], &b, theirs[i], std::uint64_t(i), 1});
  }
  S min_dist = std::numeric_limits<S>::max();
  sweepDistance<S>(items, true, cdata, callback, min_dist);
}

template <class S>
bool CollisionManager<S>::empty() const {
  return impl_->index.empty();
}

template <class S>
size_t CollisionManager<S>::size() const {
  return impl_->index.size();
}

template class CollisionManager<float>;
template class CollisionManager<double>;

}  // namespace kdet_fcl
