// Procedural scenes moved by analytic deformations (no physics engine).

#include "kdet_fcl/scenes.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "kdet_fcl/errors.h"

namespace kdet_fcl {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

template <class S>
TriangleMesh<S> makeSphere(const Vec3<S>& center, S radius, int segments, int rings) {
  if (segments < 3 || rings < 2 || !(radius > 0))
    throw InvalidInputError("makeSphere: need segments >= 3, rings >= 2 and radius > 0");
  TriangleMesh<S> m;
  const auto vid = [&](int ring, int seg) {
    // ring 0 and ring `rings` are the poles (one vertex each)
    if (ring == 0) return std::uint32_t(0);
    if (ring == rings) return std::uint32_t(1 + (rings - 1) * segments);
    return std::uint32_t(1 + (ring - 1) * segments + (seg % segments));
  };
  m.vertices.push_back({center.x, center.y, S(center.z + radius)});
  for (int r = 1; r < rings; ++r) {
    const double th = kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double ph = 2 * kPi * s / segments;
      m.vertices.push_back({S(center.x + radius * std::sin(th) * std::cos(ph)),
                            S(center.y + radius * std::sin(th) * std::sin(ph)),
                            S(center.z + radius * std::cos(th))});
    }
  }
  m.vertices.push_back({center.x, center.y, S(center.z - radius)});
  for (int s = 0; s < segments; ++s) {
    m.triangles.push_back({vid(0, 0), vid(1, s), vid(1, s + 1)});
    for (int r = 1; r < rings - 1; ++r) {
      m.triangles.push_back({vid(r, s), vid(r + 1, s), vid(r + 1, s + 1)});
      m.triangles.push_back({vid(r, s), vid(r + 1, s + 1), vid(r, s + 1)});
    }
    m.triangles.push_back({vid(rings - 1, s), vid(rings, 0), vid(rings - 1, s + 1)});
  }
  return m;
}

template <class S>
TriangleMesh<S> makeDrapedCloth(int n, S size, S sphere_radius, S penetration, S time) {
  if (n < 1 || !(size > 0) || !(sphere_radius > 0))
    throw InvalidInputError("makeDrapedCloth: need n >= 1, size > 0 and sphere_radius > 0");
  TriangleMesh<S> m;
  const double R = sphere_radius, Rin = R * (1 - double(penetration));
  const double t = std::clamp(double(time), 0.0, 1.0);
  const double half = size / 2.0;
  const double fold_x = half * 0.6;  // the strip beyond this is folded back over the cloth
  m.vertices.reserve(std::size_t(n + 1) * (n + 1));
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      double x = -half + size * double(i) / n, y = -half + size * double(j) / n;
      double lift = 0;
      if (x > fold_x) {
        // Fold the border strip back over the cloth with a wave, so that it dips through the
        // cloth beneath it (self-intersections away from the crease).
        const double u = x - fold_x;
        x = fold_x - u;
        lift = R * 0.04 * std::sin(6 * kPi * u / (half - fold_x + 1e-12) + 0.5) + R * 0.005;
      }
      const double r = std::sqrt(x * x + y * y);
      // Drape: a cap on a sphere slightly smaller than the solid one (so the cloth cuts into
      // it), then hanging down outside it.
      const double zd = r <= Rin ? std::sqrt(Rin * Rin - r * r) : -(r - Rin) * 1.5;
      const double z = (1 - t) * (R * 1.2) + t * zd + lift;
      m.vertices.push_back({S(x), S(y), S(z)});
    }
  const auto id = [&](int i, int j) { return std::uint32_t(i * (n + 1) + j); };
  m.triangles.reserve(std::size_t(2) * n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

template <class S>
TriangleMesh<S> makeRandomSoup(std::size_t count, S extent, S min_size, S max_size,
                               std::uint64_t seed) {
  if (!(min_size > 0) || !(max_size >= min_size) || !(extent >= 0))
    throw InvalidInputError("makeRandomSoup: need 0 < min_size <= max_size and extent >= 0");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  TriangleMesh<S> m;
  const double lmin = std::log(double(min_size)), lmax = std::log(double(max_size));
  for (std::size_t k = 0; k < count; ++k) {
    const double c[3] = {extent * u01(rng), extent * u01(rng), extent * u01(rng)};
    const double s = std::exp(lmin + (lmax - lmin) * u01(rng));
    Vec3<S> p[3];
    for (auto& q : p)
      q = {S(c[0] + s * (u01(rng) - 0.5)), S(c[1] + s * (u01(rng) - 0.5)),
           S(c[2] + s * (u01(rng) - 0.5))};
    m.addTriangle(p[0], p[1], p[2]);
  }
  return m;
}

template TriangleMesh<float> makeSphere(const Vec3<float>&, float, int, int);
template TriangleMesh<double> makeSphere(const Vec3<double>&, double, int, int);
template TriangleMesh<float> makeDrapedCloth(int, float, float, float, float);
template TriangleMesh<double> makeDrapedCloth(int, double, double, double, double);
template TriangleMesh<float> makeRandomSoup(std::size_t, float, float, float, std::uint64_t);
template TriangleMesh<double> makeRandomSoup(std::size_t, double, double, double, std::uint64_t);

}  // namespace kdet_fcl
