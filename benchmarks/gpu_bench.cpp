// GPU benchmark (issues 4 and 5): kDet's CUDA backend against the suite's GPU BVH baseline
// (gpu_bvh.cu), the CPU backend and FCL 0.7, per frame, in one run.
//
//   gpu_bench [--data DIR] [--repeats N] [--only SUBSTR]... [--no-fcl] [--no-cpu] [--quick]
//             [--big] [--joint deforming|all|none] [--fresh-results] [--csv FILE]
//             [--json FILE] [--md FILE]
//
// DIR holds unc/{cloth-ball,cloth-funnel,n-body-simulation} (default: $KDET_FCL_DATA_DIR, else
// ../shared/data beside the source tree); scenes whose files are missing are skipped.
//
// Scenes (float meshes, identity poses; every object that moves is a DEFORMING object):
//   - UNC frames: frame A alone (self), frames A and B as two deforming objects (inter + both
//     selfs), for the cloth ball (92/93), the funnel (227/228) and the n-body (18/19);
//   - cloth over a sphere at 20k, 40k, 90k, 200k, 250k and 1M cloth triangles: 4 frames of
//     makeDrapedCloth(n, 3, 1, 0.02, t), t = 0.3 .. 1 (the CPU suite's clothScene); the cloth
//     deforms, the sphere is static; inter + both selfs (the static sphere's self query is
//     answered from its kept result from the third frame on, by kDet GPU, the LBVH and kDet
//     CPU alike; KDET_FCL_CUDA_SELF_CACHE=0 and KDET_FCL_CPU_SELF_CACHE=0 recompute it every
//     frame). --big adds a 10M-triangle cloth (2 frames; kDet GPU and LBVH only: the CPU and
//     FCL would take minutes per frame).
// Joint form (--joint, default `deforming`): in a scene of two DEFORMING objects that asks for
// both selfs and their inter pairs (the UNC two-frame scenes), kDet GPU calls intersectAll (one
// hash of both meshes, one self query; cuda/cuda_backend.h) and the LBVH gets the same form: one
// tree over both meshes (kdet_bvh::jointMesh, its joint vertices prepared per frame outside the
// timing), one self query with the split, its pairs dealt out after the timing (splitJoint).
// `all` uses the joint form on every scene of two objects with both selfs and their inter pairs
// (the cloth over a static sphere too, whose kept self result it then gives up); `none` runs the
// three queries everywhere, for both GPU methods (the runs before 2026-11-23). The CPU methods
// and FCL are unchanged. The CSV's `form` column says which form a row ran.
// The CSV's `kdet_counted_share` column: of kDet GPU's profiled queries of the scene (kept self
// results left out), the share whose pairs were put in order by counting (1) rather than by the
// radix sort (0): QueryProfile::pairs_counted, KDET_FCL_CUDA_COUNT_ORDER.
// Results kept from frame to frame (default): each GPU method writes a frame's pairs into the
// results of the frame before, as a simulation does (kDet: intersectSelf/intersectMeshes/
// intersectAll into a result; the LBVH: its `keep` argument), so both read their pairs back into
// storage that is there already, by several host threads where that pays
// (kdet_fcl::staging::downloadInto). --fresh-results: the by-value calls, a new result per query
// (the runs before 2026-11-24). The CPU methods and FCL are unchanged.
// Device memory: cuda::deviceBytesInUse() after kDet GPU's first frame of a scene (one frame's
// meshes resident, plus the backend's scratch), divided by the scene's triangles ("B/tri").
// Per frame, each method does what a new frame costs it:
//   - kDet GPU: markDeformed on the deforming meshes, then the queries (vertex upload, device
//     re-hash, search, exact tests, sort, copy into the kept result's std::vector);
//   - LBVH GPU: vertex upload + refit of the deforming meshes' trees (tree built once, at frame
//     0), traversal, exact tests, sort, copy; also measured with a full rebuild per frame;
//   - kDet CPU (2 and 16 threads): HashedMesh::updateVertices (re-hash) + the queries;
//   - FCL OBBRSS: beginUpdateModel/updateSubModel/endUpdateModel(refit) + exhaustive collide of
//     the object pairs. FCL has no self-collision: scenes with object pairs time FCL's inter
//     queries only (kDet does more work there), scenes with none time FCL's mesh-against-itself
//     query (marked "self-pair").
// GPU times: CUDA events (medians over repeats after a warm-up round); wall: host clock.
// Correctness: in an untimed pass over every frame, the pair sets of kDet GPU, LBVH, kDet CPU 2
// and 16 threads must be equal (exact test everywhere): otherwise DISAGREEMENT and exit 1. FCL's
// pairs come from its own inexact triangle test: their difference is reported, not required.

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "bench_util.h"
#include "cuda/cuda_backend.h"
#include "gpu_bvh.cuh"
#include "kdet_fcl/kdet_fcl.h"

using namespace kdet_fcl;
using Pairs = std::vector<TrianglePair>;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}
double nowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct Obj {
  std::string name;
  std::vector<TriangleMesh<float>> frames;  // one per frame (a static object has one)
  bool deforming = false;
};

struct BScene {
  std::string id, label;
  std::vector<Obj> objs;
  std::vector<int> self;
  std::vector<std::pair<int, int>> inter;
  bool big_target = false;  // a deforming scene of >= 90k triangles (issue 5's GPU targets)
  bool huge = false;        // --big: GPU methods only
  int frames() const {
    int f = 1;
    for (const Obj& o : objs) f = std::max(f, int(o.frames.size()));
    return f;
  }
  const TriangleMesh<float>& mesh(int o, int f) const {
    const auto& fr = objs[o].frames;
    return fr[std::min<std::size_t>(f, fr.size() - 1)];
  }
  std::size_t triangles() const {
    std::size_t n = 0;
    for (std::size_t o = 0; o < objs.size(); ++o) n += mesh(int(o), 0).numTriangles();
    return n;
  }
};

