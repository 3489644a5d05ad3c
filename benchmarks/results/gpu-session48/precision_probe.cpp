// Probe (session 48): kdet_bench's GPU frame in float and in double, in one process, with the
// query's phases (cuda::setProfiling). kdet_bench's scenes are double; gpu_bench's are float, and
// its cloth ball's frame is about 0.35 ms against kdet_bench's 0.6. Where does double cost?
// Each scene's objects are made twice (HashedMesh<double> from the scene's meshes, HashedMesh<float>
// from their coordinates rounded to float) and run kdet_bench's frame (commitVertices of the
// deforming objects from a buffer filled untimed, the inter queries, the self queries, results
// kept per slot), the two precisions alternating frame by frame, rotated by round. Round 0 is a
// warm-up. ROUNDS (default 12), PROFILE=1 (default) records the phases, PROFILE=0 only host times.
// ONLY=float or ONLY=double runs one precision (for a tracer's totals per frame). FIRST=1 times
// the first pass through the frames instead (round 0: every frame new to the meshes, as in a
// simulation going forward; run it with ROUNDS=0), with each query's re-hash fallbacks.
// The pair sets are not compared across precisions (float coordinates are other triangles); each
// precision's pairs must be the same at every round of a frame ("MISMATCH", exit 1).
// Build: g++ -O2 -std=c++17 -I include -I src -I . -I benchmarks precision_probe.cpp
//        benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -o precision_probe
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
using Clock = std::chrono::steady_clock;

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}
static double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

template <class S>
TriangleMesh<S> meshIn(const kb::Mesh& m) {
  TriangleMesh<S> out;
  out.triangles = m.triangles;
  out.vertices.reserve(m.vertices.size());
  for (const auto& v : m.vertices) out.vertices.push_back({S(v.x), S(v.y), S(v.z)});
  return out;
}
template <class S>
Transform<S> poseIn(const Transform<double>& p) {
  Transform<S> out = Transform<S>::identity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.R[i][j] = S(p.R[i][j]);
  out.t = {S(p.t.x), S(p.t.y), S(p.t.z)};
  return out;
}

using Times = std::map<std::string, std::vector<double>>;

/// One precision's objects of a scene and its frame.
template <class S>
struct Run {
  const kb::Scene& s;
  std::vector<std::unique_ptr<HashedMesh<S>>> obj;
  std::vector<std::vector<TriangleMesh<S>>> meshes;  // [frame][object]
  std::vector<QueryResult> res;
  std::map<std::pair<std::size_t, std::size_t>, std::vector<TrianglePair>> ref;
  std::map<std::size_t, std::size_t> cands;  // per slot, last candidates
  Times t;
  int mismatches = 0;

  explicit Run(const kb::Scene& sc) : s(sc) {
    for (const auto& fr : s.frames) {
      meshes.emplace_back();
      for (const auto& m : fr.meshes) meshes.back().push_back(meshIn<S>(*m));
    }
    for (std::size_t o = 0; o < s.objects.size(); ++o)
      obj.push_back(std::make_unique<HashedMesh<S>>(meshes[0][o],
                                                    poseIn<S>(s.frames[0].poses[o])));
    res.resize(s.inter.size() + s.self.size());
  }

