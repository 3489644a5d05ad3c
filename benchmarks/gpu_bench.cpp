// GPU benchmark of the CUDA backend (issue 4): total time per query including the hash update.
//
//   gpu_bench [--data DIR] [--repeats N] [--big] [--csv FILE]
//
// DIR holds unc/cloth-ball/cloth_ball92.ply and 93 (default: $KDET_FCL_DATA_DIR, else
// ../shared/data beside the source tree). --big adds the 10M-triangle cloth.
//
// Each scene is "deforming": before every timed query the benchmark marks its meshes deformed
// (cuda::markDeformed), so the query re-uploads the vertices and re-hashes on the device, which is
// what a new frame costs on the GPU path (HashedMesh::updateVertices would also re-hash on the
// CPU; that CPU cost is not part of the GPU path and is left out). Reported per scene (medians
// over the repeats, after warm-up runs):
//   wall_ms    host wall clock around the API calls (upload, device work, read-backs, the copy
//              of the pairs into the std::vector)
//   device_ms  CUDA-event time from the first upload to the last copy, summed over the scene's
//              queries; build/query/output split it into re-hash, search+test and sort+copy
//   rigid_ms   the same queries without the re-hash (rigid motion: only the pose changes)
//   B/tri      device memory held by the backend after the scene / triangles in the scene
// Correctness is checked outside the timed region: the GPU pairs equal the CPU backend's.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "cuda/cuda_backend.h"
#include "kdet_fcl/kdet_fcl.h"

using namespace kdet_fcl;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

double nowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct Row {
  std::string scene;
  std::size_t triangles = 0, pairs = 0;
  double wall_ms = 0, device_ms = 0, build_ms = 0, query_ms = 0, cand_ms = 0, candidates = 0, output_ms = 0, rigid_ms = 0,
         cpu_ms = 0;
  double bytes_per_tri = 0;
  bool correct = false;
};

/// A scene: `deform` marks its meshes deformed; `run` issues its queries (returns pairs found).
struct Scene {
  std::string name;
  std::size_t triangles;
  std::function<void()> deform;
  std::function<std::size_t(Backend)> run;
  std::function<bool()> check;  // GPU == CPU, outside the timed region
};

Row measure(const Scene& sc, int repeats, bool time_cpu) {
  Row r;
  r.scene = sc.name;
  r.triangles = sc.triangles;
  cuda::releaseDeviceMemory();
  cuda::setProfiling(false);
  for (int w = 0; w < 3; ++w) {  // warm-up: allocations, module load, output capacity
    sc.deform();
    sc.run(Backend::Cuda);
  }
  std::vector<double> wall, rigid;
  for (int k = 0; k < repeats; ++k) {
    sc.deform();
    const double t0 = nowMs();
    r.pairs = sc.run(Backend::Cuda);
    const double t1 = nowMs();
    wall.push_back(t1 - t0);
  }
  // Rigid motion: no re-hash, the same queries.
  for (int k = 0; k < repeats; ++k) {
    const double t0 = nowMs();
    sc.run(Backend::Cuda);
    rigid.push_back(nowMs() - t0);
  }
  r.wall_ms = median(wall);
  r.rigid_ms = median(rigid);
  r.bytes_per_tri = double(cuda::deviceBytesInUse()) / double(sc.triangles);
  if (time_cpu) {
    std::vector<double> cpu;
    for (int k = 0; k < std::max(3, repeats / 10); ++k) {
      const double t0 = nowMs();
      sc.run(Backend::Cpu);
      cpu.push_back(nowMs() - t0);
    }
    r.cpu_ms = median(cpu);
  }
  r.correct = sc.check();
  return r;
}

/// Sums the profiles of the queries issued by f (profiling must be on).
struct ProfileSum {
  double device = 0, build = 0, query = 0, output = 0, cand = 0, ncand = 0;
  void add() {
    const cuda::QueryProfile p = cuda::lastQueryProfile();
    cand += p.candidates_ms;
    ncand += double(p.candidates);
    device += p.total_ms;
    build += p.build_ms;
    query += p.query_ms;
    output += p.output_ms;
  }
};

void deviceSplit(const Scene& sc, const std::function<void(ProfileSum&)>& queries, int repeats,
                 Row& r) {
  cuda::setProfiling(true);
  std::vector<double> dev, build, query, output, cand;
  for (int k = 0; k < repeats; ++k) {
    sc.deform();
    ProfileSum s;
    queries(s);
    cand.push_back(s.cand);
    r.candidates = s.ncand;
    dev.push_back(s.device);
    build.push_back(s.build);
    query.push_back(s.query);
    output.push_back(s.output);
  }
  cuda::setProfiling(false);
  r.device_ms = median(dev);
  r.build_ms = median(build);
  r.query_ms = median(query);
  r.output_ms = median(output);
  r.cand_ms = median(cand);
}

QueryOptions opts(Backend b) {
  QueryOptions o;
  o.backend = b;
  return o;
}

