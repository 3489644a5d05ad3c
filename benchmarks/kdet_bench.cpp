/// \file
/// kdet_bench: the benchmark suite of issue 5, CPU part. kDet (kdet_fcl on the CPU, 1 and 2
/// threads) and FCL 0.7 (BVHModel<OBBRSS>, <OBB>, <AABB>) run in the same process on the same
/// scenes; every method's pair set is checked against kDet's and differences are settled with
/// the exact triangle predicate. Writes a Markdown table in the layout of the paper's Table 1,
/// JSON, gnuplot data and PNG plots. The GPU columns (kDet on CUDA through the library, the
/// suite's GPU BVH baseline of benchmarks/gpu_bvh.cu, both in double and host-timed) run where
/// the library and this program were built with CUDA and a device is present, with a table of
/// their own against the GPU targets; elsewhere they read "n/a (not built)" or "n/a (no CUDA
/// device)". The GPU methods keep their objects from run to run (runKdetOnce, runBvhOnce), as
/// FCL's models are kept (FclCache). kDet's GPU runs take a deforming object's positions as a
/// simulation that writes them into the mesh's vertexWriteBuffer() does (commitVertices checks
/// them in place, timed), or with --gpu-update copy through updateVertices (checked and copied).
///
///   kdet_bench [--quick] [--reps R] [--frames F] [--only a,b] [--methods a,b] [--out DIR]
///              [--include-1m] [--gpu-update commit|copy] [--fresh-results]
///              [--tiny N] [--rigid-poses N] [--no-plots] [--no-kfree]
///   kdet_bench --export-scenes DIR [--quick]     (meshes for benchmarks/kfree_study.sh)

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <thread>
#include <vector>

#include <fcl/config.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/AABB.h>
#include <fcl/math/bv/OBB.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>

#include <kdet_fcl/detail/pose.h>
#include <kdet_fcl/detail/triangle_distance.h>
#include <kdet_fcl/detail/triangle_intersection.h>
#include <kdet_fcl/kdet_fcl.h>

#include "bench_util.h"
#include "bench_scenes.h"
// KDET_BENCH_GPU_BVH (benchmarks/CMakeLists.txt, CUDA builds): gpu_bvh.cu is linked in, so the
// "GPU BVH" column runs the suite's GPU BVH baseline.
#ifndef KDET_BENCH_GPU_BVH
#define KDET_BENCH_GPU_BVH 0
#endif
#if KDET_BENCH_GPU_BVH
#include "gpu_bvh.cuh"
#endif

namespace kb = kdet_bench;
using kdet_fcl::TrianglePair;
using Clock = std::chrono::steady_clock;
using PairList = std::vector<TrianglePair>;

