// The CPU backend of kDet's queries (paper Algorithms 1-3).
//
// Pairs (i of A, j of B) are split by size: A's triangle i looks for B's triangles with
// d_j >= d_i in B's hierarchy (its own level and every coarser one), B's triangle j looks for A's
// triangles with d_i > d_j in A's hierarchy. Each pair is thus examined in one direction, and in
// that direction only from the cell that holds the minimum corner of the two boxes' overlap, so
// it is reported exactly once with no de-duplication set. Every reported pair is decided by the
// exact triangle test on A's coordinates mapped into B's frame (detail/pose.h), the same
// coordinates the brute-force reference uses.

#include <algorithm>
#include <limits>
#include <mutex>
#include <numeric>
#include <string>

#include "cpu/hierarchical_hash.h"
#include "cpu/parallel.h"
#include "cpu/scan.h"
#include "kdet_fcl/backend.h"
#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "kdet_fcl/errors.h"
#include "kdet_fcl/query.h"
#include "kept_self_result.h"

namespace kdet_fcl {
namespace cpu {
namespace {

using detail::Aabb;
using detail::HierarchicalHash;

constexpr std::size_t kChunk = 1024;           // triangles per unit of parallel work
constexpr std::size_t kCappedChunk = 256;       // the same for a query with max_pairs
constexpr std::size_t kSampleStep = 8;         // a capped query's sample: one index in 8
constexpr std::size_t kSampleMaxPairs = 4096;   // capped queries up to this many pairs sample
constexpr std::size_t kParallelMinimum = 16384; // below this, threads cost more than they save

/// The order in which a query visits one mesh's triangles, cut into chunks. A query that finds
/// every pair visits them in index order (its arrays' locality), in chunks of kChunk. A capped
/// query (max_pairs > 0) wants some pairs soon, and index order would first visit every
/// triangle before the contact: a whole region of a mesh built row by row. So it visits first a
/// sample, every kSampleStep-th index (0, 8, 16, ...), spread over the mesh (sample q at
/// q * stride mod s, with s samples and the stride near s / golden ratio and coprime to s, so
/// each once, like a low-discrepancy sequence), then the other indices in index order. A
/// contact region holding a share f of the triangles is met after about 1/f samples; a query
/// with no pair visits one triangle in kSampleStep out of order. Chunks of kCappedChunk. A query
/// capped above kSampleMaxPairs (FCL's "every contact" requests cap at INT_MAX) keeps index
/// order: it visits most of any contact anyway. The order depends on n and on whether the
/// query samples, so the pairs do not depend on the thread count.
struct VisitOrder {
  std::size_t n = 0, chunk = kChunk, samples = 0, stride = 0;  // stride 0: index order

