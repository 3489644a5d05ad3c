// Probe (session 42): kdet_bench's GPU frame, form against form, in one process. Session 41 found
// the scan's spans (KDET_FCL_CUDA_SPANS=1) faster in cells_probe.cpp (profiling on, inter
// queries after the self queries) and in ncu, but slower in kdet_bench's frames (profiling off,
// the inter query first). This probe runs kdet_bench's frame as kdet_bench does (double meshes
// kept across runs, commitVertices of the deforming ones, then the inter queries, then the self
// queries, results kept per slot; host clock) and switches the form by frame, rotated by round,
// so every form sees every frame in the same process. Round 0 is a warm-up.
// Forms (FORMS, ';'-separated): each a '+'-separated list of VAR=VALUE set for its frames
// ("base" or an empty form: the defaults); default "base;KDET_FCL_CUDA_SPANS=1".
// BLOCK=b: each form runs in blocks instead (the scene's frames once untimed, then b times
// timed; the forms' order rotated by round), for knobs whose switch costs a rebuild (the build's
// form, graphs); all ROUNDS rounds timed.
// PROFILE=1 turns cuda::setProfiling on and prints each query's phases (medians), else only
// host times (kdet_bench runs with profiling off). ROUNDS (default 8). UPDATE=copy (since
// session 43) takes a deforming object's positions by updateVertices from a buffer filled
// untimed, as kdet_bench --gpu-update copy does, instead of commitVertices.
// Each form's pairs must equal those of the first form run on the same frame and slot
// ("MISMATCH", exit 1).
// Build: g++ -O2 -std=c++17 -I include -I src -I . -I benchmarks frame_probe.cpp
//        benchmarks/bench_scenes.cpp -L build-gpu -lkdet_fcl -o frame_probe
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

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

struct Form {
  std::string name;
  std::vector<std::pair<std::string, std::string>> vars;
};

static std::vector<std::string> split(const std::string& s, char c) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string x;
  while (std::getline(ss, x, c)) out.push_back(x);
  return out;
}

// KNOBCOST=1: the cost of cuda::checkKnobs() (every query runs it first) with no knob set, with
// one knob at a constant value, and with that value changing at every call (a full read each
// time), and of std::thread::hardware_concurrency(); microseconds per call, then exit.
static int knobCost() {
  const auto per = [](int n, auto&& f) {
    const auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) f(i);
    return msSince(t0) * 1000.0 / n;
  };
  unsetenv("KDET_FCL_CUDA_TILE");
  const double none = per(20000, [](int) { cuda::checkKnobs(); });
  setenv("KDET_FCL_CUDA_TILE", "8", 1);
  const double same = per(20000, [](int) { cuda::checkKnobs(); });
  const double changing = per(20000, [](int i) {
    setenv("KDET_FCL_CUDA_TILE", i % 2 ? "4" : "8", 1);
    cuda::checkKnobs();
  });
  const double setenv_only = per(20000, [](int i) { setenv("KDET_FCL_CUDA_TILE", i % 2 ? "4" : "8", 1); });
  unsetenv("KDET_FCL_CUDA_TILE");
  unsigned sink = 0;
  const double hw = per(20000, [&](int) { sink += std::thread::hardware_concurrency(); });
  std::printf("checkKnobs, us per call: none set %.3f, one set unchanged %.3f, one set changing "
              "%.3f (setenv alone %.3f); hardware_concurrency %.3f us (%u); environment %zu entries\n",
              none, same, changing, setenv_only, hw, sink / 20000, [] {
                std::size_t n = 0;
                for (char** e = environ; *e; ++e) ++n;
                return n;
              }());
  return 0;
}

