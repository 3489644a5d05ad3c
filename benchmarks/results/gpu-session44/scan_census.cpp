// Census (session 44, CPU only): the scan of the coarser levels (selfCandidatesWarpKernel after
// the cells' pairs) on the default grid: its visits, the canonical ones, those whose spans
// overlap; and what an early exit in cells sorted by an axis's low slab would leave (the entries
// whose low slab is at most the query's high slab on that axis; "both ends": also the entries
// whose high slab reaches the query's low slab).
// Build (repository root, after a build in build/): g++ -O2 -std=c++17 -I include -I src -I .
//   -I build -I benchmarks -isystem /usr/include/eigen3 benchmarks/results/gpu-session44/scan_census.cpp
//   benchmarks/bench_scenes.cpp -L build -lkdet_fcl -lfcl -lccd -o census
// Run: KDET_FCL_DATA_DIR=../shared/data LD_LIBRARY_PATH=build ./census SCENE... (kdet_bench keys)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unordered_map>
#include <vector>

#include "bench_scenes.h"
#include "cpu/hierarchical_hash.h"
#include "kdet_fcl/kdet_fcl.h"

namespace kb = kdet_bench;
using namespace kdet_fcl;
using namespace kdet_fcl::detail;

struct KH { std::size_t operator()(const CellKey& k) const { return hashCellKey(k); } };

int main(int argc, char** argv) {
  kb::SceneConfig cfg;
  cfg.frames = 3;
  cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  std::vector<std::string> want;
  for (int i = 1; i < argc; ++i) want.push_back(argv[i]);
  const std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, want);
  for (const auto& s : scenes) {
    if (s.self.empty()) continue;
    const std::size_t f = s.frames.size() > 1 ? 1 : 0;
    const auto& src = *s.frames[f].meshes[s.self[0]];
    TriangleMesh<double> m;
    for (const auto& v : src.vertices) m.vertices.push_back({v.x, v.y, v.z});
    m.triangles = src.triangles;
    HierarchicalHash<double> h;
    h.build(m, 0);
    const std::size_t n = m.triangles.size();
    // log2(d / d_min) histogram
    std::vector<int> hist(80, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const double r = std::log2(h.diameter[i] / h.d_min);
      int b = int(r * 8);
      if (b >= 0 && b < 80) hist[b]++;
    }
    std::printf("== %s: %zu triangles, d_min %g d_max %g, default levels:", s.name.c_str(), n, h.d_min, h.d_max);
    std::printf("\n log2(d/dmin) histogram (1/8 bins):");
    for (int b = 0; b < 80; ++b) if (hist[b]) std::printf(" %d:%d", b, hist[b]);
    std::printf("\n| phi | levels (tris) | entries | cell pairs | cell canon | cell spans | scan visits | scan canon | scan spans | total visits | boxes |\n");
    for (int ph = 0; ph < 1; ++ph) {
      GridParams g = h.grid;
      g.cell0 = h.grid.cell0 * std::pow(2.0, ph / 8.0);
      g.inv_cell0 = 1.0 / g.cell0;
      g.num_levels = kMaxLevels;
      const int top = levelFor(h.d_max, g);
      g.num_levels = top + 1;
      std::vector<int> lev(n);
      std::vector<std::size_t> per(top + 1, 0);
      std::vector<std::unordered_map<CellKey, std::vector<std::uint32_t>, KH>> cells(top + 1);
      std::size_t entries = 0;
      for (std::size_t i = 0; i < n; ++i) {
        lev[i] = levelFor(h.diameter[i], g);
        per[lev[i]]++;
        const CellRange r = cellRange(h.boxes[i], lev[i], g);
        for (auto x = r.lo[0]; x <= r.hi[0]; ++x)
          for (auto y = r.lo[1]; y <= r.hi[1]; ++y)
            for (auto z = r.lo[2]; z <= r.hi[2]; ++z) {
              cells[lev[i]][makeCellKey(lev[i], x, y, z)].push_back(std::uint32_t(i));
              ++entries;
            }
      }
      auto box_ov = [&](std::uint32_t a, std::uint32_t b) {
        const auto &p = h.boxes[a], &q = h.boxes[b];
        return p.lo.x <= q.hi.x && q.lo.x <= p.hi.x && p.lo.y <= q.hi.y && q.lo.y <= p.hi.y &&
               p.lo.z <= q.hi.z && q.lo.z <= p.hi.z;
      };
      auto canon = [&](std::uint32_t a, std::uint32_t b, const CellId& c) {
        return isCanonicalCell(h.boxes[a], h.boxes[b], levelScale(c.level), g, c.x, c.y, c.z);
      };
      double cp = 0, cc = 0, cs = 0, sv = 0, sc = 0, ss = 0, boxes = 0, sx[3] = {0,0,0}, sxx[3] = {0,0,0};
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
              boxes += sp && box_ov(e[a], e[b]);
            }
        }
      for (std::size_t i = 0; i < n; ++i)
        for (int l = lev[i] + 1; l <= top; ++l) {
          if (cells[l].empty()) continue;
          const CellRange r = cellRange(h.boxes[i], l, g);
          for (auto x = r.lo[0]; x <= r.hi[0]; ++x)
            for (auto y = r.lo[1]; y <= r.hi[1]; ++y)
              for (auto z = r.lo[2]; z <= r.hi[2]; ++z) {
                auto it = cells[l].find(makeCellKey(l, x, y, z));
                if (it == cells[l].end()) continue;
                const std::uint32_t qs = subcellSpan(h.boxes[i], l, x, y, z, g);
                for (std::uint32_t j : it->second) {
                  sv += 1;
                  const std::uint32_t es = subcellSpan(h.boxes[j], l, x, y, z, g);
                  for (int ax = 0; ax < 3; ++ax) {
                    const unsigned qhi = (qs >> (15 + 5 * ax)) & 15u, elo = (es >> (5 * ax)) & 15u;
                    if (elo <= qhi) sx[ax] += 1;
                    const unsigned qlo = (qs >> (5 * ax)) & 15u, ehi = (es >> (15 + 5 * ax)) & 15u;
                    if (elo <= qhi && ehi >= qlo) sxx[ax] += 1;
                  }
                  if (!canon(std::uint32_t(i), j, CellId{l, x, y, z})) continue;
                  sc += 1;
                  const bool sp = subcellSpansOverlap(qs, subcellSpan(h.boxes[j], l, x, y, z, g));
                  ss += sp;
                  boxes += sp && box_ov(std::uint32_t(i), j);
                }
              }
        }
      std::printf("   scan visits under a lo-sorted early exit: x %.0f y %.0f z %.0f; both ends x %.0f y %.0f z %.0f\n", sx[0], sx[1], sx[2], sxx[0], sxx[1], sxx[2]);
      std::string lv;
      for (int l = 0; l <= top; ++l) if (per[l]) lv += std::to_string(l) + ":" + std::to_string(per[l]) + " ";
      std::printf("| %.3f | %s| %zu | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f |\n", ph / 8.0, lv.c_str(), entries,
                  cp, cc, cs, sv, sc, ss, cp + sv, boxes);
      std::fflush(stdout);
    }
  }
  return 0;
}