  static bool samples_for(std::size_t max_pairs) {
    return max_pairs > 0 && max_pairs <= kSampleMaxPairs;
  }
  static VisitOrder of(std::size_t n, std::size_t max_pairs) {
    VisitOrder o;
    o.n = n;
    if (!samples_for(max_pairs)) return o;
    o.chunk = kCappedChunk;
    o.samples = (n + kSampleStep - 1) / kSampleStep;
    if (o.samples < 3) return o;
    o.stride = std::max<std::size_t>(1, std::size_t(0.6180339887498949 * double(o.samples)));
    while (std::gcd(o.stride, o.samples) != 1) ++o.stride;
    return o;
  }
  std::size_t chunks() const { return (n + chunk - 1) / chunk; }
  std::size_t begin(std::size_t k) const { return k * chunk; }
  std::size_t end(std::size_t k) const { return std::min(n, (k + 1) * chunk); }
  /// The index visited at position p < n (a bijection of [0, n); n < 2^32, so products fit).
  std::size_t operator[](std::size_t p) const {
    if (stride == 0) return p;
    if (p < samples) return kSampleStep * (p * stride % samples);
    const std::size_t q = p - samples;  // the q-th index that is not a sample
    return q / (kSampleStep - 1) * kSampleStep + 1 + q % (kSampleStep - 1);
  }
};

/// Runs `num_chunks` chunks of work, each producing pairs in a deterministic order, and
/// concatenates them in chunk order. With max_pairs > 0, stops once the completed prefix of
/// chunks holds max_pairs pairs, so the reported pairs are the first ones of the chunks' order
/// whatever the thread count. fn(chunk, out, stats) may stop its chunk early once `out` holds
/// max_pairs pairs. The first `serial_first` chunks run on the calling thread before any worker
/// is woken: a capped query that meets its pairs there (a first-contact check) pays for no
/// thread's wake-up, which cost more than the whole query (an 80k/20k-triangle first contact:
/// 3.8 us on one thread, 65 us on an H200 host's 16; benchmarks/RESULTS.md, section "Python").
template <class Fn>
QueryResult runChunks(std::size_t num_chunks, int threads, std::size_t max_pairs, Fn&& fn,
                      std::size_t serial_first = 0) {
  struct Out {
    std::vector<TrianglePair> pairs;
    QueryStats stats;
    bool done = false;
  };
  std::vector<Out> outs(num_chunks);
  std::mutex m;
  std::size_t frontier = 0, prefix_pairs = 0;
  auto capped = [&] { return max_pairs > 0 && prefix_pairs >= max_pairs; };
  while (frontier < std::min(serial_first, num_chunks) && !capped()) {
    fn(frontier, outs[frontier].pairs, outs[frontier].stats);
    outs[frontier].done = true;
    prefix_pairs += outs[frontier++].pairs.size();
  }
  const std::size_t first = frontier;
  if (!capped() && first < num_chunks) {
    forEachChunk(num_chunks - first, threads, [&](std::size_t k) {
      const std::size_t c = first + k;
      fn(c, outs[c].pairs, outs[c].stats);
      std::lock_guard<std::mutex> lock(m);
      outs[c].done = true;
      while (frontier < num_chunks && outs[frontier].done) prefix_pairs += outs[frontier++].pairs.size();
      return !capped();
    });
  }
  QueryResult res;
  for (std::size_t c = 0; c < num_chunks && outs[c].done; ++c) {
    const Out& o = outs[c];
    res.stats.lookups += o.stats.lookups;
    res.stats.cells_visited += o.stats.cells_visited;
    res.stats.box_tests += o.stats.box_tests;
    res.stats.triangle_tests += o.stats.triangle_tests;
    for (const TrianglePair& p : o.pairs) {
      if (max_pairs > 0 && res.pairs.size() >= max_pairs) break;
      res.pairs.push_back(p);
    }
  }
  // Fewer than max_pairs pairs means every chunk ran to its end.
  res.complete = max_pairs == 0 || res.pairs.size() < max_pairs;
  return res;
}

/// The exact test of one candidate pair, out of line: inlined, its three kernels would crowd the
/// scan loop it is called from (the compiler then stops inlining the loop's own small helpers).
template <class S>
#if defined(__GNUC__) || defined(__clang__)
__attribute__((noinline))
#endif
bool testPair(Predicate predicate, const Vec3<S>& p0, const Vec3<S>& p1, const Vec3<S>& p2,
              const Vec3<S>& q0, const Vec3<S>& q1, const Vec3<S>& q2) {
  return detail::trianglesIntersect(predicate, p0, p1, p2, q0, q1, q2);
}

}  // namespace

template <class S>
QueryResult intersectMeshes(const HashedMesh<S>& A, const HashedMesh<S>& B,
                            const QueryOptions& options) {
  const TriangleMesh<S>& ma = A.mesh();
  const TriangleMesh<S>& mb = B.mesh();
  const std::size_t na = ma.triangles.size(), nb = mb.triangles.size();
  if (na == 0 || nb == 0) return QueryResult{};
  // The per-triangle data first (boxes, diameters, levels, bounds); the cell tables below, once
  // it is known which levels the lookups visit, and only if the meshes' bounds meet.
  constexpr int kNoTable = HierarchicalHash<S>::kNoTable;
  const HierarchicalHash<S>& ga = A.hashFrom(kNoTable);
  const HierarchicalHash<S>& gb = B.hashFrom(kNoTable);

  const detail::RelativePose rp = detail::relativePose(A.pose(), B.pose());
  const int threads = (na + nb >= kParallelMinimum) ? options.threads : 1;
  const Vec3<S>* va = ma.vertices.data();
  const Vec3<S>* vb = mb.vertices.data();
  const Triangle* ta = ma.triangles.data();
  const Triangle* tb = mb.triangles.data();

  // Every exact test of this query uses A's vertices mapped into B's frame (detail::mapPoint:
  // mapped in double, rounded once to S) and B's own. Vertices are mapped when a triangle needs
  // them, so triangles far from the other mesh cost nothing beyond a box test.
  auto vertexInB = [&](std::uint32_t v) {
    return rp.identity ? va[v] : detail::mapPoint(rp.a_to_b, va[v]);
  };
  struct Tri {
    Vec3<S> p[3];
  };
  auto triangleInB = [&](std::uint32_t i) {
    return Tri{{vertexInB(ta[i][0]), vertexInB(ta[i][1]), vertexInB(ta[i][2])}};
  };

  // Lookups of B's triangles in A's hierarchy use B's coordinates mapped back into A's frame,
  // which differ from the exact geometry by rounding: of A's vertices when mapped into B (at most
  // ~u_S times their magnitude, i.e. near a touching point x of B's triangle j: |x| + d_i), of the
  // back-mapping (u_double times |b| + |t|), and R's distance from orthonormal (delta times the
  // same). A candidate on A's level L has d_i <= cell_L, so growing the lookup box by
  //   grow(L) = K (u_S + u_double + delta) (|b_j|_max + |t| + cell_L)
  // keeps every touching pair a candidate, and stays local to the triangle looked up.
  const double unit = double(std::numeric_limits<S>::epsilon()) +
                      std::numeric_limits<double>::epsilon() + rp.orthonormal_defect;
  const double grow_rel = rp.identity ? 0.0 : 64 * unit;
  const double tmag =
      std::fabs(rp.a_to_b.t.x) + std::fabs(rp.a_to_b.t.y) + std::fabs(rp.a_to_b.t.z);
  auto maxAbs = [](const Aabb<double>& b) {
    double m = 0;
    for (int k = 0; k < 3; ++k) m = std::max({m, std::fabs(b.lo[k]), std::fabs(b.hi[k])});
    return m;
  };
  // Coarse filters: the other mesh's bounds in each frame, grown by a scene-wide bound on the
  // same rounding. A triangle outside them meets nothing.
  auto mappedBounds = [&](const Aabb<double>& b, const Transform<double>& T, double grow) {
    Aabb<double> r{{1, 1, 1}, {0, 0, 0}};
    for (int c = 0; c < 8; ++c) {
      const Vec3<double> p =
          T.apply({c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z});
      if (c == 0) r = {p, p};
      for (int k = 0; k < 3; ++k) {
        r.lo[k] = std::min(r.lo[k], p[k]);
        r.hi[k] = std::max(r.hi[k], p[k]);
      }
    }
    return detail::inflate(r, grow);
  };
  const double scene_grow =
      rp.identity ? 0.0 : 64 * unit * (maxAbs(ga.bounds) + maxAbs(gb.bounds) + tmag) +
                              std::numeric_limits<double>::min();
  const Aabb<double> b_in_a = rp.identity ? detail::inflate(gb.bounds, 0)
                                          : mappedBounds(gb.bounds, rp.b_to_a, scene_grow);
  const Aabb<double> a_in_b = rp.identity ? detail::inflate(ga.bounds, 0)
                                          : mappedBounds(ga.bounds, rp.a_to_b, scene_grow);

  // Constant-time rejection of separated meshes (the common case of a rigid pair): no triangle of
  // A can meet B if A's bounds miss B's grown bounds mapped into A's frame.
  if (!detail::boxesOverlap(ga.bounds, b_in_a) || !detail::boxesOverlap(gb.bounds, a_in_b))
    return QueryResult{};

  // The levels the lookups visit. A's triangle i looks B up (when d_i <= B's d_max) from
  // levelFor(d_i) in B's grid up, B's triangle j looks A up (when d_j < A's d_max) from
  // levelFor(d_j) in A's grid up; levelFor is monotone, so the other mesh's smallest triangle
  // gives the lowest level. Only those tables are built: a fine cloth against a coarse body
  // needs the few cloth cells of the body's triangles' levels, not the cloth's whole table.
  const int from_a =
      gb.d_smallest < ga.d_max ? detail::levelFor(gb.d_smallest, ga.grid) : kNoTable;
  const int from_b =
      ga.d_smallest <= gb.d_max ? detail::levelFor(ga.d_smallest, gb.grid) : kNoTable;
  const HierarchicalHash<S>& ha = A.hashFrom(from_a);
  const HierarchicalHash<S>& hb = B.hashFrom(from_b);

  auto exact = [&](const Tri& a, std::uint32_t j) {
    return testPair(options.predicate, a.p[0], a.p[1], a.p[2], vb[tb[j][0]], vb[tb[j][1]],
                    vb[tb[j][2]]);
  };

  // The chunks: A's then B's; in a query that samples (VisitOrder) they alternate, A's first,
  // so that a direction whose size rule finds nothing (every triangle of A larger than B's)
  // is not visited whole first.
  const std::size_t max_pairs = options.max_pairs;
  const bool sampled = VisitOrder::samples_for(max_pairs);
  const VisitOrder order_a = VisitOrder::of(na, max_pairs);
  const VisitOrder order_b = VisitOrder::of(nb, max_pairs);
  const std::size_t chunks_a = order_a.chunks(), chunks_b = order_b.chunks();
  const std::size_t both = std::min(chunks_a, chunks_b);
  // Chunk c: which direction (true: A -> B) and which of that direction's chunks.
  auto chunkOf = [&](std::size_t c) -> std::pair<bool, std::size_t> {
    if (!sampled) return {c < chunks_a, c < chunks_a ? c : c - chunks_a};
    if (c < 2 * both) return {c % 2 == 0, c / 2};
    return {chunks_a > chunks_b, c - both};
  };
  // A sampled (capped) query takes its first chunk of each direction on the calling thread.
  return runChunks(chunks_a + chunks_b, threads, max_pairs,
                   [&](std::size_t c, std::vector<TrianglePair>& out, QueryStats& st) {
    auto emit = [&](TrianglePair p) {
      out.push_back(p);
      return !(max_pairs > 0 && out.size() >= max_pairs);
    };
    const auto [a_to_b, k] = chunkOf(c);
    if (a_to_b) {
      // A -> B: A's triangle i against B's triangles at least as large.
      for (std::size_t pos = order_a.begin(k); pos < order_a.end(k); ++pos) {
        const std::size_t i = order_a[pos];
        const double di = ha.diameter[i];
        if (di > hb.d_max) continue;  // nothing in B is as large
        if (!detail::boxesOverlap(ha.boxes[i], b_in_a)) continue;
        const auto ui = std::uint32_t(i);
        const Tri a = triangleInB(ui);
        const Aabb<double> q = detail::triangleBox<double>(a.p[0], a.p[1], a.p[2]);
        const bool go = scanCandidates(
            hb, q, di, [&](std::uint32_t, double dj) { return dj >= di ? 1 : -1; },
            [&](std::uint32_t j) {
              ++st.triangle_tests;
              return exact(a, j) ? emit({ui, j}) : true;
            },
            st);
        if (!go) return;
      }
    } else {
      // B -> A: B's triangle j against A's strictly larger triangles, looked up in A's frame.
      for (std::size_t pos = order_b.begin(k); pos < order_b.end(k); ++pos) {
        const std::size_t j = order_b[pos];
        const double dj = hb.diameter[j];
        if (dj >= ha.d_max) continue;  // nothing in A is strictly larger
        if (!detail::boxesOverlap(hb.boxes[j], a_in_b)) continue;
        Aabb<double> q = hb.boxes[j];
        double grow_abs = 0;
        if (!rp.identity) {
          Vec3<double> p[3];
          for (int k = 0; k < 3; ++k) {
            const Vec3<S>& b = vb[tb[j][k]];
            p[k] = rp.b_to_a.apply(Vec3<double>{double(b.x), double(b.y), double(b.z)});
          }
          q = detail::triangleBox<double>(p[0], p[1], p[2]);
          grow_abs = grow_rel * (maxAbs(hb.boxes[j]) + tmag) + std::numeric_limits<double>::min();
        }
        const auto uj = std::uint32_t(j);
        const bool go = scanCandidates(
            ha, q, dj, [&](std::uint32_t, double di) { return di > dj ? 1 : -1; },
            [&](std::uint32_t i) {
              ++st.triangle_tests;
              return exact(triangleInB(i), uj) ? emit({i, uj}) : true;
            },
            st, grow_abs, grow_rel);
        if (!go) return;
      }
    }
  }, sampled ? 2 : 0);
}

template <class S>
QueryResult computeSelf(const HashedMesh<S>& M, const QueryOptions& options) {
  const TriangleMesh<S>& m = M.mesh();
  const HierarchicalHash<S>& h = M.hash();
  const std::size_t n = m.triangles.size();
  if (n < 2) return QueryResult{};
  const int threads = (n >= kParallelMinimum) ? options.threads : 1;
  const Vec3<S>* v = m.vertices.data();
  const Triangle* t = m.triangles.data();
  const std::size_t max_pairs = options.max_pairs;

  const VisitOrder order = VisitOrder::of(n, max_pairs);
  // A sampled (capped) query takes its first chunk on the calling thread.
  return runChunks(order.chunks(), threads, max_pairs,
                   [&](std::size_t c, std::vector<TrianglePair>& out, QueryStats& st) {
    for (std::size_t pos = order.begin(c); pos < order.end(c); ++pos) {
      const std::size_t i = order[pos];
      const double di = h.diameter[i];
      const auto ui = std::uint32_t(i);
      // The larger triangle of each pair is the one with the larger (diameter, index).
      const bool go = scanCandidates(
          h, h.boxes[i], di,
          [&](std::uint32_t j, double dj) { return dj > di ? 1 : (dj == di ? (j > ui ? 1 : 0) : -1); },
          [&](std::uint32_t j) {
            if (m.sharesVertex(ui, j)) return true;  // adjacent, not colliding
            // The compact box test's survivors, confirmed on the double boxes (scanCandidates).
            if (!detail::boxesOverlap(h.boxes[i], h.boxes[j])) return true;
            ++st.triangle_tests;
            // Lower index first: the plain (inexact) predicates are not symmetric, and this is
            // the order bruteForceIntersectSelf uses.
            const TrianglePair p = ui < j ? TrianglePair{ui, j} : TrianglePair{j, ui};
            const Triangle &ta = t[p.a], &tb = t[p.b];
            if (!testPair(options.predicate, v[ta[0]], v[ta[1]], v[ta[2]], v[tb[0]], v[tb[1]],
                          v[tb[2]]))
              return true;
            out.push_back(p);
            return !(max_pairs > 0 && out.size() >= max_pairs);
          },
          st, 0, 0, false);
      if (!go) return;
    }
  }, VisitOrder::samples_for(max_pairs) ? 1 : 0);
}

/// A self query, answered from the mesh's kept result when its geometry did not change (see
/// QueryResult::kept and detail::KeptSelfResult); the threads do not matter to the pairs.
template <class S>
QueryResult intersectSelf(const HashedMesh<S>& M, const QueryOptions& options) {
  detail::KeptSelfResult& kept = M.keptSelf();
  detail::KeptSelfResult::Ticket ticket;
  QueryResult r;
  if (kept.find(M.version(), options, &r, &ticket)) return r;
  r = computeSelf(M, options);
  kept.offer(ticket, options, r);
  return r;
}

}  // namespace cpu
}  // namespace kdet_fcl