struct Row {
  std::string id, label;
  std::size_t triangles = 0;
  int frames = 0;
  double pairs = 0;  // mean pairs per frame
  double kdet_ms = 0, kdet_wall = 0, kdet_build = 0, kdet_query = 0, kdet_cand_ms = 0,
         kdet_out = 0, kdet_cands = 0;
  // kDet GPU per frame with the pairs left on the device (intersect*OnDevice)
  double kdet_device_ms = std::nan("");
  // Share of kDet's profiled GPU queries whose pairs were put in order by counting, not by the
  // radix sort (QueryProfile::pairs_counted; kept self results, which run no query, left out)
  double kdet_counted = std::nan("");
  double bvh_ms = 0, bvh_wall = 0, bvh_rebuild_ms = 0, bvh_upload = 0, bvh_refit = 0,
         bvh_traverse = 0, bvh_exact = 0, bvh_out = 0, bvh_cands = 0;
  double cpu2_ms = std::nan(""), cpu16_ms = std::nan("");
  double bytes_per_tri = std::nan("");  // kDet GPU device memory per triangle (one frame)
  double fcl_ms = std::nan(""), fcl_refit = std::nan("");
  std::string fcl_kind = "skipped";
  double fcl_pairs = 0, fcl_diff = 0;
  bool agree = true, big_target = false;
  std::string disagreement;
  std::string form = "separate";  // the GPU methods' form: "joint" or "separate" (--joint)
};

QueryOptions opts(Backend b, int threads = 0) {
  QueryOptions o;
  o.backend = b;
  o.threads = threads;
  return o;
}

Pairs sortedPairs(Pairs p) {
  std::sort(p.begin(), p.end());
  return p;
}

std::size_t symDiff(const Pairs& a, const Pairs& b) {
  std::size_t i = 0, j = 0, d = 0;
  while (i < a.size() || j < b.size()) {
    if (j == b.size() || (i < a.size() && a[i] < b[j])) ++i, ++d;
    else if (i == a.size() || b[j] < a[i]) ++j, ++d;
    else ++i, ++j;
  }
  return d;
}

// ---- FCL ----
using FclModel = fcl::BVHModel<fcl::OBBRSSd>;
std::vector<fcl::Vector3d> fclPoints(const TriangleMesh<float>& m) {
  std::vector<fcl::Vector3d> v;
  v.reserve(m.vertices.size());
  for (const auto& p : m.vertices) v.emplace_back(double(p.x), double(p.y), double(p.z));
  return v;
}
std::shared_ptr<FclModel> fclBuild(const TriangleMesh<float>& m) {
  auto model = std::make_shared<FclModel>();
  std::vector<fcl::Triangle> t;
  t.reserve(m.triangles.size());
  for (const auto& tr : m.triangles) t.emplace_back(tr[0], tr[1], tr[2]);
  model->beginModel(int(t.size()), int(m.vertices.size()));
  model->addSubModel(fclPoints(m), t);
  model->endModel();
  return model;
}
Pairs fclCollide(const FclModel& a, const FclModel& b, bool collect) {
  fcl::CollisionRequestd req(std::numeric_limits<int>::max(), false);
  fcl::CollisionResultd res;
  const fcl::Transform3d I = fcl::Transform3d::Identity();
  fcl::collide(&a, I, &b, I, req, res);
  Pairs out;
  if (!collect) {
    out.resize(res.numContacts());
    return out;
  }
  std::vector<fcl::Contactd> cs;
  res.getContacts(cs);
  for (const auto& c : cs) out.push_back({std::uint32_t(c.b1), std::uint32_t(c.b2)});
  return sortedPairs(out);
}
using kdet_bench_util::selfFromPair;

struct Config {
  int repeats = 10;
  bool fcl = true, cpu = true, quick = false, big = false;
  std::string joint = "deforming";  // --joint: deforming | all | none
  bool fresh = false;  // --fresh-results: the by-value queries (a new result every frame)
  std::vector<std::string> only;
};

