// Near-coplanar quadruples of points for the exact orientations' short sums
// (exact::orient3dSignShort), of each of its forms and of neither: test_predicates checks them
// against the rational referee, test_cuda_predicates checks the device's signs against the
// host's.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "kdet_fcl/vec3.h"

namespace kdet_test {

/// Which form of orient3dSignShort a case was made for.
enum class ShortForm {
  ExactDifferences,  ///< every coordinate difference exact in double: 24 terms
  Floats,            ///< floats whose differences are not all exact in double: 48 terms
  Neither,           ///< doubles with inexact differences: left to the expansion
};

struct NearCoplanarCase {
  ShortForm form;
  kdet_fcl::Vec3<double> p[4];
};

/// `rounds` cases of each form, in turn, from `seed`:
/// - ExactDifferences: a, b, c on the grid of 2^-10 (offset by 0 or 2^20), d = a + s (b - a) +
///   t (c - a) exactly for small integers s, t, then d.z moved by -2^-30, 0 or 2^-30;
/// - Floats: (x, y, x + y) on the plane z = x + y through the origin, each point at its own scale
///   2^-44 to 2^16 (x, y of 23 significant bits, so that x + y is a float and the products need
///   two doubles), then one coordinate of the last moved by one float ulp, or none;
/// - Neither: doubles near a plane, one coordinate tiny (1e-30) against 1 + 2^-40, then one ulp
///   off it.
inline std::vector<NearCoplanarCase> nearCoplanarCases(int rounds, std::uint64_t seed) {
  using V = kdet_fcl::Vec3<double>;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> K(-4000, 4000), S(-2, 2), E(-40, 20), O(0, 3);
  std::uniform_int_distribution<int> M(-(1 << 22) + 1, (1 << 22) - 1);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<NearCoplanarCase> cases;
  for (int it = 0; it < rounds; ++it) {
    const double off = (it & 1) ? 0x1p20 : 0.0;
    auto gp = [&] { return V{off + K(rng) * 0x1p-10, off + K(rng) * 0x1p-10, K(rng) * 0x1p-10}; };
    NearCoplanarCase g{ShortForm::ExactDifferences, {gp(), gp(), gp(), {}}};
    const int s = S(rng), t = S(rng);
    g.p[3] = g.p[0] + (g.p[1] - g.p[0]) * double(s) + (g.p[2] - g.p[0]) * double(t);
    g.p[3].z += double(O(rng) - 1) * 0x1p-30;
    cases.push_back(g);
    NearCoplanarCase f{ShortForm::Floats, {}};
    for (V& q : f.p) {
      const int e = E(rng) - 4, mx = M(rng), my = M(rng);
      q = {double(std::ldexp(float(mx), e)), double(std::ldexp(float(my), e)),
           double(std::ldexp(float(mx + my), e))};
    }
    const int move = O(rng);
    if (move < 3) {
      double& x = f.p[3][move];
      x = double(std::nextafter(float(x), (it & 2) ? INFINITY : -INFINITY));
    }
    cases.push_back(f);
    NearCoplanarCase n{ShortForm::Neither, {}};
    n.p[0] = {1e-30, U(rng), U(rng)};
    n.p[1] = {1 + 0x1p-40, U(rng), U(rng)};
    n.p[2] = {U(rng), 1e7, U(rng)};
    n.p[3] = n.p[0] + (n.p[1] - n.p[0]) * 0.25 + (n.p[2] - n.p[0]) * 0.5;
    n.p[3].z = std::nextafter(n.p[3].z, (it & 1) ? INFINITY : -INFINITY);
    cases.push_back(n);
  }
  return cases;
}

}  // namespace kdet_test
