// Probe (session 41): the self query's phase 1 under each form of the cells' pairs
// (selfCellPairsKernel), in one process so every form sees the same frames and the same machine
// state. kdet_bench's scenes, double meshes kept across frames as its GPU form keeps them, but
// per frame updateVertices of the deforming objects (kdet_bench commits: commitVertices), then
// the self queries. The kept-result cache is off
// (KDET_FCL_CUDA_SELF_CACHE=0) so every query runs on the device.
// Default: each self query once per form after an untimed first query (which re-hashes), the
// forms' order rotated every frame: phase 1 (candidates_ms: the cells' kernel beside the scan of
// the coarser levels) and the query's total without a build.
// FIRST=1: each frame's first self query (the one that re-hashes, as in kdet_bench) in one form,
// the form rotated by frame and round; then an untimed query in the first form to compare with;
// then each inter query in the frame's form (timed) and in the first (to compare with).
// Every form's pairs must equal the first form's (else "MISMATCH", exit 1).
// Forms: base (the defaults), spans (KDET_FCL_CUDA_CELL_SPANS=1), nospans (=0), and spans-r16,
// spans-r8, nospans-r8 (also KDET_FCL_CUDA_CELL_ROWS=16 or 8), allspans (KDET_FCL_CUDA_SPANS=1:
// the scan of the coarser levels tests spans too); FORMS=a,b,... picks some (default base,spans). Medians over frames 1.. of rounds 1..R-1 (ROUNDS, default 4).
// (Call 1 also had the forms spans+index and index, KDET_FCL_CUDA_CELL_INDEX_FIRST=1 of
// call1-tree.diff.)
// Build: g++ -O2 -std=c++17 -I include -I src -I . -I benchmarks cells_probe.cpp
//        benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -o probe
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench_scenes.h"
#include "cuda/cuda_backend.h"
#include "kdet_fcl/kdet_fcl.h"

namespace kb = kdet_bench;
using namespace kdet_fcl;

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

struct Form {
  std::string name;
  const char* spans;           // KDET_FCL_CUDA_CELL_SPANS (nullptr: unset)
  const char* rows = nullptr;  // KDET_FCL_CUDA_CELL_ROWS
  const char* scan = nullptr;  // KDET_FCL_CUDA_SPANS (the scan's spans too)
};

static void setKnob(const char* name, const char* v) {
  if (v) setenv(name, v, 1);
  else unsetenv(name);
}

