// update_bench: the host cost of a deforming frame's HashedMesh::updateVertices, next to its
// floor, to commitVertices and to the way it used to work, in the same process.
//
// For a draped cloth over a sphere (float, as the GPU benchmarks use) of about 92k, 250k and 1M
// triangles, alternating between two frames' vertex arrays, the median over --reps calls of:
//   updateVertices   the library call: one pass that checks every coordinate and gives the
//                    bounds, then a copy into the mesh's own buffer;
//   copy only        std::copy of the same array into a buffer of the same size (the floor of
//                    updateVertices: it cannot do less than read the input and write the mesh);
//   commitVertices   the same positions written into the mesh's vertexWriteBuffer() (untimed,
//                    as a simulation writes them), then the call: the check and bounds in place,
//                    the two buffers traded, no copy;
//   copy, check, move  what updateVertices did before 2026-11-23: a copy into a new vector, the
//                    check of that copy, the new vector moved into the mesh (the old buffer
//                    freed), then a second pass for the bounds.
// Each updateVertices is checked: the mesh must hold exactly the array passed in, in the same
// buffer as before; each commitVertices: the mesh must hold the written positions in the buffer
// they were written into. A failure exits 1. Results: benchmarks/RESULTS.md.
//
// Usage: update_bench [--reps R] [--max-n N] [--threads T] [--double]
//   N: the largest cloth grid side (default 700); T: the meshes' threads (HashedMesh's argument,
//   0 = the hardware's, the default); --double: double positions (kdet_bench's scenes) instead
//   of float.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <kdet_fcl/detail/knobs.h>
#include <kdet_fcl/hashed_mesh.h>
#include <kdet_fcl/scenes.h>

namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double timeUs(F&& f) {
  const auto a = Clock::now();
  f();
  return std::chrono::duration<double, std::micro>(Clock::now() - a).count();
}

template <class S>
int run(int reps, int max_n, int threads) {
  using kdet_fcl::Vec3;
  std::printf("%s positions, the meshes' threads %d (0: the hardware's)\n\n",
              sizeof(S) == sizeof(float) ? "float" : "double", threads);
  std::printf("| triangles | vertex bytes | updateVertices (us) | copy only (us) | "
              "commitVertices (us) | copy, check, move (us) |\n|---:|---:|---:|---:|---:|---:|\n");
  for (int n : {215, 354, 700}) {
    n = std::min(n, max_n);
    const kdet_fcl::TriangleMesh<S> f0 = kdet_fcl::makeDrapedCloth<S>(n, 4, 1, S(0.03), S(0.5));
    const std::vector<Vec3<S>> f1 = kdet_fcl::makeDrapedCloth<S>(n, 4, 1, S(0.03), S(0.7)).vertices;
    kdet_fcl::HashedMesh<S> mesh(f0, kdet_fcl::Transform<S>::identity(), threads),
        committed(f0, kdet_fcl::Transform<S>::identity(), threads);
    const Vec3<S>* buffer = mesh.mesh().vertices.data();
    std::vector<Vec3<S>> dst = f0.vertices, held = f0.vertices;
    std::vector<double> upd, copy, commit, old;
    volatile double sink = 0;
    for (int r = 0; r <= reps; ++r) {  // the first round warms up and is not counted
      const std::vector<Vec3<S>>& v = r % 2 ? f1 : f0.vertices;
      const double tu = timeUs([&] { mesh.updateVertices(v); });
      if (mesh.mesh().vertices != v || mesh.mesh().vertices.data() != buffer) {
        std::fprintf(stderr, "update_bench: updateVertices did not store the array in place\n");
        return 1;
      }
      const double tc = timeUs([&] { std::copy(v.begin(), v.end(), dst.begin()); });
      Vec3<S>* w = committed.vertexWriteBuffer();
      std::copy(v.begin(), v.end(), w);  // the simulation's write (untimed)
      const double tm = timeUs([&] { committed.commitVertices(); });
      if (committed.mesh().vertices != v || committed.mesh().vertices.data() != w) {
        std::fprintf(stderr, "update_bench: commitVertices did not make the written buffer the mesh's\n");
        return 1;
      }
      const double to = timeUs([&] {
        kdet_fcl::TriangleMesh<S> probe;
        probe.vertices = v;
        probe.validate(false, "update_bench");
        held = std::move(probe.vertices);
        const double inf = std::numeric_limits<double>::infinity();
        double lo[3] = {inf, inf, inf}, hi[3] = {-inf, -inf, -inf};
        for (const Vec3<S>& p : held)
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], double(p[a]));
            hi[a] = std::max(hi[a], double(p[a]));
          }
        sink += lo[0] + lo[1] + lo[2] + hi[0] + hi[1] + hi[2];  // keeps the bounds pass
      });
      if (r == 0) continue;
      upd.push_back(tu);
      copy.push_back(tc);
      commit.push_back(tm);
      old.push_back(to);
    }
    std::printf("| %zu | %zu | %.0f | %.0f | %.0f | %.0f |\n", f0.triangles.size(),
                f0.vertices.size() * sizeof(Vec3<S>), median(upd), median(copy), median(commit),
                median(old));
    std::fflush(stdout);
    if (n == max_n) break;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 30, max_n = 700, threads = 0;
  bool dbl = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--reps" || a == "--max-n" || a == "--threads") && i + 1 < argc) {
      std::uint64_t v = 0;
      const std::uint64_t least = a == "--threads" ? 0 : 1;
      if (!kdet_fcl::detail::parseWholeNumber(argv[++i], &v) || v < least || v > 1000000) {
        std::fprintf(stderr, "update_bench: %s needs a whole number from %d to 1000000, got '%s'\n",
                     a.c_str(), int(least), argv[i]);
        return 2;
      }
      (a == "--reps" ? reps : a == "--max-n" ? max_n : threads) = int(v);
    } else if (a == "--double") {
      dbl = true;
    } else {
      std::fprintf(stderr, "usage: update_bench [--reps R] [--max-n N] [--threads T] [--double]\n");
      return 2;
    }
  }
  return dbl ? run<double>(reps, max_n, threads) : run<float>(reps, max_n, threads);
}
