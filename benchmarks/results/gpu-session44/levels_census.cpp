// Census (session 44, CPU only): the self query's work on other level grids. Per scene, a
// histogram of log2(d / d_min) (1/8 bins), then one row per grid: the triangles per level, the
// entries, the cells' pairs (visited, canonical, spans overlapping), the scan of the coarser
// levels (visited, canonical, spans overlapping), their visits together and the pairs whose boxes
// overlap; under each row, the scan's visits that an early exit in cells sorted by an axis's low
// slab would leave (the entries whose low slab is at most the query's high slab on that axis;
// "both ends": also those whose high slab reaches the query's low slab), and those a cell binned
// by its entries' low slabs on all three axes would leave (bins above the query's high slab on
// any axis skipped; halves: 8 bins, quarters: 64).
//   levels_census SCENE...          grids whose level-0 cell is the default's times 2^(k/8),
//                                   k = 0..7 (where the level boundaries cut the diameters)
//   levels_census --floor SCENE...  the default grid with every triangle below level k lifted to
//                                   it, k = 0..7 (floor 0: the default hierarchy)
// Build and run: census_common.h.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "census_common.h"

using namespace kdet_fcl::detail;

int main(int argc, char** argv) {
  const bool floors = argc > 1 && std::strcmp(argv[1], "--floor") == 0;
  if (floors) --argc, ++argv;
  census::forEachSelfMesh(argc, argv, [&](const std::string& name, const auto& m,
                                          const census::Hash& h) {
    const std::size_t n = m.triangles.size();
    std::vector<int> hist(80, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const int b = int(std::log2(h.diameter[i] / h.d_min) * 8);
      if (b >= 0 && b < 80) hist[b]++;
    }
    std::printf("== %s: %zu triangles, d_min %g d_max %g\n log2(d/dmin) histogram (1/8 bins):",
                name.c_str(), n, h.d_min, h.d_max);
    for (int b = 0; b < 80; ++b)
      if (hist[b]) std::printf(" %d:%d", b, hist[b]);
    std::printf("\n| %s | levels (tris) | entries | cell pairs | cell canon | cell spans | scan visits "
                "| scan canon | scan spans | total visits | boxes |\n",
                floors ? "floor" : "phi");
    for (int k = 0; k < 8; ++k) {
      GridParams g = h.grid;
      if (!floors) g.cell0 = h.grid.cell0 * std::pow(2.0, k / 8.0);
      g.inv_cell0 = 1.0 / g.cell0;
      g.num_levels = kMaxLevels;
      const int top = levelFor(h.d_max, g);
      g.num_levels = top + 1;
      std::vector<int> lev(n);
      std::vector<std::size_t> per(top + 1, 0);
      std::vector<std::unordered_map<CellKey, std::vector<std::uint32_t>, census::KeyHash>> cells(
          top + 1);
      std::size_t entries = 0;
      for (std::size_t i = 0; i < n; ++i) {
        lev[i] = levelFor(h.diameter[i], g);
        if (floors) lev[i] = std::max(lev[i], std::min(k, top));
        per[lev[i]]++;
        census::forEachCell(h.boxes[i], lev[i], g, [&](const CellId& c) {
          cells[c.level][makeCellKey(c.level, c.x, c.y, c.z)].push_back(std::uint32_t(i));
          ++entries;
        });
      }
      const auto canon = [&](std::uint32_t a, std::uint32_t b, const CellId& c) {
        return isCanonicalCell(h.boxes[a], h.boxes[b], levelScale(c.level), g, c.x, c.y, c.z);
      };
      double cp = 0, cc = 0, cs = 0, sv = 0, sc = 0, ss = 0, boxes = 0;
      double exit_lo[3] = {0, 0, 0}, exit_both[3] = {0, 0, 0}, bins[3] = {0, 0, 0};
      for (int l = 0; l <= top; ++l)
        for (const auto& kv : cells[l]) {
          const CellId c = cellOfKey(kv.first);
          const auto& e = kv.second;
          for (std::size_t a = 0; a < e.size(); ++a)
            for (std::size_t b = a + 1; b < e.size(); ++b) {
              cp += 1;
              if (!canon(e[a], e[b], c)) continue;
              cc += 1;
              const bool sp = subcellSpansOverlap(subcellSpan(h.boxes[e[a]], l, c.x, c.y, c.z, g),
                                                  subcellSpan(h.boxes[e[b]], l, c.x, c.y, c.z, g));
              cs += sp;
              boxes += sp && census::boxesOverlap(h.boxes[e[a]], h.boxes[e[b]]);
            }
        }
      for (std::size_t i = 0; i < n; ++i)
        census::forEachOccupiedCell(
            h.boxes[i], lev[i] + 1, top, g, cells, [&](const CellId& c, const auto& e) {
            const int l = c.level;
            const std::uint32_t qs = subcellSpan(h.boxes[i], l, c.x, c.y, c.z, g);
            for (std::uint32_t j : e) {
              sv += 1;
              const std::uint32_t es = subcellSpan(h.boxes[j], l, c.x, c.y, c.z, g);
              // The bins: halves and quarters of the low slabs on every axis; one run of the
              // halves' bins up to the last the query needs (index 4x + 2y + z).
              bool halves = true, quarters = true;
              unsigned entry_bin = 0, query_bin = 0;
              for (int a = 0; a < 3; ++a) {
                const unsigned lo = census::spanLo(es, a), q_hi = census::spanHi(qs, a);
                exit_lo[a] += lo <= q_hi;
                exit_both[a] += lo <= q_hi && census::spanHi(es, a) >= census::spanLo(qs, a);
                halves = halves && lo / 8 <= q_hi / 8;
                quarters = quarters && lo / 4 <= q_hi / 4;
                entry_bin = 2 * entry_bin + lo / 8;
                query_bin = 2 * query_bin + q_hi / 8;
              }
              bins[0] += halves;
              bins[1] += quarters;
              bins[2] += entry_bin <= query_bin;
              if (!canon(std::uint32_t(i), j, c)) continue;
              sc += 1;
              const bool sp = subcellSpansOverlap(qs, es);
              ss += sp;
              boxes += sp && census::boxesOverlap(h.boxes[i], h.boxes[j]);
            }
          });
      std::string lv;
      for (int l = 0; l <= top; ++l)
        if (per[l]) lv += std::to_string(l) + ":" + std::to_string(per[l]) + " ";
      std::printf("| %s | %s| %zu | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f |\n",
                  floors ? std::to_string(k).c_str() : std::to_string(k / 8.0).substr(0, 5).c_str(),
                  lv.c_str(), entries, cp, cc, cs, sv, sc, ss, cp + sv, boxes);
      std::printf("   scan visits under a low-slab early exit: x %.0f y %.0f z %.0f; both ends x %.0f "
                  "y %.0f z %.0f; cells binned by the low slab's half (8 bins) %.0f, quarter (64 "
                  "bins) %.0f, 8 bins in one run %.0f\n",
                  exit_lo[0], exit_lo[1], exit_lo[2], exit_both[0], exit_both[1], exit_both[2],
                  bins[0], bins[1], bins[2]);
    }
  });
  return 0;
}
