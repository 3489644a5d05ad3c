#pragma once
// Helpers of the FCL cross-check tests (test_fcl_collide.cpp, test_fcl_mesh.cpp): FCL models from
// kdet meshes, exhaustive pair sets of FCL and kdet_fcl, and the exact settlement of differences.

#include <fcl/fcl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/detail/triangle_distance.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "kdet_fcl/kdet_fcl.h"

namespace kdet_fcl_test {

using Pair = std::pair<long, long>;
using Pairs = std::vector<Pair>;

/// An FCL model (any BV, or kdet_fcl::Mesh) built from a kdet mesh with addSubModel.
template <class Model, class S>
std::shared_ptr<Model> makeModel(const kdet_fcl::TriangleMesh<S>& m) {
  auto model = std::make_shared<Model>();
  std::vector<fcl::Vector3<S>> ps;
  for (const auto& v : m.vertices) ps.emplace_back(v.x, v.y, v.z);
  std::vector<fcl::Triangle> ts;
  for (const auto& t : m.triangles) ts.emplace_back(t[0], t[1], t[2]);
  model->beginModel(int(ts.size()), int(ps.size()));
  model->addSubModel(ps, ts);
  model->endModel();
  return model;
}

template <class S>
fcl::Transform3<S> toFcl(const kdet_fcl::Transform<S>& t) {
  fcl::Transform3<S> tf = fcl::Transform3<S>::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) tf.linear()(i, j) = t.R[i][j];
    tf.translation()[i] = t.t[i];
  }
  return tf;
}

/// FCL-test-style pose: translation uniform in [lo, hi] per axis, rotation from a random
/// unit quaternion.
template <class S>
fcl::Transform3<S> randomPose(std::mt19937_64& rng, const double lo[3], const double hi[3]) {
  std::normal_distribution<double> g(0, 1);
  Eigen::Quaternion<double> q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  fcl::Transform3<S> tf = fcl::Transform3<S>::Identity();
  tf.linear() = q.toRotationMatrix().cast<S>();
  for (int i = 0; i < 3; ++i) tf.translation()[i] = S(std::uniform_real_distribution<double>(lo[i], hi[i])(rng));
  return tf;
}

template <class S>
Pairs pairsOf(const fcl::CollisionResult<S>& r, bool unique = true) {
  Pairs p;
  for (std::size_t i = 0; i < r.numContacts(); ++i)
    p.emplace_back(long(r.getContact(i).b1), long(r.getContact(i).b2));
  std::sort(p.begin(), p.end());
  if (unique) p.erase(std::unique(p.begin(), p.end()), p.end());
  return p;
}

/// Exhaustive pair set of FCL's own collide.
template <class S>
Pairs fclPairs(const fcl::CollisionGeometry<S>* a, const fcl::Transform3<S>& ta,
               const fcl::CollisionGeometry<S>* b, const fcl::Transform3<S>& tb) {
  fcl::CollisionRequest<S> req(std::numeric_limits<int>::max(), false);
  fcl::CollisionResult<S> res;
  fcl::collide(a, ta, b, tb, req, res);
  return pairsOf(res);
}

/// Exhaustive pair set of kdet_fcl::collide; also checks one contact per pair and o1/o2.
template <class S>
Pairs kdetPairs(const fcl::CollisionGeometry<S>* a, const fcl::Transform3<S>& ta,
                const fcl::CollisionGeometry<S>* b, const fcl::Transform3<S>& tb,
                bool* one_per_pair = nullptr) {
  fcl::CollisionRequest<S> req(std::numeric_limits<int>::max(), false);
  fcl::CollisionResult<S> res;
  const std::size_t n = kdet_fcl::collide(a, ta, b, tb, req, res);
  Pairs p = pairsOf(res, false);
  bool ok = n == res.numContacts();
  for (std::size_t i = 0; i < res.numContacts(); ++i)
    ok = ok && res.getContact(i).o1 == a && res.getContact(i).o2 == b;
  const std::size_t before = p.size();
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (one_per_pair) *one_per_pair = ok && before == p.size();
  return p;
}

template <class S>
kdet_fcl::Vec3<double> worldPoint(const fcl::Transform3<S>& tf, const kdet_fcl::Vec3<S>& p) {
  const Eigen::Vector3d w = tf.template cast<double>() * Eigen::Vector3d(p.x, p.y, p.z);
  return {w[0], w[1], w[2]};
}

