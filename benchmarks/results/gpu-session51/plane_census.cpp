// Census (session 51, CPU): of a mesh's box-overlapping, non-adjacent triangle pairs (the GPU
// self query's phase-1 candidates: 773,566 on cloth_ball92.ply, as QueryProfile::candidates),
// how many would a box-against-plane test reject (one triangle's box wholly on one side of the
// other's plane), and how many the plane filter's vertex test (one triangle's three vertices
// strictly on one side of the other's plane, in double)?
// Build from the repository root after scripts/setup.sh:
//   g++ -O2 -std=c++17 -I include benchmarks/results/gpu-session51/plane_census.cpp \
//     -L build -lkdet_fcl -Wl,-rpath,$PWD/build -o /tmp/plane_census
// Run: /tmp/plane_census ../shared/data/unc/cloth-ball/cloth_ball92.ply
#include <kdet_fcl/mesh_io.h>
#include <array>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>
#include <vector>
using namespace kdet_fcl;
struct Box { double lo[3], hi[3]; };
int main(int argc, char** argv) {
  TriangleMesh<float> m = readMesh<float>(argv[1]);
  const size_t n = m.triangles.size();
  std::vector<Box> box(n);
  std::vector<std::array<double, 4>> pl(n);
  double maxd = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto& t = m.triangles[i];
    double v[3][3];
    for (int k = 0; k < 3; ++k) { const auto& p = m.vertices[t[k]]; v[k][0] = p.x; v[k][1] = p.y; v[k][2] = p.z; }
    for (int a = 0; a < 3; ++a) {
      box[i].lo[a] = std::min({v[0][a], v[1][a], v[2][a]});
      box[i].hi[a] = std::max({v[0][a], v[1][a], v[2][a]});
      maxd = std::max(maxd, box[i].hi[a] - box[i].lo[a]);
    }
    double e1[3], e2[3];
    for (int a = 0; a < 3; ++a) { e1[a] = v[1][a] - v[0][a]; e2[a] = v[2][a] - v[0][a]; }
    double nn[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    pl[i] = {nn[0], nn[1], nn[2], nn[0] * v[0][0] + nn[1] * v[0][1] + nn[2] * v[0][2]};
  }
  const double c = maxd;
  auto key = [](long x, long y, long z) { return (x * 73856093L) ^ (y * 19349663L) ^ (z * 83492791L); };
  std::unordered_multimap<long, size_t> grid;
  for (size_t i = 0; i < n; ++i) {
    long x = long(std::floor(box[i].lo[0] / c)), y = long(std::floor(box[i].lo[1] / c)), z = long(std::floor(box[i].lo[2] / c));
    grid.emplace(key(x, y, z), i);
  }
  size_t cand = 0, boxrej = 0, vertrej = 0, both = 0;
  auto side = [&](size_t a, size_t b) {  // box b vs plane a: +1/-1 wholly one side, 0 straddles
    const auto& p = pl[a]; double ctr = -p[3], rad = 0;
    for (int k = 0; k < 3; ++k) { double cc = 0.5 * (box[b].lo[k] + box[b].hi[k]), h = 0.5 * (box[b].hi[k] - box[b].lo[k]); ctr += p[k] * cc; rad += std::fabs(p[k]) * h; }
    return ctr > rad ? 1 : ctr < -rad ? -1 : 0;
  };
  auto vside = [&](size_t a, size_t b) {
    const auto& p = pl[a]; int pos = 0, neg = 0;
    for (int k = 0; k < 3; ++k) { const auto& q = m.vertices[m.triangles[b][k]]; double s = p[0] * q.x + p[1] * q.y + p[2] * q.z - p[3]; pos += s > 0; neg += s < 0; }
    return pos == 3 || neg == 3;
  };
  for (size_t i = 0; i < n; ++i) {
    long x0 = long(std::floor(box[i].lo[0] / c)), y0 = long(std::floor(box[i].lo[1] / c)), z0 = long(std::floor(box[i].lo[2] / c));
    for (long x = x0 - 1; x <= x0 + 1; ++x) for (long y = y0 - 1; y <= y0 + 1; ++y) for (long z = z0 - 1; z <= z0 + 1; ++z) {
      auto r = grid.equal_range(key(x, y, z));
      for (auto it = r.first; it != r.second; ++it) {
        size_t j = it->second; if (j <= i) continue;
        long xj = long(std::floor(box[j].lo[0] / c)), yj = long(std::floor(box[j].lo[1] / c)), zj = long(std::floor(box[j].lo[2] / c));
        if (xj != x || yj != y || zj != z) continue;  // hash collision
        bool ov = true; for (int a = 0; a < 3; ++a) ov = ov && box[i].lo[a] <= box[j].hi[a] && box[j].lo[a] <= box[i].hi[a];
        if (!ov) continue;
        bool adj = false; for (int a = 0; a < 3; ++a) for (int b = 0; b < 3; ++b) adj = adj || m.triangles[i][a] == m.triangles[j][b];
        if (adj) continue;
        ++cand;
        bool br = side(i, j) != 0 || side(j, i) != 0;
        bool vr = vside(i, j) || vside(j, i);
        boxrej += br; vertrej += vr; both += br && vr;
      }
    }
  }
  std::printf("%s: %zu triangles, %zu candidates, box-vs-plane rejects %zu (%.1f%%), vertex-vs-plane rejects %zu (%.1f%%), both %zu\n",
              argv[1], n, cand, boxrej, 100.0 * boxrej / cand, vertrej, 100.0 * vertrej / cand, both);
}