template <class S>
bool samePairs(const QueryResult& gpu, QueryResult cpu) {
  std::sort(cpu.pairs.begin(), cpu.pairs.end());
  return gpu.pairs == cpu.pairs;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data, csv;
  int repeats = 30;
  bool big = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc) data = argv[++i];
    else if (a == "--repeats" && i + 1 < argc) repeats = std::atoi(argv[++i]);
    else if (a == "--big") big = true;
    else if (a == "--csv" && i + 1 < argc) csv = argv[++i];
    else {
      std::fprintf(stderr, "usage: gpu_bench [--data DIR] [--repeats N] [--big] [--csv FILE]\n");
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
  std::printf("device: %s\n", cudaDeviceDescription(0).c_str());
  std::vector<Row> rows;

  auto report = [&](Row r) {
    std::printf(
        "%-34s tris=%9zu pairs=%9zu cands=%9.0f wall=%8.3f ms device=%8.3f (build %.3f query %.3f "
        "[cand %.3f] out %.3f) rigid=%8.3f cpu=%8.3f B/tri=%6.1f %s\n",
        r.scene.c_str(), r.triangles, r.pairs, r.candidates, r.wall_ms, r.device_ms, r.build_ms,
        r.query_ms, r.cand_ms, r.output_ms, r.rigid_ms, r.cpu_ms, r.bytes_per_tri, r.correct ? "OK" : "MISMATCH");
    std::fflush(stdout);
    rows.push_back(r);
  };

  // ---- UNC cloth ball ----
  const std::string f92 = data + "/unc/cloth-ball/cloth_ball92.ply";
  const std::string f93 = data + "/unc/cloth-ball/cloth_ball93.ply";
  if (std::filesystem::exists(f92) && std::filesystem::exists(f93)) {
    HashedMesh<float> a(readMesh<float>(f92)), b(readMesh<float>(f93));
    {
      Scene sc{"cloth-ball frame 92 (self)", a.numTriangles(),
               [&] { cuda::markDeformed(a); },
               [&](Backend be) { return intersectSelf(a, opts(be)).pairs.size(); },
               [&] {
                 return samePairs<float>(intersectSelf(a, opts(Backend::Cuda)),
                                         intersectSelf(a, opts(Backend::Cpu)));
               }};
      Row r = measure(sc, repeats, true);
      deviceSplit(sc, [&](ProfileSum& s) { intersectSelf(a, opts(Backend::Cuda)); s.add(); },
                  repeats, r);
      report(r);
    }
    {
      Scene sc{"cloth-ball 92+93 (inter + 2 selfs)", a.numTriangles() + b.numTriangles(),
               [&] {
                 cuda::markDeformed(a);
                 cuda::markDeformed(b);
               },
               [&](Backend be) {
                 return intersectMeshes(a, b, opts(be)).pairs.size() +
                        intersectSelf(a, opts(be)).pairs.size() +
                        intersectSelf(b, opts(be)).pairs.size();
               },
               [&] {
                 return samePairs<float>(intersectMeshes(a, b, opts(Backend::Cuda)),
                                         intersectMeshes(a, b, opts(Backend::Cpu))) &&
                        samePairs<float>(intersectSelf(b, opts(Backend::Cuda)),
                                         intersectSelf(b, opts(Backend::Cpu)));
               }};
      Row r = measure(sc, repeats, true);
      deviceSplit(sc,
                  [&](ProfileSum& s) {
                    intersectMeshes(a, b, opts(Backend::Cuda));
                    s.add();
                    intersectSelf(a, opts(Backend::Cuda));
                    s.add();
                    intersectSelf(b, opts(Backend::Cuda));
                    s.add();
                  },
                  repeats, r);
      report(r);
    }
  } else {
    std::printf("cloth-ball frames not found under %s: skipped\n", data.c_str());
  }

  // ---- procedural cloth over a sphere ----
  std::vector<int> sizes = {50, 100, 158, 224, 707};  // 5k, 20k, 50k, 100k, 1M triangles
  if (big) sizes.push_back(2236);                     // 10M
  for (int n : sizes) {
    HashedMesh<float> cloth(makeDrapedCloth<float>(n, 4.f, 1.f, 0.03f, 1.f));
    HashedMesh<float> sphere(makeSphere<float>({0, 0, 0}, 1.f, 256, 128));
    const bool huge = n > 1000;
    Scene sc{"cloth " + std::to_string(cloth.numTriangles()) + " + sphere 65k",
             cloth.numTriangles() + sphere.numTriangles(),
             [&] { cuda::markDeformed(cloth); },
             [&](Backend be) {
               return intersectMeshes(cloth, sphere, opts(be)).pairs.size() +
                      intersectSelf(cloth, opts(be)).pairs.size();
             },
             [&] {
               if (huge) return true;  // the CPU reference takes too long at 10M: not checked
               return samePairs<float>(intersectMeshes(cloth, sphere, opts(Backend::Cuda)),
                                       intersectMeshes(cloth, sphere, opts(Backend::Cpu))) &&
                      samePairs<float>(intersectSelf(cloth, opts(Backend::Cuda)),
                                       intersectSelf(cloth, opts(Backend::Cpu)));
             }};
    Row r = measure(sc, huge ? 5 : repeats, !huge);
    deviceSplit(sc,
                [&](ProfileSum& s) {
                  intersectMeshes(cloth, sphere, opts(Backend::Cuda));
                  s.add();
                  intersectSelf(cloth, opts(Backend::Cuda));
                  s.add();
                },
                huge ? 5 : repeats, r);
    if (huge) r.scene += " (not cross-checked)";
    report(r);
  }

  if (!csv.empty()) {
    std::ofstream out(csv);
    out << "scene,triangles,pairs,candidates,wall_ms,device_ms,build_ms,query_ms,candidates_ms,"
           "output_ms,rigid_ms,cpu_ms,"
           "bytes_per_triangle,correct\n";
    for (const Row& r : rows)
      out << '"' << r.scene << "\"," << r.triangles << ',' << r.pairs << ',' << r.candidates << ','
          << r.wall_ms << ',' << r.device_ms << ',' << r.build_ms << ',' << r.query_ms << ','
          << r.cand_ms << ',' << r.output_ms << ','
          << r.rigid_ms << ',' << r.cpu_ms << ',' << r.bytes_per_tri << ',' << r.correct << '\n';
  }
  bool ok = true;
  for (const Row& r : rows) ok = ok && r.correct;
  return ok ? 0 : 1;
}
