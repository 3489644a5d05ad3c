// libFuzzer target: the exact closed triangle-triangle test (detail/triangle_intersection.h) on
// triangles decoded from bytes (degenerate, coplanar and one-ulp constructions included) against
// the independent GMP referee (tests/exact_referee.h), plus its symmetries: swapping the two
// triangles, permuting and reversing vertices, and float inputs equal to their double values.

#include <cstdint>
#include <cstdlib>

#include "exact_referee.h"
#include "fuzz_bytes.h"
#include "kdet_fcl/detail/triangle_intersection.h"

using kdet_fcl::Vec3;
using kdet_fcl::detail::trianglesIntersect;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  kdet_fuzz::ByteReader r(data, size);
  Vec3<double> P[3], Q[3];
  kdet_fuzz::triangle(r, P);
  kdet_fuzz::triangle(r, Q);
  if (r.u8() & 1) {  // share the plane of P exactly: Q's points as affine combinations would
    for (int k = 0; k < 3; ++k) Q[k].z = P[0].z;  // round, so use a common z plane instead
    for (int k = 0; k < 3; ++k) P[k].z = P[0].z;
  }
  const bool got = trianglesIntersect(P[0], P[1], P[2], Q[0], Q[1], Q[2]);
  const bool ref = kdet_referee::trianglesMeet({P[0], P[1], P[2]}, {Q[0], Q[1], Q[2]});
  if (got != ref) std::abort();
  // Symmetries.
  if (trianglesIntersect(Q[0], Q[1], Q[2], P[0], P[1], P[2]) != got) std::abort();
  if (trianglesIntersect(P[1], P[2], P[0], Q[2], Q[0], Q[1]) != got) std::abort();
  if (trianglesIntersect(P[2], P[1], P[0], Q[0], Q[2], Q[1]) != got) std::abort();
  // Float inputs: the same decision on the float values (converted exactly to double).
  Vec3<float> pf[3], qf[3];
  Vec3<double> pd[3], qd[3];
  for (int k = 0; k < 3; ++k) {
    pf[k] = {float(P[k].x), float(P[k].y), float(P[k].z)};
    qf[k] = {float(Q[k].x), float(Q[k].y), float(Q[k].z)};
    pd[k] = {double(pf[k].x), double(pf[k].y), double(pf[k].z)};
    qd[k] = {double(qf[k].x), double(qf[k].y), double(qf[k].z)};
  }
  bool finite = true;
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 3; ++c) finite = finite && std::isfinite(pd[k][c]) && std::isfinite(qd[k][c]);
  if (finite && trianglesIntersect(pf[0], pf[1], pf[2], qf[0], qf[1], qf[2]) !=
                    trianglesIntersect(pd[0], pd[1], pd[2], qd[0], qd[1], qd[2]))
    std::abort();
  return 0;
}