namespace {

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// ------------------------------------------------------------------------------------------
// Measurements

/// One frame of one method: times in ms, pair counts, and (for the checking run) the pairs.
struct FrameRecord {
  double update_ms = 0;   ///< build (frame 0), refit / re-hash / rebuild, or pose change
  double self_ms = 0;     ///< self queries (kDet) or mesh-against-itself queries (FCL)
  double inter_ms = 0;    ///< queries between objects
  std::size_t self_pairs = 0, inter_pairs = 0;
  int height = 0;         ///< kDet: tallest hierarchy over the objects
  std::uint64_t box_tests = 0, triangle_tests = 0;  ///< kDet's QueryStats, summed over queries
  std::vector<PairList> self_sets, inter_sets;  ///< sorted, only in the checking run
};

struct MethodResult {
  std::string id;                       ///< kdet_cpu_1t, fcl_obbrss, ...
  std::string status = "ok";            ///< "ok" or why not measured ("n/a (not built)")
  bool self_as_pair = false;            ///< FCL: query = the mesh against itself
  std::vector<FrameRecord> frames;      ///< per frame, median over the timed repetitions
  std::vector<FrameRecord> check;       ///< the checking run (pairs)
  int timed_runs = 0;                   ///< runs the medians are taken over
  /// Timed runs whose pair counts differ from the checking run's in some frame (the agreement
  /// check reads the checking run's pairs only), and the first such difference.
  int unsteady_runs = 0;
  std::string unsteady;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Runs `once(collect)` reps+1 times (first: warm-up and checking run, pairs kept) and keeps the
/// per-frame medians of the timed runs. With reps == 0 the checking run's times are reported.
double g_rep_budget_s = 20;  ///< --rep-budget: seconds of timed runs per method and scene
bool g_fresh_results = false;  ///< --fresh-results: the GPU runs' queries return new results
std::string g_inject_unsteady;  ///< --inject-unsteady ID: test hook (one count changed, below)

/// The first frame whose pair counts in `run` differ from the checking run's, described; empty
/// when every frame's counts are the same.
std::string pairCountsDiffer(const std::vector<FrameRecord>& check, const std::vector<FrameRecord>& run) {
  if (run.size() != check.size())
    return std::to_string(run.size()) + " frames, the checking run's " + std::to_string(check.size());
  for (std::size_t f = 0; f < run.size(); ++f) {
    const FrameRecord &a = check[f], &b = run[f];
    if (a.self_pairs != b.self_pairs || a.inter_pairs != b.inter_pairs)
      return "frame " + std::to_string(f) + ": " + std::to_string(b.self_pairs) + " self and " +
             std::to_string(b.inter_pairs) + " inter pairs, the checking run's " +
             std::to_string(a.self_pairs) + " and " + std::to_string(a.inter_pairs);
  }
  return {};
}

template <class F>
void repeat(MethodResult& r, int reps, bool skip, const std::string& scene, F once) {
  if (skip) {
    r.status = "skipped (--methods)";
    return;
  }
  std::vector<std::vector<FrameRecord>> runs;
  for (int rep = 0; rep <= reps; ++rep) {
    std::fprintf(stderr, "  %-22s %-20s %s\n", scene.c_str(), r.id.c_str(),
                 rep == 0 ? "check/warm-up run" : ("timed run " + std::to_string(rep) + "/" + std::to_string(reps)).c_str());
    const auto t0 = Clock::now();
    std::vector<FrameRecord> fr = once(rep == 0);
    const double run_s = msSince(t0) / 1000;
    if (rep == 0) {
      r.check = fr;
      // Long runs (FCL's mesh-against-itself on 100k+ triangles takes many seconds) get fewer
      // timed repetitions: as many as fit in g_rep_budget_s, at least one.
      if (reps > 1 && run_s * reps > g_rep_budget_s)
        reps = std::max(1, int(g_rep_budget_s / std::max(run_s, 1e-9)));
    }
    if (rep > 0) {
      // Every timed run must count the checking run's pairs in every frame: the agreement
      // check compares the checking run's pairs only.
      if (rep == 1 && r.id == g_inject_unsteady && !fr.empty()) ++fr.back().inter_pairs;
      const std::string d = pairCountsDiffer(r.check, fr);
      if (!d.empty()) {
        if (r.unsteady_runs++ == 0) r.unsteady = "timed run " + std::to_string(rep) + ", " + d;
        std::fprintf(stderr, "  *** UNSTEADY *** %s: %s timed run %d: %s\n", scene.c_str(),
                     r.id.c_str(), rep, d.c_str());
      }
    }
    if (rep > 0 || reps == 0) runs.push_back(std::move(fr));
  }
  r.timed_runs = int(runs.size());
  const std::size_t nf = runs[0].size();
  r.frames.resize(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    std::vector<double> u, s, i;
    for (auto& run : runs) {
      u.push_back(run[f].update_ms);
      s.push_back(run[f].self_ms);
      i.push_back(run[f].inter_ms);
    }
    FrameRecord& o = r.frames[f];
    o.update_ms = median(u);
    o.self_ms = median(s);
    o.inter_ms = median(i);
    o.self_pairs = r.check[f].self_pairs;
    o.inter_pairs = r.check[f].inter_pairs;
    o.height = r.check[f].height;
    o.box_tests = r.check[f].box_tests;
    o.triangle_tests = r.check[f].triangle_tests;
  }
}

PairList sorted(std::vector<TrianglePair> v) {
  std::sort(v.begin(), v.end());
  return v;
}

// ------------------------------------------------------------------------------------------
// kDet

// One run over a scene's frames. Timed per frame: the update (frame 0: the constructor plus the
// whole CPU hash; later frames: setPose, updateVertices or setMesh, which only validate and mark
// the CPU hash stale), the inter-object queries, then the self queries. The CPU hash of a changed
// mesh is rebuilt lazily inside the first query that needs it, and only for the levels that
// query's lookups visit (HashedMesh::hashFrom), so the inter queries come first: their time plus
// the update's is what an FCL user's frame costs (FCL answers no self query), and a self query
// then adds the levels still missing, which it times.
using Positions = std::vector<kdet_fcl::Vec3<double>>;

/// A deforming object's positions in mesh `m` written into the buffer a simulation keeps for it
/// (its storage kept from frame to frame), as both GPU methods' runs hand them over.
const Positions& simulationFrame(Positions& buffer, const kb::Mesh& m) {
  buffer.assign(m.vertices.begin(), m.vertices.end());
  return buffer;
}

/// kDet's objects kept from run to run (obj.size() == objects; null until built), and each
/// deforming object's positions as a simulation keeps them (as BvhObjects).
struct KdetObjects {
  std::vector<std::unique_ptr<kdet_fcl::HashedMesh<double>>> obj;
  std::vector<Positions> positions;
  /// One result per query of a frame (the inter queries, then the self queries), kept from
  /// frame to frame as a simulation keeps them: each query reads its pairs back into its
  /// result's storage (intersectMeshes and intersectSelf into a result), as the GPU BVH's do.
  std::vector<kdet_fcl::QueryResult> results;
};

/// How kDet's GPU runs take a deforming object's new positions (--gpu-update).
enum class GpuUpdate { Commit, Copy };

/// One run of kDet over the scene's frames. With `kept` (the GPU runs), the objects live from
/// run to run, as a simulation's do (and as FCL's cached models, FclCache): the first run builds
/// them; frame 0 of a later run brings each back to frame 0's state (a deformed object's
/// positions, a fractured one's mesh, a rigid one's pose), timed as that frame's update, so that
/// the frames after it are the steady state, without the device's first-use costs (buffer sizes
/// and the vertex buffer's registration learnt in a mesh's first frames). The GPU runs also hand
/// updateVertices the positions from one buffer per object that the simulation has just filled
/// (untimed), as runBvhOnce hands them to the GPU BVH, so that both GPU methods start each frame
/// from the same place; with GpuUpdate::Commit that buffer is the mesh's own write buffer
/// (HashedMesh::vertexWriteBuffer, filled untimed) and the timed update is commitVertices, which
/// checks the positions in place and copies nothing. The hierarchy's height (HashedMesh::stats,
/// which builds a stale CPU hash) is taken in the checking run only (`collect`), whose records
/// the tables read it from. The GPU runs read each query's pairs back into a result kept from
/// frame to frame (KdetObjects::results).
std::vector<FrameRecord> runKdetOnce(const kb::Scene& s, int threads, kdet_fcl::Backend backend,
                                     bool collect, KdetObjects* kept = nullptr,
                                     GpuUpdate how = GpuUpdate::Copy) {
  using kdet_fcl::HashedMesh;
  std::vector<FrameRecord> out;
  KdetObjects own;
  KdetObjects& objects = kept != nullptr ? *kept : own;
  auto& obj = objects.obj;
  obj.resize(s.objects.size());
  objects.positions.resize(s.objects.size());
  // The positions updateVertices gets for object o in frame fr: the frame's own array (CPU runs),
  // or a copy of it in the object's buffer, made before the timer starts (kept objects).
  auto frameVertices = [&](const kb::Frame& fr, std::size_t o) -> const Positions& {
    if (kept == nullptr) return fr.meshes[o]->vertices;
    return simulationFrame(objects.positions[o], *fr.meshes[o]);
  };
  // A deforming kept object's new positions: written into its write buffer (untimed), then
  // committed (timed: t0 is taken after the write).
  const bool commit = kept != nullptr && how == GpuUpdate::Commit;
  auto deform = [&](const kb::Frame& fr, std::size_t o, double& update_ms) {
    if (commit) {
      const auto& v = fr.meshes[o]->vertices;
      std::copy(v.begin(), v.end(), obj[o]->vertexWriteBuffer());
      const auto t0 = Clock::now();
      obj[o]->commitVertices();
      update_ms += msSince(t0);
      return;
    }
    const Positions& v = frameVertices(fr, o);
    const auto t0 = Clock::now();
    obj[o]->updateVertices(v);  // the re-hash is in the next query
    update_ms += msSince(t0);
  };
  kdet_fcl::QueryOptions q;
  q.threads = threads;
  q.backend = backend;
  for (std::size_t f = 0; f < s.frames.size(); ++f) {
    const kb::Frame& fr = s.frames[f];
    FrameRecord rec;
    for (std::size_t o = 0; o < obj.size(); ++o) {
      if (f == 0 && obj[o] != nullptr) {  // a kept object back to frame 0's state
        // Untimed, as below: the fractured mesh's copy, the deformed one's positions.
        const kb::Motion motion = s.motion[o];
        if (motion == kb::Motion::Deform) deform(fr, o, rec.update_ms);
        kb::Mesh copy = motion == kb::Motion::Fracture ? *fr.meshes[o] : kb::Mesh{};
        const auto t0 = Clock::now();
        if (motion == kb::Motion::Fracture) obj[o]->setMesh(std::move(copy));
        obj[o]->setPose(fr.poses[o]);
        rec.update_ms += msSince(t0);
        continue;
      }
      if (f == 0) {
        kb::Mesh copy = *fr.meshes[o];  // untimed: the constructor takes the mesh by value
        const auto t0 = Clock::now();
        obj[o] = std::make_unique<HashedMesh<double>>(std::move(copy), fr.poses[o], threads);
        if (backend != kdet_fcl::Backend::Cuda) obj[o]->prepareCpuHash();
        rec.update_ms += msSince(t0);
        continue;
      }
      switch (s.motion[o]) {
        case kb::Motion::Static: break;
        case kb::Motion::Rigid: {
          const auto t0 = Clock::now();
          obj[o]->setPose(fr.poses[o]);
          rec.update_ms += msSince(t0);
          break;
        }
        case kb::Motion::Deform: {
          if (fr.meshes[o] == s.frames[f - 1].meshes[o]) break;
          deform(fr, o, rec.update_ms);  // the re-hash is in the next query
          break;
        }
        case kb::Motion::Fracture: {
          kb::Mesh copy = *fr.meshes[o];
          const auto t0 = Clock::now();
          obj[o]->setMesh(std::move(copy));  // the re-hash is in the next query
          rec.update_ms += msSince(t0);
          break;
        }
      }
    }
    // The query's result: new (CPU runs, --fresh-results) or the kept one of its slot (GPU runs).
    const bool keep = kept != nullptr && !g_fresh_results;
    objects.results.resize(s.inter.size() + s.self.size());
    std::size_t slot = 0;
    kdet_fcl::QueryResult fresh;
    for (auto [a, b] : s.inter) {
      kdet_fcl::QueryResult& r = keep ? objects.results[slot++] : fresh;
      const auto t0 = Clock::now();
      if (keep) kdet_fcl::intersectMeshes(*obj[a], *obj[b], r, q);
      else r = kdet_fcl::intersectMeshes(*obj[a], *obj[b], q);
      rec.inter_ms += msSince(t0);
      rec.inter_pairs += r.pairs.size();
      rec.box_tests += r.stats.box_tests;
      rec.triangle_tests += r.stats.triangle_tests;
      if (collect) rec.inter_sets.push_back(sorted(r.pairs));
    }
    for (int o : s.self) {
      kdet_fcl::QueryResult& r = keep ? objects.results[slot++] : fresh;
      const auto t0 = Clock::now();
      if (keep) kdet_fcl::intersectSelf(*obj[o], r, q);
      else r = kdet_fcl::intersectSelf(*obj[o], q);
      rec.self_ms += msSince(t0);
      rec.self_pairs += r.pairs.size();
      rec.box_tests += r.stats.box_tests;
      rec.triangle_tests += r.stats.triangle_tests;
      if (collect) rec.self_sets.push_back(sorted(r.pairs));
    }
    if (collect)
      for (auto& h : obj) rec.height = std::max(rec.height, h->stats().height);
    out.push_back(std::move(rec));
  }
  return out;
}

#if KDET_BENCH_GPU_BVH
/// The suite's GPU BVH baseline (benchmarks/gpu_bvh.cu) on the scene's frames, in double as the
/// scenes are, doing what a frame costs it, host-timed as kDet's GPU runs are: frame 0 builds
/// each object's tree; a deforming object's new positions are uploaded and its tree refit
/// (GpuBvh::updateVertices); a fractured one is rebuilt (setMesh); a rigid one's pose goes with
/// its queries. Then the same self and inter queries as kDet's, with the same exact test.
/// A deforming object's positions go through one vertex buffer per object, as a simulation keeps
/// its own, so that the tree registers it once as page-locked memory and copies each frame
/// straight from it (GpuBvh::setStableSources; kDet registers its meshes' own buffers so).
/// Filling that buffer is the simulation's work, not the baseline's: untimed. The trees and
/// buffers live from run to run (`kept`), as kDet's GPU objects do (runKdetOnce): frame 0 of a
/// later run refits a deformed object to frame 0's positions and rebuilds a fractured one. Each
/// query reads its pairs back into a result kept from frame to frame, as kDet's GPU runs do.
struct BvhObjects {
  std::vector<std::unique_ptr<kdet_bvh::GpuBvh<double>>> tree;
  std::vector<Positions> positions;
  std::vector<PairList> results;  ///< one per query of a frame, kept (as KdetObjects::results)
};

std::vector<FrameRecord> runBvhOnce(const kb::Scene& s, bool collect, BvhObjects& kept) {
  const std::size_t n = s.objects.size();
  auto& obj = kept.tree;
  auto& positions = kept.positions;
  obj.resize(n);
  positions.resize(n);
  std::vector<kdet_fcl::Transform<double>> pose(n);
  std::vector<FrameRecord> out;
  for (std::size_t f = 0; f < s.frames.size(); ++f) {
    const kb::Frame& fr = s.frames[f];
    FrameRecord rec;
    for (std::size_t o = 0; o < n; ++o) {
      pose[o] = fr.poses[o];
      const kb::Motion motion = s.motion[o];
      if (obj[o] == nullptr || motion == kb::Motion::Fracture) {
        const auto t0 = Clock::now();
        if (obj[o] == nullptr) {
          obj[o] = std::make_unique<kdet_bvh::GpuBvh<double>>();
          obj[o]->setStableSources(true);
        }
        obj[o]->setMesh(*fr.meshes[o]);
        if (motion == kb::Motion::Deform) {  // its buffer registered in the build frame
          obj[o]->updateVertices(simulationFrame(positions[o], *fr.meshes[o]));
        }
        rec.update_ms += msSince(t0);
        continue;
      }
      if (motion != kb::Motion::Deform ||
          (f > 0 && fr.meshes[o] == s.frames[f - 1].meshes[o]))
        continue;
      const Positions& v = simulationFrame(positions[o], *fr.meshes[o]);
      const auto t0 = Clock::now();
      obj[o]->updateVertices(v);
      rec.update_ms += msSince(t0);
    }
    // Each query reads its pairs back into the storage of its kept result (`keep`), or into a
    // new one (--fresh-results).
    kept.results.resize(s.inter.size() + s.self.size());
    std::size_t slot = 0;
    PairList* const none = nullptr;
    for (auto [a, b] : s.inter) {
      PairList& p = kept.results[slot++];
      const auto t0 = Clock::now();
      p = kdet_bvh::intersect(*obj[a], pose[a], *obj[b], pose[b], kdet_fcl::Predicate::Exact,
                              g_fresh_results ? none : &p);
      rec.inter_ms += msSince(t0);
      rec.inter_pairs += p.size();
      if (collect) rec.inter_sets.push_back(p);  // (sorted by (a, b) already)
    }
    for (int o : s.self) {
      PairList& p = kept.results[slot++];
      const auto t0 = Clock::now();
      p = kdet_bvh::intersectSelf(*obj[o], kdet_fcl::Predicate::Exact, 0,
                                  g_fresh_results ? none : &p);
      rec.self_ms += msSince(t0);
      rec.self_pairs += p.size();
      if (collect) rec.self_sets.push_back(p);
    }
    out.push_back(std::move(rec));
  }
  return out;
}
#endif

/// Why a GPU method is not measured here, or "" when it can be: the library (or this program)
/// built without CUDA, or no usable device.
std::string gpuUnavailable(bool program_has_it) {
  if (!kdet_fcl::builtWithCuda() || !program_has_it) return "n/a (not built)";
  if (kdet_fcl::cudaDeviceCount() == 0) return "n/a (no CUDA device)";
  return "";
}

// ------------------------------------------------------------------------------------------
// FCL

/// A mesh in FCL's input format, converted once outside every timed region (an FCL user holds
/// their geometry in this form already).
struct FclMesh {
  std::vector<fcl::Vector3d> v;
  std::vector<fcl::Triangle> t;
};

class FclCache {
 public:
  const FclMesh& get(const kb::MeshPtr& m) {
    auto it = cache_.find(m.get());
    if (it != cache_.end()) return *it->second;
    auto fm = std::make_shared<FclMesh>();
    fm->v.reserve(m->vertices.size());
    for (const auto& p : m->vertices) fm->v.emplace_back(p.x, p.y, p.z);
    fm->t.reserve(m->triangles.size());
    for (const auto& t : m->triangles) fm->t.emplace_back(t[0], t[1], t[2]);
    cache_[m.get()] = fm;
    return *fm;
  }