  void frame(std::size_t f, bool timed, bool profile) {
    QueryOptions q;
    q.backend = Backend::Cuda;
    double update = 0;
    for (std::size_t o = 0; o < obj.size(); ++o) {
      const kb::Motion m = s.motion[o];
      if (m == kb::Motion::Deform) {
        const auto& v = meshes[f][o].vertices;
        std::copy(v.begin(), v.end(), obj[o]->vertexWriteBuffer());  // untimed, as kdet_bench
        const auto t0 = Clock::now();
        obj[o]->commitVertices();
        update += msSince(t0);
      } else if (m == kb::Motion::Rigid) {
        const auto t0 = Clock::now();
        obj[o]->setPose(poseIn<S>(s.frames[f].poses[o]));
        update += msSince(t0);
      } else if (m == kb::Motion::Fracture) {
        std::fprintf(stderr, "precision_probe: fracturing scenes are not run\n");
        std::exit(2);
      }
    }
    double total = update;
    std::size_t slot = 0;
    auto one = [&](auto&& call) {
      const auto t0 = Clock::now();
      call(res[slot]);
      const double ms = msSince(t0);
      total += ms;
      const cuda::QueryProfile p = profile ? cuda::lastQueryProfile() : cuda::QueryProfile{};
      auto key = std::make_pair(f, slot);
      auto it = ref.find(key);
      if (it == ref.end()) ref[key] = res[slot].pairs;
      else if (it->second != res[slot].pairs) {
        ++mismatches;
        std::printf("MISMATCH %s frame %zu slot %zu: %zu pairs, first %zu\n", s.name.c_str(), f,
                    slot, res[slot].pairs.size(), it->second.size());
      }
      if (timed) {
        const std::string k = "q" + std::to_string(slot);
        t[k].push_back(ms);
        if (profile) {
          t[k + " build"].push_back(p.build_ms);
          t[k + " cands"].push_back(p.candidates_ms);
          t[k + " filter"].push_back(p.filter_ms);
          t[k + " query"].push_back(p.query_ms);
          t[k + " output"].push_back(p.output_ms);
          t[k + " total"].push_back(p.total_ms);
          t[k + " #cand"].push_back(double(p.candidates));
          t[k + " #exact"].push_back(double(p.exact_tests));
          t[k + " #pairs"].push_back(double(p.pairs));
          t[k + " #fallbacks"].push_back(double(p.rehash_fallbacks));
        }
      }
      ++slot;
    };
    for (auto [a, b] : s.inter)
      one([&](QueryResult& r) { intersectMeshes(*obj[a], *obj[b], r, q); });
    for (int o : s.self) one([&](QueryResult& r) { intersectSelf(*obj[o], r, q); });
    if (timed) {
      t["update"].push_back(update);
      t["frame"].push_back(total);
    }
  }
};

int main(int argc, char** argv) {
  kb::SceneConfig cfg;
  cfg.frames = 5;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  const int rounds = std::getenv("ROUNDS") ? std::atoi(std::getenv("ROUNDS")) : 12;
  const bool profile = !(std::getenv("PROFILE") && std::string(std::getenv("PROFILE")) == "0");
  const bool first = std::getenv("FIRST") && std::string(std::getenv("FIRST")) == "1";
  std::vector<std::string> want;
  for (int i = 1; i < argc; ++i) want.push_back(argv[i]);
  if (want.empty()) want = {"unc-cloth-ball", "cloth-90k"};
  cuda::setProfiling(profile);
  int mismatches = 0;
  for (const auto& s : kb::makeAllScenes(cfg, want)) {
    if (std::find(want.begin(), want.end(), s.name) == want.end()) continue;
    const std::string only = std::getenv("ONLY") ? std::getenv("ONLY") : "";
    const bool do_f = only != "double", do_d = only != "float";
    Run<float> rf(s);
    Run<double> rd(s);
    // kdet_bench's timed frames: every frame after the build frame (frame 0), each round
    // starting from frame 0 again; the two precisions alternate frame by frame, their order
    // swapped every round.
    for (int r = 0; r <= rounds; ++r) {
      for (std::size_t f = 0; f < s.frames.size(); ++f) {
        const bool timed = (first ? r == 0 : r > 0) && f > 0;
        if (r % 2 == 0) {
          if (do_f) rf.frame(f, timed, profile);
          if (do_d) rd.frame(f, timed, profile);
        } else {
          if (do_d) rd.frame(f, timed, profile);
          if (do_f) rf.frame(f, timed, profile);
        }
      }
    }
    mismatches += rf.mismatches + rd.mismatches;
    std::printf("\n%s (%zu frames, %d rounds; medians over the timed frames, ms or counts)\n",
                s.name.c_str(), s.frames.size(), rounds);
    std::printf("| what | float | double | double/float |\n|---|---:|---:|---:|\n");
    auto sum = [](const std::vector<double>& v) {
      double x = 0;
      for (double y : v) x += y;
      return x;
    };
    for (const auto& [k, v] : (do_d ? rd.t : rf.t)) {
      const bool total = k.find("#fallbacks") != std::string::npos;  // summed, not a median
      const double a = total ? sum(rf.t[k]) : median(rf.t[k]);
      const double b = total ? sum(rd.t[k]) : median(rd.t[k]);
      std::printf("| %s | %.4f | %.4f | %.2f |\n", k.c_str(), a, b, a > 0 ? b / a : 0.0);
    }
  }
  return mismatches == 0 ? 0 : 1;
}
