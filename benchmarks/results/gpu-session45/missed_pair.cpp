// Check (session 45, CPU only): the one missed pair that kdet_bench's H100 run named,
// (57312, 59964) of unc-n-body-pair's inter query (call 5): each triangle's diameter, level and
// box, the query side (the smaller, j of B, in A's hash on A's level 2), the query's cell range
// and sub-cell span corners in A's grid from its box in double and from its fixed-point
// coordinates (the device's two ways), and the entry's span in each of its cells. Output:
// missed_pair.txt. Build and run as skip_rule_check.cpp.
#include <cstdio>
#include "nbody_pair.h"
using namespace kdet_fcl;
using namespace kdet_fcl::detail;
int main() {
  NbodyPair p;
  loadNbodyPair(p);
  const auto &A = p.A, &B = p.B;
  const auto &ha = p.ha, &hb = p.hb;
  const std::uint32_t i = 57312, j = 59964;
  std::printf("A tris %zu, B tris %zu; grid A cell0 %.9g origin %.9g %.9g %.9g; B cell0 %.9g origin %.9g %.9g %.9g\n",
    A.triangles.size(), B.triangles.size(), ha.grid.cell0, ha.grid.origin[0], ha.grid.origin[1], ha.grid.origin[2],
    hb.grid.cell0, hb.grid.origin[0], hb.grid.origin[1], hb.grid.origin[2]);
  std::printf("d_i %.17g (level A %d, level in B's grid %d), d_j %.17g (level B %d, in A's grid %d)\n",
    ha.diameter[i], levelFor(ha.diameter[i], ha.grid), levelFor(ha.diameter[i], hb.grid),
    hb.diameter[j], levelFor(hb.diameter[j], hb.grid), levelFor(hb.diameter[j], ha.grid));
  auto pb = [](const char* n, const Aabb<double>& b) { std::printf("%s [%.17g %.17g %.17g] - [%.17g %.17g %.17g]\n", n, b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z); };
  pb("box i", ha.boxes[i]); pb("box j", hb.boxes[j]);
  for (int k = 0; k < 3; ++k) { auto v = A.vertices[A.triangles[i][k]]; std::printf(" i v%d %.17g %.17g %.17g\n", k, v.x, v.y, v.z); }
  for (int k = 0; k < 3; ++k) { auto v = B.vertices[B.triangles[j][k]]; std::printf(" j v%d %.17g %.17g %.17g\n", k, v.x, v.y, v.z); }
  {
    const auto& H = ha; const Aabb<double> qb = intersectBoxes(hb.boxes[j], H.bounds);
    const int L = levelFor(H.diameter[i], H.grid);
    const CellRange rq = cellRange(qb, L, H.grid), re = cellRange(H.boxes[i], L, H.grid);
    std::printf("L %d rq [%lld %lld %lld]-[%lld %lld %lld] re [%lld %lld %lld]-[%lld %lld %lld]\n", L,
      (long long)rq.lo[0],(long long)rq.lo[1],(long long)rq.lo[2],(long long)rq.hi[0],(long long)rq.hi[1],(long long)rq.hi[2],
      (long long)re.lo[0],(long long)re.lo[1],(long long)re.lo[2],(long long)re.hi[0],(long long)re.hi[1],(long long)re.hi[2]);
    const std::uint32_t corners = subcellSpanCorners(qb, L, rq, H.grid);
    std::uint32_t fcorners = 0; long long flo[3], fhi[3];
    for (int a = 0; a < 3; ++a) {
      const std::uint32_t lo = (std::uint32_t)cellCoordScaled(qb.lo[a], a, 16.0, H.grid);
      const std::uint32_t hi = (std::uint32_t)cellCoordScaled(qb.hi[a], a, 16.0, H.grid);
      flo[a] = lo >> (L + 4); fhi[a] = hi >> (L + 4);
      fcorners |= (((lo >> L) & 15u) << (5 * a)) | (((hi >> L) & 15u) << (15 + 5 * a));
    }
    std::printf("corners double %08x fixed %08x; fixed range [%lld %lld %lld]-[%lld %lld %lld]\n", corners, fcorners,
      flo[0], flo[1], flo[2], fhi[0], fhi[1], fhi[2]);
    for (auto x = re.lo[0]; x <= re.hi[0]; ++x) for (auto y = re.lo[1]; y <= re.hi[1]; ++y) for (auto z = re.lo[2]; z <= re.hi[2]; ++z) {
      const std::uint32_t es = subcellSpan(H.boxes[i], L, x, y, z, H.grid);
      std::printf(" entry cell %lld %lld %lld span lo %u %u %u hi %u %u %u\n", (long long)x,(long long)y,(long long)z,
        es & 15, (es >> 5) & 15, (es >> 10) & 15, (es >> 15) & 15, (es >> 20) & 15, (es >> 25) & 15);
    }
    std::printf("bounds A lo %.17g %.17g %.17g hi %.17g %.17g %.17g\n", H.bounds.lo.x, H.bounds.lo.y, H.bounds.lo.z, H.bounds.hi.x, H.bounds.hi.y, H.bounds.hi.z);
  }
  std::printf("tri i %u %u %u, tri j %u %u %u\n", A.triangles[i][0], A.triangles[i][1], A.triangles[i][2], B.triangles[j][0], B.triangles[j][1], B.triangles[j][2]);
}
