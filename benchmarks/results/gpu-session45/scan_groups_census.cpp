// Census (session 45, CPU only): the self query's scan of the coarser levels (each triangle
// against the cells of its range on every level above its own, as selfCandidatesWarpKernel with
// level_skip = 1), and the visits left if each cell's entries were grouped by their sub-cell
// span on one axis a, so that a query visits one contiguous run of its cell:
//   lo2:  two groups, low slab in the cell's lower half first; a query whose high slab lies in
//         the lower half visits the first group only;
//   mid3: three groups: entries wholly in the lower half (high slab < 8), then those that cross
//         the middle, then those wholly in the upper half (low slab >= 8); a query wholly in one
//         half skips the other half's group;
//   lo4:  four groups by the low slab's quarter, a query visiting those up to its high slab's;
//   sort: sorted by the low slab, a query stopping past its high slab (session 44's early exit).
// Also the lookups (cells found) and the visits by cell size.
// Build and run: ../gpu-session44/census_common.h (this file's path in its build line).
#include "../gpu-session44/census_common.h"

using namespace kdet_fcl::detail;

int main(int argc, char** argv) {
  census::forEachSelfMesh(argc, argv, [&](const std::string& name, const auto& m,
                                          const census::Hash& h) {
    const std::size_t n = m.triangles.size();
    const GridParams& g = h.grid;
    const int top = h.top_level;
    std::vector<int> lev;
    const std::vector<census::CellMap> cells = census::cellsOf(h, &lev);
    double lookups = 0, visits = 0, spans = 0;
    double lo2[3] = {}, mid3[3] = {}, lo4[3] = {}, sorted[3] = {};
    double by_size[4] = {};  // visits in cells of 1-3, 4-15, 16-63, 64+ entries
    double cell_count = 0, two_split_fits = 0;
    for (int l = 0; l <= top; ++l) cell_count += double(cells[l].size());
    for (std::size_t i = 0; i < n; ++i)
      census::forEachOccupiedCell(
          h.boxes[i], lev[i] + 1, top, g, cells, [&](const CellId& c, const auto& e) {
          const int l = c.level;
          const std::uint32_t qs = subcellSpan(h.boxes[i], l, c.x, c.y, c.z, g);
          lookups += 1;
          visits += double(e.size());
          by_size[e.size() < 4 ? 0 : e.size() < 16 ? 1 : e.size() < 64 ? 2 : 3] += double(e.size());
          for (std::uint32_t j : e) {
            const std::uint32_t es = subcellSpan(h.boxes[j], l, c.x, c.y, c.z, g);
            spans += subcellSpansOverlap(qs, es);
            for (int a = 0; a < 3; ++a) {
              const unsigned lo = census::spanLo(es, a), hi = census::spanHi(es, a);
              const unsigned q_lo = census::spanLo(qs, a), q_hi = census::spanHi(qs, a);
              lo2[a] += q_hi >= 8 || lo < 8;
              // mid3: groups 0 (hi < 8), 1 (crossing), 2 (lo >= 8).
              const int grp = hi < 8 ? 0 : (lo >= 8 ? 2 : 1);
              mid3[a] += !((q_hi < 8 && grp == 2) || (q_lo >= 8 && grp == 0));
              lo4[a] += lo / 4 <= q_hi / 4;
              sorted[a] += lo <= q_hi;
            }
          }
        });
    for (int l = 0; l <= top; ++l)
      for (const auto& kv : cells[l]) two_split_fits += kv.second.size() < 65536;
    std::printf("== %s: %zu triangles, %.0f cells (%.0f under 65536 entries), scan lookups %.0f, "
                "visits %.0f (%.1f per lookup), spans overlapping %.0f\n",
                name.c_str(), n, cell_count, two_split_fits, lookups, visits,
                lookups > 0 ? visits / lookups : 0.0, spans);
    std::printf("   visits by cell size: 1-3 %.0f, 4-15 %.0f, 16-63 %.0f, 64+ %.0f\n", by_size[0],
                by_size[1], by_size[2], by_size[3]);
    for (int a = 0; a < 3; ++a)
      std::printf("   axis %c: lo2 %.0f (%.1f %%), mid3 %.0f (%.1f %%), lo4 %.0f (%.1f %%), sort "
                  "%.0f (%.1f %%)\n",
                  "xyz"[a], lo2[a], 100 * lo2[a] / visits, mid3[a], 100 * mid3[a] / visits,
                  lo4[a], 100 * lo4[a] / visits, sorted[a], 100 * sorted[a] / visits);
  });
  return 0;
}