// ---- Backend dispatch: Backend::Cuda (or Auto on a large query with a device) goes to the CUDA
//      backend behind its host-only seam (cuda/cuda_backend.h). ----
#ifndef KDET_FCL_HAVE_CUDA
#define KDET_FCL_HAVE_CUDA 0
#endif
#if KDET_FCL_HAVE_CUDA
#include "../cuda/cuda_backend.h"
#endif

namespace kdet_fcl {

template <class S>
QueryResult intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options) {
  // resolveBackend throws BackendUnavailableError for Cuda without a build or a device.
  if (resolveBackend(options.backend, a.numTriangles() + b.numTriangles()) == Backend::Cuda) {
#if KDET_FCL_HAVE_CUDA
    return cuda::intersectMeshes(a, b, options);
#endif
  }
  return cpu::intersectMeshes(a, b, options);
}

template <class S>
QueryResult intersectSelf(const HashedMesh<S>& mesh, const QueryOptions& options) {
  if (resolveBackend(options.backend, mesh.numTriangles()) == Backend::Cuda) {
#if KDET_FCL_HAVE_CUDA
    return cuda::intersectSelf(mesh, options);
#endif
  }
  return cpu::intersectSelf(mesh, options);
}

template <class S>
void intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b, QueryResult& out,
                     const QueryOptions& options) {
  if (resolveBackend(options.backend, a.numTriangles() + b.numTriangles()) == Backend::Cuda) {
#if KDET_FCL_HAVE_CUDA
    cuda::intersectMeshes(a, b, options, out);
    return;
#endif
  }
  out = cpu::intersectMeshes(a, b, options);
}

