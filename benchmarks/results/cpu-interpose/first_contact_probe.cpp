// Session 52: where a first-contact query of small meshes goes (kDet's CPU backend, one
// thread). The bench's 2,304-triangle sphere against its 3,072-triangle torus at the 12 poses of
// examples/unmodified_fcl.cpp: the full query's pairs, lookups and exact tests, then the
// max_pairs = 1 query's first pair, counters and time (mean of 200); then the same for the
// sphere of radius 0.62 cutting the torus at identity poses (near_contact_probe.cpp's scene).
// Build (from the checkout, after scripts/setup.sh), on one line:
//   g++ -O2 -std=c++17 -Iinclude -Iexamples -isystem /usr/include/eigen3
//     benchmarks/results/cpu-interpose/first_contact_probe.cpp -o /tmp/first_contact_probe
//     -Lbuild -lkdet_fcl -lfcl -Wl,-rpath,$PWD/build
#include <fcl/fcl.h>
#include <kdet_fcl/kdet_fcl.h>
#include <chrono>
#include <cstdio>

#include "fcl_only_meshes.h"
#include "probe_util.h"

using namespace fcl_only;

// The pose of examples/unmodified_fcl.cpp.
fcl::Transform3d pose(int i) {
  std::uint64_t x = 0x9E3779B97F4A7C15ull * std::uint64_t(i + 1);
  auto next = [&x] { x ^= x >> 33; x *= 0xff51afd7ed558ccdull; x ^= x >> 33; return double(x >> 11) / double(1ull << 53); };
  fcl::Vector3d axis(next() - 0.5, next() - 0.5, next() - 0.5 + 1e-3);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = fcl::AngleAxisd(2 * kPi * next(), axis.normalized()).toRotationMatrix();
  tf.translation() = fcl::Vector3d(next() - 0.5, next() - 0.5, next() - 0.5) * 1.6;
  return tf;
}

using probe::mesh;

// One scene's line: the full query, then the first-contact query (mean of 200), one thread.
void measure(const char* name, const kdet_fcl::HashedMesh<double>& a,
           const kdet_fcl::HashedMesh<double>& b) {
  kdet_fcl::QueryOptions o;
  o.threads = 1;
  const auto full = kdet_fcl::intersectMeshes(a, b, o);
  o.max_pairs = 1;
  const auto t0 = std::chrono::steady_clock::now();
  kdet_fcl::QueryResult one;
  for (int k = 0; k < 200; ++k) one = kdet_fcl::intersectMeshes(a, b, o);
  const double us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
      200;
  std::printf("%s: full %4zu pairs lookups %6llu tests %5llu | first (%u,%u) lookups %6llu box "
              "%6llu tests %4llu  %.1f us\n",
              name, full.pairs.size(), (unsigned long long)full.stats.lookups,
              (unsigned long long)full.stats.triangle_tests, one.pairs[0].a, one.pairs[0].b,
              (unsigned long long)one.stats.lookups, (unsigned long long)one.stats.box_tests,
              (unsigned long long)one.stats.triangle_tests, us);
}

int main() {
  kdet_fcl::HashedMesh<double> a(mesh(sphere(1.0, 48, 24))), b(mesh(torus(0.9, 0.3, 64, 24)));
  for (int i = 0; i < 12; ++i) {
    const auto tf = pose(i);
    kdet_fcl::Transform<double> T;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) T.R[r][c] = tf.linear()(r, c);
    T.t = {tf.translation()[0], tf.translation()[1], tf.translation()[2]};
    b.setPose(T);
    char name[16];
    std::snprintf(name, sizeof name, "pose %2d", i);
    measure(name, a, b);
  }
  // near_contact_probe.cpp's second scene: a sphere of radius 0.62 cutting the torus's tube.
  measure("r 0.62 ", kdet_fcl::HashedMesh<double>(mesh(sphere(0.62, 48, 24))),
        kdet_fcl::HashedMesh<double>(mesh(torus(0.9, 0.3, 64, 24))));
}
