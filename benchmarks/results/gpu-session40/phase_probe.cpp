// Probe (session 40, device call 1): where kdet_bench's kDet GPU frame of a deforming cloth goes,
// query by query. kdet_bench's form: double meshes kept across frames; per frame the cloth's new
// positions are copied into a buffer (untimed, the simulation's), handed to updateVertices
// (timed), then the inter query (cloth against the static sphere) and the cloth's self query,
// each into a result kept across frames. Printed per query: host wall and the backend's
// QueryProfile (build = uploads + device re-hash, candidates, filter, output, total; candidate
// and pair counts). Medians over frames 1-4 of rounds 1..R-1.
// Args: scene names (default cloth-90k cloth-250k cloth-1000k); env ROUNDS (default 5).
// Build: g++ -O2 -std=c++17 -I include -I src -I . -I benchmarks phase_probe.cpp
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

int main(int argc, char** argv) {
  kb::SceneConfig cfg;
  cfg.frames = 5;
  cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  const int rounds = std::getenv("ROUNDS") ? std::atoi(std::getenv("ROUNDS")) : 5;
  std::vector<std::string> want;
  for (int i = 1; i < argc; ++i) want.push_back(argv[i]);
  if (want.empty()) want = {"cloth-90k", "cloth-250k", "cloth-1000k"};
  const std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, want);
  using S = double;
  QueryOptions q;
  q.backend = Backend::Cuda;
  cuda::setProfiling(true);
  for (const auto& s : scenes) {
    if (std::find(want.begin(), want.end(), s.name) == want.end()) continue;
    std::vector<std::vector<std::vector<Vec3<S>>>> pos(s.objects.size());
    std::vector<TriangleMesh<S>> first(s.objects.size());
    for (std::size_t o = 0; o < s.objects.size(); ++o) {
      for (const auto& fr : s.frames) {
        std::vector<Vec3<S>> p;
        for (const auto& v : fr.meshes[o]->vertices) p.push_back({v.x, v.y, v.z});
        pos[o].push_back(std::move(p));
      }
      first[o].vertices = pos[o][0];
      first[o].triangles = s.frames[0].meshes[o]->triangles;
    }
    std::vector<std::unique_ptr<HashedMesh<S>>> obj;
    for (std::size_t o = 0; o < s.objects.size(); ++o)
      obj.push_back(std::make_unique<HashedMesh<S>>(first[o], Transform<S>::identity()));
    std::vector<std::vector<Vec3<S>>> sim(s.objects.size());
    std::map<std::string, std::vector<double>> t;
    std::vector<QueryResult> inter_res(s.inter.size()), self_res(s.self.size());
    for (int round = 0; round < rounds; ++round)
      for (std::size_t f = 0; f < s.frames.size(); ++f) {
        double upd = 0;
        for (std::size_t o = 0; o < obj.size(); ++o) {
          if (s.motion[o] != kb::Motion::Deform) continue;
          sim[o] = pos[o][f];
          const double t0 = nowMs();
          obj[o]->updateVertices(sim[o]);
          upd += nowMs() - t0;
        }
        const bool keep = round > 0 && f > 0;
        if (keep) t["update"].push_back(upd);
        auto rec = [&](const std::string& k, double wall) {
          if (!keep) return;
          const cuda::QueryProfile p = cuda::lastQueryProfile();
          t[k + " wall"].push_back(wall);
          t[k + " build"].push_back(p.build_ms);
          t[k + " candidates"].push_back(p.candidates_ms);
          t[k + " filter"].push_back(p.filter_ms);
          t[k + " query"].push_back(p.query_ms);
          t[k + " output"].push_back(p.output_ms);
          t[k + " total"].push_back(p.total_ms);
          t[k + " #cand"].push_back(double(p.candidates));
          t[k + " #pairs"].push_back(double(p.pairs));
          t[k + " #exact"].push_back(double(p.exact_tests));
        };
        for (std::size_t i = 0; i < s.inter.size(); ++i) {
          const double t0 = nowMs();
          intersectMeshes(*obj[s.inter[i].first], *obj[s.inter[i].second], inter_res[i], q);
          rec("inter", nowMs() - t0);
        }
        for (std::size_t i = 0; i < s.self.size(); ++i) {
          const double t0 = nowMs();
          intersectSelf(*obj[s.self[i]], self_res[i], q);
          rec("self", nowMs() - t0);
        }
      }
    std::printf("== %s (%zu objects; triangles:", s.name.c_str(), obj.size());
    for (auto& m : obj) std::printf(" %zu", m->numTriangles());
    std::printf(")\n");
    for (auto& [k, v] : t) std::printf("  %-18s %12.4f\n", k.c_str(), median(v));
    std::fflush(stdout);
  }
  return 0;
}
