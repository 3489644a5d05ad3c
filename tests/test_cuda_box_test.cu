// The float box test of the warp-wide candidate scan (cuda/device_hash.cuh): the query box, a
// double box, is rounded inward to float once (testBoxOf), and each entry's float box is compared
// with it in float (boxesInFloat). That must decide exactly what detail::boxesOverlap decides on
// the double query box, for every query bound, including bounds that are no float, bounds one
// double step away from a float, and bounds beyond the float range. Skips without a device.

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "cuda/device_hash.cuh"
#include "cuda_device.h"

namespace {

using kdet_fcl::detail::Aabb;

__global__ void floatBoxTestKernel(std::size_t n, const Aabb<double>* q, const Aabb<float>* e,
                                   int* out) {
  const std::size_t k = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (k < n)
    out[k] = kdet_fcl::cuda::boxesInFloat(kdet_fcl::cuda::testBoxOf(q[k]),
                                          kdet_fcl::cuda::loadBox(e + k))
                 ? 1
                 : 0;
}

/// Doubles at and around the float f: f, the next doubles either side, the midpoints to its float
/// neighbours (no float), and those neighbours.
std::vector<double> around(float f) {
  const double d = f, up = std::nextafter(f, INFINITY), down = std::nextafter(f, -INFINITY);
  std::vector<double> v = {d, std::nextafter(d, INFINITY), std::nextafter(d, -INFINITY)};
  if (std::isfinite(up)) v.insert(v.end(), {up, 0.5 * (d + up)});
  if (std::isfinite(down)) v.insert(v.end(), {down, 0.5 * (d + down)});
  return v;
}

TEST(CudaFloatBoxTest, DecidesExactlyWhatTheDoubleTestDecides) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  std::mt19937 rng(5);
  std::vector<float> pivots = {0.f, 1.f, -1.f, 0.1f, -0.3f, 1e-30f, -1e-30f, 3.5e7f, FLT_MAX,
                               -FLT_MAX, FLT_MIN, 1e30f};
  std::uniform_real_distribution<float> mant(-1.f, 1.f);
  std::uniform_int_distribution<int> expo(-40, 40);
  for (int k = 0; k < 40; ++k) pivots.push_back(std::ldexp(mant(rng), expo(rng)));
  std::vector<Aabb<double>> qs;
  std::vector<Aabb<float>> es;
  // One axis at a time carries the case (the others overlap widely), on each axis, for both the
  // query's lo against the entry's hi and the entry's lo against the query's hi.
  for (const float f : pivots)
    for (const double x : around(f))
      for (const float ef :
           {f, std::nextafter(f, INFINITY), std::nextafter(f, -INFINITY)}) {
        if (!std::isfinite(ef)) continue;
        for (int axis = 0; axis < 3; ++axis) {
          Aabb<double> q{{-1e300, -1e300, -1e300}, {1e300, 1e300, 1e300}};
          Aabb<float> e{{-FLT_MAX, -FLT_MAX, -FLT_MAX}, {FLT_MAX, FLT_MAX, FLT_MAX}};
          Aabb<double> q2 = q;
          Aabb<float> e2 = e;
          double* ql = &q.lo.x;
          float* eh = &e.hi.x;
          ql[axis] = x;  // x <= e.hi ?
          eh[axis] = ef;
          double* qh = &q2.hi.x;
          float* el = &e2.lo.x;
          qh[axis] = x;  // e.lo <= x ?
          el[axis] = ef;
          qs.push_back(q);
          es.push_back(e);
          qs.push_back(q2);
          es.push_back(e2);
        }
      }
  // Bounds beyond the float range (a mapped query box may reach there).
  for (const double x : {1e39, -1e39, double(FLT_MAX) * 1.0000001, -double(FLT_MAX) * 1.0000001}) {
    Aabb<double> q{{x, -1.0, -1.0}, {1e300, 1.0, 1.0}};
    Aabb<float> e{{-FLT_MAX, -1.f, -1.f}, {FLT_MAX, 1.f, 1.f}};
    qs.push_back(q);
    es.push_back(e);
    Aabb<double> q2{{-1e300, -1.0, -1.0}, {x, 1.0, 1.0}};
    qs.push_back(q2);
    es.push_back(e);
  }
  const std::size_t n = qs.size();
  Aabb<double>* dq = nullptr;
  Aabb<float>* de = nullptr;
  int* dout = nullptr;
  ASSERT_EQ(cudaMalloc(&dq, n * sizeof(Aabb<double>)), cudaSuccess);
  ASSERT_EQ(cudaMalloc(&de, n * sizeof(Aabb<float>)), cudaSuccess);
  ASSERT_EQ(cudaMalloc(&dout, n * sizeof(int)), cudaSuccess);
  ASSERT_EQ(cudaMemcpy(dq, qs.data(), n * sizeof(Aabb<double>), cudaMemcpyHostToDevice),
            cudaSuccess);
  ASSERT_EQ(cudaMemcpy(de, es.data(), n * sizeof(Aabb<float>), cudaMemcpyHostToDevice),
            cudaSuccess);
  floatBoxTestKernel<<<static_cast<unsigned>((n + 127) / 128), 128>>>(n, dq, de, dout);
  ASSERT_EQ(cudaGetLastError(), cudaSuccess);
  std::vector<int> got(n);
  ASSERT_EQ(cudaMemcpy(got.data(), dout, n * sizeof(int), cudaMemcpyDeviceToHost), cudaSuccess);
  cudaFree(dq);
  cudaFree(de);
  cudaFree(dout);
  std::size_t yes = 0, no = 0, nearest_wrong = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const bool want = kdet_fcl::detail::boxesOverlap(qs[k], es[k]);
    EXPECT_EQ(got[k] != 0, want) << "case " << k;
    (want ? yes : no) += 1;
    // The query box converted to the nearest floats instead: wrong on some of these cases, so
    // they do test the directed rounding.
    const Aabb<float> nearest{{float(qs[k].lo.x), float(qs[k].lo.y), float(qs[k].lo.z)},
                              {float(qs[k].hi.x), float(qs[k].hi.y), float(qs[k].hi.z)}};
    if (kdet_fcl::detail::boxesOverlap(nearest, es[k]) != want) ++nearest_wrong;
  }
  EXPECT_GT(yes, n / 4);
  EXPECT_GT(no, n / 4);
  EXPECT_GT(nearest_wrong, 100u);
}

}  // namespace