 private:
  std::map<const kb::Mesh*, std::shared_ptr<FclMesh>> cache_;
};

fcl::Transform3d toFcl(const kb::Pose& p) {
  fcl::Transform3d t = fcl::Transform3d::Identity();
  fcl::Matrix3d R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) = p.R[i][j];
  t.linear() = R;
  t.translation() = fcl::Vector3d(p.t.x, p.t.y, p.t.z);
  return t;
}

/// Exhaustive collide (every pair: CollisionRequest(INT_MAX, false)); returns the pairs (b1, b2).
template <class BV>
PairList fclCollide(const fcl::BVHModel<BV>& a, const fcl::Transform3d& ta, const fcl::BVHModel<BV>& b,
                    const fcl::Transform3d& tb, double& ms, bool collect) {
  fcl::CollisionRequestd req(std::numeric_limits<int>::max(), false);
  fcl::CollisionResultd res;
  const auto t0 = Clock::now();
  fcl::collide(&a, ta, &b, tb, req, res);
  ms += msSince(t0);
  PairList out;
  if (!collect) {
    out.resize(res.numContacts());  // only the count is used
    return out;
  }
  std::vector<fcl::Contactd> cs;
  res.getContacts(cs);
  out.reserve(cs.size());
  for (const auto& c : cs) out.push_back({std::uint32_t(c.b1), std::uint32_t(c.b2)});
  return out;
}

using kdet_bench_util::selfFromPair;

enum class FclMode { Scene, SelfPair };

/// One run of FCL over the scene. Mode Scene: inter-object queries, or the mesh against itself
/// when the scene has no object pairs. Mode SelfPair: the mesh-against-itself query of every
/// object whose self-collision is asked (FCL has no self-collision).
template <class BV>
std::vector<FrameRecord> runFclOnce(const kb::Scene& s, FclCache& cache, FclMode mode, bool collect) {
  using Model = fcl::BVHModel<BV>;
  std::vector<FrameRecord> out;
  std::vector<std::shared_ptr<Model>> obj(s.objects.size());
  const bool self_as_pair = mode == FclMode::SelfPair || s.inter.empty();
  for (std::size_t f = 0; f < s.frames.size(); ++f) {
    const kb::Frame& fr = s.frames[f];
    FrameRecord rec;
    for (std::size_t o = 0; o < obj.size(); ++o) {
      const FclMesh& m = cache.get(fr.meshes[o]);
      const bool rebuild = f == 0 || s.motion[o] == kb::Motion::Fracture;
      const bool refit = !rebuild && s.motion[o] == kb::Motion::Deform && fr.meshes[o] != s.frames[f - 1].meshes[o];
      if (rebuild) {
        const auto t0 = Clock::now();
        auto model = std::make_shared<Model>();
        model->beginModel(int(m.t.size()), int(m.v.size()));
        model->addSubModel(m.v, m.t);
        model->endModel();
        rec.update_ms += msSince(t0);
        obj[o] = std::move(model);
      } else if (refit) {
        const auto t0 = Clock::now();
        obj[o]->beginUpdateModel();
        obj[o]->updateSubModel(m.v);
        obj[o]->endUpdateModel(true, true);
        rec.update_ms += msSince(t0);
      }
    }
    if (self_as_pair) {
      for (int o : s.self) {
        const fcl::Transform3d t = toFcl(fr.poses[o]);
        PairList raw = fclCollide(*obj[o], t, *obj[o], t, rec.self_ms, collect);
        if (collect) {
          PairList p = selfFromPair(*fr.meshes[o], raw);
          rec.self_pairs += raw.size();
          rec.self_sets.push_back(std::move(p));
        } else {
          rec.self_pairs += raw.size();
        }
      }
    }
    if (mode == FclMode::Scene) {
      for (auto [a, b] : s.inter) {
        PairList p = fclCollide(*obj[a], toFcl(fr.poses[a]), *obj[b], toFcl(fr.poses[b]), rec.inter_ms, collect);
        rec.inter_pairs += p.size();
        if (collect) rec.inter_sets.push_back(sorted(std::move(p)));
      }
    }
    out.push_back(std::move(rec));
  }
  return out;
}

// ------------------------------------------------------------------------------------------
// Agreement: every method's pairs against kDet's (1 thread), settled by the exact predicate.

struct Settle {
  std::size_t compared = 0;         ///< queries compared
  std::size_t equal = 0;            ///< queries with identical sets
  std::size_t extra_rounding = 0;   ///< peer-only pairs, not intersecting, distance within rounding
  std::size_t extra_wrong = 0;      ///< peer-only pairs, not intersecting, clearly apart
  std::size_t extra_coplanar = 0;   ///<   ... of which coplanar (all six points on one plane)
  std::size_t missed_rounding = 0;  ///< kDet-only pairs (exactly intersecting) that only touch
  std::size_t missed_wrong = 0;     ///< kDet-only pairs that intersect robustly
  std::size_t kdet_wrong = 0;       ///< differences the exact predicate settles AGAINST kDet
  std::size_t duplicates = 0;       ///< pairs the peer reported more than once

