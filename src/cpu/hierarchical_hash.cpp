#include "cpu/hierarchical_hash.h"

#include <algorithm>
#include <limits>

#include "cpu/parallel.h"
#include "kdet_fcl/detail/enclosing_sphere.h"
#include "kdet_fcl/errors.h"

namespace kdet_fcl {
namespace detail {

template <class S>
void HierarchicalHash<S>::build(const std::vector<Vec3<S>>& vertices,
                                const std::vector<Triangle>& triangles, int threads) {
  const std::size_t n = triangles.size();
  // resize, not assign: every element is overwritten below, and a rebuild of a mesh of the same
  // size (a deforming mesh) then touches no allocator and zeroes nothing.
  boxes.resize(n);
  diameter.resize(n);
  level.resize(n);
  if (n == 0) {
    entries.clear();
    slots_.clear();
  }
  mask_ = 0;
  cells_ = 0;
  level_mask = 0;
  top_level = 0;
  d_min = d_max = 0;
  bounds = Aabb<double>{};
  grid = GridParams{};
  if (n == 0) return;

  const Vec3<S>* v = vertices.data();
  const Triangle* t = triangles.data();
  cpu::parallelFor(n, 8192, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Vec3<S>&p = v[t[i][0]], &q = v[t[i][1]], &r = v[t[i][2]];
      boxes[i] = triangleBox<double>(p, q, r);
      diameter[i] = enclosingDiameter(p, q, r);
    }
  });

  bounds = boxes[0];
  double dmin_pos = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      bounds.lo[a] = std::min(bounds.lo[a], boxes[i].lo[a]);
      bounds.hi[a] = std::max(bounds.hi[a], boxes[i].hi[a]);
    }
    d_max = std::max(d_max, diameter[i]);
    if (diameter[i] > 0) dmin_pos = std::min(dmin_pos, diameter[i]);
  }
  d_min = std::isfinite(dmin_pos) ? dmin_pos : 0.0;
  const double extent = std::max({bounds.hi.x - bounds.lo.x, bounds.hi.y - bounds.lo.y,
                                  bounds.hi.z - bounds.lo.z});
  // Level-0 cells are as small as the smallest triangle, but not so small that cell coordinates
  // would overflow the key (a point-like triangle must not make the grid infinitely fine).
  double cell0 = d_min;
  const double floor_cell = std::ldexp(extent, -kCellRange);
  if (cell0 < floor_cell) cell0 = floor_cell;
  if (!(cell0 > 0) || !std::isfinite(1.0 / cell0)) cell0 = extent > 0 ? extent : 1.0;
  for (int a = 0; a < 3; ++a) grid.origin[a] = bounds.lo[a];
  grid.cell0 = cell0;
  grid.inv_cell0 = 1.0 / cell0;
  grid.num_levels = kMaxLevels;
  top_level = levelFor(d_max, grid);
  grid.num_levels = top_level + 1;

  // Entries per triangle: the cells its box covers on its level (at most 8 up to rounding).
  std::vector<std::uint64_t>& offset = scratch_offset_;
  offset.resize(n + 1);
  offset[0] = 0;
  cpu::parallelFor(n, 8192, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      level[i] = std::uint8_t(levelFor(diameter[i], grid));
      offset[i + 1] = std::uint64_t(cellRange(boxes[i], level[i], grid).count());
    }
  });
  for (std::size_t i = 0; i < n; ++i) {
    offset[i + 1] += offset[i];
    level_mask |= std::uint64_t(1) << level[i];
  }
  const std::uint64_t total = offset[n];
  if (total >= std::numeric_limits<std::uint32_t>::max())
    throw InvalidInputError("mesh too large for the hierarchical hash: " + std::to_string(total) +
                            " cell entries");

  // Open addressing with capacity >= 1.25 * entries (>= 1.25 * cells) keeps probes short; keys
  // are compared in full.
  std::uint64_t capacity = 16;
  while (capacity < total + total / 4) capacity <<= 1;
  slots_.assign(capacity, Slot{{0, 0}, 0, 0});
  mask_ = capacity - 1;
  std::vector<std::uint32_t>& entry_slot = scratch_slot_;
  std::vector<std::uint8_t>& entry_mask = scratch_mask_;
  entry_slot.resize(total);
  entry_mask.resize(total);
  // Sequential insertion in triangle order: the table layout (and so every output order) is
  // independent of the thread count.
  for (std::size_t i = 0; i < n; ++i) {
    const CellRange r = cellRange(boxes[i], level[i], grid);
    std::uint64_t k = offset[i];
    for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
      for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
        for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
          const CellKey key = makeCellKey(level[i], x, y, z);
          std::uint64_t s = hashCellKey(key) & mask_;
          while (slots_[s].count != 0 && !(slots_[s].key == key)) s = (s + 1) & mask_;
          if (slots_[s].count == 0) {
            slots_[s].key = key;
            ++cells_;
          }
          ++slots_[s].count;
          entry_mask[k] = std::uint8_t((x == r.lo[0] ? 1 : 0) | (y == r.lo[1] ? 2 : 0) |
                                       (z == r.lo[2] ? 4 : 0));
          entry_slot[k++] = std::uint32_t(s);
        }
  }
  std::uint32_t running = 0;
  for (Slot& s : slots_) {
    s.begin = running;
    running += s.count;
  }
  entries.resize(total);
  // Fill cells in order of decreasing diameter (ties: increasing id), so every cell lists its
  // triangles largest first and a lookup can stop at the first triangle smaller than the query.
  std::vector<std::uint32_t>& order = scratch_order_;
  order.resize(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return diameter[a] != diameter[b] ? diameter[a] > diameter[b] : a < b;
  });
  std::vector<std::uint32_t>& fill = scratch_fill_;
  fill.assign(capacity, 0);
  for (const std::uint32_t i : order)
    for (std::uint64_t k = offset[i]; k < offset[i + 1]; ++k) {
      const std::uint32_t s = entry_slot[k];
      entries[slots_[s].begin + fill[s]++] =
          Entry{boxes[i], diameter[i], std::uint32_t(i), entry_mask[k]};
    }
}

template <class S>
HierarchyStats HierarchicalHash<S>::stats() const {
  HierarchyStats st;
  st.triangles = diameter.size();
  if (diameter.empty()) return st;
  for (int l = 0; l < 64; ++l) st.levels += levelOccupied(l) ? 1 : 0;
  st.height = top_level + 1;
  st.d_min = d_min;
  st.d_max = d_max;
  st.cell_size0 = grid.cell0;
  st.cells = cells_;
  st.entries = entries.size();
  for (const Slot& s : slots_) st.max_cell_load = std::max<std::size_t>(st.max_cell_load, s.count);
  st.memory_bytes = memoryBytes();
  return st;
}

template <class S>
std::size_t HierarchicalHash<S>::memoryBytes() const {
  return boxes.capacity() * sizeof(Aabb<double>) + diameter.capacity() * sizeof(double) +
         level.capacity() + entries.capacity() * sizeof(Entry) + slots_.capacity() * sizeof(Slot) +
         scratch_offset_.capacity() * sizeof(std::uint64_t) +
         (scratch_slot_.capacity() + scratch_order_.capacity() + scratch_fill_.capacity()) *
             sizeof(std::uint32_t) +
         scratch_mask_.capacity();
}

template class HierarchicalHash<float>;
template class HierarchicalHash<double>;

}  // namespace detail
}  // namespace kdet_fcl
