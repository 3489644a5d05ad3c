/// \file
/// kdet_fcl::CollisionManager: kDet's hierarchical hash over object AABBs (see collision_manager.h).

#include "kdet_fcl/collision_manager.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
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

struct CellKeyHash {
  std::size_t operator()(const CellKey& k) const { return std::size_t(detail::hashCellKey(k)); }
};

/// The cell coordinates of a key (the inverse of detail::makeCellKey's packing).
void decodeCellKey(const CellKey& k, std::int64_t c[3]) {
  constexpr std::uint64_t kMask = (std::uint64_t(1) << detail::kCellBits) - 1;
  c[0] = std::int64_t((k.hi >> 16) & kMask);
  c[1] = std::int64_t(((k.hi & 0xFFFFull) << 24) | (k.lo >> 40));
  c[2] = std::int64_t(k.lo & kMask);
}

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
  static constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;

  struct Entry {
    Obj* obj = nullptr;          ///< nullptr: a free slot
    std::uint64_t seq = 0;       ///< registration number: self-query order and same-level tie-break
    fcl::AABB<S> fbox;           ///< the stored box, as FCL holds it (distance)
    Aabb<double> box;            ///< the same box in double (grid, overlap test)
    int level = -1;              ///< hash level; -1: in the loose list
    std::uint32_t list_pos = 0;  ///< index in level_members[level] or in loose
    bool placed = false;         ///< in a list (and its cells) now
  };

  std::vector<Entry> slots;
  std::vector<std::uint32_t> free_slots;
  std::unordered_map<const Obj*, std::uint32_t> index;
  std::uint64_t next_seq = 0;

  // The grid. Its parameters matter for speed only: cell coordinates are monotone (and clamped
  // monotonically), which is all the canonical-cell rule needs for exactness.
  GridParams grid;
  bool grid_valid = false;
  bool changed_since_rebuild = false;  ///< setup() re-derives the grid only after changes
  double grid_upper[3] = {0, 0, 0};  ///< coordinates above these would be clamped
  double min_cell0 = 0;              ///< the smallest level-0 cell the range allows
  std::unordered_map<CellKey, std::vector<std::uint32_t>, CellKeyHash> cells;
  std::vector<std::uint32_t> level_members[detail::kMaxLevels];
  std::vector<std::uint32_t> loose;  ///< unbounded or empty boxes: tested against everything

  // ---- grid maintenance ----

  bool needsRebuild(const Aabb<double>& b) const {
    if (!grid_valid) return true;
    for (int a = 0; a < 3; ++a)
      if (axisLo(b, a) < grid.origin[a] || axisHi(b, a) > grid_upper[a]) return true;
    const double ext = maxExtent(b);
    // Much smaller than a level-0 cell: many such objects would crowd one cell.
    return ext > 0 && ext < 0.5 * grid.cell0 && grid.cell0 > min_cell0;
  }

  void cellsOf(const Entry& e, CellRange& r) const { r = detail::cellRange(e.box, e.level, grid); }

  void insertEntry(std::uint32_t s) {
    Entry& e = slots[s];
    e.placed = true;
    changed_since_rebuild = true;
    if (!grid_valid || !isHashable<S>(e.box)) {
      e.level = -1;
      e.list_pos = std::uint32_t(loose.size());
      loose.push_back(s);
      return;
    }
    e.level = detail::levelFor(maxExtent(e.box), grid);
    std::vector<std::uint32_t>& members = level_members[e.level];
    e.list_pos = std::uint32_t(members.size());
    members.push_back(s);
    CellRange r;
    cellsOf(e, r);
    for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
      for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
        for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z)
          cells[detail::makeCellKey(e.level, x, y, z)].push_back(s);
  }

  void removeEntry(std::uint32_t s) {
    Entry& e = slots[s];
    if (!e.placed) return;
    e.placed = false;
    changed_since_rebuild = true;
    std::vector<std::uint32_t>& list = e.level < 0 ? loose : level_members[e.level];
    const std::uint32_t last = list.back();
    list[e.list_pos] = last;
    slots[last].list_pos = e.list_pos;
    list.pop_back();
    if (e.level < 0) return;
    CellRange r;
    cellsOf(e, r);
    for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
      for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
        for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
          auto it = cells.find(detail::makeCellKey(e.level, x, y, z));
          std::vector<std::uint32_t>& v = it->second;
          *std::find(v.begin(), v.end(), s) = v.back();
          v.pop_back();
          if (v.empty()) cells.erase(it);
        }
  }

  /// Derives the grid from the stored boxes and re-inserts everything. O(n).
  ///
  /// The level-0 cell is the smallest positive box extent (kDet's rule), the origin lies one
  /// scene span below the boxes' minimum, and the range reaches at least one span above their
  /// maximum, so drifting objects trigger few rebuilds (the span at least doubles each time).
  void rebuildGrid() {
    cells.clear();
    for (auto& m : level_members) m.clear();
    loose.clear();
    for (Entry& e : slots) e.placed = false;
    const double inf = std::numeric_limits<double>::infinity();
    double lo[3] = {inf, inf, inf}, hi[3] = {-inf, -inf, -inf};
    double min_ext = inf;
    std::size_t hashable = 0;
    for (const Entry& e : slots) {
      if (e.obj == nullptr || !isHashable<S>(e.box)) continue;
      ++hashable;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], axisLo(e.box, a));
        hi[a] = std::max(hi[a], axisHi(e.box, a));
      }
      const double ext = maxExtent(e.box);
      if (ext > 0) min_ext = std::min(min_ext, ext);
    }
    grid_valid = hashable > 0;
    if (grid_valid) {
      double span = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
      if (!(span > 0)) {
        double maxabs = 1;
        for (int a = 0; a < 3; ++a) maxabs = std::max({maxabs, std::fabs(lo[a]), std::fabs(hi[a])});
        span = maxabs;
      }
      const double width = 3 * span;
      min_cell0 = std::ldexp(width, -detail::kCellRange);
      double cell0 = min_ext < inf ? min_ext : width / 1024;
      cell0 = std::max(cell0, min_cell0);
      grid.num_levels = detail::kMaxLevels;
      grid.cell0 = cell0;
      grid.inv_cell0 = 1 / cell0;
      const double reach = std::ldexp(cell0, detail::kCellRange);
      for (int a = 0; a < 3; ++a) {
        grid.origin[a] = lo[a] - span;
        grid_upper[a] = grid.origin[a] + reach;
      }
      cells.reserve(2 * hashable);
    }
    for (std::uint32_t s = 0; s < slots.size(); ++s)
      if (slots[s].obj != nullptr) insertEntry(s);
    changed_since_rebuild = false;
  }

  void setBox(Entry& e, const fcl::AABB<S>& a) {
    e.fbox = a;
    e.box = toBox(a);
  }

  /// Adds an object whose box was validated; no grid work (see placeNew).
  std::uint32_t addEntry(Obj* obj, const fcl::AABB<S>& a) {
    std::uint32_t s;
    if (!free_slots.empty()) {
      s = free_slots.back();
      free_slots.pop_back();
    } else {
      s = std::uint32_t(slots.size());
      slots.emplace_back();
    }
    Entry& e = slots[s];
    e.obj = obj;
    e.seq = next_seq++;
    setBox(e, a);
    index.emplace(obj, s);
    return s;
  }

  /// Puts an entry that is in no list into the hash, rebuilding the grid where it does not fit.
  void place(std::uint32_t s) {
    if (isHashable<S>(slots[s].box) && needsRebuild(slots[s].box))
      rebuildGrid();  // inserts s too
    else
      insertEntry(s);
  }

  void reset() {
    slots.clear();
    free_slots.clear();
    index.clear();
    cells.clear();
    for (auto& m : level_members) m.clear();
    loose.clear();
    grid_valid = false;
  }

  // ---- queries ----

  /// Calls f(slot) once for every stored object whose box overlaps q (closed); stops and returns
  /// true when f does.
  template <class F>
  bool queryBox(const Aabb<double>& q, F&& f) const {
    const bool hashed_query = grid_valid && isHashable<S>(q);
    const int lq = hashed_query ? detail::levelFor(maxExtent(q), grid) : 0;
    for (int l = 0; l < detail::kMaxLevels; ++l) {
      const std::vector<std::uint32_t>& members = level_members[l];
      if (members.empty()) continue;
      bool scan = !hashed_query;
      CellRange r{};
      if (hashed_query) {
        r = detail::cellRange(q, l, grid);
        // On finer levels than its own the query covers many cells: visit whichever is fewer,
        // the cells or the level's objects.
        scan = l < lq && cellCount(r) > double(members.size());
      }
      if (scan) {
        for (std::uint32_t b : members)
          if (detail::boxesOverlap(slots[b].box, q) && f(b)) return true;
        continue;
      }
      const double scale = detail::levelScale(l);
      for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
        for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
          for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
            auto it = cells.find(detail::makeCellKey(l, x, y, z));
            if (it == cells.end()) continue;
            for (std::uint32_t b : it->second) {
              const Aabb<double>& bb = slots[b].box;
              if (!detail::boxesOverlap(bb, q)) continue;
              if (!detail::isCanonicalCell(bb, q, scale, grid, x, y, z)) continue;
              if (f(b)) return true;
            }
          }
    }
    for (std::uint32_t b : loose)
      if (detail::boxesOverlap(slots[b].box, q) && f(b)) return true;
    return false;
  }

  bool reportSelf(const Entry& a, const Entry& b, void* cdata,
                  fcl::CollisionCallBack<S> callback) const {
    return a.seq < b.seq ? callback(a.obj, b.obj, cdata) : callback(b.obj, a.obj, cdata);
  }

  /// All overlapping pairs once, each in the canonical cell of the two boxes' overlap on the
  /// coarser object's level: pairs of one level inside each cell; pairs of different levels by
  /// the finer object querying every coarser occupied level.
  bool selfCollide(void* cdata, fcl::CollisionCallBack<S> callback) const {
    for (const auto& [key, members] : cells) {
      if (members.size() < 2) continue;
      const int l = int(key.hi >> 56);
      const double scale = detail::levelScale(l);
      std::int64_t c[3];
      decodeCellKey(key, c);
      for (std::size_t i = 0; i + 1 < members.size(); ++i) {
        const Entry& A = slots[members[i]];
        for (std::size_t j = i + 1; j < members.size(); ++j) {
          const Entry& B = slots[members[j]];
          if (!detail::boxesOverlap(A.box, B.box)) continue;
          if (!detail::isCanonicalCell(A.box, B.box, scale, grid, c[0], c[1], c[2])) continue;
          if (reportSelf(A, B, cdata, callback)) return true;
        }
      }
    }
    for (std::uint32_t a = 0; a < slots.size(); ++a) {
      const Entry& A = slots[a];
      if (A.obj == nullptr || A.level < 0) continue;
      for (int l = A.level + 1; l < detail::kMaxLevels; ++l) {
        if (level_members[l].empty()) continue;
        const double scale = detail::levelScale(l);
        const CellRange r = detail::cellRange(A.box, l, grid);
        for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
          for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
            for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
              auto it = cells.find(detail::makeCellKey(l, x, y, z));
              if (it == cells.end()) continue;
              for (std::uint32_t b : it->second) {
                const Entry& B = slots[b];
                if (!detail::boxesOverlap(A.box, B.box)) continue;
                if (!detail::isCanonicalCell(A.box, B.box, scale, grid, x, y, z)) continue;
                if (reportSelf(A, B, cdata, callback)) return true;
              }
            }
      }
    }
    // Loose objects against everything; two loose ones by the earlier-registered one.
    for (std::uint32_t u : loose) {
      const Entry& U = slots[u];
      for (std::uint32_t b = 0; b < slots.size(); ++b) {
        const Entry& B = slots[b];
        if (B.obj == nullptr || b == u) continue;
        if (B.level < 0 && B.seq < U.seq) continue;
        if (detail::boxesOverlap(U.box, B.box) && reportSelf(U, B, cdata, callback)) return true;
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
  // Take every object out of (or keep it away from) the hash first, then place the batch with
  // at most one grid rebuild. An object already managed (or listed twice) just gets a new box.
  std::vector<std::uint32_t> batch;
  batch.reserve(other_objs.size());
  for (fcl::CollisionObject<S>* o : other_objs) {
    auto it = m.index.find(o);
    if (it == m.index.end()) {
      batch.push_back(m.addEntry(o, o->getAABB()));
    } else {
      m.removeEntry(it->second);
      m.setBox(m.slots[it->second], o->getAABB());
      batch.push_back(it->second);
    }
  }
  bool rebuild = false;
  for (std::uint32_t s : batch)
    rebuild = rebuild || (isHashable<S>(m.slots[s].box) && m.needsRebuild(m.slots[s].box));
  if (rebuild) {
    m.rebuildGrid();  // inserts every object
    return;
  }
  for (std::uint32_t s : batch)
    if (!m.slots[s].placed) m.insertEntry(s);
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
  m.place(m.addEntry(obj, a));
}

template <class S>
void CollisionManager<S>::unregisterObject(fcl::CollisionObject<S>* obj) {
  Impl& m = *impl_;
  auto it = m.index.find(obj);
  if (it == m.index.end()) return;
  const std::uint32_t s = it->second;
  m.removeEntry(s);
  m.slots[s].obj = nullptr;
  m.free_slots.push_back(s);
  m.index.erase(it);
  if (m.index.empty()) m.reset();
}

template <class S>
void CollisionManager<S>::setup() {
  if (!impl_->index.empty() && impl_->changed_since_rebuild) impl_->rebuildGrid();
}

template <class S>
void CollisionManager<S>::update() {
  Impl& m = *impl_;
  for (const auto& e : m.slots)
    if (e.obj != nullptr) checkedAabb(e.obj, "update");
  for (auto& e : m.slots)
    if (e.obj != nullptr) m.setBox(e, e.obj->getAABB());
  if (!m.index.empty()) m.rebuildGrid();
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
  m.removeEntry(s);
  m.setBox(e, a);
  m.place(s);
}

template <class S>
void CollisionManager<S>::update(const std::vector<fcl::CollisionObject<S>*>& updated_objs) {
  Impl& m = *impl_;
  for (fcl::CollisionObject<S>* o : updated_objs)
    if (m.index.count(o) != 0) checkedAabb(o, "update");
  if (2 * updated_objs.size() > m.index.size()) {
    // Most objects moved: re-reading them and rebuilding once is cheaper and adapts the grid.
    for (fcl::CollisionObject<S>* o : updated_objs) {
      auto it = m.index.find(o);
      if (it != m.index.end()) m.setBox(m.slots[it->second], o->getAABB());
    }
    if (!m.index.empty()) m.rebuildGrid();
    return;
  }
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
  const Impl& m = *impl_;
  const Aabb<double> q = toBox(checkedAabb(obj, "collide"));
  if (m.index.empty()) return;
  m.queryBox(q, [&](std::uint32_t b) { return callback(m.slots[b].obj, obj, cdata); });
}

template <class S>
void CollisionManager<S>::collide(void* cdata, fcl::CollisionCallBack<S> callback) const {
  if (impl_->index.size() < 2) return;
  impl_->selfCollide(cdata, callback);
}

template <class S>
void CollisionManager<S>::collide(fcl::BroadPhaseCollisionManager<S>* other_manager, void* cdata,
                                  fcl::CollisionCallBack<S> callback) const {
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
      for (std::uint32_t s : o.liveSlots()) {
        fcl::CollisionObject<S>* theirs = o.slots[s].obj;
        if (m.queryBox(o.slots[s].box,
                       [&](std::uint32_t b) { return callback(m.slots[b].obj, theirs, cdata); }))
          return;
      }
    } else {
      for (std::uint32_t s : m.liveSlots()) {
        fcl::CollisionObject<S>* mine = m.slots[s].obj;
        if (o.queryBox(m.slots[s].box,
                       [&](std::uint32_t b) { return callback(mine, o.slots[b].obj, cdata); }))
          return;
      }
    }
    return;
  }
  std::vector<fcl::CollisionObject<S>*> theirs;
  other_manager->getObjects(theirs);
  for (fcl::CollisionObject<S>* q : theirs) checkedAabb(q, "collide(other manager)");
  if (m.index.empty()) return;
  for (fcl::CollisionObject<S>* q : theirs)
    if (m.queryBox(toBox(q->getAABB()),
                   [&](std::uint32_t b) { return callback(m.slots[b].obj, q, cdata); }))
      return;
}

template <class S>
void CollisionManager<S>::distance(fcl::CollisionObject<S>* obj, void* cdata,
                                   fcl::DistanceCallBack<S> callback) const {
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
