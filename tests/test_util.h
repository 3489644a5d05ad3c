#pragma once
// Helpers shared by the tests (tested themselves in test_geometry.cpp).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "kdet_fcl/kdet_fcl.h"

namespace kdet_test {

/// Built with AddressSanitizer (some tests shrink or skip: shadow memory, RLIMIT_AS).
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

/// Absolute path of a data file, or "" when it is absent (tests skip). The folder is
/// $KDET_FCL_DATA_DIR when set (an offline GPU box keeps a copy of the files it needs there, see
/// scripts/gpu_check.sh), else ../shared/data beside the checkout.
inline std::string sharedData(const std::string& rel) {
  const char* env = std::getenv("KDET_FCL_DATA_DIR");
  const std::filesystem::path root = (env && *env) ? std::filesystem::path(env)
                                                   : std::filesystem::path(KDET_FCL_SHARED_DATA);
  const std::filesystem::path p = root / rel;
  return std::filesystem::exists(p) ? p.string() : std::string();
}

/// Skips a GPU test on a machine without a CUDA device (or a build without CUDA).
#define KDET_SKIP_WITHOUT_DEVICE()                                                     \
  do {                                                                                 \
    if (kdet_fcl::cudaDeviceCount() == 0)                                              \
      GTEST_SKIP() << (kdet_fcl::builtWithCuda() ? "no CUDA device" : "built without CUDA"); \
  } while (0)

inline std::vector<kdet_fcl::TrianglePair> sorted(std::vector<kdet_fcl::TrianglePair> v) {
  std::sort(v.begin(), v.end());
  return v;
}

/// A random rigid pose: rotation from a random unit quaternion, translation uniform in the box.
template <class S>
kdet_fcl::Transform<S> randomPose(std::mt19937_64& rng, double lo, double hi) {
  std::normal_distribution<double> g(0, 1);
  double q[4] = {g(rng), g(rng), g(rng), g(rng)};
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& c : q) c /= n;
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                          {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                          {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
  kdet_fcl::Transform<S> T;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) T.R[i][j] = S(R[i][j]);
  std::uniform_real_distribution<double> u(lo, hi);
  T.t = {S(u(rng)), S(u(rng)), S(u(rng))};
  return T;
}

/// Converts a mesh between precisions.
template <class To, class From>
kdet_fcl::TriangleMesh<To> convert(const kdet_fcl::TriangleMesh<From>& m) {
  kdet_fcl::TriangleMesh<To> r;
  r.triangles = m.triangles;
  for (const auto& v : m.vertices) r.vertices.push_back({To(v.x), To(v.y), To(v.z)});
  return r;
}

/// Two triangulated sheets in (nearly) the same plane: sheet A flat at z = 0, sheet B shifted by a
/// fraction of a cell, its vertices at z = 0 exactly, one or a few ulps off, 1e-9 off, or clearly
/// off (a mix per vertex), so that most candidate pairs are touching, coplanar or within
/// rounding of the other's plane: the cases where a plane-side filter that drops too much would
/// lose true pairs. `tilt` adds a slope to sheet B so that its triangles cross A's plane.
template <class S>
kdet_fcl::TriangleMesh<S> nearCoplanarSheets(int n, bool tilt, std::uint64_t seed,
                                             bool sheet_a = true, bool sheet_b = true) {
  std::mt19937_64 rng(seed);
  kdet_fcl::TriangleMesh<S> m;
  const S h = S(1) / S(n);
  auto offset = [&](S base) {
    switch (rng() % 7) {
      case 0: return base;
      case 1: return std::nextafter(base, S(1));
      case 2: return std::nextafter(base, S(-1));
      case 3: return std::nextafter(std::nextafter(base, S(1)), S(1));
      case 4: return base + S(1e-9);
      case 5: return base - S(1e-9);
      default: return base + S(rng() % 2 ? 0.01 : -0.01);
    }
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const S x = S(i) * h, y = S(j) * h;
      if (sheet_a) {
        m.addTriangle({x, y, 0}, {x + h, y, 0}, {x, y + h, 0});
        m.addTriangle({x + h, y, 0}, {x + h, y + h, 0}, {x, y + h, 0});
      }
      if (sheet_b) {
        const S bx = x + S(0.5) * h, by = y + S(0.25) * h;
        auto z = [&](S px, S py) {
          const S base = tilt ? (px - S(0.5)) * S(1e-6) + (py - S(0.5)) * S(3e-7) : S(0);
          return offset(base);
        };
        m.addTriangle({bx, by, z(bx, by)}, {bx + h, by, z(bx + h, by)},
                      {bx, by + h, z(bx, by + h)});
        m.addTriangle({bx + h, by, z(bx + h, by)}, {bx + h, by + h, z(bx + h, by + h)},
                      {bx, by + h, z(bx, by + h)});
      }
    }
  return m;
}

}  // namespace kdet_test
