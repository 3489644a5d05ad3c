// Census (session 41, CPU only): the self query's same-level pairs (selfCellPairsKernel's work)
// counted for each order of its tests, to pick what to try on the device. Session 40's census
// (../gpu-session40/cell_pairs_census.cpp) counted canonical -> box -> adjacency. Here, of the
// canonical pairs of each cell: how many pass the sub-cell spans (4 bytes per entry, read
// coalesced from the cell; off for sparse meshes), how many of those overlap by box, how many
// canonical pairs share a vertex index (the 12-byte test the direction "adjacency before the box"
// would run first), and how many pass spans and do not share an index (the boxes that order
// would still load). Same hash as the device's (levels, cells, first-cell bits).
// Build (repository root, after a build in build/): g++ -O2 -std=c++17 -I include -I src -I .
//   -I build -I benchmarks -isystem /usr/include/eigen3 cell_pairs_orders.cpp
//   benchmarks/bench_scenes.cpp -L build -lkdet_fcl -lfcl -lccd -o orders
#include <cstdio>
#include <cstdlib>
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
  std::printf("| mesh | visited | canonical | spans | spans+box | share index | spans, no shared index | candidates |\n|---|---:|---:|---:|---:|---:|---:|---:|\n");
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
    double c[7] = {0, 0, 0, 0, 0, 0, 0};
    std::vector<const detail::HierarchicalHash<double>::Table*> tables = {&h.table(h.top_level)};
    if (&h.table(0) != tables[0]) tables.push_back(&h.table(0));
    std::vector<std::uint32_t> span;
    for (const auto* t : tables)
      for (const auto& sl : t->slots) {
        if (sl.count == 0) continue;
        const detail::CellId cell = detail::cellOfKey(sl.key);
        const auto* e = t->entries.data() + sl.begin;
        span.resize(sl.count);
        for (std::uint32_t a = 0; a < sl.count; ++a)
          span[a] = detail::subcellSpan(h.boxes[e[a].id], cell.level, cell.x, cell.y, cell.z,
                                        h.grid);
        for (std::uint32_t a = 0; a < sl.count; ++a)
          for (std::uint32_t b = a + 1; b < sl.count; ++b) {
            c[0] += 1;
            if (((e[a].lo_mask | e[b].lo_mask) & 7u) != 7u) continue;
            c[1] += 1;
            const auto& ta = m.triangles[e[a].id];
            const auto& tb = m.triangles[e[b].id];
            bool share = false;
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) share |= ta[i] == tb[j];
            c[4] += share;
            const bool sp = detail::subcellSpansOverlap(span[a], span[b]);
            c[2] += sp;
            c[5] += sp && !share;
            const bool box = overlap(h.boxes[e[a].id], h.boxes[e[b].id]);
            if (sp && box) c[3] += 1;
            if (box && !share) c[6] += 1;
            if (box && !sp) std::printf("!! spans dropped an overlapping pair\n");
          }
      }
    std::printf("| %s (%zu) | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f |\n", s.name.c_str(),
                m.triangles.size(), c[0], c[1], c[2], c[3], c[4], c[5], c[6]);
    std::fflush(stdout);
  }
  return 0;
}
