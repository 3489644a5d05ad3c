// The 90k cloth's frame 0 (or a mesh file): its non-adjacent box-overlapping pairs and what the
// plane filter's verdict leaves undecided, by kind (session 34, before the change; compiled
// against include/ of b34a53f: g++ -O2 -std=c++17 -Iinclude undecided.cpp src/scenes.cpp).
#include <kdet_fcl/scenes.h>
#include <kdet_fcl/detail/triangle_intersection.h>
#include <algorithm>
#include <cstdio>
#include <vector>
using namespace kdet_fcl;
int main(int argc, char** argv) {
  int n = argc > 1 ? atoi(argv[1]) : 212;
  double t = argc > 2 ? atof(argv[2]) : 0.3;
  auto m = makeDrapedCloth<float>(n, 3.0f, 1.0f, 0.02f, float(t));
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
  size_t cand = 0, und = 0, isect = 0, und_share = 0, und_cop = 0, und_trans = 0, und_other = 0;
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
      ++cand;
      const auto& p0 = m.vertices[A[0]]; const auto& p1 = m.vertices[A[1]]; const auto& p2 = m.vertices[A[2]];
      const auto& q0 = m.vertices[Bt[0]]; const auto& q1 = m.vertices[Bt[1]]; const auto& q2 = m.vertices[Bt[2]];
      int sp[3], sq[3]; detail::FilterVerdict v;
      bool last = detail::planeFilterSigns(p0, p1, p2, q0, q1, q2, sp, sq, v);
      if (last) v = detail::transversalFilterVerdict(sp, sq, p0, p1, p2, q0, q1, q2);
      if (v == detail::FilterVerdict::Intersect) ++isect;
      if (v != detail::FilterVerdict::Undecided) continue;
      ++und;
      bool share = false;
      for (int a = 0; a < 3; ++a) for (int b = 0; b < 3; ++b) share = share || m.vertices[A[a]] == m.vertices[Bt[b]];
      if (share) ++und_share;
      else if (sp[0] == 0 && sp[1] == 0 && sp[2] == 0) ++und_cop;
      else if (last) ++und_trans;
      else ++und_other;
    }
  }
  printf("n=%d t=%.3f tris=%zu cand(non-adjacent box overlaps)=%zu filter-intersect=%zu undecided=%zu (share-coords %zu, coplanar %zu, transversal-undecided %zu, a zero sign %zu)\n",
         n, t, nt, cand, isect, und, und_share, und_cop, und_trans, und_other);
}