  void add(const Settle& o) {
    compared += o.compared; equal += o.equal; extra_rounding += o.extra_rounding;
    extra_wrong += o.extra_wrong; extra_coplanar += o.extra_coplanar;
    missed_rounding += o.missed_rounding; missed_wrong += o.missed_wrong;
    kdet_wrong += o.kdet_wrong; duplicates += o.duplicates;
  }
  bool agreed() const { return compared == equal; }
};

using V3 = kdet_fcl::Vec3<double>;

struct Tri {
  V3 p[3];
};

Tri triOf(const kb::Mesh& m, std::uint32_t i, const kdet_fcl::detail::RelativePose* map) {
  Tri t;
  for (int k = 0; k < 3; ++k) {
    const V3& v = m.vertices[m.triangles[i][k]];
    t.p[k] = map ? kdet_fcl::detail::mapPoint(map->a_to_b, v) : v;
  }
  return t;
}

bool isect(const Tri& a, const Tri& b) {
  return kdet_fcl::detail::trianglesIntersect(a.p[0], a.p[1], a.p[2], b.p[0], b.p[1], b.p[2]);
}

double scaleOf(const Tri& a, const Tri& b) {
  double s = 0;
  for (const Tri* t : {&a, &b})
    for (int k = 0; k < 3; ++k) {
      s = std::max({s, std::fabs(t->p[k].x), std::fabs(t->p[k].y), std::fabs(t->p[k].z)});
      const V3 e = t->p[(k + 1) % 3] - t->p[k];
      s = std::max(s, std::sqrt(kdet_fcl::dot(e, e)));
    }
  return s;
}

Tri shrink(const Tri& t, double f) {
  const V3 c = (t.p[0] + t.p[1] + t.p[2]) * (1.0 / 3);
  Tri o;
  for (int k = 0; k < 3; ++k) o.p[k] = c + (t.p[k] - c) * f;
  return o;
}

bool coplanar(const Tri& a, const Tri& b) {
  const V3 n = kdet_fcl::cross(a.p[1] - a.p[0], a.p[2] - a.p[0]);
  const double nn = std::sqrt(kdet_fcl::dot(n, n));
  if (nn == 0) return false;
  const double s = scaleOf(a, b);
  for (int k = 0; k < 3; ++k)
    if (std::fabs(kdet_fcl::dot(n, b.p[k] - a.p[0])) > 1e-12 * nn * s) return false;
  return true;
}

/// Compares `peer` with `ref` (kDet's set) for one query and settles each difference.
Settle settle(const PairList& ref, PairList peer, const kb::Mesh& A, const kb::Pose& pa, const kb::Mesh& B,
              const kb::Pose& pb, bool self, std::string* example) {
  Settle st;
  st.compared = 1;
  std::sort(peer.begin(), peer.end());
  const std::size_t before = peer.size();
  peer.erase(std::unique(peer.begin(), peer.end()), peer.end());
  st.duplicates = before - peer.size();
  if (peer == ref) {
    st.equal = 1;
    return st;
  }
  kdet_fcl::detail::RelativePose rp;
  const kdet_fcl::detail::RelativePose* map = nullptr;
  if (!self) {
    rp = kdet_fcl::detail::relativePose(pa, pb);
    if (!rp.identity) map = &rp;
  }
  PairList only_peer, only_ref;
  std::set_difference(peer.begin(), peer.end(), ref.begin(), ref.end(), std::back_inserter(only_peer));
  std::set_difference(ref.begin(), ref.end(), peer.begin(), peer.end(), std::back_inserter(only_ref));
  const auto note = [&](const char* what, TrianglePair p) {
    if (example && example->empty()) *example = std::string(what) + " (" + std::to_string(p.a) + "," + std::to_string(p.b) + ")";
  };
  for (TrianglePair p : only_peer) {
    const Tri a = triOf(A, p.a, map), b = triOf(self ? A : B, p.b, nullptr);
    if (isect(a, b)) {
      ++st.kdet_wrong;  // kDet missed an exactly intersecting pair
      note("kDet missed", p);
      continue;
    }
    const double d = std::sqrt(kdet_fcl::detail::triangleDistanceSquared(a.p[0], a.p[1], a.p[2], b.p[0], b.p[1], b.p[2]));
    if (d <= 1e-9 * scaleOf(a, b)) {
      ++st.extra_rounding;
    } else {
      ++st.extra_wrong;
      if (coplanar(a, b)) ++st.extra_coplanar;
      note("peer reported a separated pair", p);
    }
  }
  for (TrianglePair p : only_ref) {
    const Tri a = triOf(A, p.a, map), b = triOf(self ? A : B, p.b, nullptr);
    if (!isect(a, b)) {
      ++st.kdet_wrong;  // kDet reported a pair the exact predicate rejects
      note("kDet false pair", p);
      continue;
    }
    // A pair that still intersects after shrinking both triangles by 1e-6 about their centroids
    // crosses robustly; otherwise it only touches (the peer's rounding may decide either way).
    if (isect(shrink(a, 1 - 1e-6), shrink(b, 1 - 1e-6))) {
      ++st.missed_wrong;
      note("peer missed a robust pair", p);
    } else {
      ++st.missed_rounding;
    }
  }
  return st;
}

// ------------------------------------------------------------------------------------------
// Per-scene results and summaries

struct SceneResult {
  const kb::Scene* scene = nullptr;
  std::vector<MethodResult> methods;
  kdet_fcl::KFreeStats k;
  bool have_k = false;
  double k_seconds = 0;
  std::map<std::string, Settle> agreement;  ///< per method id
  std::vector<std::string> examples;
};

const MethodResult* find(const SceneResult& r, const std::string& id) {
  for (const auto& m : r.methods)
    if (m.id == id) return &m;
  return nullptr;
}

/// Measured (not skipped, not unavailable).
bool ok(const MethodResult* m) { return m && m->status.rfind("ok", 0) == 0; }

/// Frames that count for the per-frame averages: all but the build frame in animations.
std::vector<std::size_t> steadyFrames(const kb::Scene& s) {
  std::vector<std::size_t> f;
  for (std::size_t i = s.frames.size() > 1 ? 1 : 0; i < s.frames.size(); ++i) f.push_back(i);
  return f;
}

struct Summary {
  double update = 0, query = 0, total = 0;  ///< mean over steady frames of the per-frame medians
  double self = 0, inter = 0;
  double comparable = 0;  ///< kDet: update + only the queries FCL answers (inter, or self when none)
  double build = 0;       ///< frame 0 update
  double pairs = 0;       ///< mean pairs per frame (self + inter)
};

Summary summarize(const kb::Scene& s, const MethodResult& m, bool kdet) {
  Summary o;
  const auto fs = steadyFrames(s);
  for (std::size_t f : fs) {
    const FrameRecord& r = m.frames[f];
    o.update += r.update_ms;
    o.self += r.self_ms;
    o.inter += r.inter_ms;
    o.pairs += double(r.self_pairs + r.inter_pairs);
  }
  const double n = double(fs.size());
  o.update /= n; o.self /= n; o.inter /= n; o.pairs /= n;
  o.query = o.self + o.inter;
  o.total = o.update + o.query;
  o.comparable = kdet ? o.update + (s.inter.empty() ? o.self : o.inter) : o.total;
  o.build = m.frames[0].update_ms;
  return o;
}

std::string fmt(double v, int prec = 2) {
  char b[64];
  if (std::isnan(v)) return "n/a";
  if (v != 0 && std::fabs(v) < 0.01 && prec <= 2) std::snprintf(b, sizeof b, "%.3f", v);
  else std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

std::string jnum(double v) {
  if (!std::isfinite(v)) return "null";
  char b[64];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

std::string jstr(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (c == '\n') { o += "\\n"; continue; }
    o += c;
  }
  return o + "\"";
}

std::string readFirstLine(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line))
    if (key.empty() || line.rfind(key, 0) == 0) return line;
  return "";
}

std::string cpuModel() {
  std::string l = readFirstLine("/proc/cpuinfo", "model name");
  const auto p = l.find(':');
  return p == std::string::npos ? "unknown" : l.substr(p + 2);
}

std::string loadAvg() { return readFirstLine("/proc/loadavg", ""); }

std::string nowUtc() {
  std::time_t t = std::time(nullptr);
  char b[64];
  std::strftime(b, sizeof b, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&t));
  return b;
}

// ------------------------------------------------------------------------------------------

struct Options {
  bool quick = false;
  int reps = 3;
  bool reps_set = false;
  int frames = 6;
  std::vector<std::string> only;
  std::string out = "bench_out";
  bool include_1m = false;
  std::size_t tiny = 1000000;
  int rigid_poses = 100;
  bool plots = true;
  bool kfree = true;
  std::string export_dir;
  std::string command;
  std::vector<std::string> methods;  ///< run only methods whose id contains one of these
  GpuUpdate gpu_update = GpuUpdate::Commit;  ///< --gpu-update
  bool fresh_results = false;  ///< --fresh-results: the GPU runs' queries return new results
  std::string inject_unsteady;  ///< --inject-unsteady ID (test hook)
};

/// Whether --methods asks for method `id`: a word ending in '$' names a whole id, any other word
/// any id containing it (so "fcl_obbrss$" runs FCL OBBRSS without its mesh-against-itself twin).
bool methodWanted(const Options& o, const std::string& id) {
  if (o.methods.empty() || id == "kdet_cpu_1t") return true;  // the reference always runs
  for (const auto& m : o.methods) {
    if (!m.empty() && m.back() == '$') {
      if (id == m.substr(0, m.size() - 1)) return true;
    } else if (id.find(m) != std::string::npos) {
      return true;
    }
  }
  return false;
}

[[noreturn]] void usage(int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: kdet_bench [--quick] [--reps R] [--frames F] [--only name,name] [--out DIR]\n"
               "                  [--include-1m] [--tiny N] [--rigid-poses N] [--rep-budget S]\n"
               "                  [--no-plots] [--no-kfree] [--gpu-update commit|copy] [--fresh-results]\n"
               "       kdet_bench --export-scenes DIR [--quick]\n"
               "  --quick        small scenes, 1 run, agreement checked (CI smoke test; not timed)\n"
               "  --reps R       timed repetitions after one warm-up/check run (default 3)\n"
               "  --rep-budget S a method whose check run is long gets only as many timed runs as\n"
               "                 fit in S seconds (at least 1; default 20)\n"
               "  --only a,b     scenes whose name contains one of the words\n"
               "  --methods a,b  only methods whose id contains a word, or is a word ending in '$'\n"
               "                 without it (kdet_cpu_1t always runs; ids: kdet_cpu_1t, kdet_cpu_2t,\n"
               "                 kdet_gpu, fcl_obbrss, fcl_obb, fcl_aabb, gpu_bvh, fcl_obbrss_selfpair)\n"
               "  --out DIR      where bench.md, bench.json, *.dat, *.gp and *.png go (default bench_out)\n"
               "  --gpu-update commit|copy  how kDet's GPU runs take a deforming object's positions:\n"
               "                 written into the mesh's write buffer and committed (default), or\n"
               "                 handed to updateVertices, which copies them\n"
               "  --fresh-results  the GPU methods' queries return new results (default: each reads\n"
               "                 its pairs back into a result kept from frame to frame)\n"
               "  --inject-unsteady ID  (test of the check below) adds one pair to the count of\n"
               "                 method ID's first timed run\n"
               "Every timed run's pair counts must equal the checking run's, frame by frame.\n"
               "The UNC and FCL meshes come from $KDET_FCL_DATA_DIR, else ../shared/data beside the\n"
               "source tree; scenes whose files are missing are left out.\n"
               "Exit code: 0 ok, 1 a disagreement settled against kDet or pair counts that changed from\n"
               "run to run, 2 usage.\n");
  std::exit(code);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 0; i < argc; ++i) o.command += (i ? " " : "") + std::string(argv[i]);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto val = [&]() -> std::string {
      if (i + 1 >= argc) usage(2);
      return argv[++i];
    };
    if (a == "--quick") o.quick = true;
    else if (a == "--reps") { o.reps = std::stoi(val()); o.reps_set = true; }
    else if (a == "--frames") o.frames = std::stoi(val());
    else if (a == "--only") {
      std::stringstream ss(val());
      std::string w;
      while (std::getline(ss, w, ',')) if (!w.empty()) o.only.push_back(w);
    } else if (a == "--methods") {
      std::stringstream ss(val());
      std::string w;
      while (std::getline(ss, w, ',')) if (!w.empty()) o.methods.push_back(w);
    } else if (a == "--out") o.out = val();
    else if (a == "--include-1m") o.include_1m = true;
    else if (a == "--tiny") o.tiny = std::stoul(val());
    else if (a == "--rigid-poses") o.rigid_poses = std::stoi(val());
    else if (a == "--no-plots") o.plots = false;
    else if (a == "--rep-budget") g_rep_budget_s = std::stod(val());
    else if (a == "--no-kfree") o.kfree = false;
    else if (a == "--fresh-results") o.fresh_results = true;
    else if (a == "--inject-unsteady") o.inject_unsteady = val();
    else if (a == "--gpu-update") {
      const std::string v = val();
      if (v != "commit" && v != "copy") usage(2);
      o.gpu_update = v == "commit" ? GpuUpdate::Commit : GpuUpdate::Copy;
    }
    else if (a == "--export-scenes") o.export_dir = val();
    else if (a == "--help" || a == "-h") usage(0);
    else usage(2);
  }
  if (o.quick && !o.reps_set) o.reps = 0;
  if (o.reps < 0 || o.frames < 1) usage(2);
  return o;
}

