// The exact expansions each undecided pair's exact test runs (session 34). Compiled against a
// copy of include/ of b34a53f in which orient2dSignExact and orient3dSignExact increment the
// counters g_o2 and g_o3 (inline long, in namespace exact), with -DTINYOBJLOADER_USE_DOUBLE,
// src/scenes.cpp, src/mesh_io.cpp, src/triangle_mesh.cpp and -ltinyobjloader. The pass counts
// it printed came from a prototype of the short sums and are superseded by passes.cpp.
#include <kdet_fcl/scenes.h>
#include <kdet_fcl/mesh_io.h>
#include <string>
#include <kdet_fcl/detail/triangle_intersection.h>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <vector>
using namespace kdet_fcl;
int main(int argc, char** argv) {
  int n = argc > 1 ? atoi(argv[1]) : 212;
  double t = argc > 2 ? atof(argv[2]) : 0.3;
  TriangleMesh<float> m = (argc > 3) ? readMesh<float>(argv[3]) : makeDrapedCloth<float>(n, 3.0f, 1.0f, 0.02f, float(t));
  size_t nt = m.triangles.size();
  struct B { float lo[3], hi[3]; };
  std::vector<B> bx(nt);
  for (size_t i = 0; i < nt; ++i) {
    auto& T = m.triangles[i];
    for (int a = 0; a < 3; ++a) {
      float v0 = (&m.vertices[T[0]].x)[a], v1 = (&m.vertices[T[1]].x)[a], v2 = (&m.vertices[T[2]].x)[a];
      bx[i].lo[a] = std::min({v0, v1, v2}); bx[i].hi[a] = std::max({v0, v1, v2});
    }
  }
  std::vector<unsigned> ord(nt);
  for (size_t i = 0; i < nt; ++i) ord[i] = i;
  std::sort(ord.begin(), ord.end(), [&](unsigned a, unsigned b) { return bx[a].lo[0] < bx[b].lo[0]; });
  std::vector<std::pair<unsigned,unsigned>> und;
  for (size_t x = 0; x < nt; ++x) {
    unsigned i = ord[x];
    for (size_t y = x + 1; y < nt && bx[ord[y]].lo[0] <= bx[i].hi[0]; ++y) {
      unsigned j = ord[y];
      bool ov = true;
      for (int a = 1; a < 3; ++a) ov = ov && bx[i].lo[a] <= bx[j].hi[a] && bx[j].lo[a] <= bx[i].hi[a];
      if (!ov) continue;
      auto& A = m.triangles[i]; auto& Bt = m.triangles[j];
      bool adj = false;
      for (int a = 0; a < 3; ++a) for (int b = 0; b < 3; ++b) adj = adj || A[a] == Bt[b];
      if (adj) continue;
      auto V=[&](unsigned k){return m.vertices[k];};
      if (detail::trianglesFilterVerdict(V(A[0]),V(A[1]),V(A[2]),V(Bt[0]),V(Bt[1]),V(Bt[2])) == detail::FilterVerdict::Undecided)
        und.push_back({std::min(i,j), std::max(i,j)});
    }
  }
  std::map<std::pair<long,long>, int> hist; int hits = 0;
  int share=0, zero_plane=0, trans=0, trans_fix=0;
  for (auto [i,j] : und) {
    auto& A = m.triangles[i]; auto& Bt = m.triangles[j];
    auto V=[&](unsigned k){return m.vertices[k];};
    bool sh=false; for(int a=0;a<3;++a)for(int b=0;b<3;++b) sh = sh || V(A[a])==V(Bt[b]);
    int sp[3], sq[3]; detail::FilterVerdict v;
    if (sh) { ++share; continue; }
    if (!detail::planeFilterSigns(V(A[0]),V(A[1]),V(A[2]),V(Bt[0]),V(Bt[1]),V(Bt[2]),sp,sq,v)) { ++zero_plane; continue; }
    ++trans;
    Vec3<float> a,b,c,d,e,f;
    detail::tri_isect::transversalVertices(sp,sq,V(A[0]),V(A[1]),V(A[2]),V(Bt[0]),V(Bt[1]),V(Bt[2]),a,b,c,d,e,f);
    using detail::toDouble;
    int o1 = detail::orient3dFilterSign(toDouble(b),toDouble(d),toDouble(a),toDouble(e));
    bool z1 = o1==0 && detail::sameCoordinate(toDouble(b),toDouble(d),toDouble(a),toDouble(e));
    if (o1==0 && !z1) continue;
    if (o1>0) { ++trans_fix; continue; }
    int o2 = detail::orient3dFilterSign(toDouble(a),toDouble(d),toDouble(c),toDouble(f));
    bool z2 = o2==0 && detail::sameCoordinate(toDouble(a),toDouble(d),toDouble(c),toDouble(f));
    if (o2==0 && !z2) continue;
    ++trans_fix;
  }
  printf("undecided: share-coords %d, a plane sign unproven %d, transversal %d (decided with exact zeros: %d)\n", share, zero_plane, trans, trans_fix);
  for (auto [i,j] : und) {
    long o2 = detail::exact::g_o2, o3 = detail::exact::g_o3;
    auto& A = m.triangles[i]; auto& Bt = m.triangles[j];
    auto V=[&](unsigned k){return m.vertices[k];};
    { bool sh=false; for(int a=0;a<3;++a)for(int b=0;b<3;++b) sh = sh || V(A[a])==V(Bt[b]); if (sh) continue; }
    hits += detail::trianglesIntersect(V(A[0]),V(A[1]),V(A[2]),V(Bt[0]),V(Bt[1]),V(Bt[2]));
    hist[{detail::exact::g_o3 - o3, detail::exact::g_o2 - o2}]++;
  }
  auto t0 = std::chrono::steady_clock::now();
  for (int r = 0; r < 20; ++r) for (auto [i,j] : und) {
    auto& A = m.triangles[i]; auto& Bt = m.triangles[j];
    auto V=[&](unsigned k){return m.vertices[k];};
    hits += detail::trianglesIntersect(V(A[0]),V(A[1]),V(A[2]),V(Bt[0]),V(Bt[1]),V(Bt[2]));
  }
  double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / 20 / und.size();
  for(int q=0;q<8;++q) printf("pass%d: %ld  ", q, detail::exact::g_pass[q]); printf(" tails %ld\n", detail::exact::g_tail);
  printf("undecided %zu, hits %d, %.3f us per pair (CPU)\n", und.size(), hits, us);
  for (auto& [k, c] : hist) printf("  exact orient3d %ld, orient2d %ld: %d pairs\n", k.first, k.second, c);
}
