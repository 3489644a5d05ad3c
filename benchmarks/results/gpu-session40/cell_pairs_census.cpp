// Census (session 40, CPU only): where the self query's same-level work goes, the work of the
// CUDA backend's selfCellPairsKernel (416 us of the 1M cloth's frame on an H200, call 1's ncu).
// That kernel tests every unordered pair of entries of each cell once: the canonical-cell test
// (both entries' first-cell bits together cover x, y and z), then the box test, then the
// adjacency rule. Here, on the CPU hash of the same meshes (the same levels, cells and
// first-cell bits as the device's build), per scene: cells and entries per level, the pairs the
// kernel visits (sum of m(m-1)/2), and how many pass each test in turn.
// Build (from the repository root, after a build in build/): g++ -O2 -std=c++17 -I include -I src
//   -I . -I build -I benchmarks -isystem /usr/include/eigen3 cell_pairs_census.cpp
//   benchmarks/bench_scenes.cpp -L build -lkdet_fcl -lfcl -lccd -o census
#include <cstdio>
#include <cstdlib>
#include <map>
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
  for (const auto& s : scenes) {
    if (s.self.empty()) continue;
    const int o = s.self[0];
    const auto& src = *s.frames[1].meshes[o];
    TriangleMesh<double> m;
    for (const auto& v : src.vertices) m.vertices.push_back({v.x, v.y, v.z});
    m.triangles = src.triangles;
    detail::HierarchicalHash<double> h;
    h.build(m, 0);
    std::map<int, std::vector<double>> lv;  // level: cells, entries, pairs, canonical, boxes, nonadjacent
    std::vector<const detail::HierarchicalHash<double>::Table*> tables = {&h.table(h.top_level)};
    if (&h.table(0) != tables[0]) tables.push_back(&h.table(0));
    for (const auto* t : tables) {
      for (const auto& sl : t->slots) {
        if (sl.count == 0) continue;
        const int L = h.level[t->entries[sl.begin].id];  // (a cell holds its level's triangles)
        auto& r = lv[L];
        r.resize(6);
        r[0] += 1;
        r[1] += sl.count;
        const auto* e = t->entries.data() + sl.begin;
        for (std::uint32_t a = 0; a < sl.count; ++a)
          for (std::uint32_t b = a + 1; b < sl.count; ++b) {
            r[2] += 1;
            if (((e[a].lo_mask | e[b].lo_mask) & 7u) != 7u) continue;
            r[3] += 1;
            if (!overlap(h.boxes[e[a].id], h.boxes[e[b].id])) continue;
            r[4] += 1;
            const auto& ta = m.triangles[e[a].id];
            const auto& tb = m.triangles[e[b].id];
            bool share = false;
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) share |= ta[i] == tb[j];
            if (!share) r[5] += 1;
          }
      }
    }
    std::printf("== %s, object %d: %zu triangles, %zu entries\n", s.name.c_str(), o,
                m.triangles.size(), h.numEntries());
    std::printf("| level | cells | entries | entries/cell | pairs visited | canonical | boxes overlap | not adjacent |\n|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (auto& [L, r] : lv)
      std::printf("| %d | %.0f | %.0f | %.2f | %.0f | %.0f | %.0f | %.0f |\n", L, r[0], r[1],
                  r[1] / r[0], r[2], r[3], r[4], r[5]);
    std::fflush(stdout);
  }
  return 0;
}