const char* kMethodOrder[] = {"kdet_cpu_1t", "kdet_cpu_2t", "kdet_gpu", "fcl_obbrss", "fcl_obb", "fcl_aabb",
                              "gpu_bvh", "fcl_obbrss_selfpair"};

std::string methodTitle(const std::string& id) {
  if (id == "kdet_cpu_1t") return "kDet CPU 1T";
  if (id == "kdet_cpu_2t") return "kDet CPU 2T";
  if (id == "kdet_gpu") return "kDet GPU";
  if (id == "fcl_obbrss") return "FCL OBBRSS";
  if (id == "fcl_obb") return "FCL OBB";
  if (id == "fcl_aabb") return "FCL AABB";
  if (id == "gpu_bvh") return "GPU BVH";
  if (id == "fcl_obbrss_selfpair") return "FCL OBBRSS mesh-vs-itself";
  return id;
}

bool isKdet(const std::string& id) { return id.rfind("kdet", 0) == 0; }

SceneResult runScene(const kb::Scene& s, const Options& o) {
  SceneResult R;
  R.scene = &s;
  std::fprintf(stderr, "kdet_bench: scene %s (%zu frames, %zu triangles in frame 0)\n", s.name.c_str(),
               s.frames.size(), s.triangles(0));
  // k-free analysis once per scene, on the middle frame, all objects merged in world coordinates
  // (kDet's paper puts all polygons of a scene in one hierarchy for these numbers).
  if (o.kfree) {
    const auto t0 = Clock::now();
    kdet_fcl::KFreeOptions ko;
    ko.threads = 2;
    R.k = kdet_fcl::analyzeKFree(kb::mergedWorld(s, s.frames.size() / 2), ko);
    R.have_k = true;
    R.k_seconds = msSince(t0) / 1000;
    std::fprintf(stderr, "  k-free: k=%u mean=%.2f sd=%.2f height=%d (%.1f s)\n", R.k.k, R.k.mean, R.k.sd,
                 R.k.height, R.k_seconds);
  }
  for (int threads : {1, 2}) {
    MethodResult m;
    m.id = "kdet_cpu_" + std::to_string(threads) + "t";
    repeat(m, o.reps, !methodWanted(o, m.id), s.name, [&](bool c) { return runKdetOnce(s, threads, kdet_fcl::Backend::Cpu, c); });
    R.methods.push_back(std::move(m));
  }
  {
    MethodResult m;
    m.id = "kdet_gpu";
    m.status = gpuUnavailable(true);
    if (m.status.empty()) {
      m.status = "ok (host timer)";
      KdetObjects kept;  // from run to run (runKdetOnce)
      repeat(m, o.reps, !methodWanted(o, m.id), s.name, [&](bool c) {
        return runKdetOnce(s, 0, kdet_fcl::Backend::Cuda, c, &kept, o.gpu_update);
      });
    }
    R.methods.push_back(std::move(m));
  }
  FclCache cache;
  {
    MethodResult m;
    m.id = "fcl_obbrss";
    m.self_as_pair = s.inter.empty();
    repeat(m, o.reps, !methodWanted(o, m.id), s.name, [&](bool c) { return runFclOnce<fcl::OBBRSSd>(s, cache, FclMode::Scene, c); });
    R.methods.push_back(std::move(m));
  }
  {
    MethodResult m;
    m.id = "fcl_obb";
    m.self_as_pair = s.inter.empty();
    repeat(m, o.reps, !methodWanted(o, m.id), s.name, [&](bool c) { return runFclOnce<fcl::OBBd>(s, cache, FclMode::Scene, c); });
    R.methods.push_back(std::move(m));
  }
  {
    MethodResult m;
    m.id = "fcl_aabb";
    m.self_as_pair = s.inter.empty();
    repeat(m, o.reps, !methodWanted(o, m.id), s.name, [&](bool c) { return runFclOnce<fcl::AABBd>(s, cache, FclMode::Scene, c); });
    R.methods.push_back(std::move(m));
  }
  {
    MethodResult m;
    m.id = "gpu_bvh";
    m.status = gpuUnavailable(KDET_BENCH_GPU_BVH != 0);
#if KDET_BENCH_GPU_BVH
    if (m.status.empty()) {
      m.status = "ok (host timer)";
      BvhObjects kept;  // from run to run (runBvhOnce)
      repeat(m, o.reps, !methodWanted(o, m.id), s.name, [&](bool c) { return runBvhOnce(s, c, kept); });
    }
#endif
    R.methods.push_back(std::move(m));
  }
  if (!s.inter.empty() && !s.self.empty()) {
    MethodResult m;
    m.id = "fcl_obbrss_selfpair";
    m.self_as_pair = true;
    repeat(m, o.reps, !methodWanted(o, m.id), s.name, [&](bool c) { return runFclOnce<fcl::OBBRSSd>(s, cache, FclMode::SelfPair, c); });
    R.methods.push_back(std::move(m));
  }

  // Agreement: everything against kDet with 1 thread.
  const MethodResult* ref = find(R, "kdet_cpu_1t");
  for (const auto& m : R.methods) {
    if (m.id == ref->id || m.check.empty()) continue;
    Settle total;
    for (std::size_t f = 0; f < s.frames.size(); ++f) {
      const kb::Frame& fr = s.frames[f];
      const FrameRecord& a = ref->check[f];
      const FrameRecord& b = m.check[f];
      std::string ex;
      for (std::size_t q = 0; q < b.self_sets.size(); ++q) {
        const int ob = s.self[q];
        total.add(settle(a.self_sets[q], b.self_sets[q], *fr.meshes[ob], fr.poses[ob], *fr.meshes[ob], fr.poses[ob], true, &ex));
      }
      for (std::size_t q = 0; q < b.inter_sets.size(); ++q) {
        const auto [x, y] = s.inter[q];
        total.add(settle(a.inter_sets[q], b.inter_sets[q], *fr.meshes[x], fr.poses[x], *fr.meshes[y], fr.poses[y], false, &ex));
      }
      if (!ex.empty()) R.examples.push_back(s.name + " frame " + std::to_string(f) + " " + m.id + ": " + ex);
    }
    // kDet with 2 threads (or on the GPU) must give exactly kDet's 1-thread set.
    if (isKdet(m.id) && !total.agreed()) total.kdet_wrong = std::max<std::size_t>(total.kdet_wrong, 1);
    if (!total.agreed()) {
      std::fprintf(stderr,
                   "  *** DISAGREEMENT *** %s: %s differs from kDet in %zu of %zu queries: peer-only pairs %zu "
                   "(rounding %zu, separated %zu of which coplanar %zu), kDet-only pairs %zu (touching %zu, "
                   "robust %zu); settled against kDet: %zu\n",
                   s.name.c_str(), m.id.c_str(), total.compared - total.equal, total.compared,
                   total.extra_rounding + total.extra_wrong, total.extra_rounding, total.extra_wrong,
                   total.extra_coplanar, total.missed_rounding + total.missed_wrong, total.missed_rounding,
                   total.missed_wrong, total.kdet_wrong);
    }
    R.agreement[m.id] = total;
  }
  // Free the pair sets.
  for (auto& m : R.methods) m.check.clear();
  return R;
}

// ------------------------------------------------------------------------------------------
// Output

std::string kCell(const SceneResult& r) {
  if (!r.have_k) return "n/a";
  char b[96];
  std::snprintf(b, sizeof b, "%u (%.1f ± %.1f)", r.k.k, r.k.mean, r.k.sd);
  return b;
}

