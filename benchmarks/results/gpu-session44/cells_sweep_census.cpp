// Census (session 44, CPU only): what a sweep inside each cell would leave of the cells' pair
// visits (selfCellPairsKernel visits every pair of a cell). Per mesh: the cells, the pairs
// visited, the canonical ones (first-cell bits), the pairs whose sub-cell spans overlap on axis
// x, y or z alone (what a cell sorted by that axis's low slab and swept would visit), the least
// of the three per cell, the canonical pairs whose spans overlap on every axis; and the visits
// by cell size. Build and run: census_common.h.
#include <algorithm>

#include "census_common.h"

using namespace kdet_fcl::detail;

int main(int argc, char** argv) {
  std::printf("| mesh | cells | visited | canonical | sweep x | sweep y | sweep z | best axis | spans |\n");
  census::forEachSelfMesh(argc, argv, [](const std::string& name, const auto& m,
                                         const census::Hash& h) {
    double c[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // visited, canonical, x, y, z, best, spans, cells
    double by_size[6] = {0, 0, 0, 0, 0, 0};
    std::vector<std::uint32_t> span;
    for (const auto* t : census::tablesOf(h))
      for (const auto& sl : t->slots) {
        if (sl.count == 0) continue;
        c[7] += 1;
        const CellId cell = cellOfKey(sl.key);
        const auto* e = t->entries.data() + sl.begin;
        span.resize(sl.count);
        for (std::uint32_t a = 0; a < sl.count; ++a)
          span[a] = subcellSpan(h.boxes[e[a].id], cell.level, cell.x, cell.y, cell.z, h.grid);
        const double n = sl.count;
        by_size[n <= 4 ? 0 : n <= 8 ? 1 : n <= 16 ? 2 : n <= 32 ? 3 : n <= 64 ? 4 : 5] +=
            n * (n - 1) / 2;
        double axis[3] = {0, 0, 0};
        for (std::uint32_t a = 0; a < sl.count; ++a)
          for (std::uint32_t b = a + 1; b < sl.count; ++b) {
            c[0] += 1;
            for (int k = 0; k < 3; ++k)
              axis[k] += census::spanLo(span[a], k) <= census::spanHi(span[b], k) &&
                         census::spanLo(span[b], k) <= census::spanHi(span[a], k);
            if (((e[a].lo_mask | e[b].lo_mask) & 7u) != 7u) continue;
            c[1] += 1;
            c[6] += subcellSpansOverlap(span[a], span[b]);
          }
        for (int k = 0; k < 3; ++k) c[2 + k] += axis[k];
        c[5] += std::min(axis[0], std::min(axis[1], axis[2]));
      }
    std::printf("| %s (%zu) | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f |\n",
                name.c_str(), m.triangles.size(), c[7], c[0], c[1], c[2], c[3], c[4], c[5], c[6]);
    std::printf("   pair visits by cell size <=4,8,16,32,64,>64: %.0f %.0f %.0f %.0f %.0f %.0f\n",
                by_size[0], by_size[1], by_size[2], by_size[3], by_size[4], by_size[5]);
  });
  return 0;
}
