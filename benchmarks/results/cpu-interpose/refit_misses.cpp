// Session 52: does FCL 0.7 miss pairs after its refit? The unmodified program's bench scene
// (examples/unmodified_fcl.cpp: an 80k-triangle wavy sheet through a 20k-triangle sphere, both
// BVHModel<OBBRSS>), deformed through beginUpdateModel/updateVertex/endUpdateModel as the bench
// does. Per frame: FCL on the refitted model, FCL on a model built fresh from the same vertices,
// and kdet_fcl::collide; at the first and the last frame also the exact O(n*m) brute force.
//
// Build (from the checkout, after scripts/setup.sh), on one line:
//   g++ -O2 -std=c++17 -Iinclude -Iexamples -isystem /usr/include/eigen3
//     benchmarks/results/cpu-interpose/refit_misses.cpp -o /tmp/refit_misses
//     -Lbuild -lkdet_fcl -lfcl -Wl,-rpath,$PWD/build
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include <fcl/fcl.h>
#include <kdet_fcl/kdet_fcl.h>

#include "fcl_only_meshes.h"  // examples/: the same sphere and sheet
#include "probe_util.h"

namespace {
using fcl_only::Soup;
using fcl_only::sheet;
using fcl_only::sheetPoint;
using fcl_only::sphere;
std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> model(const Soup& s) {
  return fcl_only::model<fcl::OBBRSSd>(s);
}
using probe::mesh;
using probe::Pairs;
using probe::pairsOf;
}  // namespace

int main() {
  const int side = 200, frames = 9;
  const Soup ball = sphere(1.0, 140, 72);
  auto cloth_model = model(sheet(side, 0.0));
  fcl::CollisionObjectd c(cloth_model), s(model(ball));
  const fcl::CollisionRequestd all(std::numeric_limits<int>::max(), false);
  for (int i = 0; i < frames; ++i) {
    const double t = 0.1 * i;
    cloth_model->beginUpdateModel();
    for (int j = 0; j <= side; ++j)
      for (int k = 0; k <= side; ++k)
        cloth_model->updateVertex(sheetPoint(double(k) / side, double(j) / side, t));
    cloth_model->endUpdateModel();
    c.computeAABB();
    fcl::CollisionResultd refit, fresh, kdet;
    fcl::collide(&c, &s, all, refit);
    kdet_fcl::collide(&c, &s, all, kdet);
    fcl::CollisionObjectd rebuilt(model(sheet(side, t)));
    fcl::collide(&rebuilt, &s, all, fresh);
    const Pairs a = pairsOf(refit), b = pairsOf(fresh), k = pairsOf(kdet);
    std::printf("frame %d (t = %.1f): FCL refitted %zu, FCL built fresh %zu, kdet_fcl %zu\n", i, t,
                a.size(), b.size(), k.size());
    for (const auto& p : k)
      if (!a.count(p))
        std::printf("  (%ld, %ld): kdet_fcl and FCL built fresh %s, FCL refitted no\n", p.first,
                    p.second, b.count(p) ? "yes" : "NO");
    for (const auto& p : a)
      if (!k.count(p)) std::printf("  (%ld, %ld): FCL refitted only\n", p.first, p.second);
    if (i == 0 || i == frames - 1) {
      const auto exact = kdet_fcl::bruteForceIntersectMeshes(
          mesh(sheet(side, t)), kdet_fcl::Transform<double>{}, mesh(ball),
          kdet_fcl::Transform<double>{});
      Pairs e;
      for (const auto& q : exact) e.emplace(q.a, q.b);
      std::printf("  exact brute force: %zu pairs; kdet_fcl %s it, FCL built fresh %s it\n",
                  e.size(), e == k ? "equals" : "DIFFERS FROM", e == b ? "equals" : "differs from");
    }
  }
}