std::string heightCell(const SceneResult& r) {
  const MethodResult* m = find(r, "kdet_cpu_1t");
  std::vector<double> h;
  for (std::size_t f : steadyFrames(*r.scene)) h.push_back(m->frames[f].height);
  const double mean = std::accumulate(h.begin(), h.end(), 0.0) / h.size();
  double var = 0;
  for (double x : h) var += (x - mean) * (x - mean);
  char b[64];
  std::snprintf(b, sizeof b, "%.1f (%.1f)", mean, std::sqrt(var / h.size()));
  return b;
}

std::string agreeCell(const SceneResult& r) {
  bool all = true;
  std::size_t kw = 0, diff = 0;
  std::string who;
  for (const auto& [id, st] : r.agreement) {
    kw += st.kdet_wrong;
    if (!st.agreed()) {
      all = false;
      diff += st.extra_rounding + st.extra_wrong + st.missed_rounding + st.missed_wrong + st.kdet_wrong;
      who += (who.empty() ? "" : ", ") + id;
    }
  }
  std::string unsteady;
  for (const auto& m : r.methods)
    if (m.unsteady_runs > 0) unsteady += (unsteady.empty() ? "" : ", ") + m.id;
  if (!unsteady.empty()) return "**NO: pair counts changed from run to run (" + unsteady + ")**";
  if (all) return "yes";
  if (kw) return "**NO: kDet wrong on " + std::to_string(kw) + " pairs**";
  return "settled for kDet (" + who + ")";
}

/// A method's total ms per frame (mean over the steady frames), or why it was not measured.
std::string totalCell(const kb::Scene& s, const MethodResult& m) {
  return ok(&m) ? fmt(summarize(s, m, isKdet(m.id)).total) : m.status;
}

/// Mean triangles over the steady frames.
std::size_t steadyTriangles(const kb::Scene& s) {
  std::size_t tris = 0;
  for (std::size_t f : steadyFrames(s)) tris += s.triangles(f);
  return tris / steadyFrames(s).size();
}

/// The GPU table (issue 5): kDet's CUDA backend against the suite's GPU BVH baseline (every self
/// and inter query of the frame for both, so totals against totals) and against FCL OBBRSS
/// (FCL total / kDet GPU comparable, as the CPU's speedup column), with the GPU targets of the
/// deforming scenes of 90k triangles or more: at least 3x the GPU BVH and 100x FCL.
void writeGpuTable(std::ofstream& md, const std::vector<SceneResult>& res, GpuUpdate how,
                   bool fresh_results) {
  bool any = false;
  for (const auto& r : res) any = any || ok(find(r, "kdet_gpu"));
  if (!any) return;
  md << "\n### GPU: kDet's CUDA backend against the GPU BVH baseline and FCL (same run; ms per frame, "
        "host timer)\n\n";
  md << "GPU: " << kdet_bench_util::backendGpu() << ". Both GPU methods run every self and "
        "inter-object query of the frame in double (the scenes' precision) and read the pairs back "
     << (fresh_results ? "into new results (--fresh-results), "
                       : "into results kept from frame to frame, ")
     << "with their objects kept from run to run as a simulation keeps them (kDet: "
     << (how == GpuUpdate::Commit ? "commitVertices" : "updateVertices")
     << ", setMesh, setPose on its HashedMesh objects; the GPU BVH: refit, rebuild), each "
        "deforming object's new positions written by the simulation (untimed) "
     << (how == GpuUpdate::Commit
             ? "into kDet's mesh's write buffer, where its update checks them on the host in "
               "place, and into a buffer of its own for the GPU BVH, "
             : "into one buffer per object and method; kDet's update checks them and copies them "
               "into the mesh on the host, ")
     << "the GPU BVH's query uploads them unchecked; "
        "\"vs GPU BVH\" is total against total; \"vs FCL\" is FCL OBBRSS total / kDet GPU "
        "comparable, as the CPU speedup. Target (issue 5, deforming scenes of 90k triangles or "
        "more): at least 3× the GPU BVH and 100× FCL.\n\n";
  md << "| Scene | # polys | deforming | kDet GPU total | GPU BVH total | vs GPU BVH | FCL total | vs FCL | "
        "target |\n";
  md << "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | --- |\n";
  for (const auto& r : res) {
    const kb::Scene& s = *r.scene;
    const MethodResult* g = find(r, "kdet_gpu");
    const MethodResult* b = find(r, "gpu_bvh");
    const MethodResult* fm = find(r, "fcl_obbrss");
    const std::size_t tris = steadyTriangles(s);
    const bool gok = ok(g), bok = ok(b), fok = ok(fm);
    const Summary gs = gok ? summarize(s, *g, true) : Summary{};
    const double vb = gok && bok ? summarize(s, *b, false).total / gs.total : NAN;
    const double vf = gok && fok ? summarize(s, *fm, false).total / gs.comparable : NAN;
    std::string target = "(not a target scene)";
    if (s.deforming() && tris >= 90000) {
      if (std::isnan(vb) || std::isnan(vf)) target = "not measured";
      else if (vb >= 3 && vf >= 100) target = "met";
      else target = std::string("**missed**: ") + (vb < 3 ? "vs GPU BVH < 3×" : "") +
                    (vb < 3 && vf < 100 ? ", " : "") + (vf < 100 ? "vs FCL < 100×" : "");
    }
    md << "| " << s.label << " | " << tris << " | " << (s.deforming() ? "yes" : "no") << " | "
       << totalCell(s, *g) << " | " << totalCell(s, *b) << " | "
       << (std::isnan(vb) ? "" : fmt(vb, 2) + "×") << " | "
       << (fok ? fmt(summarize(s, *fm, false).total) : fm->status) << (fok && fm->self_as_pair ? "*" : "")
       << " | " << (std::isnan(vf) ? "" : fmt(vf, 1) + "×") << " | " << target << " |\n";
  }
}

void writeMarkdown(const std::vector<SceneResult>& res, const Options& o, const std::string& path,
                   const std::string& load_before, const std::string& load_after) {
  std::ofstream md(path);
  md << "<!-- generated by kdet_bench; do not edit by hand -->\n";
  md << "Command: `" << o.command << "`  \n";
  md << "CPU: " << cpuModel() << ", " << std::thread::hardware_concurrency() << " hardware threads; "
     << "load average before: " << load_before << "; after: " << load_after << "  \n";
  md << "Date: " << nowUtc() << "; FCL " << FCL_VERSION << "; kdet_fcl built with CUDA: "
     << (kdet_fcl::builtWithCuda() ? "yes" : "no") << "; GPU: " << kdet_bench_util::backendGpu()
     << "; repetitions: " << o.reps
     << " timed after 1 warm-up (per-frame medians; scene values are means over the frames after the build frame)\n\n";

  md << "### Table 1 layout (times in ms per frame)\n\n";
  md << "kDet = kdet_fcl CPU, 2 threads, all self + inter-object queries of the frame. FCL = "
        "BVHModel<OBBRSS>: refit/rebuild + exhaustive inter-object collide (FCL has no self-collision; "
        "scenes of one object use the mesh against itself, marked *). Speedup = FCL total / kDet "
        "comparable (kDet update + only the queries FCL answers).\n\n";
  md << "| Scene | # polys | k (mean ± sd) | height (sd) | kDet col det | kDet update | kDet total | "
        "FCL col det | FCL update | FCL total | speedup (2T) | kDet GPU total | GPU BVH total | pairs | agree |\n";
  md << "| --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- | ---: | --- |\n";
  for (const auto& r : res) {
    const kb::Scene& s = *r.scene;
    const MethodResult* km = ok(find(r, "kdet_cpu_2t")) ? find(r, "kdet_cpu_2t") : find(r, "kdet_cpu_1t");
    const Summary k2 = summarize(s, *km, true);
    const MethodResult* fm = find(r, "fcl_obbrss");
    const bool fok = ok(fm);
    const Summary fo = fok ? summarize(s, *fm, false) : Summary{};
    const std::string gcell = totalCell(s, *find(r, "kdet_gpu"));
    const std::string bcell = totalCell(s, *find(r, "gpu_bvh"));
    const std::size_t tris = steadyTriangles(s);
    md << "| " << s.label << " | " << tris << " | " << kCell(r) << " | " << heightCell(r) << " | "
       << fmt(k2.query) << " | " << fmt(k2.update) << " | " << fmt(k2.total) << " | "
       << (fok ? fmt(fo.query) : fm->status) << (fok && fm->self_as_pair ? "*" : "") << " | "
       << (fok ? fmt(fo.update) : "") << " | " << (fok ? fmt(fo.total) : "") << " | "
       << (fok ? fmt(fo.total / k2.comparable, 1) + "×" : "") << " | " << gcell << " | " << bcell << " | "
       << std::size_t(k2.pairs) << " | " << agreeCell(r) << " |\n";
  }

  writeGpuTable(md, res, o.gpu_update, o.fresh_results);

  md << "\n### Every method (ms per frame: update / query / total; build = frame 0)\n\n";
  md << "| Scene | frames | method | runs | build | update | query | total | comparable | pairs/frame | vs kDet 1T |\n";
  md << "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n";
  for (const auto& r : res) {
    const kb::Scene& s = *r.scene;
    for (const char* id : kMethodOrder) {
      const MethodResult* m = find(r, id);
      if (!m) continue;
      if (m->status.rfind("ok", 0) != 0) {
        md << "| " << s.name << " | " << s.frames.size() << " | " << methodTitle(id) << " | | " << m->status
           << " | | | | | | |\n";
        continue;
      }
      const Summary x = summarize(s, *m, isKdet(id));
      std::string agree = "reference";
      auto it = r.agreement.find(id);
      if (it != r.agreement.end()) {
        const Settle& st = it->second;
        if (st.agreed()) agree = "same pairs";
        else {
          agree = "differs in " + std::to_string(st.compared - st.equal) + "/" + std::to_string(st.compared) +
                  " queries: +" + std::to_string(st.extra_rounding + st.extra_wrong) + " (" +
                  std::to_string(st.extra_wrong) + " separated, " + std::to_string(st.extra_coplanar) +
                  " coplanar) −" + std::to_string(st.missed_rounding + st.missed_wrong) + " (" +
                  std::to_string(st.missed_wrong) + " robust)";
          if (st.kdet_wrong) agree += " **kDet wrong: " + std::to_string(st.kdet_wrong) + "**";
        }
      }
      if (m->unsteady_runs > 0)
        agree += " **pair counts changed in " + std::to_string(m->unsteady_runs) + "/" +
                 std::to_string(m->timed_runs) + " timed runs (" + m->unsteady + ")**";
      std::string title = methodTitle(id);
      if (m->self_as_pair && !isKdet(id) && std::string(id) != "fcl_obbrss_selfpair") title += " (mesh vs itself)";
      md << "| " << s.name << " | " << s.frames.size() << " | " << title << " | " << m->timed_runs << " | "
         << fmt(x.build) << " | "
         << fmt(x.update) << " | " << fmt(x.query) << " | " << fmt(x.total) << " | "
         << (isKdet(id) ? fmt(x.comparable) : fmt(x.total)) << " | " << std::size_t(x.pairs) << " | " << agree
         << " |\n";
    }
  }
  md << "\nPairs of `FCL … (mesh vs itself)` count FCL's raw contacts (each pair in both orders, each "
        "triangle with itself, neighbours sharing a vertex); the agreement check compares them after "
        "removing those.\n";
  if (!res.empty()) {
    bool any = false;
    for (const auto& r : res)
      for (const auto& e : r.examples) {
        if (!any) md << "\nFirst differing pair per scene/method/frame (examples):\n\n";
        any = true;
        md << "- " << e << "\n";
      }
  }
}

