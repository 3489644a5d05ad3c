// Session 52: first contact and every pair where the meshes' bounds overlap, FCL's own collide
// against kdet_fcl::collide in one process. A sphere (48 x 24 quads) at the centre of the
// examples' torus (R 0.9, r 0.3, 64 x 24 quads), both BVHModel<OBBRSS>, identity poses: with
// radius 0.55 the sphere sits in the ring's hole (a near miss, 0.05 from the tube); with 0.62 it
// cuts the tube shallowly. Medians of 2,000 calls each, in µs; then each pair set against the
// exact O(n*m) brute force.
// Build (from the checkout, after scripts/setup.sh), on one line:
//   g++ -O2 -std=c++17 -Iinclude -Iexamples -isystem /usr/include/eigen3
//     benchmarks/results/cpu-interpose/near_contact_probe.cpp -o /tmp/near_contact_probe
//     -Lbuild -lkdet_fcl -lfcl -Wl,-rpath,$PWD/build
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include <fcl/fcl.h>
#include <kdet_fcl/detail/triangle_distance.h>
#include <kdet_fcl/kdet_fcl.h>

#include "fcl_only_meshes.h"  // examples/: the same sphere and torus
#include "probe_util.h"

using namespace fcl_only;

using probe::mesh;
using probe::Pairs;
using probe::pairsOf;

int main() {
  const Soup ring = torus(0.9, 0.3, 64, 24);
  for (double radius : {0.55, 0.62}) {
    const Soup ball = sphere(radius, 48, 24);
    fcl::CollisionObjectd a(model<fcl::OBBRSSd>(ball)), b(model<fcl::OBBRSSd>(ring));
    Pairs by_fcl, by_kdet;
    for (const auto& [name, cap] : {std::pair<const char*, int>{"first contact", 1},
                                   std::pair<const char*, int>{"every pair", std::numeric_limits<int>::max()}}) {
      for (int lib = 0; lib < 2; ++lib) {
        std::vector<double> us;
        fcl::CollisionResultd last;
        for (int k = 0; k < 2000; ++k) {
          fcl::CollisionResultd r;
          const fcl::CollisionRequestd request(cap, false);
          const auto t0 = std::chrono::steady_clock::now();
          if (lib == 0)
            fcl::collide(&a, &b, request, r);
          else
            kdet_fcl::collide(&a, &b, request, r);
          us.push_back(
              std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0)
                  .count());
          last = r;
        }
        std::sort(us.begin(), us.end());
        std::printf("radius %.2f, %-13s %-9s %8.1f us, contacts %zu\n", radius, name,
                    lib == 0 ? "FCL" : "kdet_fcl", us[us.size() / 2], last.numContacts());
        if (cap != 1) (lib == 0 ? by_fcl : by_kdet) = pairsOf(last);
      }
    }
    Pairs exact;
    const auto ma = mesh(ball), mb = mesh(ring);
    for (const auto& q : kdet_fcl::bruteForceIntersectMeshes(ma, kdet_fcl::Transform<double>{}, mb,
                                                            kdet_fcl::Transform<double>{}))
      exact.emplace(q.a, q.b);
    std::size_t fcl_extra = 0, fcl_missing = 0;
    for (const auto& p : by_fcl) {
      if (exact.count(p)) continue;
      ++fcl_extra;
      const auto& ta = ma.triangles[std::size_t(p.first)];
      const auto& tb = mb.triangles[std::size_t(p.second)];
      const double d2 = kdet_fcl::detail::triangleDistanceSquared(
          ma.vertices[ta[0]], ma.vertices[ta[1]], ma.vertices[ta[2]], mb.vertices[tb[0]],
          mb.vertices[tb[1]], mb.vertices[tb[2]]);
      std::printf("  FCL's (%ld, %ld): not intersecting exactly; distance %.2g (double)\n",
                  p.first, p.second, std::sqrt(d2));
    }
    for (const auto& p : exact) fcl_missing += by_fcl.count(p) ? 0 : 1;
    std::printf("radius %.2f: exact pairs %zu; kdet_fcl %s; FCL %zu not in the exact set, %zu missed\n",
                radius, exact.size(), by_kdet == exact ? "equals them" : "DIFFERS", fcl_extra,
                fcl_missing);
  }
}