Row runScene(const BScene& sc, const Config& cfg) {
  Row r;
  r.id = sc.id;
  r.label = sc.label;
  r.triangles = sc.triangles();
  r.frames = sc.frames();
  r.big_target = sc.big_target;
  const int F = sc.frames();
  const int nobj = int(sc.objs.size());
  const int rounds = std::max(cfg.repeats, (30 + F - 1) / F);
  const bool large = r.triangles > 300000;
  const bool do_cpu = cfg.cpu && !sc.huge, do_fcl = cfg.fcl && !sc.huge;
  // Both GPU methods run a scene of two objects with both selfs and their inter pairs as one
  // query (the joint form, see the file comment) when --joint allows it.
  const bool pair_scene = nobj == 2 && sc.self == std::vector<int>{0, 1} &&
                          sc.inter == std::vector<std::pair<int, int>>{{0, 1}};
  const bool joint = pair_scene && (cfg.joint == "all" ||
                                    (cfg.joint == "deforming" && sc.objs[0].deforming &&
                                     sc.objs[1].deforming));
  r.form = joint ? "joint" : "separate";
  std::fprintf(stderr, "[%s] %zu triangles, %d frame(s): preparing\n", sc.id.c_str(), r.triangles, F);
  cuda::releaseDeviceMemory();

  // kDet GPU: one HashedMesh per (object, frame); markDeformed forces the device re-hash.
  std::vector<std::vector<std::unique_ptr<HashedMesh<float>>>> hm(nobj);
  for (int o = 0; o < nobj; ++o)
    for (const auto& m : sc.objs[o].frames)
      hm[o].push_back(std::make_unique<HashedMesh<float>>(m, Transform<float>::identity(), 16));
  auto H = [&](int o, int f) -> HashedMesh<float>& {
    return *hm[o][std::min<std::size_t>(f, hm[o].size() - 1)];
  };
  std::size_t queries_profiled = 0, queries_counted = 0;  // (Row::kdet_counted)
  // The results kept from frame to frame (cfg.fresh: unused), one per query of a frame, in the
  // order the frame runs them; kDet's and the LBVH's alike.
  std::vector<QueryResult> kept_q(sc.self.size() + sc.inter.size());
  AllPairsResult kept_all;
  std::vector<Pairs> bvh_kept(sc.self.size() + sc.inter.size() + 1);
  // on_dev: the queries leave their pairs in that device buffer (intersect*OnDevice; grown and
  // asked again when they do not fit); sets then gets them read back.
  auto kdetGpuFrame = [&](int f, std::vector<Pairs>* sets, cuda::QueryProfile* prof,
                          kdet_bvh::DevicePairBuffer* on_dev) {
    for (int o = 0; o < nobj; ++o)
      if (sc.objs[o].deforming) cuda::markDeformed(H(o, f));
    std::size_t n = 0;
    auto profiled = [&] {  // after each GPU call
      if (!prof) return;
      const cuda::QueryProfile p = cuda::lastQueryProfile();
      if (!p.self_cached) {
        ++queries_profiled;
        if (p.pairs_counted) ++queries_counted;
      }
      prof->build_ms += p.build_ms;
      prof->query_ms += p.query_ms;
      prof->candidates_ms += p.candidates_ms;
      prof->output_ms += p.output_ms;
      prof->total_ms += p.total_ms;
      prof->candidates += p.candidates;
      prof->rounds = std::max(prof->rounds, p.rounds);
      prof->candidate_key_bytes = std::max(prof->candidate_key_bytes, p.candidate_key_bytes);
    };
    auto take = [&](const QueryResult& q) {
      n += q.pairs.size();
      if (sets) sets->push_back(q.pairs);
    };
    // After a joint call: when the backend ran the three queries instead (e.g.
    // KDET_FCL_CUDA_JOINT=0), the profile is the last one's only; warns once (--joint none times
    // the three queries). `warned`: the call's own flag.
    auto warnIfNotJoint = [&](const char* call, bool& warned) {
      if (prof && !cuda::lastQueryProfile().joint && !warned) {
        std::fprintf(stderr,
                     "warning: %s did not run joint; device times cover only its last query "
                     "(use --joint none)\n",
                     call);
        warned = true;
      }
    };
    // query(buffer, capacity) into on_dev, grown and asked again when its `count(result)` pairs
    // did not fit.
    auto intoBuffer = [&](auto&& query, auto&& count) {
      auto d = query(on_dev->data(), on_dev->capacity());
      if (count(d) > on_dev->capacity()) {
        on_dev->reserve(count(d));
        d = query(on_dev->data(), on_dev->capacity());
      }
      profiled();
      return d;
    };
    if (on_dev != nullptr && joint) {
      const AllDevicePairsResult d = intoBuffer(
          [&](TrianglePair* p, std::size_t c) {
            return intersectAllOnDevice(H(0, f), H(1, f), p, c, opts(Backend::Cuda));
          },
          [](const AllDevicePairsResult& r) { return r.total(); });
      static bool device_warned = false;
      warnIfNotJoint("intersectAllOnDevice", device_warned);
      if (sets) {  // the three runs, as intersectAll's three results
        const Pairs p = on_dev->read(d.total());
        const auto ea = p.begin() + std::ptrdiff_t(d.self_a.count);
        const auto eb = ea + std::ptrdiff_t(d.self_b.count);
        sets->push_back(Pairs(p.begin(), ea));
        sets->push_back(Pairs(ea, eb));
        sets->push_back(Pairs(eb, p.end()));
      }
      return d.total();
    }
    if (on_dev != nullptr) {
      auto onDevice = [&](auto&& query) {  // query(buffer, capacity) -> DevicePairsResult
        const DevicePairsResult d =
            intoBuffer(query, [](const DevicePairsResult& r) { return r.count; });
        n += d.count;
        if (sets) sets->push_back(on_dev->read(d.count));
      };
      for (int o : sc.self)
        onDevice([&](TrianglePair* p, std::size_t c) {
          return intersectSelfOnDevice(H(o, f), p, c, opts(Backend::Cuda));
        });
      for (const auto& ab : sc.inter)
        onDevice([&](TrianglePair* p, std::size_t c) {
          return intersectMeshesOnDevice(H(ab.first, f), H(ab.second, f), p, c,
                                         opts(Backend::Cuda));
        });
      return n;
    }
    if (joint) {
      if (cfg.fresh) kept_all = intersectAll(H(0, f), H(1, f), opts(Backend::Cuda));
      else intersectAll(H(0, f), H(1, f), kept_all, opts(Backend::Cuda));
      profiled();
      static bool host_warned = false;
      warnIfNotJoint("intersectAll", host_warned);
      take(kept_all.self_a);
      take(kept_all.self_b);
      take(kept_all.inter);
      return n;
    }
    std::size_t q = 0;
    for (int o : sc.self) {
      QueryResult& k = kept_q[q++];
      if (cfg.fresh) k = intersectSelf(H(o, f), opts(Backend::Cuda));
      else intersectSelf(H(o, f), k, opts(Backend::Cuda));
      take(k);
      profiled();
    }
    for (auto [a, b] : sc.inter) {
      QueryResult& k = kept_q[q++];
      if (cfg.fresh) k = intersectMeshes(H(a, f), H(b, f), opts(Backend::Cuda));
      else intersectMeshes(H(a, f), H(b, f), k, opts(Backend::Cuda));
      take(k);
      profiled();
    }
    return n;
  };

  // LBVH GPU: one tree per object, built at frame 0, refit (or rebuilt) per frame; in the joint
  // form one tree over both objects (their joint meshes, one per frame, made here).
  // (joint_frames before bv: the trees, which may hold registrations of these arrays, go first.)
  std::vector<TriangleMesh<float>> joint_frames;
  std::vector<std::unique_ptr<kdet_bvh::GpuBvh<float>>> bv(joint ? 1 : nobj);
  const auto split = static_cast<std::uint32_t>(sc.mesh(0, 0).numTriangles());
  if (joint)
    for (int f = 0; f < F; ++f)
      joint_frames.push_back(kdet_bvh::jointMesh(sc.mesh(0, f), sc.mesh(1, f)));
  for (std::size_t o = 0; o < bv.size(); ++o) {
    bv[o] = std::make_unique<kdet_bvh::GpuBvh<float>>();
    bv[o]->setStableSources(true);  // the frames' meshes live through the scene
    bv[o]->setMesh(joint ? joint_frames[0] : sc.mesh(int(o), 0));
  }
  auto bvhFrame = [&](int f, bool rebuild, std::vector<Pairs>* sets) {
    if (joint) {
      const auto& v = joint_frames[f].vertices;
      if (rebuild) bv[0]->rebuildVertices(v);
      else bv[0]->updateVertices(v);
      Pairs& all = bvh_kept.back();
      all = kdet_bvh::intersectSelf(*bv[0], Predicate::Exact, split,
                                    cfg.fresh ? nullptr : &all);
      const std::size_t n = all.size();
      if (sets)
        for (Pairs& p : kdet_bvh::splitJoint(all, split)) sets->push_back(std::move(p));
      return n;
    }
    for (int o = 0; o < nobj; ++o)
      if (sc.objs[o].deforming) {
        if (rebuild) bv[o]->rebuildVertices(sc.mesh(o, f).vertices);
        else bv[o]->updateVertices(sc.mesh(o, f).vertices);
      }
    std::size_t n = 0, q = 0;
    auto take = [&](Pairs& p) {
      n += p.size();
      if (sets) sets->push_back(p);
    };
    const Transform<float> I = Transform<float>::identity();
    for (int o : sc.self) {
      Pairs& k = bvh_kept[q++];
      k = kdet_bvh::intersectSelf(*bv[o], Predicate::Exact, 0, cfg.fresh ? nullptr : &k);
      take(k);
    }
    for (auto [a, b] : sc.inter) {
      Pairs& k = bvh_kept[q++];
      k = kdet_bvh::intersect(*bv[a], I, *bv[b], I, Predicate::Exact, cfg.fresh ? nullptr : &k);
      take(k);
    }
    return n;
  };

  // kDet CPU with T threads: one HashedMesh per object, updateVertices per frame.
  auto makeCpu = [&](int threads) {
    std::vector<std::unique_ptr<HashedMesh<float>>> c(nobj);
    for (int o = 0; o < nobj; ++o)
      c[o] = std::make_unique<HashedMesh<float>>(sc.mesh(o, 0), Transform<float>::identity(),
                                                 threads);
    return c;
  };
  auto cpuFrame = [&](std::vector<std::unique_ptr<HashedMesh<float>>>& c, int threads, int f,
                      std::vector<Pairs>* sets) {
    for (int o = 0; o < nobj; ++o)
      if (sc.objs[o].deforming) c[o]->updateVertices(sc.mesh(o, f).vertices);
    std::size_t n = 0;
    auto take = [&](QueryResult q) {
      n += q.pairs.size();
      if (sets) sets->push_back(sortedPairs(std::move(q.pairs)));
    };
    for (int o : sc.self) take(intersectSelf(*c[o], opts(Backend::Cpu, threads)));
    for (auto [a, b] : sc.inter) take(intersectMeshes(*c[a], *c[b], opts(Backend::Cpu, threads)));
    return n;
  };

  // Device memory of one frame: the caches of frame 0's meshes plus the backend's scratch (and
  // the most rounds one of its queries took, cuda::QueryProfile::rounds, and the most bytes a
  // candidate took: a first frame has no forecast to pack its candidates by).
  cuda::setProfiling(true);
  cuda::QueryProfile first;
  kdetGpuFrame(0, nullptr, &first, nullptr);
  cuda::setProfiling(false);
  r.bytes_per_tri = double(cuda::deviceBytesInUse()) / double(r.triangles);
  std::fprintf(stderr,
               "[%s] device memory %.0f B/tri (first frame: rounds %d, %d-byte candidates): %s\n",
               sc.id.c_str(), r.bytes_per_tri, first.rounds, first.candidate_key_bytes,
               cuda::deviceMemoryReport().c_str());

  kdet_bvh::DevicePairBuffer dev_pairs;  // kDet's pairs left on the device

  // ---- correctness pass (untimed): every frame, every method ----
  std::vector<std::unique_ptr<HashedMesh<float>>> cpu2, cpu16;
  if (do_cpu) {
    cpu2 = makeCpu(2);
    cpu16 = makeCpu(16);
  }
  std::fprintf(stderr, "[%s] checking pair sets\n", sc.id.c_str());
  double total_pairs = 0;
  std::vector<std::vector<Pairs>> ref_sets(F);  // kDet GPU's, per frame (for FCL's diff)
  for (int f = 0; f < F; ++f) {
    std::vector<Pairs> g, l, c2, c16;
    kdetGpuFrame(f, &g, nullptr, nullptr);
    bvhFrame(f, false, &l);
    for (const Pairs& p : g) total_pairs += double(p.size());
    auto cmp = [&](const char* who, const std::vector<Pairs>& other) {
      for (std::size_t q = 0; q < g.size(); ++q)
        if (other[q] != g[q]) {
          r.agree = false;
          r.disagreement += std::string(who) + " query " + std::to_string(q) + " frame " +
                            std::to_string(f) + ": " + std::to_string(other[q].size()) +
                            " vs kDet GPU " + std::to_string(g[q].size()) + " pairs, " +
                            std::to_string(symDiff(other[q], g[q])) + " differ; ";
        }
    };
    cmp("LBVH", l);
    {  // the same queries with their pairs left on the device, read back here
      std::vector<Pairs> d;
      kdetGpuFrame(f, &d, nullptr, &dev_pairs);
      cmp("kDet GPU, pairs on the device,", d);
    }
    if (do_cpu) {
      cpuFrame(cpu2, 2, f, &c2);
      cpuFrame(cpu16, 16, f, &c16);
      cmp("CPU 2T", c2);
      cmp("CPU 16T", c16);
    }
    ref_sets[f] = std::move(g);
  }
  r.pairs = total_pairs / F;

  // ---- kDet GPU ----
  std::fprintf(stderr, "[%s] kDet GPU\n", sc.id.c_str());
  cuda::setProfiling(false);
  for (int f = 0; f < F; ++f) kdetGpuFrame(f, nullptr, nullptr, nullptr);  // warm-up
  std::vector<double> wall, dev, b1, q1, c1, o1, nc;
  for (int k = 0; k < rounds; ++k)
    for (int f = 0; f < F; ++f) {
      const double t0 = nowMs();
      kdetGpuFrame(f, nullptr, nullptr, nullptr);
      wall.push_back(nowMs() - t0);
    }
  cuda::setProfiling(true);
  for (int k = 0; k < rounds; ++k)
    for (int f = 0; f < F; ++f) {
      cuda::QueryProfile p;
      kdetGpuFrame(f, nullptr, &p, nullptr);
      dev.push_back(p.total_ms);
      b1.push_back(p.build_ms);
      q1.push_back(p.query_ms);
      c1.push_back(p.candidates_ms);
      o1.push_back(p.output_ms);
      nc.push_back(double(p.candidates));
    }
  // The same frames with the pairs left on the device (the buffer was sized by the check above).
  std::vector<double> on_dev;
  for (int k = 0; k < rounds; ++k)
    for (int f = 0; f < F; ++f) {
      cuda::QueryProfile p;
      kdetGpuFrame(f, nullptr, &p, &dev_pairs);
      on_dev.push_back(p.total_ms);
    }
  r.kdet_device_ms = median(on_dev);
  cuda::setProfiling(false);
  r.kdet_wall = median(wall);
  r.kdet_ms = median(dev);
  r.kdet_build = median(b1);
  r.kdet_query = median(q1);
  r.kdet_cand_ms = median(c1);
  r.kdet_out = median(o1);
  r.kdet_cands = median(nc);
  if (queries_profiled > 0) r.kdet_counted = double(queries_counted) / double(queries_profiled);
  hm.clear();
  cuda::releaseDeviceMemory();

  // ---- LBVH GPU ----
  std::fprintf(stderr, "[%s] LBVH GPU\n", sc.id.c_str());
  kdet_bvh::setTiming(false);
  for (int f = 0; f < F; ++f) bvhFrame(f, false, nullptr);
  wall.clear();
  for (int k = 0; k < rounds; ++k)
    for (int f = 0; f < F; ++f) {
      const double t0 = nowMs();
      bvhFrame(f, false, nullptr);
      wall.push_back(nowMs() - t0);
    }
  r.bvh_wall = median(wall);
  kdet_bvh::setTiming(true);
  std::vector<double> d2, up, rf, tr, ex, ou, cands, reb;
  for (int k = 0; k < rounds; ++k)
    for (int f = 0; f < F; ++f) {
      kdet_bvh::resetTimes();
      bvhFrame(f, false, nullptr);
      const kdet_bvh::BvhTimes t = kdet_bvh::times();
      d2.push_back(t.total_ms);
      up.push_back(t.upload_ms);
      rf.push_back(t.refit_ms);
      tr.push_back(t.traverse_ms);
      ex.push_back(t.exact_ms);
      ou.push_back(t.output_ms);
      cands.push_back(double(t.candidates));
    }
  for (int k = 0; k < rounds; ++k)
    for (int f = 0; f < F; ++f) {
      kdet_bvh::resetTimes();
      bvhFrame(f, true, nullptr);
      reb.push_back(kdet_bvh::times().total_ms);
    }
  kdet_bvh::setTiming(false);
  r.bvh_ms = median(d2);
  r.bvh_upload = median(up);
  r.bvh_refit = median(rf);
  r.bvh_traverse = median(tr);
  r.bvh_exact = median(ex);
  r.bvh_out = median(ou);
  r.bvh_cands = median(cands);
  r.bvh_rebuild_ms = median(reb);
  bv.clear();

  // ---- kDet CPU ----
  if (do_cpu) {
    const int cpu_rounds = large ? 1 : 3;
    for (int threads : {2, 16}) {
      std::fprintf(stderr, "[%s] kDet CPU %d threads\n", sc.id.c_str(), threads);
      auto& c = threads == 2 ? cpu2 : cpu16;
      std::vector<double> t;
      for (int k = 0; k < cpu_rounds; ++k)
        for (int f = 0; f < F; ++f) {
          const double t0 = nowMs();
          cpuFrame(c, threads, f, nullptr);
          t.push_back(nowMs() - t0);
        }
      (threads == 2 ? r.cpu2_ms : r.cpu16_ms) = median(t);
    }
  }

  // ---- FCL OBBRSS ----
  const bool self_pair = sc.inter.empty();
  if (do_fcl && !(self_pair && large)) {
    std::fprintf(stderr, "[%s] FCL OBBRSS (%s)\n", sc.id.c_str(), self_pair ? "self-pair" : "inter");
    r.fcl_kind = self_pair ? "self-pair" : "inter";
    std::vector<std::shared_ptr<FclModel>> fm(nobj);
    for (int o = 0; o < nobj; ++o) fm[o] = fclBuild(sc.mesh(o, 0));
    std::vector<std::vector<std::vector<fcl::Vector3d>>> pts(nobj);
    for (int o = 0; o < nobj; ++o)
      for (const auto& m : sc.objs[o].frames) pts[o].push_back(fclPoints(m));
    const int fcl_rounds = large ? 1 : 3;
    std::vector<double> tot, refit;
    double diff = 0, fpairs = 0;
    for (int k = 0; k < fcl_rounds; ++k)
      for (int f = 0; f < F; ++f) {
        const bool collect = k == 0;
        const double t0 = nowMs();
        for (int o = 0; o < nobj; ++o)
          if (sc.objs[o].deforming) {
            fm[o]->beginUpdateModel();
            fm[o]->updateSubModel(pts[o][std::min<std::size_t>(f, pts[o].size() - 1)]);
            fm[o]->endUpdateModel(true, true);
          }
        const double t1 = nowMs();
        std::vector<Pairs> got;
        if (self_pair)
          for (int o : sc.self) got.push_back(fclCollide(*fm[o], *fm[o], collect));
        else
          for (auto [a, b] : sc.inter) got.push_back(fclCollide(*fm[a], *fm[b], collect));
        const double t2 = nowMs();
        tot.push_back(t2 - t0);
        refit.push_back(t1 - t0);
        if (collect) {
          // Compare with kDet's sets for the same queries (self queries come first in ref_sets).
          for (std::size_t q = 0; q < got.size(); ++q) {
            const Pairs mine = self_pair ? selfFromPair(sc.mesh(sc.self[q], f), got[q]) : got[q];
            const Pairs& ref = ref_sets[f][self_pair ? q : sc.self.size() + q];
            fpairs += double(mine.size());
            diff += double(symDiff(mine, ref));
          }
        }
      }
    r.fcl_ms = median(tot);
    r.fcl_refit = median(refit);
    r.fcl_pairs = fpairs / F;
    r.fcl_diff = diff / F;
  }
  return r;
}

