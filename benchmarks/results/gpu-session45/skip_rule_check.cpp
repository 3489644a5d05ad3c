// Check (session 45, CPU only): the groups' skip rule of groups.diff (cellGroupRun) against the
// pairs of unc-n-body-pair's inter query, which kdet_bench's H100 run found short by 3 on the GPU
// (call 5). For every intersecting pair (the CPU's), the smaller triangle queries the larger
// one's hash as the device does (ties: A queries B); in the pair's canonical cell it takes the
// query's span from its clipped box's range corners and the cell's ends, the entry's span from
// its box, and counts a pair as bad where their spans miss or, on any axis, the groups' rule
// would skip the entry. Output: skip_rule_check.txt (0 bad of 62,052).
// Build (repository root, after a build in build/):
//   g++ -O2 -std=c++17 -I include -I src -I . -I build -I benchmarks -isystem /usr/include/eigen3
//     benchmarks/results/gpu-session45/skip_rule_check.cpp benchmarks/bench_scenes.cpp -L build
//     -lkdet_fcl -lfcl -lccd -o skip_rule_check
// Run: LD_LIBRARY_PATH=build ./skip_rule_check   (reads ../shared/data)
#include <cstdio>
#include "nbody_pair.h"
using namespace kdet_fcl;
using namespace kdet_fcl::detail;
using census::spanHi;
using census::spanLo;
int main() {
  NbodyPair p;
  loadNbodyPair(p);
  std::printf("unc-n-body-pair\n");
  const auto &A = p.A, &B = p.B;
  const auto &ha = p.ha, &hb = p.hb;
  // All intersecting inter pairs via the CPU library.
  HashedMesh<double> ma(A), mb(B);
  auto res = intersectMeshes(ma, mb);
  std::printf("pairs %zu\n", res.pairs.size());
  std::size_t bad = 0, checked = 0;
  for (auto [i, j] : res.pairs) {
    // The smaller one queries the larger one's hash (ties: A queries B).
    const bool a_queries = ha.diameter[i] <= hb.diameter[j];
    const auto& H = a_queries ? hb : ha;
    const std::uint32_t e = a_queries ? j : i, q = a_queries ? i : j;
    const Aabb<double> qb = intersectBoxes(a_queries ? ha.boxes[q] : hb.boxes[q], H.bounds);
    const Aabb<double> eb = H.boxes[e];
    const int L = levelFor(H.diameter[e], H.grid);
    const CellRange rq = cellRange(qb, L, H.grid), re = cellRange(eb, L, H.grid);
    const std::uint32_t corners = subcellSpanCorners(qb, L, rq, H.grid);
    for (auto x = rq.lo[0]; x <= rq.hi[0]; ++x)
      for (auto y = rq.lo[1]; y <= rq.hi[1]; ++y)
        for (auto z = rq.lo[2]; z <= rq.hi[2]; ++z) {
          if (x < re.lo[0] || x > re.hi[0] || y < re.lo[1] || y > re.hi[1] || z < re.lo[2] ||
              z > re.hi[2]) continue;
          const bool canon = (x == re.lo[0] || x == rq.lo[0]) && (y == re.lo[1] || y == rq.lo[1]) &&
                             (z == re.lo[2] || z == rq.lo[2]);
          if (!canon) continue;
          const unsigned ends = (x == rq.lo[0]) | (y == rq.lo[1]) << 1 | (z == rq.lo[2]) << 2 |
                                (x == rq.hi[0]) << 3 | (y == rq.hi[1]) << 4 | (z == rq.hi[2]) << 5;
          const std::uint32_t qs = subcellSpanInCell(corners, ends);
          const std::uint32_t es = subcellSpan(eb, L, x, y, z, H.grid);
          ++checked;
          const bool spans = subcellSpansOverlap(qs, es);
          for (int a = 0; a < 3; ++a) {
            const unsigned g = spanHi(es, a) < 8 ? 0 : (spanLo(es, a) >= 8 ? 2 : 1);
            const bool skip = (spanHi(qs, a) < 8 && g == 2) || (spanLo(qs, a) >= 8 && g == 0);
            if (skip || !spans) {
              ++bad;
              if (bad < 10)
                std::printf("pair (%u,%u) axis %d: skip %d spans %d q [%u,%u] e [%u,%u]\n", i, j, a,
                            skip, spans, spanLo(qs, a), spanHi(qs, a), spanLo(es, a), spanHi(es, a));
            }
          }
        }
  }
  std::printf("canonical cells checked %zu, bad %zu\n", checked, bad);
}
