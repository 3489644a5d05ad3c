// Probe (session 39, device call 4): with the vertex check split over more kept workers,
// kdet_bench's 1M and 250k cloths showed a smaller update column but a longer inter query (its
// upload and re-hash of the deformed cloth), 1.09 -> 1.54 ms at 1M across two machines. Does the
// number of threads that check the positions change the query that follows on the same machine?
// For the 250k and 1M cloths (double, kdet_bench's scenes), one set of HashedMesh objects per
// thread count T (HashedMesh's threads argument: the commit's check runs on min(T, its shares)
// threads), T in turn over rounds; per frame: the positions written into the write buffer
// (untimed), commitVertices (timed), then the inter query and the self query (host wall, and the
// backend's build_ms: uploads + device re-hash). Medians over the rounds' frames 1-4.
// Build: g++ -O2 -std=c++17 -I include -I src -I . -I benchmarks commit_probe.cpp
//        benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -o probe
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bench_scenes.h"
#include "cuda/cuda_backend.h"
#include "kdet_fcl/kdet_fcl.h"

namespace kb = kdet_bench;
using namespace kdet_fcl;

static double nowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

int main() {
  kb::SceneConfig cfg;
  cfg.frames = 5;
  cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  const std::vector<std::string> want = {"cloth-250k", "cloth-1000k"};
  const std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, want);
  using S = double;
  QueryOptions q;
  q.backend = Backend::Cuda;
  cuda::setProfiling(true);
  const int counts[] = {1, 6, 16};
  for (const auto& s : scenes) {
    if (std::find(want.begin(), want.end(), s.name) == want.end()) continue;
    std::vector<std::vector<TriangleMesh<S>>> mesh(s.objects.size());
    for (std::size_t o = 0; o < s.objects.size(); ++o)
      for (const auto& fr : s.frames) {
        TriangleMesh<S> m;
        for (const auto& v : fr.meshes[o]->vertices) m.vertices.push_back({v.x, v.y, v.z});
        m.triangles = fr.meshes[o]->triangles;
        mesh[o].push_back(std::move(m));
      }
    std::map<int, std::vector<std::unique_ptr<HashedMesh<S>>>> objs;
    std::map<int, std::map<std::string, std::vector<double>>> t;
    for (int round = 0; round < 6; ++round)
      for (int T : counts) {
        auto& obj = objs[T];
        if (obj.empty())
          for (std::size_t o = 0; o < s.objects.size(); ++o)
            obj.push_back(std::make_unique<HashedMesh<S>>(mesh[o][0], Transform<S>::identity(), T));
        for (std::size_t f = 0; f < s.frames.size(); ++f) {
          double commit = 0;
          for (std::size_t o = 0; o < obj.size(); ++o) {
            if (s.motion[o] != kb::Motion::Deform) continue;
            Vec3<S>* w = obj[o]->vertexWriteBuffer();
            std::copy(mesh[o][f].vertices.begin(), mesh[o][f].vertices.end(), w);
            const double t0 = nowMs();
            obj[o]->commitVertices();
            commit += nowMs() - t0;
          }
          double inter = 0, inter_build = 0, self = 0;
          for (auto [a, b] : s.inter) {
            const double t0 = nowMs();
            const QueryResult r = intersectMeshes(*obj[a], *obj[b], q);
            inter += nowMs() - t0;
            inter_build += cuda::lastQueryProfile().build_ms;
            (void)r;
          }
          for (int o : s.self) {
            const double t0 = nowMs();
            const QueryResult r = intersectSelf(*obj[o], q);
            self += nowMs() - t0;
            (void)r;
          }
          if (round == 0 || f == 0) continue;
          t[T]["commit"].push_back(commit);
          t[T]["inter"].push_back(inter);
          t[T]["inter_build"].push_back(inter_build);
          t[T]["self"].push_back(self);
          t[T]["sum"].push_back(commit + inter + self);
        }
      }
    for (int T : counts)
      std::printf("%s threads %2d: commit %.3f | inter %.3f (build %.3f) | self %.3f | sum %.3f ms\n",
                  s.name.c_str(), T, median(t[T]["commit"]), median(t[T]["inter"]),
                  median(t[T]["inter_build"]), median(t[T]["self"]), median(t[T]["sum"]));
    std::fflush(stdout);
  }
  return 0;
}