// ---- scenes ----

TriangleMesh<float> sphereFor(int n) {
  const int seg = std::max(16, std::min(512, n / 2));
  return makeSphere<float>({0, 0, 0}, 1.f, seg, std::max(8, seg / 2));
}

std::vector<BScene> makeScenes(const std::string& data, const Config& cfg) {
  std::vector<BScene> out;
  auto wanted = [&](const std::string& id) {
    if (cfg.only.empty()) return true;
    for (const auto& o : cfg.only)
      if (id.find(o) != std::string::npos) return true;
    return false;
  };
  struct Unc {
    const char* id;
    const char* label;
    const char* dir;
    const char* a;
    const char* b;
  };
  const Unc uncs[] = {
      {"cloth-ball", "Whirling cloth (UNC)", "cloth-ball", "cloth_ball92.ply", "cloth_ball93.ply"},
      {"funnel", "Funnel (UNC)", "cloth-funnel", "227.ply", "228.ply"},
      {"n-body", "N-body (UNC)", "n-body-simulation", "balls16_18.ply", "balls16_19.ply"}};
  if (!cfg.quick)
    for (const Unc& u : uncs) {
      const std::string fa = data + "/unc/" + u.dir + "/" + u.a;
      const std::string fb = data + "/unc/" + u.dir + "/" + u.b;
      if (!std::filesystem::exists(fa) || !std::filesystem::exists(fb)) {
        std::fprintf(stderr, "gpu_bench: %s or %s missing: %s skipped\n", fa.c_str(), fb.c_str(), u.id);
        continue;
      }
      const std::string id1 = std::string("unc-") + u.id + "-self";
      const std::string id2 = std::string("unc-") + u.id + "-2frames";
      if (!wanted(id1) && !wanted(id2)) continue;
      TriangleMesh<float> A = readMesh<float>(fa), B = readMesh<float>(fb);
      if (wanted(id1)) {
        BScene s;
        s.id = id1;
        s.label = std::string(u.label) + " " + u.a + ", self";
        s.objs.push_back({"A", {A}, true});
        s.self = {0};
        s.big_target = A.numTriangles() >= 90000;
        out.push_back(std::move(s));
      }
      if (wanted(id2)) {
        BScene s;
        s.id = id2;
        s.label = std::string(u.label) + " " + u.a + " + " + u.b + ", inter + 2 selfs";
        s.objs.push_back({"A", {A}, true});
        s.objs.push_back({"B", {B}, true});
        s.self = {0, 1};
        s.inter = {{0, 1}};
        s.big_target = A.numTriangles() + B.numTriangles() >= 90000;
        out.push_back(std::move(s));
      }
    }
  std::vector<std::pair<int, std::size_t>> sweep = {{100, 20000},  {141, 40000},  {212, 90000},
                                                    {316, 200000}, {354, 250000}, {707, 1000000}};
  if (cfg.quick) sweep = {{32, 2000}, {45, 4000}};
  if (cfg.big) sweep.push_back({2236, 10000000});
  for (auto [n, nominal] : sweep) {
    const bool huge = nominal > 1000000;
    const int F = cfg.quick || huge ? 2 : 4;
    const std::string id = "cloth-" + std::to_string(nominal / 1000) + "k";
    if (!wanted(id)) continue;
    BScene s;
    s.id = id;
    s.label = "Cloth on sphere " + std::to_string(nominal / 1000) + "k (" + std::to_string(F) +
              " frames)";
    Obj cloth{"cloth", {}, true};
    for (int f = 0; f < F; ++f) {
      const float t = F > 1 ? 0.3f + 0.7f * float(f) / float(F - 1) : 1.f;
      cloth.frames.push_back(makeDrapedCloth<float>(n, 3.f, 1.f, 0.02f, t));
    }
    s.objs.push_back(std::move(cloth));
    s.objs.push_back({"sphere", {sphereFor(n)}, false});
    s.self = {0, 1};
    s.inter = {{0, 1}};
    s.big_target = nominal >= 90000;
    s.huge = huge;
    out.push_back(std::move(s));
  }
  return out;
}

