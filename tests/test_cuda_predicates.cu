// The exact predicates on the device (include/kdet_fcl/detail/exact_predicates.h and
// triangle_intersection.h, compiled by nvcc with fma and run in a kernel): every sign the device
// gives is the host's, whose predicates test_predicates checks against an exact rational
// referee. Near-coplanar points of both forms of the short sums (exact differences; floats whose
// differences are not exact) and of neither, and the plane filter's verdict on triangles whose
// edges cross in an axis-aligned plane. Skips without a device.

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <cstddef>
#include <random>
#include <vector>

#include "cuda_device.h"
#include "kdet_fcl/detail/exact_predicates.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "near_coplanar_points.h"

namespace {

using kdet_fcl::Vec3;
using V = Vec3<double>;
namespace kd = kdet_fcl::detail;

/// Per case k (points p[4k .. 4k + 3]): out[3k] the full predicate, out[3k + 1] the short sums,
/// out[3k + 2] the expansion.
__global__ void orientKernel(std::size_t n, const V* p, int* out) {
  const std::size_t k = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (k >= n) return;
  const V* q = p + 4 * k;
  out[3 * k] = kd::orient3dSign(q[0], q[1], q[2], q[3]);
  out[3 * k + 1] = kd::exact::orient3dSignShort(q[0], q[1], q[2], q[3]);
  out[3 * k + 2] = kd::exact::orient3dSignExact(q[0], q[1], q[2], q[3]);
}

/// Per pair k (float triangles t[6k .. 6k + 5]): out[2k] the filters' verdict, out[2k + 1] the
/// exact test.
__global__ void verdictKernel(std::size_t n, const Vec3<float>* t, int* out) {
  const std::size_t k = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (k >= n) return;
  const Vec3<float>* q = t + 6 * k;
  out[2 * k] = static_cast<int>(kd::trianglesFilterVerdict(q[0], q[1], q[2], q[3], q[4], q[5]));
  out[2 * k + 1] = kd::trianglesIntersect(q[0], q[1], q[2], q[3], q[4], q[5]) ? 1 : 0;
}

/// Runs `kernel` over n cases of `in` (per_case inputs each) and returns its `per_out` ints each.
template <class T, class Kernel>
std::vector<int> runOnDevice(Kernel kernel, const std::vector<T>& in, std::size_t per_case,
                             std::size_t per_out) {
  const std::size_t n = in.size() / per_case;
  T* d_in = nullptr;
  int* d_out = nullptr;
  EXPECT_EQ(cudaMalloc(&d_in, in.size() * sizeof(T)), cudaSuccess);
  EXPECT_EQ(cudaMalloc(&d_out, n * per_out * sizeof(int)), cudaSuccess);
  EXPECT_EQ(cudaMemcpy(d_in, in.data(), in.size() * sizeof(T), cudaMemcpyHostToDevice),
            cudaSuccess);
  kernel<<<static_cast<unsigned int>((n + 127) / 128), 128>>>(n, d_in, d_out);
  EXPECT_EQ(cudaGetLastError(), cudaSuccess);
  std::vector<int> out(n * per_out);
  EXPECT_EQ(cudaMemcpy(out.data(), d_out, out.size() * sizeof(int), cudaMemcpyDeviceToHost),
            cudaSuccess);
  cudaFree(d_in);
  cudaFree(d_out);
  return out;
}

/// The points of near_coplanar_points.h's cases, four per case.
std::vector<V> nearCoplanarPoints(int rounds) {
  std::vector<V> p;
  for (const kdet_test::NearCoplanarCase& k : kdet_test::nearCoplanarCases(rounds, 2027))
    p.insert(p.end(), std::begin(k.p), std::end(k.p));
  return p;
}

TEST(CudaPredicates, DeviceSignsAreTheHostsOnNearCoplanarPoints) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  const std::vector<V> p = nearCoplanarPoints(2000);
  const std::vector<int> out = runOnDevice(orientKernel, p, 4, 3);
  const std::size_t n = p.size() / 4;
  ASSERT_EQ(out.size(), 3 * n);
  int zero = 0, short_decided = 0, short_undecided = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const V* q = &p[4 * k];
    const int host = kd::exact::orient3dSignExact(q[0], q[1], q[2], q[3]);
    ASSERT_EQ(out[3 * k + 2], host) << "case " << k << ": the expansion";
    ASSERT_EQ(out[3 * k], host) << "case " << k << ": orient3dSign";
    const int host_short = kd::exact::orient3dSignShort(q[0], q[1], q[2], q[3]);
    ASSERT_EQ(out[3 * k + 1], host_short) << "case " << k << ": the short sums";
    if (host_short != kd::exact::kSignUnknown) {
      ASSERT_EQ(host_short, host) << "case " << k;
      ++short_decided;
    } else {
      ++short_undecided;
    }
    zero += host == 0;
  }
  EXPECT_GT(zero, int(n) / 10);                // exact zeros occur
  EXPECT_GT(short_decided, int(n) / 2);        // the two short forms (two cases in three)
  EXPECT_GT(short_undecided, int(n) / 5);      // and the points of neither kind
}

TEST(CudaPredicates, DeviceFilterVerdictsOnEdgesCrossingInAnAxisPlaneAreTheExactTests) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  std::mt19937_64 rng(12);
  std::uniform_int_distribution<int> I(-3, 3), Y(1, 2), B(0, 1);
  std::vector<Vec3<float>> t;
  for (int it = 0; it < 20000; ++it)
    for (int k = 0; k < 2; ++k) {
      t.push_back({float(I(rng)), 0.f, float(I(rng))});
      t.push_back({float(I(rng)), 0.f, float(I(rng))});
      t.push_back({float(I(rng)), float(B(rng) ? Y(rng) : -Y(rng)), float(I(rng))});
    }
  const std::vector<int> out = runOnDevice(verdictKernel, t, 6, 2);
  const std::size_t n = t.size() / 6;
  ASSERT_EQ(out.size(), 2 * n);
  int decided = 0, hits = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3<float>* q = &t[6 * k];
    const bool exact = kd::trianglesIntersect(q[0], q[1], q[2], q[3], q[4], q[5]);
    const auto verdict = kd::trianglesFilterVerdict(q[0], q[1], q[2], q[3], q[4], q[5]);
    ASSERT_EQ(out[2 * k + 1], exact ? 1 : 0) << "pair " << k;
    ASSERT_EQ(out[2 * k], static_cast<int>(verdict)) << "pair " << k;
    if (verdict != kd::FilterVerdict::Undecided) {
      ++decided;
      ASSERT_EQ(verdict == kd::FilterVerdict::Intersect, exact) << "pair " << k;
    }
    hits += exact;
  }
  EXPECT_GT(decided, int(n) / 2);
  EXPECT_GT(hits, int(n) / 10);
}

}  // namespace
