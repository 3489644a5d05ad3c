#pragma once
// Session 44's CPU censuses (this folder): the self mesh of each kdet_bench scene named on the
// command line (kdet_bench's keys; frame 1 where a scene has several, as session 40's census), as
// a double mesh with its CPU hash, whose levels, cells and first-cell bits are the device's.
// Build a census (repository root, after a build in build/):
//   g++ -O2 -std=c++17 -I include -I src -I . -I build -I benchmarks -isystem /usr/include/eigen3
//     benchmarks/results/gpu-session44/NAME.cpp benchmarks/bench_scenes.cpp -L build -lkdet_fcl
//     -lfcl -lccd -o census
// Run: KDET_FCL_DATA_DIR=../shared/data LD_LIBRARY_PATH=build ./census SCENE...
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unordered_map>
#include <vector>

#include "bench_scenes.h"
#include "cpu/hierarchical_hash.h"
#include "kdet_fcl/kdet_fcl.h"

namespace census {

using Hash = kdet_fcl::detail::HierarchicalHash<double>;

/// A scene's mesh as a double mesh (the hash's input).
template <class M>
kdet_fcl::TriangleMesh<double> doubleMesh(const M& src) {
  kdet_fcl::TriangleMesh<double> m;
  for (const auto& v : src.vertices) m.vertices.push_back({v.x, v.y, v.z});
  m.triangles = src.triangles;
  return m;
}

/// Calls f(name, mesh, hash) for the self mesh of each scene named in argv[1..].
template <class F>
void forEachSelfMesh(int argc, char** argv, F&& f) {
  kdet_bench::SceneConfig cfg;
  cfg.frames = 3;
  cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  std::vector<std::string> want;
  for (int i = 1; i < argc; ++i) want.push_back(argv[i]);
  for (const auto& s : kdet_bench::makeAllScenes(cfg, want)) {
    if (s.self.empty() || s.frames.empty()) continue;
    const std::size_t fr = s.frames.size() > 1 ? 1 : 0;
    if (s.frames[fr].meshes.size() <= std::size_t(s.self[0])) continue;
    const kdet_fcl::TriangleMesh<double> m = doubleMesh(*s.frames[fr].meshes[s.self[0]]);
    Hash h;
    h.build(m, 0);
    f(s.name, m, h);
    std::fflush(stdout);
  }
}

/// The hash's cell tables (the upper one, and the lower one where it is another).
inline std::vector<const Hash::Table*> tablesOf(const Hash& h) {
  std::vector<const Hash::Table*> t = {&h.table(h.top_level)};
  if (&h.table(0) != t[0]) t.push_back(&h.table(0));
  return t;
}

/// A span's low and high slab on axis a (kdet_fcl::detail::subcellSpan's layout).
inline unsigned spanLo(std::uint32_t span, int a) { return (span >> (5 * a)) & 15u; }
inline unsigned spanHi(std::uint32_t span, int a) { return (span >> (15 + 5 * a)) & 15u; }

/// Hash of a cell key for std::unordered_map.
struct KeyHash {
  std::size_t operator()(const kdet_fcl::detail::CellKey& k) const {
    return kdet_fcl::detail::hashCellKey(k);
  }
};

/// Calls f(cell) for each cell (a CellId) of box b's cell range on `level`.
template <class F>
void forEachCell(const kdet_fcl::detail::Aabb<double>& b, int level,
                 const kdet_fcl::detail::GridParams& g, F&& f) {
  const kdet_fcl::detail::CellRange r = kdet_fcl::detail::cellRange(b, level, g);
  for (auto x = r.lo[0]; x <= r.hi[0]; ++x)
    for (auto y = r.lo[1]; y <= r.hi[1]; ++y)
      for (auto z = r.lo[2]; z <= r.hi[2]; ++z) f(kdet_fcl::detail::CellId{level, x, y, z});
}

/// Each level's cells of the hash's own grid: cells[l] maps the key of a level-l cell to its
/// triangles in index order (each triangle on its level, levelFor of its diameter, also given in
/// `level` when asked for).
using CellMap = std::unordered_map<kdet_fcl::detail::CellKey, std::vector<std::uint32_t>, KeyHash>;
inline std::vector<CellMap> cellsOf(const Hash& h, std::vector<int>* level = nullptr) {
  std::vector<CellMap> cells(h.top_level + 1);
  if (level != nullptr) level->assign(h.diameter.size(), 0);
  for (std::size_t i = 0; i < h.diameter.size(); ++i) {
    const int l = kdet_fcl::detail::levelFor(h.diameter[i], h.grid);
    if (level != nullptr) (*level)[i] = l;
    forEachCell(h.boxes[i], l, h.grid, [&](const kdet_fcl::detail::CellId& c) {
      cells[l][kdet_fcl::detail::makeCellKey(l, c.x, c.y, c.z)].push_back(std::uint32_t(i));
    });
  }
  return cells;
}

/// Calls f(cell, entries) for each cell of box b's cell range on the levels from..top that
/// `cells` holds, where cells[l] maps the key of a level-l cell to its entries (the scan of the
/// coarser levels, from = the triangle's own level + 1).
template <class Cells, class F>
void forEachOccupiedCell(const kdet_fcl::detail::Aabb<double>& b, int from, int top,
                         const kdet_fcl::detail::GridParams& g, const Cells& cells, F&& f) {
  for (int l = from; l <= top; ++l) {
    if (cells[l].empty()) continue;
    forEachCell(b, l, g, [&](const kdet_fcl::detail::CellId& c) {
      const auto it = cells[l].find(kdet_fcl::detail::makeCellKey(l, c.x, c.y, c.z));
      if (it != cells[l].end()) f(c, it->second);
    });
  }
}

/// Whether two boxes overlap (closed intervals).
inline bool boxesOverlap(const kdet_fcl::detail::Aabb<double>& p,
                         const kdet_fcl::detail::Aabb<double>& q) {
  return p.lo.x <= q.hi.x && q.lo.x <= p.hi.x && p.lo.y <= q.hi.y && q.lo.y <= p.hi.y &&
         p.lo.z <= q.hi.z && q.lo.z <= p.hi.z;
}

}  // namespace census