template <class S>
void intersectSelf(const HashedMesh<S>& mesh, QueryResult& out, const QueryOptions& options) {
  if (resolveBackend(options.backend, mesh.numTriangles()) == Backend::Cuda) {
#if KDET_FCL_HAVE_CUDA
    cuda::intersectSelf(mesh, options, out);
    return;
#endif
  }
  out = cpu::intersectSelf(mesh, options);
}

template <class S>
void intersectAll(const HashedMesh<S>& a, const HashedMesh<S>& b, AllPairsResult& out,
                  const QueryOptions& options) {
  QueryOptions o = options;  // one backend for the three queries, chosen by both meshes' size
  o.backend = resolveBackend(options.backend, a.numTriangles() + b.numTriangles());
#if KDET_FCL_HAVE_CUDA
  if (o.backend == Backend::Cuda && cuda::intersectJoint(a, b, o, &out)) return;
#endif
  intersectSelf(a, out.self_a, o);
  intersectSelf(b, out.self_b, o);
  intersectMeshes(a, b, out.inter, o);
}

template <class S>
AllPairsResult intersectAll(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options) {
  AllPairsResult r;  // (no storage to reuse: each result is filled as the by-value queries do)
  intersectAll(a, b, r, options);
  return r;
}

namespace {
/// The checks of the device-output queries that need no device: the backend, the buffer.
void checkDeviceOutput(const QueryOptions& options, const TrianglePair* out,
                       std::size_t capacity) {
  if (options.backend == Backend::Cpu)
    throw InvalidInputError(
        "pairs on the device need the CUDA backend: QueryOptions::backend is Backend::Cpu "
        "(use Backend::Cuda or Backend::Auto, or intersectSelf/intersectMeshes for host pairs)");
  if (out == nullptr && capacity > 0)
    throw InvalidInputError("device pair buffer is null but its capacity is " +
                            std::to_string(capacity) + " pairs");
  (void)resolveBackend(Backend::Cuda);  // BackendUnavailableError without a build or a device
}
}  // namespace

