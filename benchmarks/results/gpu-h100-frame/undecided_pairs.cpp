// Which candidate pairs does the GPU's plane filter leave undecided (CPU count; session 24,
// extended in session 28 to the procedural cloth: `cloth N T` builds makeDrapedCloth(N, 3, 1,
// 0.02, T), as gpu_bench's cloth scenes do)?
// The candidates as phase 1 finds them (boxes that overlap, no shared vertex index), by a
// uniform grid; for each, detail::trianglesFilterVerdict; the undecided ones classified by
// their exact zero signs. Built against the library:
//   g++ -std=c++17 -O2 -ffp-contract=off -Iinclude undecided_pairs.cpp -Lbuild -lkdet_fcl
//   ./a.out ../shared/data/unc/cloth-ball/cloth_ball92.ply   or   ./a.out cloth 316 1.0
#include "kdet_fcl/mesh_io.h"
#include "kdet_fcl/scenes.h"
#include <string>
#include "kdet_fcl/detail/triangle_intersection.h"
#include <cstdio>
#include <unordered_map>
#include <vector>
#include <algorithm>
#include <cmath>
using namespace kdet_fcl;
using namespace kdet_fcl::detail;
int main(int argc, char** argv) {
  auto m = std::string(argv[1]) == "cloth"
               ? makeDrapedCloth<float>(std::stoi(argv[2]), 3.f, 1.f, 0.02f, std::stof(argv[3]))
               : readMesh<float>(argv[1]);
  const size_t n = m.numTriangles();
  std::vector<float> lo(3*n), hi(3*n);
  double avg = 0;
  for (size_t t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k) { lo[3*t+k] = 1e30f; hi[3*t+k] = -1e30f; }
    for (int c = 0; c < 3; ++c) { const auto& v = m.vertices[m.triangles[t][c]];
      for (int k = 0; k < 3; ++k) { lo[3*t+k] = std::min(lo[3*t+k], v[k]); hi[3*t+k] = std::max(hi[3*t+k], v[k]); } }
    avg += hi[3*t] - lo[3*t];
  }
  const double cs = 2 * avg / n;
  std::unordered_map<long long, std::vector<unsigned>> grid;
  auto key = [&](long long x, long long y, long long z) { return (x * 73856093LL) ^ (y * 19349663LL) ^ (z * 83492791LL); };
  for (size_t t = 0; t < n; ++t) {
    long long a[3], b[3];
    for (int k = 0; k < 3; ++k) { a[k] = (long long)std::floor(lo[3*t+k]/cs); b[k] = (long long)std::floor(hi[3*t+k]/cs); }
    for (long long x = a[0]; x <= b[0]; ++x) for (long long y = a[1]; y <= b[1]; ++y) for (long long z = a[2]; z <= b[2]; ++z) grid[key(x,y,z)].push_back(t);
  }
  std::vector<std::pair<unsigned,unsigned>> cand;
  for (auto& [k, v] : grid) for (size_t i = 0; i < v.size(); ++i) for (size_t j = i+1; j < v.size(); ++j) {
    unsigned a = std::min(v[i], v[j]), b = std::max(v[i], v[j]);
    bool ov = true; for (int d = 0; d < 3; ++d) ov = ov && lo[3*a+d] <= hi[3*b+d] && lo[3*b+d] <= hi[3*a+d];
    if (!ov) continue;
    bool adj = false; for (int x = 0; x < 3; ++x) for (int y = 0; y < 3; ++y) adj = adj || m.triangles[a][x] == m.triangles[b][y];
    if (!adj) cand.push_back({a, b});
  }
  std::sort(cand.begin(), cand.end()); cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
  size_t axis_zeros = 0, all_zeros = 0, und = 0, sharedc = 0, coplanar = 0, onezero = 0, hits = 0, und_hits = 0;
  for (auto [a, b] : cand) {
    const Vec3<float>* P[3] = {&m.vertices[m.triangles[a][0]], &m.vertices[m.triangles[a][1]], &m.vertices[m.triangles[a][2]]};
    const Vec3<float>* Q[3] = {&m.vertices[m.triangles[b][0]], &m.vertices[m.triangles[b][1]], &m.vertices[m.triangles[b][2]]};
    auto v = trianglesFilterVerdict(*P[0], *P[1], *P[2], *Q[0], *Q[1], *Q[2]);
    bool r = trianglesIntersect(*P[0], *P[1], *P[2], *Q[0], *Q[1], *Q[2]);
    hits += r;
    if (v != FilterVerdict::Undecided) continue;
    ++und; und_hits += r;
    bool sc = false; for (int x = 0; x < 3; ++x) for (int y = 0; y < 3; ++y) sc = sc || *P[x] == *Q[y];
    if (sc) { ++sharedc; continue; }
    int z = 0; for (int i = 0; i < 3; ++i) z += orient3dSign(toDouble(*Q[0]), toDouble(*Q[1]), toDouble(*Q[2]), toDouble(*P[i])) == 0;
    int z2 = 0; for (int i = 0; i < 3; ++i) z2 += orient3dSign(toDouble(*P[0]), toDouble(*P[1]), toDouble(*P[2]), toDouble(*Q[i])) == 0;
    if (z == 3 && z2 == 3) ++coplanar; else if (z + z2 > 0) ++onezero;
    // Exact zeros from a shared coordinate: all four points of an orientation equal on one axis.
    auto axisZero = [](const Vec3<float>& a, const Vec3<float>& b, const Vec3<float>& c, const Vec3<float>& d) {
      for (int k = 0; k < 3; ++k) if (a[k] == b[k] && b[k] == c[k] && c[k] == d[k]) return true; return false; };
    int za = 0; for (int i = 0; i < 3; ++i) za += axisZero(*Q[0], *Q[1], *Q[2], *P[i]) + axisZero(*P[0], *P[1], *P[2], *Q[i]);
    axis_zeros += za; all_zeros += z + z2;
  }
  printf("triangles %zu candidates %zu pairs %zu undecided %zu (of them pairs %zu): shared coordinates %zu, exactly coplanar %zu, some exact zero %zu, other %zu\n",
         n, cand.size(), hits, und, und_hits, sharedc, coplanar, onezero, und - sharedc - coplanar - onezero);
  printf("exact zero signs %zu, of them with four points equal on one axis %zu\n", all_zeros, axis_zeros);
}
