// The exact predicates on the device (include/kdet_fcl/detail/exact_predicates.h and
// triangle_intersection.h, compiled by nvcc with fma and run in a kernel): every sign the device
// gives is the host's, whose predicates test_predicates checks against an exact rational
// referee. Near-coplanar points of both forms of the short sums (exact differences; floats whose
// differences are not exact) and of neither, and the plane filter's verdict on triangles whose
// edges cross in an axis-aligned plane. Skips without a device.

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "cuda_device.h"
#include "kdet_fcl/detail/exact_predicates.h"
#include "kdet_fcl/detail/triangle_intersection.h"

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

/// Near-coplanar points as in test_predicates: on a grid of 2^-30 (exact differences), floats on
/// the plane z = x + y at scales 2^-44 to 2^16 (differences not exact), and doubles of neither
/// kind; each exactly coplanar or moved by one step.
std::vector<V> nearCoplanarPoints(int cases) {
  std::mt19937_64 rng(2027);
  std::uniform_int_distribution<int> K(-4000, 4000), S(-2, 2), E(-40, 20), O(0, 3);
  std::uniform_int_distribution<int> M(-(1 << 22) + 1, (1 << 22) - 1);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<V> p;
  for (int it = 0; it < cases; ++it) {
    const double off = (it & 1) ? 0x1p20 : 0.0;
    auto gp = [&] { return V{off + K(rng) * 0x1p-10, off + K(rng) * 0x1p-10, K(rng) * 0x1p-10}; };
    const V a = gp(), b = gp(), c = gp();
    V d = a + (b - a) * double(S(rng)) + (c - a) * double(S(rng));
    d.z += double(O(rng) - 1) * 0x1p-30;
    p.insert(p.end(), {a, b, c, d});
    V f[4];
    for (V& q : f) {
      const int e = E(rng) - 4, mx = M(rng), my = M(rng);
      q = {double(std::ldexp(float(mx), e)), double(std::ldexp(float(my), e)),
           double(std::ldexp(float(mx + my), e))};
    }
    const int move = O(rng);
    if (move < 3) f[3][move] = double(std::nextafter(float(f[3][move]), (it & 2) ? INFINITY : -INFINITY));
    p.insert(p.end(), {f[0], f[1], f[2], f[3]});
    // Neither form: doubles near a plane, far from the origin, one of them tiny.
    const V g0{1e-30, U(rng), U(rng)}, g1{1 + 0x1p-40, U(rng), U(rng)}, g2{U(rng), 1e7, U(rng)};
    V g3 = g0 + (g1 - g0) * 0.25 + (g2 - g0) * 0.5;
    g3.z = std::nextafter(g3.z, (it & 1) ? INFINITY : -INFINITY);
    p.insert(p.end(), {g0, g1, g2, g3});
  }
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
    if (host_short != kd::exact::kSumUndecided) {
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