void writeJson(const std::vector<SceneResult>& res, const Options& o, const std::string& path,
               const std::string& load_before, const std::string& load_after) {
  std::ofstream js(path);
  js << "{\n  \"meta\": {\"command\": " << jstr(o.command) << ", \"date\": " << jstr(nowUtc())
     << ", \"cpu\": " << jstr(cpuModel()) << ", \"hardware_threads\": " << std::thread::hardware_concurrency()
     << ", \"load_before\": " << jstr(load_before) << ", \"load_after\": " << jstr(load_after)
     << ", \"fcl_version\": " << jstr(FCL_VERSION) << ", \"built_with_cuda\": "
     << (kdet_fcl::builtWithCuda() ? "true" : "false") << ", \"gpu\": "
     << jstr(kdet_bench_util::backendGpu()) << ", \"quick\": " << (o.quick ? "true" : "false")
     << ", \"timed_repetitions\": " << o.reps << ", \"units\": \"ms\"},\n  \"scenes\": [\n";
  for (std::size_t si = 0; si < res.size(); ++si) {
    const SceneResult& r = res[si];
    const kb::Scene& s = *r.scene;
    js << "    {\"name\": " << jstr(s.name) << ", \"group\": " << jstr(s.group) << ", \"label\": " << jstr(s.label)
       << ", \"note\": " << jstr(s.note) << ", \"nominal\": " << s.nominal << ",\n     \"objects\": [";
    for (std::size_t i = 0; i < s.objects.size(); ++i)
      js << (i ? ", " : "") << "{\"name\": " << jstr(s.objects[i]) << ", \"motion\": " << jstr(kb::motionName(s.motion[i])) << "}";
    js << "],\n     \"kfree\": ";
    if (r.have_k)
      js << "{\"frame\": " << s.frames.size() / 2 << ", \"triangles\": " << r.k.triangles << ", \"k\": " << r.k.k
         << ", \"mean\": " << jnum(r.k.mean) << ", \"sd\": " << jnum(r.k.sd) << ", \"max_count\": " << r.k.max_count
         << ", \"adjacent_share\": " << jnum(r.k.adjacent_share) << ", \"height\": " << r.k.height
         << ", \"seconds\": " << jnum(r.k_seconds) << "}";
    else
      js << "null";
    js << ",\n     \"summary\": {";
    bool first = true;
    for (const char* id : kMethodOrder) {
      const MethodResult* m = find(r, id);
      if (!m) continue;
      js << (first ? "" : ", ") << "\n       " << jstr(id) << ": ";
      first = false;
      if (m->status.rfind("ok", 0) != 0) {
        js << "{\"status\": " << jstr(m->status) << "}";
        continue;
      }
      const Summary x = summarize(s, *m, isKdet(id));
      js << "{\"status\": " << jstr(m->status) << ", \"timed_runs\": " << m->timed_runs << ", \"self_as_pair\": " << (m->self_as_pair ? "true" : "false")
         << ", \"build_ms\": " << jnum(x.build) << ", \"update_ms\": " << jnum(x.update) << ", \"query_ms\": "
         << jnum(x.query) << ", \"self_ms\": " << jnum(x.self) << ", \"inter_ms\": " << jnum(x.inter)
         << ", \"total_ms\": " << jnum(x.total) << ", \"comparable_ms\": " << jnum(x.comparable)
         << ", \"pairs_per_frame\": " << jnum(x.pairs) << ", \"unsteady_runs\": " << m->unsteady_runs << "}";
    }
    js << "},\n     \"agreement\": {";
    first = true;
    for (const auto& [id, st] : r.agreement) {
      js << (first ? "" : ", ") << jstr(id) << ": {\"agreed\": " << (st.agreed() ? "true" : "false")
         << ", \"queries\": " << st.compared << ", \"equal\": " << st.equal << ", \"peer_only_rounding\": "
         << st.extra_rounding << ", \"peer_only_separated\": " << st.extra_wrong << ", \"peer_only_coplanar\": "
         << st.extra_coplanar << ", \"kdet_only_touching\": " << st.missed_rounding << ", \"kdet_only_robust\": "
         << st.missed_wrong << ", \"settled_against_kdet\": " << st.kdet_wrong << ", \"peer_duplicates\": "
         << st.duplicates << "}";
      first = false;
    }
    js << "},\n     \"frames\": [";
    for (std::size_t f = 0; f < s.frames.size(); ++f) {
      js << (f ? "," : "") << "\n       {\"frame\": " << f << ", \"triangles\": " << s.triangles(f) << ", \"methods\": {";
      bool fm = true;
      for (const char* id : kMethodOrder) {
        const MethodResult* m = find(r, id);
        if (!m) continue;
        js << (fm ? "" : ", ") << jstr(id) << ": ";
        fm = false;
        if (m->status.rfind("ok", 0) != 0) {
          js << "null";
          continue;
        }
        const FrameRecord& x = m->frames[f];
        js << "{\"update_ms\": " << jnum(x.update_ms) << ", \"self_ms\": " << jnum(x.self_ms) << ", \"inter_ms\": "
           << jnum(x.inter_ms) << ", \"total_ms\": " << jnum(x.update_ms + x.self_ms + x.inter_ms)
           << ", \"self_pairs\": " << x.self_pairs << ", \"inter_pairs\": " << x.inter_pairs;
        if (isKdet(id))
          js << ", \"height\": " << x.height << ", \"box_tests\": " << x.box_tests << ", \"triangle_tests\": "
             << x.triangle_tests;
        js << "}";
      }
      js << "}}";
    }
    js << "]}" << (si + 1 < res.size() ? "," : "") << "\n";
  }
  js << "  ]\n}\n";
}

const char* kPlotMethods[] = {"kdet_cpu_1t", "kdet_cpu_2t", "kdet_gpu", "fcl_obbrss", "fcl_obb", "fcl_aabb", "gpu_bvh"};

/// The plotted series: every method's comparable time (kDet: update + the queries FCL answers;
/// peers: update + query), plus kDet 2T with all its queries (self-collision included).
struct Series {
  std::string id, title;
  bool all_queries;
};

std::vector<Series> plotSeries(const std::vector<const SceneResult*>& rows) {
  std::vector<Series> out;
  for (const char* id : kPlotMethods) {
    bool any = false;
    for (const SceneResult* r : rows) any = any || ok(find(*r, id));
    if (!any) continue;  // e.g. GPU methods before they are built: no all-NaN column to plot
    out.push_back({id, methodTitle(id) + (isKdet(id) ? " (same queries as FCL)" : ""), false});
  }
  for (const SceneResult* r : rows)
    if (ok(find(*r, "kdet_cpu_2t"))) {
      out.push_back({"kdet_cpu_2t", "kDet CPU 2T, with self-collision", true});
      break;
    }
  return out;
}

double seriesValue(const SceneResult& r, const Series& se, std::size_t frame, bool per_frame) {
  const MethodResult* m = find(r, se.id);
  if (!ok(m)) return NAN;
  if (per_frame) {
    const FrameRecord& x = m->frames[frame];
    if (!isKdet(se.id) || se.all_queries) return x.update_ms + x.self_ms + x.inter_ms;
    return x.update_ms + (r.scene->inter.empty() ? x.self_ms : x.inter_ms);
  }
  const Summary su = summarize(*r.scene, *m, isKdet(se.id));
  return se.all_queries ? su.total : su.comparable;
}

void writeGp(const std::string& path, const std::string& png, const std::string& title, const std::string& xlabel,
             const std::string& dat, int xcol, int first_col, const std::vector<Series>& series, bool logx) {
  std::ofstream g(path);
  g << "set terminal pngcairo size 1000,600 noenhanced\nset output '" << png << "'\n"
    << "set title '" << title << "'\nset xlabel '" << xlabel << "'\nset ylabel 'ms per frame'\n"
    << (logx ? "set logscale xy\n" : "set logscale y\nset xtics 1\n") << "set key outside right\nset grid\nplot ";
  for (std::size_t i = 0; i < series.size(); ++i)
    g << (i ? ", " : "") << "'" << dat << "' using " << xcol << ":" << first_col + int(i) << " with linespoints lw 2"
      << (series[i].all_queries ? " dt 2" : "") << " title '" << series[i].title << "'";
  g << "\n";
}