std::string fmt(double v, int prec = 3) {
  if (std::isnan(v)) return "n/a";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}
std::string ratio(double num, double den) {
  if (std::isnan(num) || std::isnan(den) || den <= 0) return "n/a";
  return fmt(num / den, num / den >= 100 ? 0 : (num / den >= 10 ? 1 : 2)) + "×";
}
std::string thousands(double v) {
  std::string s = std::to_string(static_cast<long long>(std::llround(v)));
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(std::size_t(i), ",");
  return s;
}

std::string markdown(const std::vector<Row>& rows, const std::string& device) {
  std::string md;
  md += "GPU: " + device + "\n\n";
  md += "| scene | triangles | kDet GPU ms | LBVH GPU ms | kDet vs LBVH | FCL OBBRSS ms | kDet vs FCL "
        "| kDet CPU 2T ms | kDet CPU 16T ms | pairs | agree | kDet GPU B/tri |\n";
  md += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|\n";
  for (const Row& r : rows) {
    const std::string fcl = r.fcl_kind == "skipped" ? "skipped"
                            : fmt(r.fcl_ms, 1) + (r.fcl_kind == "self-pair" ? " †" : "");
    md += "| " + r.label + (r.form == "joint" ? " (joint)" : "") + " | " +
          thousands(double(r.triangles)) + " | " + fmt(r.kdet_ms) +
          " | " + fmt(r.bvh_ms) + " | " + ratio(r.bvh_ms, r.kdet_ms) + " | " + fcl + " | " +
          (r.fcl_kind == "skipped" ? "n/a" : ratio(r.fcl_ms, r.kdet_ms)) + " | " +
          fmt(r.cpu2_ms, 2) + " | " + fmt(r.cpu16_ms, 2) + " | " + thousands(r.pairs) + " | " +
          (r.agree ? "yes" : "**NO**") + " | " + fmt(r.bytes_per_tri, 0) + " |\n";
  }
  md += "\n(joint): both GPU methods ran the scene's two meshes as one query (gpu_bench --joint).\n";
  md += "\nBreakdown (medians per frame, ms; device events):\n\n";
  md += "| scene | kDet build | kDet query (cand) | kDet out | kDet cands | kDet wall | LBVH upload | "
        "LBVH refit | LBVH traverse | LBVH exact | LBVH out | LBVH cands | LBVH wall | LBVH "
        "rebuild-per-frame total | FCL refit | FCL pairs (Δ vs kDet) |\n";
  md += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& r : rows)
    md += "| " + r.id + " | " + fmt(r.kdet_build) + " | " + fmt(r.kdet_query) + " (" +
          fmt(r.kdet_cand_ms) + ") | " + fmt(r.kdet_out) + " | " + thousands(r.kdet_cands) +
          " | " + fmt(r.kdet_wall) + " | " + fmt(r.bvh_upload) + " | " + fmt(r.bvh_refit) +
          " | " + fmt(r.bvh_traverse) + " | " + fmt(r.bvh_exact) + " | " + fmt(r.bvh_out) +
          " | " + thousands(r.bvh_cands) + " | " + fmt(r.bvh_wall) + " | " +
          fmt(r.bvh_rebuild_ms) + " | " + fmt(r.fcl_refit, 1) + " | " +
          (r.fcl_kind == "skipped" ? "n/a" : thousands(r.fcl_pairs) + " (" + thousands(r.fcl_diff) + ")") +
          " |\n";
  md += "\nIssue 5 GPU targets on deforming scenes of >= 90k triangles (kDet GPU >= 3× LBVH, >= 100× "
        "FCL per frame):\n\n| scene | vs LBVH | met | vs FCL | met |\n|---|---:|---|---:|---|\n";
  for (const Row& r : rows) {
    if (!r.big_target) continue;
    const double sl = r.bvh_ms / r.kdet_ms, sf = r.fcl_ms / r.kdet_ms;
    md += "| " + r.id + " | " + ratio(r.bvh_ms, r.kdet_ms) + " | " + (sl >= 3 ? "yes" : "no") +
          " | " + (r.fcl_kind == "skipped" ? "n/a" : ratio(r.fcl_ms, r.kdet_ms)) + " | " +
          (r.fcl_kind == "skipped" ? "n/a" : (sf >= 100 ? "yes" : "no")) + " |\n";
  }
  return md;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data, csv, json, mdfile;
  Config cfg;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc) data = argv[++i];
    else if (a == "--repeats" && i + 1 < argc)
      cfg.repeats = int(kdet_bench_util::parseIntArg("gpu_bench", "--repeats", argv[++i], 1, 1000000, 2));
    else if (a == "--only" && i + 1 < argc) cfg.only.push_back(argv[++i]);
    else if (a == "--no-fcl") cfg.fcl = false;
    else if (a == "--no-cpu") cfg.cpu = false;
    else if (a == "--quick") cfg.quick = true;
    else if (a == "--big") cfg.big = true;
    else if (a == "--fresh-results") cfg.fresh = true;
    else if (a == "--joint" && i + 1 < argc) {
      cfg.joint = argv[++i];
      if (cfg.joint != "deforming" && cfg.joint != "all" && cfg.joint != "none") {
        std::fprintf(stderr, "gpu_bench: --joint takes deforming, all or none, not '%s'\n",
                     cfg.joint.c_str());
        return 2;
      }
    }
    else if (a == "--csv" && i + 1 < argc) csv = argv[++i];
    else if (a == "--json" && i + 1 < argc) json = argv[++i];
    else if (a == "--md" && i + 1 < argc) mdfile = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: gpu_bench [--data DIR] [--repeats N] [--only SUBSTR]... [--no-fcl] "
                   "[--no-cpu] [--quick] [--big] [--joint deforming|all|none] "
                   "[--fresh-results] [--csv FILE] [--json FILE] [--md FILE]\n");
      return 2;
    }
  }
  if (data.empty() && std::getenv("KDET_FCL_DATA_DIR")) data = std::getenv("KDET_FCL_DATA_DIR");
