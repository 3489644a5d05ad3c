// Census (session 44, CPU only): what a sweep inside each cell would leave of the cells' pair
// visits (selfCellPairsKernel visits every pair of a cell). Per mesh (frame 1, the CPU hash:
// the device's levels, cells and first-cell bits): the cells, the pairs visited, the canonical
// ones, the pairs whose sub-cell spans overlap on axis x, y or z alone (what a cell sorted by
// that axis's low slab and swept would visit), the least of the three per cell, the canonical
// pairs whose spans overlap on every axis; and the visits by cell size.
// Build (repository root, after a build in build/): g++ -O2 -std=c++17 -I include -I src -I .
//   -I build -I benchmarks -isystem /usr/include/eigen3 benchmarks/results/gpu-session44/cells_sweep_census.cpp
//   benchmarks/bench_scenes.cpp -L build -lkdet_fcl -lfcl -lccd -o census
// Run: KDET_FCL_DATA_DIR=../shared/data LD_LIBRARY_PATH=build ./census SCENE... (kdet_bench keys)
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <string>
#include <vector>

#include "bench_scenes.h"
#include "cpu/hierarchical_hash.h"
#include "kdet_fcl/kdet_fcl.h"

namespace kb = kdet_bench;
using namespace kdet_fcl;

static bool overlap(const detail::Aabb<double>& a, const detail::Aabb<double>& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y &&
         a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}

int main(int argc, char** argv) {
  kb::SceneConfig cfg;
  cfg.frames = 3;
  cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  std::vector<std::string> want;
  for (int i = 1; i < argc; ++i) want.push_back(argv[i]);
  if (want.empty()) want = {"unc-cloth-ball", "cloth-90k", "cloth-1000k"};
  const std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, want);
  std::printf("| mesh | cells | visited | canonical | sweep x | sweep y | sweep z | best axis | spans |\n"); if (0) std::printf("| mesh | visited | canonical | spans | spans+box | share index | spans, no shared index | candidates |\n|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& s : scenes) {
    if (s.self.empty()) continue;
    const std::size_t f = s.frames.size() > 1 ? 1 : 0;  // (frame 1, as session 40's census)
    if (s.frames.empty() || s.frames[f].meshes.size() <= std::size_t(s.self[0])) continue;
    const auto& src = *s.frames[f].meshes[s.self[0]];
    TriangleMesh<double> m;
    for (const auto& v : src.vertices) m.vertices.push_back({v.x, v.y, v.z});
    m.triangles = src.triangles;
    detail::HierarchicalHash<double> h;
    h.build(m, 0);
    double c[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // visited, canonical, sweep x, y, z, best axis, spans, cells
    std::vector<const detail::HierarchicalHash<double>::Table*> tables = {&h.table(h.top_level)};
    if (&h.table(0) != tables[0]) tables.push_back(&h.table(0));
    std::vector<std::uint32_t> span;
    double hist[6] = {0,0,0,0,0,0};
    for (const auto* t : tables)
      for (const auto& sl : t->slots) {
        if (sl.count == 0) continue;
        c[7] += 1;
        const detail::CellId cell = detail::cellOfKey(sl.key);
        const auto* e = t->entries.data() + sl.begin;
        span.resize(sl.count);
        for (std::uint32_t a = 0; a < sl.count; ++a)
          span[a] = detail::subcellSpan(h.boxes[e[a].id], cell.level, cell.x, cell.y, cell.z,
                                        h.grid);
        const double m = sl.count;
        hist[m<=4?0:m<=8?1:m<=16?2:m<=32?3:m<=64?4:5] += m*(m-1)/2;
        double ax[3] = {0,0,0};
        for (std::uint32_t a = 0; a < sl.count; ++a)
          for (std::uint32_t b = a + 1; b < sl.count; ++b) {
            c[0] += 1;
            for (int k = 0; k < 3; ++k) {
              const unsigned la = (span[a] >> (5*k)) & 15u, ha = (span[a] >> (15+5*k)) & 15u;
              const unsigned lb = (span[b] >> (5*k)) & 15u, hb = (span[b] >> (15+5*k)) & 15u;
              if (la <= hb && lb <= ha) ax[k] += 1;
            }
            if (((e[a].lo_mask | e[b].lo_mask) & 7u) != 7u) continue;
            c[1] += 1;
            c[6] += detail::subcellSpansOverlap(span[a], span[b]);
          }
        c[2] += ax[0]; c[3] += ax[1]; c[4] += ax[2];
        c[5] += std::min(ax[0], std::min(ax[1], ax[2]));
      }
    std::printf("| %s (%zu) | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f |\n", s.name.c_str(),
                m.triangles.size(), c[7], c[0], c[1], c[2], c[3], c[4], c[5], c[6]);
    std::printf("   pair visits by cell size <=4,8,16,32,64,>64: %.0f %.0f %.0f %.0f %.0f %.0f\n", hist[0],hist[1],hist[2],hist[3],hist[4],hist[5]);
    std::fflush(stdout);
  }
  return 0;
}