template <class S>
DevicePairsResult intersectSelfOnDevice(const HashedMesh<S>& mesh, TrianglePair* device_pairs,
                                        std::size_t capacity, const QueryOptions& options) {
  checkDeviceOutput(options, device_pairs, capacity);
#if KDET_FCL_HAVE_CUDA
  return cuda::intersectSelfOnDevice(mesh, options, device_pairs, capacity);
#else
  (void)mesh;
  throw BackendUnavailableError("kdet_fcl was built without CUDA");
#endif
}

template <class S>
DevicePairsResult intersectMeshesOnDevice(const HashedMesh<S>& a, const HashedMesh<S>& b,
                                          TrianglePair* device_pairs, std::size_t capacity,
                                          const QueryOptions& options) {
  checkDeviceOutput(options, device_pairs, capacity);
#if KDET_FCL_HAVE_CUDA
  return cuda::intersectMeshesOnDevice(a, b, options, device_pairs, capacity);
#else
  (void)a;
  (void)b;
  throw BackendUnavailableError("kdet_fcl was built without CUDA");
#endif
}

template <class S>
AllDevicePairsResult intersectAllOnDevice(const HashedMesh<S>& a, const HashedMesh<S>& b,
                                          TrianglePair* device_pairs, std::size_t capacity,
                                          const QueryOptions& options) {
  checkDeviceOutput(options, device_pairs, capacity);
#if KDET_FCL_HAVE_CUDA
  AllDevicePairsResult r;
  if (cuda::intersectJointOnDevice(a, b, options, device_pairs, capacity, &r)) return r;
  // The three queries, each into the rest of the buffer after the runs before it.
  std::size_t used = 0;
  auto place = [&](DevicePairsResult q) {
    used += q.count;
    return q;
  };
  auto at = [&] { return used < capacity ? device_pairs + used : nullptr; };
  auto room = [&] { return used < capacity ? capacity - used : std::size_t(0); };
  r.self_a = place(cuda::intersectSelfOnDevice(a, options, at(), room()));
  r.self_b = place(cuda::intersectSelfOnDevice(b, options, at(), room()));
  r.inter = place(cuda::intersectMeshesOnDevice(a, b, options, at(), room()));
  return r;
#else
  (void)a;
  (void)b;
  throw BackendUnavailableError("kdet_fcl was built without CUDA");
#endif
}