int main(int argc, char** argv) {
  kb::SceneConfig cfg;
  cfg.frames = 5;
  cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  const int rounds = std::getenv("ROUNDS") ? std::atoi(std::getenv("ROUNDS")) : 4;
  std::vector<std::string> want;
  for (int i = 1; i < argc; ++i) want.push_back(argv[i]);
  if (want.empty()) want = {"unc-cloth-ball", "cloth-90k", "cloth-250k", "cloth-1000k"};
  const std::vector<Form> all = {{"base", nullptr},       {"spans", "1"},
                                 {"nospans", "0"},       {"spans-r16", "1", "16"},
                                 {"spans-r8", "1", "8"}, {"nospans-r8", "0", "8"},
                                 {"allspans", nullptr, nullptr, "1"}};
  const bool first_only = std::getenv("FIRST") && std::string(std::getenv("FIRST")) == "1";
  std::vector<Form> forms;
  if (const char* f = std::getenv("FORMS")) {
    std::stringstream ss(f);
    std::string name;
    while (std::getline(ss, name, ','))
      for (const Form& x : all)
        if (x.name == name) forms.push_back(x);
  } else {
    forms = {all[0], all[1]};
  }
  setenv("KDET_FCL_CUDA_SELF_CACHE", "0", 1);
  const std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, want);
  using S = double;
  QueryOptions q;
  q.backend = Backend::Cuda;
  cuda::setProfiling(true);
  int mismatches = 0;
  for (const auto& s : scenes) {
    // (A registry key may make several scenes, "nbody" makes "nbody-181k": the keys' own ones,
    // the scene's name starting with the key, not its "-pair" twin.)
    const bool asked = std::any_of(want.begin(), want.end(), [&](const std::string& w) {
      return s.name == w || (s.name.rfind(w + "-", 0) == 0 && s.name.find("-pair") == std::string::npos);
    });
    if (!asked) continue;
    std::vector<std::unique_ptr<HashedMesh<S>>> obj;
    std::vector<std::vector<std::vector<Vec3<S>>>> pos(s.objects.size());
    for (std::size_t o = 0; o < s.objects.size(); ++o) {
      for (const auto& fr : s.frames) {
        std::vector<Vec3<S>> p;
        for (const auto& v : fr.meshes[o]->vertices) p.push_back({v.x, v.y, v.z});
        pos[o].push_back(std::move(p));
      }
      TriangleMesh<S> m;
      m.vertices = pos[o][0];
      m.triangles = s.frames[0].meshes[o]->triangles;
      obj.push_back(std::make_unique<HashedMesh<S>>(m, Transform<S>::identity()));
    }
    std::map<std::string, std::vector<double>> t;
    std::map<std::string, cuda::QueryProfile> last;
    std::vector<QueryResult> res(forms.size());
    for (int round = 0; round < rounds; ++round)
      for (std::size_t f = 0; f < s.frames.size(); ++f) {
        for (std::size_t o = 0; o < obj.size(); ++o)
          if (s.motion[o] == kb::Motion::Deform) obj[o]->updateVertices(pos[o][f]);
        const bool keep = round > 0 && f > 0;
        for (int i : s.self) {
          if (s.motion[i] != kb::Motion::Deform) continue;
          const auto record = [&](const Form& fm) {
            const cuda::QueryProfile p = cuda::lastQueryProfile();
            last[fm.name] = p;
            if (!keep) return;
            const std::string key = "obj" + std::to_string(i) + " " + fm.name;
            t[key + " candidates"].push_back(p.candidates_ms);
            t[key + " total-build"].push_back(p.total_ms - p.build_ms);
            if (first_only) t[key + " total"].push_back(p.total_ms);
          };
          const auto compare = [&](std::size_t k) {
            if (res[k].pairs == res[0].pairs) return;
            ++mismatches;
            std::printf("MISMATCH %s obj %d frame %zu: %s %zu pairs, %s %zu\n", s.name.c_str(), i,
                        f, forms[k].name.c_str(), res[k].pairs.size(), forms[0].name.c_str(),
                        res[0].pairs.size());
          };
          if (first_only) {
            const std::size_t fi = (f + round) % forms.size();
            setKnob("KDET_FCL_CUDA_CELL_SPANS", forms[fi].spans);
            setKnob("KDET_FCL_CUDA_CELL_ROWS", forms[fi].rows);
            setKnob("KDET_FCL_CUDA_SPANS", forms[fi].scan);
            intersectSelf(*obj[i], res[fi], q);
            record(forms[fi]);
            if (fi != 0) {
              setKnob("KDET_FCL_CUDA_CELL_SPANS", forms[0].spans);
              setKnob("KDET_FCL_CUDA_CELL_ROWS", forms[0].rows);
              setKnob("KDET_FCL_CUDA_SPANS", forms[0].scan);
              intersectSelf(*obj[i], res[0], q);
              compare(fi);
            }
            continue;
          }
          // A first query re-hashes (untimed here), so no form pays the build.
          setKnob("KDET_FCL_CUDA_CELL_SPANS", nullptr);
          setKnob("KDET_FCL_CUDA_CELL_ROWS", nullptr);
          setKnob("KDET_FCL_CUDA_SPANS", nullptr);
          intersectSelf(*obj[i], res[0], q);
          for (std::size_t k = 0; k < forms.size(); ++k) {
            const std::size_t fi = (k + f + round) % forms.size();
            setKnob("KDET_FCL_CUDA_CELL_SPANS", forms[fi].spans);
            setKnob("KDET_FCL_CUDA_CELL_ROWS", forms[fi].rows);
            setKnob("KDET_FCL_CUDA_SPANS", forms[fi].scan);
            intersectSelf(*obj[i], res[fi], q);
            record(forms[fi]);
          }
          for (std::size_t k = 1; k < forms.size(); ++k) compare(k);
        }
        // FIRST=1: then each inter query once, in the frame's form (no re-hash left to do), and
        // again in the first form to compare with.
        for (std::size_t k = 0; first_only && k < s.inter.size(); ++k) {
          const std::size_t fi = (f + round) % forms.size();
          const auto run = [&](const Form& fm, QueryResult& r) {
            setKnob("KDET_FCL_CUDA_CELL_SPANS", fm.spans);
            setKnob("KDET_FCL_CUDA_CELL_ROWS", fm.rows);
            setKnob("KDET_FCL_CUDA_SPANS", fm.scan);
            intersectMeshes(*obj[s.inter[k].first], *obj[s.inter[k].second], r, q);
          };
          run(forms[fi], res[fi]);
          const cuda::QueryProfile p = cuda::lastQueryProfile();
          if (keep) {
            const std::string key = "inter" + std::to_string(k) + " " + forms[fi].name;
            t[key + " candidates"].push_back(p.candidates_ms);
            t[key + " total"].push_back(p.total_ms);
          }
          if (fi != 0) {
            run(forms[0], res[0]);
            if (res[fi].pairs != res[0].pairs) {
              ++mismatches;
              std::printf("MISMATCH %s inter %zu frame %zu: %s\n", s.name.c_str(), k, f,
                          forms[fi].name.c_str());
            }
          }
        }
      }
    std::printf("== %s (triangles:", s.name.c_str());
    for (auto& m : obj) std::printf(" %zu", m->numTriangles());
    std::printf(")\n");
    for (auto& [k, v] : t) std::printf("  %-32s %9.4f ms\n", k.c_str(), median(v));
    for (auto& [k, p] : last)
      std::printf("  %-8s cell_spans %d spans %d rows %d cand %zu cells' %zu pairs %zu\n",
                  k.c_str(), p.cell_spans, p.spans, p.cell_rows, p.candidates, p.cell_candidates,
                  p.pairs);
    std::fflush(stdout);
  }
  std::printf("mismatches: %d\n", mismatches);
  return mismatches == 0 ? 0 : 1;
}
