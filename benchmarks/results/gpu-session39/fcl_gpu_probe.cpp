// Session 39, device call 5: results/cpu-fcl-deform/probe.cpp on the CUDA backend
// (setCollideOptions with Backend::Cuda). A deforming kdet_fcl::Mesh (KdetOnly mode) through
// FCL's update family: the time of endUpdateModel (FCL's checks, then kdet_fcl's eager re-sync
// of its HashedMesh) and of the next kdet_fcl::collide against a ball (the device re-hash and the
// query), medians over frames that alternate between two positions. Arguments: [reps [threads]]
// (collideOptions().threads; call 6 added it). Built as
//   g++ -O2 -std=c++17 -I include -I <eigen3> fcl_gpu_probe.cpp -L build-gpu -lkdet_fcl -lfcl
#include <kdet_fcl/fcl_collide.h>
#include <kdet_fcl/fcl_mesh.h>
#include <kdet_fcl/scenes.h>

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <vector>

using Clock = std::chrono::steady_clock;
double us(Clock::time_point a) { return std::chrono::duration<double, std::micro>(Clock::now() - a).count(); }
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int main(int argc, char** argv) {
  const int reps = argc > 1 ? std::atoi(argv[1]) : 40;
  kdet_fcl::QueryOptions gpu = kdet_fcl::collideOptions();
  gpu.backend = kdet_fcl::Backend::Cuda;
  gpu.threads = argc > 2 ? std::atoi(argv[2]) : 0;  // (call 6: 0, the hardware's, or 1)
  kdet_fcl::setCollideOptions(gpu);
  std::printf("collideOptions().threads %d\n\n", gpu.threads);
  std::printf("| cloth triangles | endUpdateModel (us) | next kdet_fcl::collide (us) | pairs |\n|---:|---:|---:|---:|\n");
  for (int n : {215, 354, 700}) {
    const auto c0 = kdet_fcl::makeDrapedCloth<double>(n, 4.0, 1.0, 0.03, 0.5);
    const auto c1 = kdet_fcl::makeDrapedCloth<double>(n, 4.0, 1.0, 0.03, 0.7);
    const auto ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, 64, 32);
    auto toFcl = [](const kdet_fcl::TriangleMesh<double>& m) {
      std::vector<fcl::Vector3d> ps;
      for (const auto& v : m.vertices) ps.emplace_back(v.x, v.y, v.z);
      return ps;
    };
    std::vector<fcl::Triangle> ts;
    for (const auto& t : c0.triangles) ts.emplace_back(t[0], t[1], t[2]);
    auto cloth = std::make_shared<kdet_fcl::Meshd>(kdet_fcl::MeshMode::KdetOnly);
    cloth->beginModel();
    cloth->addSubModel(toFcl(c0), ts);
    cloth->endModel();
    std::vector<fcl::Triangle> bt;
    for (const auto& t : ball.triangles) bt.emplace_back(t[0], t[1], t[2]);
    auto b = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
    b->beginModel();
    b->addSubModel(toFcl(ball), bt);
    b->endModel();
    const std::vector<fcl::Vector3d> p0 = toFcl(c0), p1 = toFcl(c1);
    std::vector<double> te, tq;
    std::size_t pairs = 0;
    for (int r = 0; r <= reps; ++r) {
      cloth->beginUpdateModel();
      cloth->updateSubModel(r % 2 ? p1 : p0);
      const auto a = Clock::now();
      if (cloth->endUpdateModel() != fcl::BVH_OK) return 1;
      const double e = us(a);
      fcl::CollisionRequestd req(1 << 30, false);
      fcl::CollisionResultd res;
      const auto q = Clock::now();
      kdet_fcl::collide<double>(cloth.get(), fcl::Transform3d::Identity(), b.get(),
                                fcl::Transform3d::Identity(), req, res);
      const double t = us(q);
      pairs = res.numContacts();
      if (r == 0) continue;
      te.push_back(e);
      tq.push_back(t);
    }
    std::printf("| %d | %.0f | %.0f | %zu |\n", cloth->num_tris, median(te), median(tq), pairs);
  }
  return 0;
}