/// Settles a pair on which FCL and kDet disagree. kDet decides on A's vertices mapped into B's
/// frame (detail/pose.h); the pair is acceptable when (1) the exact predicate on exactly those
/// coordinates agrees with kDet, and (2) the contact is rounding-level: kDet-only pairs must come
/// apart under a translation of one triangle by `delta` (a tiny fraction of the coordinates'
/// magnitude) in some direction; FCL-only pairs must be within `delta` of each other.
/// Returns "" when acceptable, else a description of the failure.
template <class S>
std::string settle(const kdet_fcl::TriangleMesh<S>& A, const fcl::Transform3<S>& ta,
                   const kdet_fcl::TriangleMesh<S>& B, const fcl::Transform3<S>& tb, Pair pr,
                   bool kdet_has, double rel = 1e-9) {
  kdet_fcl::Transform<S> pa, pb;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) pa.R[i][j] = ta.linear()(i, j), pb.R[i][j] = tb.linear()(i, j);
    pa.t[i] = ta.translation()[i];
    pb.t[i] = tb.translation()[i];
  }
  const auto rp = kdet_fcl::detail::relativePose(pa, pb);
  kdet_fcl::Vec3<S> P[3], Q[3];
  double scale = 0;
  for (int k = 0; k < 3; ++k) {
    const auto& v = A.vertices[A.triangles[pr.first][k]];
    P[k] = rp.identity ? v : kdet_fcl::detail::mapPoint(rp.a_to_b, v);
    Q[k] = B.vertices[B.triangles[pr.second][k]];
    for (int c = 0; c < 3; ++c)
      scale = std::max({scale, std::fabs(double(P[k][c])), std::fabs(double(Q[k][c]))});
  }
  const bool exact = kdet_fcl::detail::trianglesIntersect(P[0], P[1], P[2], Q[0], Q[1], Q[2]);
  char buf[256];
  if (exact != kdet_has) {
    std::snprintf(buf, sizeof buf, "pair (%ld,%ld): kDet says %d, the exact predicate %d",
                  pr.first, pr.second, int(kdet_has), int(exact));
    return buf;
  }
  const double delta = rel * scale;
  if (kdet_has) {
    // Directions: the axes and both normals.
    std::vector<kdet_fcl::Vec3<double>> dirs = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    auto normalOf = [](const kdet_fcl::Vec3<S>* T) {
      kdet_fcl::Vec3<double> a{double(T[1].x - T[0].x), double(T[1].y - T[0].y), double(T[1].z - T[0].z)};
      kdet_fcl::Vec3<double> b{double(T[2].x - T[0].x), double(T[2].y - T[0].y), double(T[2].z - T[0].z)};
      kdet_fcl::Vec3<double> n = kdet_fcl::cross(a, b);
      const double l = std::sqrt(kdet_fcl::dot(n, n));
      return l > 0 ? n * (1 / l) : kdet_fcl::Vec3<double>{0, 0, 1};
    };
    dirs.push_back(normalOf(P));
    dirs.push_back(normalOf(Q));
    for (const auto& d : dirs)
      for (double s : {-1.0, 1.0}) {
        kdet_fcl::Vec3<double> Qm[3], Pd[3];
        for (int k = 0; k < 3; ++k) {
          Pd[k] = {double(P[k].x), double(P[k].y), double(P[k].z)};
          Qm[k] = kdet_fcl::Vec3<double>{double(Q[k].x), double(Q[k].y), double(Q[k].z)} + d * (s * delta);
        }
        if (!kdet_fcl::detail::trianglesIntersect(Pd[0], Pd[1], Pd[2], Qm[0], Qm[1], Qm[2]))
          return "";
      }
    std::snprintf(buf, sizeof buf,
                  "pair (%ld,%ld): kDet reports it, FCL not, and it is not rounding-level "
                  "(survives every translation by %g)",
                  pr.first, pr.second, delta);
    return buf;
  }
  const double d = std::sqrt(kdet_fcl::detail::triangleDistanceSquared(P[0], P[1], P[2], Q[0], Q[1], Q[2]));
  if (d <= delta) return "";
  std::snprintf(buf, sizeof buf, "pair (%ld,%ld): FCL reports it, kDet not, distance %g > %g",
                pr.first, pr.second, d, delta);
  return buf;
}

/// Compares kDet's and FCL's sets; prints every settled difference; returns the failures.
/// `settled` counts the differences that were accepted.
template <class S>
std::vector<std::string> compareSets(const char* what, const Pairs& kdet, const Pairs& fcl_set,
                                     const kdet_fcl::TriangleMesh<S>& A,
                                     const fcl::Transform3<S>& ta,
                                     const kdet_fcl::TriangleMesh<S>& B,
                                     const fcl::Transform3<S>& tb, std::size_t& settled) {
  std::vector<std::string> failures;
  Pairs only_k, only_f;
  std::set_difference(kdet.begin(), kdet.end(), fcl_set.begin(), fcl_set.end(),
                      std::back_inserter(only_k));
  std::set_difference(fcl_set.begin(), fcl_set.end(), kdet.begin(), kdet.end(),
                      std::back_inserter(only_f));
  for (const Pair& p : only_k) {
    const std::string f = settle(A, ta, B, tb, p, true);
    if (f.empty()) {
      ++settled;
      std::printf("[settled] %s: pair (%ld,%ld) kDet yes, FCL no: touching within rounding, "
                  "exact predicate says yes\n", what, p.first, p.second);
    } else {
      failures.push_back(std::string(what) + ": " + f);
    }
  }
  for (const Pair& p : only_f) {
    const std::string f = settle(A, ta, B, tb, p, false);
    if (f.empty()) {
      ++settled;
      std::printf("[settled] %s: pair (%ld,%ld) FCL yes, kDet no: apart by rounding only, "
                  "exact predicate says no\n", what, p.first, p.second);
    } else {
      failures.push_back(std::string(what) + ": " + f);
    }
  }
  return failures;
}

}  // namespace kdet_fcl_test