template AllDevicePairsResult intersectAllOnDevice(const HashedMesh<float>&,
                                                   const HashedMesh<float>&, TrianglePair*,
                                                   std::size_t, const QueryOptions&);
template AllDevicePairsResult intersectAllOnDevice(const HashedMesh<double>&,
                                                   const HashedMesh<double>&, TrianglePair*,
                                                   std::size_t, const QueryOptions&);
template DevicePairsResult intersectSelfOnDevice(const HashedMesh<float>&, TrianglePair*,
                                                 std::size_t, const QueryOptions&);
template DevicePairsResult intersectSelfOnDevice(const HashedMesh<double>&, TrianglePair*,
                                                 std::size_t, const QueryOptions&);
template DevicePairsResult intersectMeshesOnDevice(const HashedMesh<float>&,
                                                   const HashedMesh<float>&, TrianglePair*,
                                                   std::size_t, const QueryOptions&);
template DevicePairsResult intersectMeshesOnDevice(const HashedMesh<double>&,
                                                   const HashedMesh<double>&, TrianglePair*,
                                                   std::size_t, const QueryOptions&);
template QueryResult intersectMeshes(const HashedMesh<float>&, const HashedMesh<float>&,
                                     const QueryOptions&);
template QueryResult intersectMeshes(const HashedMesh<double>&, const HashedMesh<double>&,
                                     const QueryOptions&);
template QueryResult intersectSelf(const HashedMesh<float>&, const QueryOptions&);
template QueryResult intersectSelf(const HashedMesh<double>&, const QueryOptions&);
template void intersectMeshes(const HashedMesh<float>&, const HashedMesh<float>&, QueryResult&,
                              const QueryOptions&);
template void intersectMeshes(const HashedMesh<double>&, const HashedMesh<double>&, QueryResult&,
                              const QueryOptions&);
template void intersectSelf(const HashedMesh<float>&, QueryResult&, const QueryOptions&);
template void intersectSelf(const HashedMesh<double>&, QueryResult&, const QueryOptions&);
template void intersectAll(const HashedMesh<float>&, const HashedMesh<float>&, AllPairsResult&,
                           const QueryOptions&);
template void intersectAll(const HashedMesh<double>&, const HashedMesh<double>&,
                           AllPairsResult&, const QueryOptions&);
template AllPairsResult intersectAll(const HashedMesh<float>&, const HashedMesh<float>&,
                                     const QueryOptions&);
template AllPairsResult intersectAll(const HashedMesh<double>&, const HashedMesh<double>&,
                                     const QueryOptions&);

}  // namespace kdet_fcl
