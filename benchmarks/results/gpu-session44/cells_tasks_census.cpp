// Census (session 44, CPU only): the warp tasks of the cells' pairs, rows (8 per task, as the
// default on crowded meshes, and 32) against windows of 32 entries (call 1's kernel), in
// rounds of 32 partner visits: the total, the longest task, and the tail (the longest task
// against the mean work of 4,224 resident warps: 132 SMs x 8 blocks x 4 warps).
// Build (repository root, after a build in build/): g++ -O2 -std=c++17 -I include -I src -I .
//   -I build -I benchmarks -isystem /usr/include/eigen3 benchmarks/results/gpu-session44/cells_tasks_census.cpp
//   benchmarks/bench_scenes.cpp -L build -lkdet_fcl -lfcl -lccd -o census
// Run: KDET_FCL_DATA_DIR=../shared/data LD_LIBRARY_PATH=build ./census SCENE... (kdet_bench keys)
// (Cells in the CPU table's order; the device's order differs, the cells' sizes do not.)
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>
#include "bench_scenes.h"
#include "cpu/hierarchical_hash.h"
#include "kdet_fcl/kdet_fcl.h"
namespace kb = kdet_bench;
using namespace kdet_fcl;
int main(int argc, char** argv) {
  kb::SceneConfig cfg; cfg.frames = 3; cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR"); cfg.data_dir = d ? d : "";
  std::vector<std::string> want; for (int i = 1; i < argc; ++i) want.push_back(argv[i]);
  for (const auto& s : kb::makeAllScenes(cfg, want)) {
    if (s.self.empty()) continue;
    const std::size_t f = s.frames.size() > 1 ? 1 : 0;
    const auto& src = *s.frames[f].meshes[s.self[0]];
    TriangleMesh<double> m;
    for (const auto& v : src.vertices) m.vertices.push_back({v.x, v.y, v.z});
    m.triangles = src.triangles;
    detail::HierarchicalHash<double> h; h.build(m, 0);
    std::vector<std::uint32_t> begin, end;  // cells in table order, entries contiguous
    std::uint32_t at = 0;
    std::vector<const detail::HierarchicalHash<double>::Table*> tables = {&h.table(h.top_level)};
    if (&h.table(0) != tables[0]) tables.push_back(&h.table(0));
    for (const auto* t : tables)
      for (const auto& sl : t->slots) if (sl.count) { begin.push_back(at); at += sl.count; end.push_back(at); }
    const std::uint32_t entries = at;
    std::vector<std::uint32_t> cell_of(entries);
    for (std::size_t c = 0; c < begin.size(); ++c) for (auto e = begin[c]; e < end[c]; ++e) cell_of[e] = std::uint32_t(c);
    const double warps = 4224;
    for (std::uint32_t rows : {8u, 32u}) {  // rows' tasks: partners of each row ~ m/2, in rounds of 32 over the task
      double total = 0, longest = 0; std::size_t tasks = 0;
      for (std::uint32_t first = 0; first < entries; first += rows, ++tasks) {
        double visits = 0;
        for (std::uint32_t k = first; k < std::min(entries, first + rows); ++k) {
          const std::uint32_t c = cell_of[k], mm = end[c] - begin[c], a = k - begin[c];
          visits += (mm - 1) / 2 + ((mm % 2 == 0 && a < mm / 2) ? 1 : 0);
        }
        const double rounds = std::ceil(visits / 32);
        total += rounds; longest = std::max(longest, rounds);
      }
      std::printf("%s rows %u: tasks %zu, rounds %.0f, longest %.0f, mean per warp %.1f, tail x%.1f\n", s.name.c_str(), rows, tasks, total, longest, total / warps, longest / (total / warps));
    }
    {  // windows: in-window steps (most later entries of one cell in the window) + 32 per later window of the last cell
      double total = 0, longest = 0; std::size_t tasks = 0;
      for (std::uint32_t first = 0; first < entries; first += 32, ++tasks) {
        double steps = 0;
        for (std::uint32_t e = first; e < std::min(entries, first + 32); ++e) {
          const std::uint32_t c = cell_of[e], we = std::min(first + 32, end[c]);
          steps = std::max(steps, double(we - e - 1));
        }
        const std::uint32_t last = std::min(entries, first + 32) - 1, le = end[cell_of[last]];
        for (std::uint32_t next = first + 32; next < le; next += 32) steps += std::min(32u, le - next);
        total += steps; longest = std::max(longest, steps);
      }
      std::printf("%s windows: tasks %zu, steps %.0f, longest %.0f, mean per warp %.1f, tail x%.1f\n", s.name.c_str(), tasks, total, longest, total / warps, longest / (total / warps));
    }
    std::fflush(stdout);
  }
}
