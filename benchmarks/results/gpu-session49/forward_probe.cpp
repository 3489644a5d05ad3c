// Probe (session 49): a simulation going forward, every frame new to the meshes. kdet_bench and
// gpu_bench time repeated passes over the same frames, after a warm-up pass; a simulation meets
// each frame once. Session 48's first-pass probe found the 90k cloth's re-hash taking about
// 0.5 ms a frame on a first pass against 0.14 on later passes, with at most one fallback. Are
// the re-hash graph's captures (any moved buffer captures it again) and the scratch's growth
// the rest? Per frame of the first pass, and as medians of the first pass and of the third:
// the frame's host time, each query's host time, build phase, graph captures, updates in place
// (cudaGraphExecUpdate), capture host time, device allocations and fallbacks.
// Usage: forward_probe SCENE (FRAMES, default 20, frames of the procedural animation; double;
// one scene per process, since a freed mesh's address carries its cache entry's arrays).
// Build: probe_build benchmarks/results/gpu-session49/forward_probe.cpp BIN (gpu-session48/probe_build.sh).
// Ran (calls 3 and 4) against commit bb5b5f0, whose QueryProfile had rehash_graph_updates (the
// graph updated in place, taken back after call 4); it no longer compiles against the tree.
#include <algorithm>
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
using Clock = std::chrono::steady_clock;

struct Row {
  double frame = 0, update = 0;
  std::vector<double> ms, build, capture_ms;
  std::vector<int> captures, updates, allocs, fallbacks;
};

static double med(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: forward_probe SCENE\n");
    return 2;
  }
  kb::SceneConfig cfg;
  cfg.frames = std::getenv("FRAMES") ? std::atoi(std::getenv("FRAMES")) : 20;
  cfg.data_dir = std::getenv("KDET_FCL_DATA_DIR") ? std::getenv("KDET_FCL_DATA_DIR") : "";
  std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, {argv[1]});
  auto it = std::find_if(scenes.begin(), scenes.end(),
                         [&](const kb::Scene& s) { return s.name == argv[1]; });
  if (it == scenes.end()) {
    std::fprintf(stderr, "forward_probe: no scene %s\n", argv[1]);
    return 2;
  }
  const kb::Scene& s = *it;
  std::vector<std::unique_ptr<HashedMesh<double>>> obj;
  for (std::size_t o = 0; o < s.objects.size(); ++o)
    obj.push_back(std::make_unique<HashedMesh<double>>(*s.frames[0].meshes[o], s.frames[0].poses[o]));
  const std::size_t nq = s.inter.size() + s.self.size();
  std::vector<QueryResult> res(nq);
  std::vector<std::vector<std::size_t>> first_pairs(s.frames.size(), std::vector<std::size_t>(nq));
  cuda::setProfiling(true);
  QueryOptions q;
  q.backend = Backend::Cuda;
  int mismatches = 0;
  std::vector<std::vector<Row>> passes(3);
  for (int pass = 0; pass < 3; ++pass) {
    for (std::size_t f = 0; f < s.frames.size(); ++f) {
      Row row;
      for (std::size_t o = 0; o < obj.size(); ++o) {
        if (s.motion[o] == kb::Motion::Deform) {
          const auto& v = s.frames[f].meshes[o]->vertices;
          std::copy(v.begin(), v.end(), obj[o]->vertexWriteBuffer());
          const auto t0 = Clock::now();
          obj[o]->commitVertices();
          row.update += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        } else if (s.motion[o] == kb::Motion::Rigid) {
          const auto t0 = Clock::now();
          obj[o]->setPose(s.frames[f].poses[o]);
          row.update += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        } else if (s.motion[o] == kb::Motion::Fracture) {
          std::fprintf(stderr, "forward_probe: fracturing scenes are not run\n");
          return 2;
        }
      }
      row.frame = row.update;
      for (std::size_t k = 0; k < nq; ++k) {
        const auto t0 = Clock::now();
        if (k < s.inter.size())
          intersectMeshes(*obj[s.inter[k].first], *obj[s.inter[k].second], res[k], q);
        else
          intersectSelf(*obj[s.self[k - s.inter.size()]], res[k], q);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        const cuda::QueryProfile p = cuda::lastQueryProfile();
        row.frame += ms;
        row.ms.push_back(ms);
        row.build.push_back(p.build_ms);
        row.capture_ms.push_back(p.rehash_capture_ms);
        row.captures.push_back(p.rehash_captures);
        row.updates.push_back(p.rehash_graph_updates);
        row.allocs.push_back(p.device_allocations);
        row.fallbacks.push_back(p.rehash_fallbacks);
        if (pass == 0) first_pairs[f][k] = res[k].pairs.size();
        else if (first_pairs[f][k] != res[k].pairs.size()) {
          ++mismatches;
          std::printf("MISMATCH frame %zu query %zu: %zu pairs, first pass %zu\n", f, k,
                      res[k].pairs.size(), first_pairs[f][k]);
        }
      }
      passes[pass].push_back(row);
    }
  }
  const char* upd = std::getenv("KDET_FCL_CUDA_GRAPH_UPDATE");
  std::printf("%s, %zu frames, double, KDET_FCL_CUDA_GRAPH_UPDATE=%s\n", s.name.c_str(),
              s.frames.size(), upd ? upd : "(unset)");
  std::printf("first pass, per frame (frame 0 builds): frame ms, update ms; per query q: ms, "
              "build ms, captures/updates, capture ms, allocations, fallbacks\n");
  for (std::size_t f = 0; f < passes[0].size(); ++f) {
    const Row& r = passes[0][f];
    std::printf("f%-3zu %7.3f %6.3f", f, r.frame, r.update);
    for (std::size_t k = 0; k < nq; ++k)
      std::printf(" | q%zu %6.3f %6.3f %d/%d %6.3f %2d %d", k, r.ms[k], r.build[k], r.captures[k],
                  r.updates[k], r.capture_ms[k], r.allocs[k], r.fallbacks[k]);
    std::printf("\n");
  }
  for (int pass : {0, 2}) {
    std::vector<double> fr, up;
    std::vector<std::vector<double>> ms(nq), build(nq), cap(nq);
    int captures = 0, updates = 0, allocs = 0, fallbacks = 0;
    for (std::size_t f = 1; f < passes[pass].size(); ++f) {
      const Row& r = passes[pass][f];
      fr.push_back(r.frame);
      up.push_back(r.update);
      for (std::size_t k = 0; k < nq; ++k) {
        ms[k].push_back(r.ms[k]);
        build[k].push_back(r.build[k]);
        cap[k].push_back(r.capture_ms[k]);
        captures += r.captures[k];
        updates += r.updates[k];
        allocs += r.allocs[k];
        fallbacks += r.fallbacks[k];
      }
    }
    std::printf("pass %d, frames 1..%zu: median frame %.3f ms, update %.3f", pass + 1,
                passes[pass].size() - 1, med(fr), up.empty() ? 0 : med(up));
    for (std::size_t k = 0; k < nq; ++k)
      std::printf(", q%zu %.3f (build %.3f, capture %.3f)", k, med(ms[k]), med(build[k]),
                  med(cap[k]));
    std::printf("; totals: captures %d, updates %d, allocations %d, fallbacks %d\n", captures,
                updates, allocs, fallbacks);
  }
  return mismatches == 0 ? 0 : 1;
}
