#pragma once
// The inner loop of every kDet lookup on the CPU, shared by the queries and the k-free analysis.

#include <cmath>
#include <cstdint>

#include "cpu/hierarchical_hash.h"
#include "kdet_fcl/query.h"

namespace kdet_fcl {
namespace cpu {

/// Visits every candidate of one query triangle in hierarchy `h`: triangles stored on the query's
/// level or a coarser one, in cells its box covers, accepted by `accept(id, diameter)` (the size
/// rule: 1 tests the triangle, 0 skips it, -1 means it and every later triangle of the cell are
/// too small, since cells list their triangles by decreasing diameter), whose boxes overlap the
/// query box, seen from the canonical cell of that overlap only. Calls test_and_emit(j) for each;
/// stops (returns false) when it returns false.
/// The box test runs first on the entries' compact boxes, rounded outward, which keep every pair
/// whose double boxes overlap and perhaps a few whose boxes are a rounding step apart; the pairs
/// it keeps are confirmed on the double boxes. So every predicate sees exactly the pairs whose
/// boxes overlap, as the CUDA backend does: a plain predicate, or the exact one outside its
/// validity range (subnormal coordinates, docs/numerics.md), may accept a pair across a gap
/// between the boxes, and no query reports such a pair. `confirm` = false leaves that
/// confirmation to test_and_emit (the self query runs its cheaper adjacency test first).
template <class S, class Accept, class TestEmit>
bool scanCandidates(const detail::HierarchicalHash<S>& h, const detail::Aabb<double>& qbox0,
                    double dq,
                    Accept&& accept, TestEmit&& test_and_emit, QueryStats& st,
                    double grow_abs = 0, double grow_rel = 0, bool confirm = true) {
  // The caller asked for the tables of every level visited here (HashedMesh::hashFrom; a level
  // without its table would look empty).
  for (int L = detail::levelFor(dq, h.grid); L <= h.top_level; ++L) {
    if (!h.levelOccupied(L)) continue;
    // Optionally grow the query box per level by grow_abs + grow_rel * (cell edge of level L):
    // a bound on rounding that depends on the size of the candidates stored on that level.
    const double grow = grow_abs + grow_rel * h.grid.cell0 * detail::pow2(L);
    const detail::Aabb<double> qbox = grow > 0 ? detail::inflate(qbox0, grow) : qbox0;
    const detail::Aabb<double> clipped = detail::intersectBoxes(qbox, h.bounds);
    if (detail::isEmpty(clipped)) continue;
    const detail::CellRange r = detail::cellRange(clipped, L, h.grid);
    const auto& table = h.table(L);
    // The entries' boxes lie inside h.bounds, so testing them against the clipped query box is
    // the same test; in the entries' compact form (rounded outward, never drops a pair).
    const detail::EntryBox qe = detail::entryBox(clipped, h.grid.origin);
    for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
      for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
        for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
          ++st.lookups;
          const auto* slot = table.find(detail::makeCellKey(L, x, y, z));
          if (!slot) continue;
          ++st.cells_visited;
          const auto* cell = table.entries.data() + slot->begin;
          // The canonical cell holds the overlap's minimum corner. cellCoord is monotone, so its
          // coordinate on each axis is max(first cell of the query, first cell of the
          // candidate): this is that cell iff on every axis it is the candidate's first cell or
          // the query's (r.lo is the query's first cell: clipping to the bounds never moves it).
          // So an entry passes iff its lo_mask holds every axis on which this cell is not the
          // query's first: one mask test, computed once per cell.
          const unsigned need = (x != r.lo[0] ? 1u : 0u) | (y != r.lo[1] ? 2u : 0u) |
                                (z != r.lo[2] ? 4u : 0u);
          for (std::uint32_t k = 0; k < slot->count; ++k) {
            const auto& e = cell[k];
            const int verdict = accept(e.id, e.diameter);
            if (verdict < 0) break;  // the rest of the cell is smaller still
            if (verdict == 0) continue;
            // The test needs no box, so it runs first: a pair seen from another cell of the
            // query's range costs one mask test, not a box test.
            if ((e.lo_mask & need) != need) continue;
            ++st.box_tests;
            if (!detail::entryBoxesOverlap(qe, e.box)) continue;
            if (confirm && !detail::boxesOverlap(qbox, h.boxes[e.id])) continue;
            if (!test_and_emit(e.id)) return false;
          }
        }
  }
  return true;
}

}  // namespace cpu
}  // namespace kdet_fcl