/// Figure 9 left: time per frame against triangle count (cloth sweep); Figure 9 right: time per
/// frame over one animation (the largest cloth, the fracture). Data files plus gnuplot scripts.
void writePlots(const std::vector<SceneResult>& res, const Options& o) {
  const std::string dir = o.out;
  std::vector<std::string> scripts;
  std::vector<const SceneResult*> cloth;
  for (const auto& r : res)
    if (r.scene->group == "cloth") cloth.push_back(&r);
  if (!cloth.empty()) {
    const auto series = plotSeries(cloth);
    std::ofstream d(dir + "/fig9_left.dat");
    d << "# triangles";
    for (const auto& se : series) d << " " << se.id << (se.all_queries ? "_all" : "");
    d << "   (ms per frame, mean over the frames after the build)\n";
    for (const SceneResult* r : cloth) {
      std::size_t tris = 0;
      for (std::size_t f : steadyFrames(*r->scene)) tris += r->scene->triangles(f);
      d << tris / steadyFrames(*r->scene).size();
      for (const auto& se : series) d << " " << seriesValue(*r, se, 0, false);
      d << "\n";
    }
    writeGp(dir + "/fig9_left.gp", "fig9_left.png",
            "Cloth over sphere: update + queries per frame (kDet solid: the queries FCL answers)", "triangles",
            "fig9_left.dat", 1, 2, series, true);
    scripts.push_back("fig9_left.gp");
  }
  for (const std::string grp : {"cloth", "fracture"}) {
    const SceneResult* best = nullptr;
    for (const auto& r : res)
      if (r.scene->group == grp && (!best || r.scene->triangles(0) > best->scene->triangles(0))) best = &r;
    if (!best) continue;
    const auto series = plotSeries({best});
    const std::string base = "fig9_right_" + grp;
    std::ofstream d(dir + "/" + base + ".dat");
    d << "# frame triangles";
    for (const auto& se : series) d << " " << se.id << (se.all_queries ? "_all" : "");
    d << "   (" << best->scene->name << ", ms)\n";
    for (std::size_t f = 0; f < best->scene->frames.size(); ++f) {
      d << f << " " << best->scene->triangles(f);
      for (const auto& se : series) d << " " << seriesValue(*best, se, f, true);
      d << "\n";
    }
    writeGp(dir + "/" + base + ".gp", base + ".png", best->scene->label + ": time per frame (frame 0 = build)",
            "frame", base + ".dat", 1, 3, series, false);
    scripts.push_back(base + ".gp");
  }
  if (!o.plots) return;
  for (const auto& gp : scripts) {
    const std::string cmd = "cd '" + dir + "' && gnuplot " + gp + " 2>&1";
    if (std::system(cmd.c_str()) != 0) std::fprintf(stderr, "kdet_bench: gnuplot failed on %s\n", gp.c_str());
  }
}

int exportScenes(const Options& o) {
  ::mkdir(o.export_dir.c_str(), 0755);
  kb::SceneConfig cfg;
  cfg.quick = o.quick;
  cfg.frames = 3;
  cfg.data_dir = "";  // the shared data is analysed from its own files
  cfg.huge_ratio_tiny = o.quick ? 5000 : 200000;
  std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, o.only);
  int n = 0;
  for (const auto& s : scenes) {
    // Each object on its own (first and last frame), and the whole frame merged.
    for (std::size_t f : {std::size_t(0), s.frames.size() - 1}) {
      for (std::size_t ob = 0; ob < s.objects.size(); ++ob) {
        if (f > 0 && s.frames[f].meshes[ob] == s.frames[0].meshes[ob]) continue;
        const std::string p = o.export_dir + "/" + s.name + "_f" + std::to_string(f) + "_" + s.objects[ob] + ".ply";
        kdet_fcl::writeMesh(*s.frames[f].meshes[ob], p);
        ++n;
      }
      if (s.objects.size() > 1) {
        const std::string p = o.export_dir + "/" + s.name + "_f" + std::to_string(f) + "_scene.ply";
        kdet_fcl::writeMesh(kb::mergedWorld(s, f), p);
        ++n;
      }
      if (s.frames.size() == 1) break;
    }
  }
  // A resolution sweep of plain spheres and cloths (the k-free study's bins need small meshes too).
  for (int seg : {8, 16, 32, 64, 128, 256}) {
    kdet_fcl::writeMesh(kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, seg, seg / 2),
                        o.export_dir + "/sphere_" + std::to_string(seg) + ".ply");
    kdet_fcl::writeMesh(kdet_fcl::makeDrapedCloth<double>(seg, 3.0, 1.0, 0.02, 1.0),
                        o.export_dir + "/cloth_" + std::to_string(seg) + ".ply");
    n += 2;
  }
  for (std::size_t c : {100, 1000, 10000, 100000})
    kdet_fcl::writeMesh(kdet_fcl::makeRandomSoup<double>(c, 1.0, 0.01, 0.05, 3),
                        o.export_dir + "/soup_" + std::to_string(c) + ".ply"), ++n;
  std::fprintf(stderr, "kdet_bench: wrote %d meshes to %s\n", n, o.export_dir.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  g_fresh_results = o.fresh_results;
  g_inject_unsteady = o.inject_unsteady;
  if (!o.inject_unsteady.empty() &&
      std::find(std::begin(kMethodOrder), std::end(kMethodOrder), o.inject_unsteady) == std::end(kMethodOrder)) {
    std::fprintf(stderr, "kdet_bench: --inject-unsteady: no method %s\n", o.inject_unsteady.c_str());
    return 2;
  }
  try {
    if (!o.export_dir.empty()) return exportScenes(o);
#if KDET_BENCH_GPU_BVH
    // The GPU BVH on kDet's GPU (KDET_FCL_CUDA_DEVICE, else 0): both GPU methods share one.
    if (kdet_fcl::cudaDeviceCount() > 0) kdet_bvh::useDevice(kdet_fcl::cudaDevice());
#endif
    const std::string load_before = loadAvg();
    kb::SceneConfig cfg;
    cfg.quick = o.quick;
    cfg.include_1m = o.include_1m;
    cfg.huge_ratio_tiny = o.tiny;
    cfg.frames = o.frames;
    cfg.rigid_poses = o.rigid_poses;
    // The UNC and FCL meshes: $KDET_FCL_DATA_DIR (as gpu_bench; e.g. an offline GPU machine's
    // copy of the files), else ../shared/data beside the source tree.
    const char* data_env = std::getenv("KDET_FCL_DATA_DIR");
    cfg.data_dir = data_env != nullptr && *data_env != '\0' ? data_env : KDET_BENCH_SHARED_DATA;
    const std::vector<kb::Scene> scenes = kb::makeAllScenes(cfg, o.only);
    if (scenes.empty()) {
      std::fprintf(stderr, "kdet_bench: no scene selected\n");
      return 2;
    }
    ::mkdir(o.out.c_str(), 0755);
    std::vector<SceneResult> res;
    std::size_t kdet_wrong = 0, unsteady = 0;
    for (const auto& s : scenes) {
      res.push_back(runScene(s, o));
      for (const auto& [id, st] : res.back().agreement) kdet_wrong += st.kdet_wrong;
      for (const auto& m : res.back().methods) unsteady += m.unsteady_runs > 0;
      // Write after each scene so a long run leaves usable partial results.
      const std::string load_now = loadAvg();
      writeMarkdown(res, o, o.out + "/bench.md", load_before, load_now);
      writeJson(res, o, o.out + "/bench.json", load_before, load_now);
    }
    const std::string load_after = loadAvg();
    writeMarkdown(res, o, o.out + "/bench.md", load_before, load_after);
    writeJson(res, o, o.out + "/bench.json", load_before, load_after);
    writePlots(res, o);
    std::fprintf(stderr, "kdet_bench: wrote %s/bench.md, %s/bench.json and the plots\n", o.out.c_str(), o.out.c_str());
    // Summary line per scene on stdout.
    for (const auto& r : res) {
      const Summary k1 = summarize(*r.scene, *find(r, "kdet_cpu_1t"), true);
      const Summary k2 = ok(find(r, "kdet_cpu_2t")) ? summarize(*r.scene, *find(r, "kdet_cpu_2t"), true) : k1;
      const Summary fo = ok(find(r, "fcl_obbrss")) ? summarize(*r.scene, *find(r, "fcl_obbrss"), false) : Summary{};
      std::printf("%-22s tris %8zu  kDet1T %9.3f ms  kDet2T %9.3f ms (comparable %9.3f)  FCL-OBBRSS %9.3f ms  "
                  "speedup %6.1fx  agree: %s\n",
                  r.scene->name.c_str(), r.scene->triangles(0), k1.total, k2.total, k2.comparable, fo.total,
                  fo.total / k2.comparable, agreeCell(r).c_str());
    }
    if (unsteady)
      std::fprintf(stderr, "kdet_bench: *** UNSTEADY: %zu method(s) and scene(s) whose pair counts changed "
                   "from run to run ***\n", unsteady);
    if (kdet_wrong)
      std::fprintf(stderr, "kdet_bench: *** DISAGREEMENT settled against kDet on %zu pairs ***\n", kdet_wrong);
    if (kdet_wrong || unsteady) return 1;
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kdet_bench: error: %s\n", e.what());
    return 1;
  }
}
