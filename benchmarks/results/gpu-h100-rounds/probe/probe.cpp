// Probe: the joint two cloth-ball frames under several knobs: rounds, candidates, the cells'
// candidates, phase-1 / filter / query / total device ms (medians of 15 frames).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>
#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/mesh_io.h"
#include "kdet_fcl/query.h"
#include "cuda/cuda_backend.h"
using namespace kdet_fcl;
static double med(std::vector<double> v) { std::sort(v.begin(), v.end()); return v[v.size() / 2]; }
int main(int argc, char** argv) {
  const std::string d = std::getenv("KDET_FCL_DATA_DIR");
  HashedMesh<float> a(readMesh<float>(d + "/unc/cloth-ball/cloth_ball92.ply"));
  HashedMesh<float> b(readMesh<float>(d + "/unc/cloth-ball/cloth_ball93.ply"));
  QueryOptions o; o.backend = Backend::Cuda;
  const char* label = argc > 1 ? argv[1] : "";
  cuda::setProfiling(true);
  std::vector<double> c, f, q, t; cuda::QueryProfile p;
  for (int k = 0; k < 20; ++k) {
    cuda::markDeformed(a); cuda::markDeformed(b);
    AllPairsResult r = intersectAll(a, b, o);
    p = cuda::lastQueryProfile();
    if (k < 5) continue;
    c.push_back(p.candidates_ms); f.push_back(p.filter_ms); q.push_back(p.query_ms); t.push_back(p.total_ms);
  }
  std::printf("%-28s rounds %d cands %zu cells %zu exact %zu pairs %zu | phase1 %.3f filter %.3f query %.3f total %.3f | %zu B\n",
              label, p.rounds, p.candidates, p.cell_candidates, p.exact_tests, p.pairs, med(c), med(f), med(q), med(t),
              cuda::deviceBytesInUse());
  return 0;
}
