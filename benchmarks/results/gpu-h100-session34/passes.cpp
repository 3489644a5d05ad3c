// Passes of exact::sumSign per form on the exact tests of the pairs the filter leaves undecided
// (session 34, after the change). Compiled against a copy of include/ of 0022aca in which
// sumSign increments g_pass[N == 48][pass] (inline long g_pass[2][8]) at the top of each pass.
// Counts the passes of exact::sumSign over the exact tests of every pair the plane filter leaves
// undecided (self pairs sharing no vertex by index or coordinates), per form (24 or 48 terms).
#include <kdet_fcl/detail/aabb.h>
#include <kdet_fcl/detail/triangle_intersection.h>
#include <kdet_fcl/mesh_io.h>
#include <kdet_fcl/scenes.h>
#include <algorithm>
#include <cstdio>
#include <vector>
using namespace kdet_fcl;
int main(int argc, char** argv) {
  TriangleMesh<float> m = argc > 1 ? readMesh<float>(argv[1]) : makeDrapedCloth<float>(212, 3.0f, 1.0f, 0.02f, 0.3f);
  const std::size_t nt = m.triangles.size();
  std::vector<detail::Aabb<float>> bx(nt);
  auto V = [&](std::uint32_t k) { return m.vertices[k]; };
  for (std::size_t i = 0; i < nt; ++i) {
    const auto& T = m.triangles[i];
    bx[i] = {{std::min({V(T[0]).x, V(T[1]).x, V(T[2]).x}), std::min({V(T[0]).y, V(T[1]).y, V(T[2]).y}), std::min({V(T[0]).z, V(T[1]).z, V(T[2]).z})},
             {std::max({V(T[0]).x, V(T[1]).x, V(T[2]).x}), std::max({V(T[0]).y, V(T[1]).y, V(T[2]).y}), std::max({V(T[0]).z, V(T[1]).z, V(T[2]).z})}};
  }
  std::vector<std::uint32_t> ord(nt);
  for (std::size_t i = 0; i < nt; ++i) ord[i] = std::uint32_t(i);
  std::sort(ord.begin(), ord.end(), [&](auto a, auto b) { return bx[a].lo.x < bx[b].lo.x; });
  long und = 0;
  for (std::size_t x = 0; x < nt; ++x)
    for (std::size_t y = x + 1; y < nt && bx[ord[y]].lo.x <= bx[ord[x]].hi.x; ++y) {
      const auto i = ord[x], j = ord[y];
      if (!(bx[i].lo.y <= bx[j].hi.y && bx[j].lo.y <= bx[i].hi.y && bx[i].lo.z <= bx[j].hi.z && bx[j].lo.z <= bx[i].hi.z)) continue;
      const auto& A = m.triangles[i];
      const auto& B = m.triangles[j];
      bool adj = false;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) adj = adj || A[a] == B[b] || V(A[a]) == V(B[b]);
      if (adj) continue;
      if (detail::trianglesFilterVerdict(V(A[0]), V(A[1]), V(A[2]), V(B[0]), V(B[1]), V(B[2])) != detail::FilterVerdict::Undecided) continue;
      ++und;
      (void)detail::trianglesIntersect(V(A[0]), V(A[1]), V(A[2]), V(B[0]), V(B[1]), V(B[2]));
    }
  std::printf("%zu triangles, %ld undecided pairs (no shared vertex); sumSign passes run:\n", nt, und);
  for (int f = 0; f < 2; ++f) {
    std::printf("  %d terms:", f ? 48 : 24);
    for (int p = 0; p < 4; ++p) std::printf(" pass %d: %ld", p + 1, detail::exact::g_pass[f][p]);
    std::printf("\n");
  }
}
