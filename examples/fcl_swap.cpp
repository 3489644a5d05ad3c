// Switching an FCL program to kdet_fcl: the same models, objects, requests and results; only the
// collide call changes (and, optionally, the mesh class and the broadphase callback).
//
// Runs without data files: a cloth draped over a sphere, both as FCL BVHModels. Prints FCL's and
// kdet_fcl's contact counts and times and exits non-zero if their pair sets differ.

#include <chrono>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include <fcl/fcl.h>

#include <kdet_fcl/kdet_fcl.h>

namespace {

template <class Model>
std::shared_ptr<Model> toFclModel(const kdet_fcl::TriangleMesh<double>& m) {
  std::vector<fcl::Vector3d> points;
  for (const auto& v : m.vertices) points.emplace_back(v.x, v.y, v.z);
  std::vector<fcl::Triangle> triangles;
  for (const auto& t : m.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  auto model = std::make_shared<Model>();
  model->beginModel();
  model->addSubModel(points, triangles);
  model->endModel();
  return model;
}

std::set<std::pair<long, long>> pairsOf(const fcl::CollisionResultd& r) {
  std::set<std::pair<long, long>> s;
  for (std::size_t i = 0; i < r.numContacts(); ++i)
    s.emplace(long(r.getContact(i).b1), long(r.getContact(i).b2));
  return s;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main() {
  const auto cloth = kdet_fcl::makeDrapedCloth<double>(120, 3.0, 1.0, 0.05, 1.0);
  const auto ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 96, 48);

  // An existing FCL program: BVHModel<OBBRSS> meshes inside CollisionObjects.
  fcl::CollisionObjectd cloth_obj(toFclModel<fcl::BVHModel<fcl::OBBRSSd>>(cloth));
  // kdet_fcl::Meshd is a drop-in for BVHModel<OBBRSSd> that keeps its kDet hash with it.
  fcl::CollisionObjectd ball_obj(toFclModel<kdet_fcl::Meshd>(ball));
  fcl::CollisionRequestd request(std::numeric_limits<int>::max(), /*enable_contact=*/true);

  auto t0 = std::chrono::steady_clock::now();
  fcl::CollisionResultd fcl_result;
  fcl::collide(&cloth_obj, &ball_obj, request, fcl_result);  // before
  const double fcl_ms = msSince(t0);

  t0 = std::chrono::steady_clock::now();
  fcl::CollisionResultd kdet_result;
  kdet_fcl::collide(&cloth_obj, &ball_obj, request, kdet_result);  // after: one name changed
  const double kdet_ms = msSince(t0);

  t0 = std::chrono::steady_clock::now();
  fcl::CollisionResultd again;
  kdet_fcl::collide(&cloth_obj, &ball_obj, request, again);  // cached hashes: no re-hash
  const double again_ms = msSince(t0);

  // Self-collision, which FCL does not have.
  fcl::CollisionResultd self;
  kdet_fcl::selfCollide(&cloth_obj, fcl::CollisionRequestd(std::numeric_limits<int>::max()), self);

  // A broadphase manager: pass kdet_fcl's default callback instead of FCL's.
  fcl::DynamicAABBTreeCollisionManagerd manager;
  manager.registerObject(&cloth_obj);
  manager.registerObject(&ball_obj);
  manager.setup();
  fcl::DefaultCollisionData<double> data;
  data.request.num_max_contacts = 1;
  manager.collide(&data, kdet_fcl::DefaultCollisionFunction<double>);

  const auto f = pairsOf(fcl_result), k = pairsOf(kdet_result);
  std::printf("cloth %zu triangles, sphere %zu triangles\n", cloth.triangles.size(),
              ball.triangles.size());
  std::printf("fcl::collide       %zu contacts (%zu triangle pairs)  %.2f ms\n",
              fcl_result.numContacts(), f.size(), fcl_ms);
  std::printf("kdet_fcl::collide  %zu contacts (%zu triangle pairs)  %.2f ms first call, "
              "%.2f ms cached\n",
              kdet_result.numContacts(), k.size(), kdet_ms, again_ms);
  std::printf("kdet_fcl::selfCollide: %zu self-intersecting pairs of the cloth\n",
              self.numContacts());
  std::printf("manager + kdet_fcl::DefaultCollisionFunction: in collision = %s\n",
              data.result.isCollision() ? "yes" : "no");
  if (f != k || !data.result.isCollision()) {
    std::printf("MISMATCH between FCL and kdet_fcl\n");
    return 1;
  }
  std::printf("same triangle pairs as FCL\n");
  return 0;
}