#ifdef KDET_BENCH_SHARED_DATA
  if (data.empty()) data = KDET_BENCH_SHARED_DATA;
#endif
  if (cudaDeviceCount() == 0) {
    std::fprintf(stderr, "gpu_bench: no CUDA device\n");
    return 1;
  }
  // kDet's GPU (KDET_FCL_CUDA_DEVICE, else 0), and the LBVH on the same one.
  std::string device;
  try {
    device = kdet_bench_util::backendGpu();
    kdet_bvh::useDevice(kdet_fcl::cudaDevice());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gpu_bench: %s\n", e.what());
    return 1;
  }
  std::printf("device: %s\n", device.c_str());
  std::fflush(stdout);

  const std::vector<BScene> scenes = makeScenes(data, cfg);
  std::vector<Row> rows;
  bool ok = true;
  for (const BScene& sc : scenes) {
    Row r;
    try {
      r = runScene(sc, cfg);
    } catch (const std::exception& e) {
      std::printf("%s: ERROR %s\n", sc.id.c_str(), e.what());
      ok = false;
      continue;
    }
    std::printf(
        "%-22s tris=%9zu pairs=%10.0f kDet GPU %8.3f ms (wall %8.3f, pairs on device %8.3f) | "
        "LBVH %8.3f ms (wall %8.3f, rebuild %8.3f) | x%.2f | CPU2 %9.2f CPU16 %8.2f | "
        "FCL(%s) %9.1f | %.0f B/tri | %s | %s\n",
        r.id.c_str(), r.triangles, r.pairs, r.kdet_ms, r.kdet_wall, r.kdet_device_ms, r.bvh_ms,
        r.bvh_wall,
        r.bvh_rebuild_ms, r.bvh_ms / r.kdet_ms, r.cpu2_ms, r.cpu16_ms, r.fcl_kind.c_str(),
        r.fcl_ms, r.bytes_per_tri, r.form.c_str(), r.agree ? "agree" : "DISAGREEMENT");
    if (!r.agree) {
      std::printf("\n!!!!!!!! DISAGREEMENT in %s: %s\n\n", r.id.c_str(), r.disagreement.c_str());
      ok = false;
    }
    std::fflush(stdout);
    rows.push_back(r);
  }

  const std::string md = markdown(rows, device);
  std::printf("\n%s\n", md.c_str());
  if (!mdfile.empty()) std::ofstream(mdfile) << md;
  if (!csv.empty()) {
    std::ofstream out(csv);
    out << "scene,label,triangles,frames,pairs,kdet_gpu_ms,kdet_gpu_wall_ms,kdet_build_ms,"
           "kdet_query_ms,kdet_candidates_ms,kdet_output_ms,kdet_candidates,lbvh_ms,lbvh_wall_ms,"
           "lbvh_rebuild_ms,lbvh_upload_ms,lbvh_refit_ms,lbvh_traverse_ms,lbvh_exact_ms,"
           "lbvh_output_ms,lbvh_candidates,cpu2_ms,cpu16_ms,fcl_kind,fcl_ms,fcl_refit_ms,"
           "fcl_pairs,fcl_diff,agree,kdet_bytes_per_triangle,form,kdet_device_ms,"
           "kdet_counted_share\n";
    for (const Row& r : rows)
      out << r.id << ",\"" << r.label << "\"," << r.triangles << ',' << r.frames << ',' << r.pairs
          << ',' << r.kdet_ms << ',' << r.kdet_wall << ',' << r.kdet_build << ',' << r.kdet_query
          << ',' << r.kdet_cand_ms << ',' << r.kdet_out << ',' << r.kdet_cands << ','
          << r.bvh_ms << ',' << r.bvh_wall << ',' << r.bvh_rebuild_ms << ',' << r.bvh_upload
          << ',' << r.bvh_refit << ',' << r.bvh_traverse << ',' << r.bvh_exact << ','
          << r.bvh_out << ',' << r.bvh_cands << ',' << r.cpu2_ms << ',' << r.cpu16_ms << ','
          << r.fcl_kind << ',' << r.fcl_ms << ',' << r.fcl_refit << ',' << r.fcl_pairs << ','
          << r.fcl_diff << ',' << r.agree << ',' << r.bytes_per_tri << ',' << r.form << ','
          << r.kdet_device_ms << ',' << r.kdet_counted << '\n';
  }
  if (!json.empty()) {
    std::ofstream out(json);
    auto num = [](double v) { return std::isnan(v) ? std::string("null") : fmt(v, 6); };
    out << "{\n  \"device\": \"" << device << "\",\n  \"scenes\": [\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      out << "    {\"scene\": \"" << r.id << "\", \"label\": \"" << r.label
          << "\", \"triangles\": " << r.triangles << ", \"frames\": " << r.frames
          << ", \"pairs\": " << num(r.pairs) << ", \"kdet_gpu_ms\": " << num(r.kdet_ms)
          << ", \"kdet_gpu_wall_ms\": " << num(r.kdet_wall)
          << ", \"kdet_build_ms\": " << num(r.kdet_build)
          << ", \"kdet_query_ms\": " << num(r.kdet_query)
          << ", \"kdet_output_ms\": " << num(r.kdet_out)
          << ", \"kdet_device_ms\": " << num(r.kdet_device_ms)
          << ", \"kdet_counted_share\": " << num(r.kdet_counted) << ", \"lbvh_ms\": " << num(r.bvh_ms)
          << ", \"lbvh_wall_ms\": " << num(r.bvh_wall)
          << ", \"lbvh_rebuild_ms\": " << num(r.bvh_rebuild_ms)
          << ", \"lbvh_refit_ms\": " << num(r.bvh_refit)
          << ", \"lbvh_upload_ms\": " << num(r.bvh_upload)
          << ", \"lbvh_traverse_ms\": " << num(r.bvh_traverse)
          << ", \"lbvh_exact_ms\": " << num(r.bvh_exact)
          << ", \"lbvh_output_ms\": " << num(r.bvh_out) << ", \"cpu2_ms\": " << num(r.cpu2_ms)
          << ", \"cpu16_ms\": " << num(r.cpu16_ms) << ", \"fcl_kind\": \"" << r.fcl_kind
          << "\", \"fcl_ms\": " << num(r.fcl_ms) << ", \"fcl_pairs\": " << num(r.fcl_pairs)
          << ", \"fcl_diff\": " << num(r.fcl_diff)
          << ", \"kdet_bytes_per_triangle\": " << num(r.bytes_per_tri)
          << ", \"form\": \"" << r.form << "\""
          << ", \"agree\": " << (r.agree ? "true" : "false") << "}"
          << (i + 1 < rows.size() ? "," : "") << "\n";
    }
    out << "  ]\n}\n";
  }
  if (!ok) std::printf("gpu_bench: FAILED (DISAGREEMENT or error above)\n");
  return ok ? 0 : 1;
}