int main(int argc, char** argv) {
  if (std::getenv("KNOBCOST") && std::string(std::getenv("KNOBCOST")) == "1") return knobCost();
  kb::SceneConfig cfg;
  cfg.frames = 5;
  cfg.include_1m = true;
  const char* d = std::getenv("KDET_FCL_DATA_DIR");
  cfg.data_dir = d ? d : "";
  const int rounds = std::getenv("ROUNDS") ? std::atoi(std::getenv("ROUNDS")) : 8;
  const bool profile = std::getenv("PROFILE") && std::string(std::getenv("PROFILE")) == "1";
  const int block = std::getenv("BLOCK") ? std::atoi(std::getenv("BLOCK")) : 0;
  const bool update_copy = std::getenv("UPDATE") && std::string(std::getenv("UPDATE")) == "copy";
  std::vector<std::string> want;
  for (int i = 1; i < argc; ++i) want.push_back(argv[i]);
  if (want.empty()) want = {"unc-n-body", "unc-n-body-pair"};
  std::vector<Form> forms;
  for (const std::string& f : split(std::getenv("FORMS") ? std::getenv("FORMS")
                                                         : "base;KDET_FCL_CUDA_SPANS=1",
                                    ';')) {
    Form fm{f.empty() ? "base" : f, {}};
    if (f != "base")
      for (const std::string& a : split(f, '+')) {
        const auto eq = a.find('=');
        if (eq == std::string::npos) {
          std::fprintf(stderr, "bad form %s\n", f.c_str());
          return 2;
        }
        fm.vars.push_back({a.substr(0, eq), a.substr(eq + 1)});
      }
    forms.push_back(fm);
  }
  std::vector<std::string> knobs;  // every variable some form sets
  for (const Form& f : forms)
    for (const auto& v : f.vars)
      if (std::find(knobs.begin(), knobs.end(), v.first) == knobs.end()) knobs.push_back(v.first);
  const auto apply = [&](const Form& f) {
    for (const auto& k : knobs) unsetenv(k.c_str());
    for (const auto& v : f.vars) setenv(v.first.c_str(), v.second.c_str(), 1);
  };
  cuda::setProfiling(profile);
  const std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, want);
  int mismatches = 0;
  for (const auto& s : scenes) {
    // A scene named on the command line, or made by a key without a dash ("nbody" makes
    // "nbody-181k"), not its "-pair" twin.
    const bool asked = std::any_of(want.begin(), want.end(), [&](const std::string& w) {
      return s.name == w || (w.find('-') == std::string::npos && s.name.rfind(w + "-", 0) == 0 &&
                             s.name.find("-pair") == std::string::npos);
    });
    if (!asked) continue;
    using HM = HashedMesh<double>;
    std::vector<std::unique_ptr<HM>> obj(s.objects.size());
    std::vector<std::vector<Vec3<double>>> positions(s.objects.size());  // (UPDATE=copy)
    for (std::size_t o = 0; o < obj.size(); ++o)
      obj[o] = std::make_unique<HM>(*s.frames[0].meshes[o], s.frames[0].poses[o]);
    const std::size_t slots = s.inter.size() + s.self.size();
    std::vector<QueryResult> res(slots);
    std::map<std::pair<std::size_t, std::size_t>, std::vector<TrianglePair>> ref;  // frame, slot
    // Times per form: "frame", "update", "q<slot>" (host), and with PROFILE "q<slot> <phase>".
    std::map<std::string, std::map<std::string, std::vector<double>>> t;
    std::map<std::string, std::map<std::size_t, cuda::QueryProfile>> last;
    QueryOptions q;
    q.backend = Backend::Cuda;
    // One frame in form fm (already applied): its times kept if `timed`.
    const auto runFrame = [&](const Form& fm, std::size_t f, bool timed) {
      const kb::Frame& fr = s.frames[f];
      auto& tt = t[fm.name];
      const auto frame0 = Clock::now();
      double update = 0;
      for (std::size_t o = 0; o < obj.size(); ++o) {
        const kb::Motion m = s.motion[o];
        if (m == kb::Motion::Deform && update_copy) {
          // kdet_bench --gpu-update copy: the simulation's own buffer (filled untimed), then
          // updateVertices (timed).
          const auto& v = fr.meshes[o]->vertices;
          positions[o].assign(v.begin(), v.end());
          const auto t0 = Clock::now();
          obj[o]->updateVertices(positions[o]);
          update += msSince(t0);
        } else if (m == kb::Motion::Deform) {
          const auto& v = fr.meshes[o]->vertices;
          std::copy(v.begin(), v.end(), obj[o]->vertexWriteBuffer());  // untimed, as kdet_bench
          const auto t0 = Clock::now();
          obj[o]->commitVertices();
          update += msSince(t0);
        } else if (m == kb::Motion::Rigid) {
          const auto t0 = Clock::now();
          obj[o]->setPose(fr.poses[o]);
          update += msSince(t0);
        } else if (m == kb::Motion::Fracture) {
          kb::Mesh copy = *fr.meshes[o];
          const auto t0 = Clock::now();
          obj[o]->setMesh(std::move(copy));
          update += msSince(t0);
        }
      }
      std::vector<double> qms(slots);
      std::vector<cuda::QueryProfile> prof(slots);
      std::size_t slot = 0;
      for (auto [a, b] : s.inter) {
        const auto t0 = Clock::now();
        intersectMeshes(*obj[a], *obj[b], res[slot], q);
        qms[slot] = msSince(t0);
        if (profile) prof[slot] = cuda::lastQueryProfile();
        ++slot;
      }
      for (int o : s.self) {
        const auto t0 = Clock::now();
        intersectSelf(*obj[o], res[slot], q);
        qms[slot] = msSince(t0);
        if (profile) prof[slot] = cuda::lastQueryProfile();
        ++slot;
      }
      // The frame's time without the untimed copies: update + queries.
      double frame = update;
      for (double x : qms) frame += x;
      (void)frame0;
      for (std::size_t k = 0; k < slots; ++k) {
        auto key = std::make_pair(f, k);
        auto it = ref.find(key);
        if (it == ref.end()) ref[key] = res[k].pairs;
        else if (it->second != res[k].pairs) {
          ++mismatches;
          std::printf("MISMATCH %s frame %zu slot %zu form %s: %zu pairs, first %zu\n",
                      s.name.c_str(), f, k, fm.name.c_str(), res[k].pairs.size(),
                      it->second.size());
        }
      }
      if (profile)
        for (std::size_t k = 0; k < slots; ++k) last[fm.name][k] = prof[k];
      if (!timed) return;
      tt["frame"].push_back(frame);
      tt["update"].push_back(update);
      for (std::size_t k = 0; k < slots; ++k) {
        const std::string qk = "q" + std::to_string(k);
        tt[qk].push_back(qms[k]);
        if (!profile) continue;
        const auto& p = prof[k];
        tt[qk + " total"].push_back(p.total_ms);
        tt[qk + " build"].push_back(p.build_ms);
        tt[qk + " candidates"].push_back(p.candidates_ms);
        tt[qk + " filter"].push_back(p.filter_ms);
        tt[qk + " query"].push_back(p.query_ms);
        tt[qk + " output"].push_back(p.output_ms);
        tt[qk + " host-total"].push_back(qms[k] - p.total_ms);
      }
    };
    const std::size_t nf = forms.size();
    if (block == 0) {  // the form switched by frame, rotated by round; round 0 untimed
      for (int r = 0; r < rounds; ++r)
        for (std::size_t f = 0; f < s.frames.size(); ++f) {
          const Form& fm = forms[(f + static_cast<std::size_t>(r)) % nf];
          apply(fm);
          runFrame(fm, f, r > 0);
        }
    } else {  // each form for a block: the frames once untimed, then `block` times timed
      for (int r = 0; r < rounds; ++r)
        for (std::size_t k = 0; k < nf; ++k) {
          const Form& fm = forms[(k + static_cast<std::size_t>(r)) % nf];
          apply(fm);
          for (int pass = 0; pass <= block; ++pass)
            for (std::size_t f = 0; f < s.frames.size(); ++f) runFrame(fm, f, pass > 0);
        }
    }
    std::printf("== %s (triangles %zu, frames %zu, inter %zu, self %zu; medians of %s, "
                "profiling %s%s)\n",
                s.name.c_str(), s.triangles(0), s.frames.size(), s.inter.size(), s.self.size(),
                block == 0 ? (std::to_string(rounds - 1) + " rounds").c_str()
                           : (std::to_string(rounds) + " blocks of " + std::to_string(block) +
                              " timed passes").c_str(),
                profile ? "on" : "off", update_copy ? ", updateVertices" : "");
    std::map<std::string, std::string> lines;
    for (auto& [form, m] : t)
      for (auto& [k, v] : m) {
        char buf[64];
        std::snprintf(buf, sizeof buf, " %9.4f", median(v));
        lines[k] += buf;
      }
    std::printf("  %-22s", "(ms)");
    for (auto& [form, m] : t) std::printf(" | %s", form.c_str());
    std::printf("\n");
    for (auto& [k, l] : lines) std::printf("  %-22s%s\n", k.c_str(), l.c_str());
    for (auto& [form, m] : last)
      for (auto& [k, p] : m)
        std::printf("  %s q%zu: spans %d lanes %d cell_spans %d rows %d cand %zu pairs %zu passes %d "
                    "rounds %d one_trip %d builds_rb %d async %d graphs %d\n",
                    form.c_str(), k, p.spans, p.warp_lanes, p.cell_spans, p.cell_rows,
                    p.candidates, p.pairs, p.passes, p.rounds, p.one_trip,
                    p.builds_with_readback, p.rehashes_async, p.rehash_graphs);
    std::fflush(stdout);
  }
  std::printf("mismatches: %d\n", mismatches);
  return mismatches == 0 ? 0 : 1;
}
