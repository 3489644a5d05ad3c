// Which candidate pairs does the GPU's plane filter leave undecided (CPU count, session 24), and
// (session 25) what their exact test and their unproven exact orient3d cost on one CPU core?
// The candidates as phase 1 finds them (boxes that overlap, no shared vertex index), by a
// uniform grid; for each, detail::trianglesFilterVerdict; the undecided ones classified by
// their exact zero signs. Built against the library:
//   g++ -std=c++17 -O2 -ffp-contract=off -Iinclude undecided_pairs.cpp -Lbuild -lkdet_fcl
//   ./a.out ../shared/data/unc/cloth-ball/cloth_ball92.ply
#include "kdet_fcl/mesh_io.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include <cstdio>
#include <unordered_map>
#include <vector>
#include <algorithm>
#include <cmath>
#include <chrono>
using namespace kdet_fcl;
using namespace kdet_fcl::detail;
int main(int argc, char** argv) {
  auto m = readMesh<float>(argv[1]);
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
  // Timing of the exact test on the undecided pairs, and of the exact orient3d of the signs the
  // filter cannot prove there.
  std::vector<std::pair<unsigned,unsigned>> und_list;
  for (auto [a, b] : cand) {
    const Vec3<float>* P[3] = {&m.vertices[m.triangles[a][0]], &m.vertices[m.triangles[a][1]], &m.vertices[m.triangles[a][2]]};
    const Vec3<float>* Q[3] = {&m.vertices[m.triangles[b][0]], &m.vertices[m.triangles[b][1]], &m.vertices[m.triangles[b][2]]};
    if (trianglesFilterVerdict(*P[0], *P[1], *P[2], *Q[0], *Q[1], *Q[2]) == FilterVerdict::Undecided) und_list.push_back({a, b});
  }
  size_t fails = 0, tailnz = 0; volatile int sink = 0;
  auto t0 = std::chrono::steady_clock::now();
  for (int rep = 0; rep < 20; ++rep) for (auto [a, b] : und_list) {
    const auto& T = m.triangles;
    sink += trianglesIntersect(m.vertices[T[a][0]], m.vertices[T[a][1]], m.vertices[T[a][2]], m.vertices[T[b][0]], m.vertices[T[b][1]], m.vertices[T[b][2]]);
  }
  auto t1 = std::chrono::steady_clock::now();
  for (int rep = 0; rep < 20; ++rep) for (auto [a, b] : und_list) {
    const auto& T = m.triangles;
    for (int side = 0; side < 2; ++side) {
      unsigned p = side ? b : a, q = side ? a : b;
      for (int i = 0; i < 3; ++i) {
        Vec3<double> A = toDouble(m.vertices[T[p][0]]), B = toDouble(m.vertices[T[p][1]]), C = toDouble(m.vertices[T[p][2]]), D = toDouble(m.vertices[T[q][i]]);
        if (orient3dFilterSign(A, B, C, D) == 0) { sink += exact::orient3dSignExact(A, B, C, D); if (rep == 0) ++fails; }
      }
    }
  }
  auto t2 = std::chrono::steady_clock::now();
  printf("undecided %zu: exact test %.1f ns per pair; plane signs the filter cannot prove %zu (%.2f per pair), their exact orient3d %.1f ns per pair\n",
         und_list.size(), std::chrono::duration<double, std::nano>(t1 - t0).count() / 20 / und_list.size(), fails, double(fails) / und_list.size(),
         std::chrono::duration<double, std::nano>(t2 - t1).count() / 20 / und_list.size());
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
