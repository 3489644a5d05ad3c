#pragma once
// Meshes built from FCL's types alone, for the programs that must not link kdet_fcl
// (examples/unmodified_fcl.cpp, benchmarks/results/cpu-interpose/refit_misses.cpp): a UV sphere,
// a torus and a wavy sheet, as FCL BVHModels.

#include <cmath>
#include <memory>
#include <vector>

#include <fcl/fcl.h>

namespace fcl_only {

constexpr double kPi = 3.14159265358979323846;

struct Soup {
  std::vector<fcl::Vector3d> points;
  std::vector<fcl::Triangle> triangles;
};

// A grid of nu x nv quads over (u, v) in [0,1]^2, mapped by f; a wrapping direction joins its
// last column (row) to its first.
template <class F>
Soup grid(int nu, int nv, bool wrap_u, bool wrap_v, F f) {
  Soup s;
  const int cols = wrap_u ? nu : nu + 1, rows = wrap_v ? nv : nv + 1;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) s.points.push_back(f(double(i) / nu, double(j) / nv));
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int i1 = (i + 1) % cols, j1 = (j + 1) % rows;
      const int a = j * cols + i, b = j * cols + i1, c = j1 * cols + i1, d = j1 * cols + i;
      s.triangles.emplace_back(a, b, c);
      s.triangles.emplace_back(a, c, d);
    }
  return s;
}

inline Soup sphere(double r, int nu, int nv) {
  // Poles are rings of tiny radius (not points), so every triangle has area.
  return grid(nu, nv, true, false, [r](double u, double v) {
    const double th = 2 * kPi * u, ph = kPi * (0.001 + 0.998 * v);
    return fcl::Vector3d(r * std::sin(ph) * std::cos(th), r * std::sin(ph) * std::sin(th),
                         r * std::cos(ph));
  });
}

inline Soup torus(double big, double small, int nu, int nv) {
  return grid(nu, nv, true, true, [big, small](double u, double v) {
    const double th = 2 * kPi * u, ph = 2 * kPi * v;
    return fcl::Vector3d((big + small * std::cos(ph)) * std::cos(th),
                         (big + small * std::cos(ph)) * std::sin(th), small * std::sin(ph));
  });
}

// A sheet of side 3 through the unit sphere's upper half, waving with phase t.
inline fcl::Vector3d sheetPoint(double u, double v, double t) {
  const double x = 3 * u - 1.5, y = 3 * v - 1.5;
  return {x, y, 0.4 + 0.25 * std::sin(3 * x + t) * std::cos(2 * y - t)};
}

inline Soup sheet(int n, double t) {
  return grid(n, n, false, false, [t](double u, double v) { return sheetPoint(u, v, t); });
}

template <class BV>
std::shared_ptr<fcl::BVHModel<BV>> model(const Soup& s) {
  auto m = std::make_shared<fcl::BVHModel<BV>>();
  m->beginModel();
  m->addSubModel(s.points, s.triangles);
  m->endModel();
  return m;
}

}  // namespace fcl_only
