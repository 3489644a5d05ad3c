// Probe (session 37, device call 5): why kdet_bench's kDet GPU frames (double meshes, a new
// HashedMesh per run, by-value results) took 3-5x gpu_bench's (float meshes, kept across runs).
// For the UNC cloth ball (frames 92, 93), the 90k and 1M cloths (5 frames), runs each scene's
// frames 3 times in each form and prints, per frame, the host wall of updateVertices and of each
// query, and the backend's profile of each query (device phases, passes, rounds, builds with a
// read-back, async re-hashes, fallbacks):
//   dnew   double meshes, new HashedMesh objects per run (kdet_bench's form)
//   dkeep  double meshes, the same HashedMesh objects in every run
//   fnew   float meshes, new objects per run
//   fkeep  float meshes, kept
// Build: g++ -O2 -std=c++17 -I include -I . -I benchmarks double_probe.cpp benchmarks/bench_scenes.cpp
//        -L build-gpu -lkdet_fcl -o probe
#include <chrono>
#include <cstdio>
#include <cstdlib>
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

template <class S>
TriangleMesh<S> convert(const kb::Mesh& m) {
  TriangleMesh<S> o;
  for (const auto& v : m.vertices) o.vertices.push_back({S(v.x), S(v.y), S(v.z)});
  o.triangles = m.triangles;
  return o;
}

template <class S>
void runForm(const kb::Scene& s, const char* form, bool keep) {
  // Frames' meshes converted up front (untimed).
  std::vector<std::vector<TriangleMesh<S>>> mesh(s.objects.size());
  for (std::size_t o = 0; o < s.objects.size(); ++o)
    for (const auto& fr : s.frames) mesh[o].push_back(convert<S>(*fr.meshes[o]));
  std::vector<std::unique_ptr<HashedMesh<S>>> obj(s.objects.size());
  QueryOptions q;
  q.backend = Backend::Cuda;
  cuda::setProfiling(true);
  for (int run = 0; run < 3; ++run) {
    for (std::size_t f = 0; f < s.frames.size(); ++f) {
      double upd = 0;
      for (std::size_t o = 0; o < obj.size(); ++o) {
        const double t0 = nowMs();
        if (!obj[o] || (f == 0 && !keep)) {
          obj[o] = std::make_unique<HashedMesh<S>>(mesh[o][f],
                                                   Transform<S>::identity(), 0);
        } else if (s.motion[o] == kb::Motion::Deform &&
                   !(f > 0 && s.frames[f].meshes[o] == s.frames[f - 1].meshes[o])) {
          obj[o]->updateVertices(mesh[o][f].vertices);
        }
        upd += nowMs() - t0;
      }
      std::printf("%s %s run %d frame %zu update %.3f\n", s.name.c_str(), form, run, f, upd);
      auto show = [&](const char* what, double wall, std::size_t pairs) {
        const cuda::QueryProfile p = cuda::lastQueryProfile();
        std::printf(
            "  %s wall %.3f pairs %zu | build %.3f query %.3f cand %.3f filter %.3f out %.3f total "
            "%.3f | passes %d rounds %d readback_builds %d async %d fallbacks %d graphs %d "
            "count_builds %d pinned %d cached %d cands %zu\n",
            what, wall, pairs, p.build_ms, p.query_ms, p.candidates_ms, p.filter_ms, p.output_ms,
            p.total_ms, p.passes, p.rounds, p.builds_with_readback, p.rehashes_async,
            p.rehash_fallbacks, p.rehash_graphs, p.count_builds, p.pinned_uploads,
            p.self_cached ? 1 : 0, p.candidates);
      };
      for (auto [a, b] : s.inter) {
        const double t0 = nowMs();
        const QueryResult r = intersectMeshes(*obj[a], *obj[b], q);
        show("inter", nowMs() - t0, r.pairs.size());
      }
      for (int o : s.self) {
        const double t0 = nowMs();
        const QueryResult r = intersectSelf(*obj[o], q);
        show("self ", nowMs() - t0, r.pairs.size());
      }
    }
  }
}

int main() {
  kb::SceneConfig cfg;
  cfg.frames = 5;
  cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  const std::vector<std::string> want = {"unc-cloth-ball", "cloth-90k", "cloth-1000k"};
  const std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, want);
  for (const auto& s : scenes) {
    bool wanted = false;
    for (const auto& w : want) wanted = wanted || s.name == w;
    if (!wanted) continue;
    runForm<double>(s, "dnew", false);
    runForm<double>(s, "dkeep", true);
    runForm<float>(s, "fnew", false);
    runForm<float>(s, "fkeep", true);
  }
  return 0;
}
