// Census (session 44, CPU only): each triangle also stored, as a guest, in the cells of the next
// finer occupied level; the cells then give native-native and native-guest pairs, and the scan
// runs from a triangle's level to the levels two or more above it only. Visits (a cell's
// guest-guest pairs skipped) and span passes against the present scheme's visits.
// Build (repository root, after a build in build/): g++ -O2 -std=c++17 -I include -I src -I .
//   -I build -I benchmarks -isystem /usr/include/eigen3 benchmarks/results/gpu-session44/guest_census.cpp
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
    HierarchicalHash<double> h; h.build(m, 0);
    const GridParams g = h.grid; const int top = h.top_level; const std::size_t n = m.triangles.size();
    std::vector<int> lev(n);
    for (std::size_t i = 0; i < n; ++i) lev[i] = h.level[i];
    // next finer occupied level below l
    std::vector<int> finer(top + 1, -1);
    for (int l = 0; l <= top; ++l) for (int k = l - 1; k >= 0; --k) if (h.levelOccupied(k)) { finer[l] = k; break; }
    std::vector<std::unordered_map<CellKey, std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>>, KH>> cells(top + 1);
    double native_e = 0, guest_e = 0;
    for (std::size_t i = 0; i < n; ++i) {
      auto put = [&](int l, bool guest) {
        const CellRange r = cellRange(h.boxes[i], l, g);
        for (auto x = r.lo[0]; x <= r.hi[0]; ++x) for (auto y = r.lo[1]; y <= r.hi[1]; ++y) for (auto z = r.lo[2]; z <= r.hi[2]; ++z) {
          auto& c = cells[l][makeCellKey(l, x, y, z)];
          (guest ? c.second : c.first).push_back(std::uint32_t(i));
          (guest ? guest_e : native_e) += 1;
        }
      };
      put(lev[i], false);
      if (finer[lev[i]] >= 0) put(finer[lev[i]], true);
    }
    double cv = 0, cspan = 0, sv = 0, sspan = 0, cv_native = 0;
    for (int l = 0; l <= top; ++l) for (const auto& kv : cells[l]) {
      const CellId c = cellOfKey(kv.first);
      const auto& a = kv.second.first; const auto& b = kv.second.second;
      const double na = a.size(), nb = b.size();
      cv_native += na * (na - 1) / 2;
      cv += na * (na - 1) / 2 + na * nb;
      auto sp = [&](std::uint32_t t) { return subcellSpan(h.boxes[t], l, c.x, c.y, c.z, g); };
      for (std::size_t p = 0; p < a.size(); ++p) {
        for (std::size_t q = p + 1; q < a.size(); ++q) cspan += subcellSpansOverlap(sp(a[p]), sp(a[q]));
        for (std::size_t q = 0; q < b.size(); ++q) cspan += subcellSpansOverlap(sp(a[p]), sp(b[q]));
      }
    }
    double sv_old = 0;
    for (std::size_t i = 0; i < n; ++i) {
      int skip_to = -1;  // the next occupied level above lev[i]: its pairs come from the guests
      for (int l = lev[i] + 1; l <= top; ++l) if (h.levelOccupied(l)) { skip_to = l; break; }
      for (int l = lev[i] + 1; l <= top; ++l) {
        if (!h.levelOccupied(l)) continue;
        const CellRange r = cellRange(h.boxes[i], l, g);
        for (auto x = r.lo[0]; x <= r.hi[0]; ++x) for (auto y = r.lo[1]; y <= r.hi[1]; ++y) for (auto z = r.lo[2]; z <= r.hi[2]; ++z) {
          auto it = cells[l].find(makeCellKey(l, x, y, z));
          if (it == cells[l].end()) continue;
          const double k = it->second.first.size();
          sv_old += k;
          if (l == skip_to) continue;
          sv += k;
          const std::uint32_t qs = subcellSpan(h.boxes[i], l, x, y, z, g);
          for (std::uint32_t j : it->second.first) sspan += subcellSpansOverlap(qs, subcellSpan(h.boxes[j], l, x, y, z, g));
        }
      }
    }
    std::printf("%s: entries native %.0f guest %.0f | now: cells %.0f + scan %.0f = %.0f | guests: cells %.0f (spans pass %.0f) + scan %.0f (spans pass %.0f) = %.0f\n",
                s.name.c_str(), native_e, guest_e, cv_native, sv_old, cv_native + sv_old, cv, cspan, sv, sspan, cv + sv);
    std::fflush(stdout);
  }
}
