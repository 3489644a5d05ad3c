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

#include "cpu/hierarchical_hash.h"
#include "cpu/parallel.h"
#include "cpu/scan.h"
#include "kdet_fcl/backend.h"
#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/detail/triangle_intersection.h"
#include "kdet_fcl/errors.h"
#include "kdet_fcl/query.h"

namespace kdet_fcl {
namespace cpu {
namespace {

using detail::Aabb;
using detail::HierarchicalHash;

constexpr std::size_t kChunk = 1024;           // triangles per unit of parallel work
constexpr std::size_t kParallelMinimum = 16384; // below this, threads cost more than they save

/// Runs `num_chunks` chunks of work, each producing pairs in a deterministic order, and
/// concatenates them in chunk order. With max_pairs > 0, stops once the completed prefix of
/// chunks holds max_pairs pairs, so the reported pairs are the first ones of the full order
/// whatever the thread count. fn(chunk, out, stats) may stop its chunk early once `out` holds
/// max_pairs pairs.
template <class Fn>
QueryResult runChunks(std::size_t num_chunks, int threads, std::size_t max_pairs, Fn&& fn) {
  struct Out {
    std::vector<TrianglePair> pairs;
    QueryStats stats;
    bool done = false;
  };
  std::vector<Out> outs(num_chunks);
  std::mutex m;
  std::size_t frontier = 0, prefix_pairs = 0;
  forEachChunk(num_chunks, threads, [&](std::size_t c) {
    fn(c, outs[c].pairs, outs[c].stats);
    std::lock_guard<std::mutex> lock(m);
    outs[c].done = true;
    while (frontier < num_chunks && outs[frontier].done) prefix_pairs += outs[frontier++].pairs.size();
    return !(max_pairs > 0 && prefix_pairs >= max_pairs);
  });
  QueryResult res;
  for (std::size_t c = 0; c < num_chunks && outs[c].done; ++c) {
    const Out& o = outs[c];
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

}  // namespace

template <class S>
QueryResult intersectMeshes(const HashedMesh<S>& A, const HashedMesh<S>& B,
                            const QueryOptions& options) {
  const TriangleMesh<S>& ma = A.mesh();
  const TriangleMesh<S>& mb = B.mesh();
  const HierarchicalHash<S>& ha = A.hash();
  const HierarchicalHash<S>& hb = B.hash();
  const std::size_t na = ma.triangles.size(), nb = mb.triangles.size();
  if (na == 0 || nb == 0) return QueryResult{};

  const detail::RelativePose rp = detail::relativePose(A.pose(), B.pose());
  const int threads = (na + nb >= kParallelMinimum) ? options.threads : 1;

  // A's vertices in B's frame: the coordinates every exact test of this query uses.
  std::vector<Vec3<S>> mapped;
  const Vec3<S>* va = ma.vertices.data();
  if (!rp.identity) {
    mapped.resize(ma.vertices.size());
    parallelFor(mapped.size(), 16384, threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v) mapped[v] = detail::mapPoint(rp.a_to_b, ma.vertices[v]);
    });
    va = mapped.data();
  }
  const Vec3<S>* vb = mb.vertices.data();
  const Triangle* ta = ma.triangles.data();
  const Triangle* tb = mb.triangles.data();

  // B's boxes mapped back into A's frame differ from the exact geometry by rounding (the mapping
  // of A into B, the inverse mapping, R's distance from orthonormal); grow them by a bound on
  // that so no touching pair is missed.
  double eps = 0;
  if (!rp.identity) {
    double mag = std::fabs(rp.a_to_b.t.x) + std::fabs(rp.a_to_b.t.y) + std::fabs(rp.a_to_b.t.z);
    for (int k = 0; k < 3; ++k)
      mag += std::max(std::fabs(ha.bounds.lo[k]), std::fabs(ha.bounds.hi[k])) +
             std::max(std::fabs(hb.bounds.lo[k]), std::fabs(hb.bounds.hi[k]));
    eps = (16 * rp.orthonormal_defect + 64 * double(std::numeric_limits<S>::epsilon())) * mag +
          std::numeric_limits<double>::min();
  }

  auto exact = [&](std::uint32_t i, std::uint32_t j) {
    return detail::trianglesIntersect(options.predicate, va[ta[i][0]], va[ta[i][1]], va[ta[i][2]], vb[tb[j][0]],
                                      vb[tb[j][1]], vb[tb[j][2]]);
  };

  const std::size_t chunks_a = (na + kChunk - 1) / kChunk;
  const std::size_t chunks_b = (nb + kChunk - 1) / kChunk;
  const std::size_t max_pairs = options.max_pairs;
  return runChunks(chunks_a + chunks_b, threads, max_pairs,
                   [&](std::size_t c, std::vector<TrianglePair>& out, QueryStats& st) {
    auto emit = [&](TrianglePair p) {
      out.push_back(p);
      return !(max_pairs > 0 && out.size() >= max_pairs);
    };
    if (c < chunks_a) {
      // A -> B: A's triangle i against B's triangles at least as large.
      const std::size_t end = std::min(na, (c + 1) * kChunk);
      for (std::size_t i = c * kChunk; i < end; ++i) {
        const double di = ha.diameter[i];
        if (di > hb.d_max) continue;  // nothing in B is as large
        const Aabb<double> q =
            detail::triangleBox<double>(va[ta[i][0]], va[ta[i][1]], va[ta[i][2]]);
        const auto ui = std::uint32_t(i);
        const bool go = scanCandidates(
            hb, q, di, [&](std::uint32_t, double dj) { return dj >= di ? 1 : -1; },
            [&](std::uint32_t j) {
              ++st.triangle_tests;
              return exact(ui, j) ? emit({ui, j}) : true;
            },
            st);
        if (!go) return;
      }
    } else {
      // B -> A: B's triangle j against A's strictly larger triangles, looked up in A's frame.
      const std::size_t cb = c - chunks_a;
      const std::size_t end = std::min(nb, (cb + 1) * kChunk);
      for (std::size_t j = cb * kChunk; j < end; ++j) {
        const double dj = hb.diameter[j];
        if (dj >= ha.d_max) continue;  // nothing in A is strictly larger
        Aabb<double> q;
        if (rp.identity) {
          q = hb.boxes[j];
        } else {
          const Vec3<double> p0 = rp.b_to_a.apply(Vec3<double>{double(vb[tb[j][0]].x),
                                                               double(vb[tb[j][0]].y),
                                                               double(vb[tb[j][0]].z)});
          const Vec3<double> p1 = rp.b_to_a.apply(Vec3<double>{double(vb[tb[j][1]].x),
                                                               double(vb[tb[j][1]].y),
                                                               double(vb[tb[j][1]].z)});
          const Vec3<double> p2 = rp.b_to_a.apply(Vec3<double>{double(vb[tb[j][2]].x),
                                                               double(vb[tb[j][2]].y),
                                                               double(vb[tb[j][2]].z)});
          q = detail::inflate(detail::triangleBox<double>(p0, p1, p2), eps);
        }
        const auto uj = std::uint32_t(j);
        const bool go = scanCandidates(
            ha, q, dj, [&](std::uint32_t, double di) { return di > dj ? 1 : -1; },
            [&](std::uint32_t i) {
              ++st.triangle_tests;
              return exact(i, uj) ? emit({i, uj}) : true;
            },
            st);
        if (!go) return;
      }
    }
  });
}

template <class S>
QueryResult intersectSelf(const HashedMesh<S>& M, const QueryOptions& options) {
  const TriangleMesh<S>& m = M.mesh();
  const HierarchicalHash<S>& h = M.hash();
  const std::size_t n = m.triangles.size();
  if (n < 2) return QueryResult{};
  const int threads = (n >= kParallelMinimum) ? options.threads : 1;
  const Vec3<S>* v = m.vertices.data();
  const Triangle* t = m.triangles.data();
  const std::size_t max_pairs = options.max_pairs;

  // Pairs that share a vertex (by index, or by equal coordinates for soups) are adjacent, not
  // colliding.
  auto sharesVertex = [&](std::uint32_t i, std::uint32_t j) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        if (t[i][a] == t[j][b] || v[t[i][a]] == v[t[j][b]]) return true;
    return false;
  };

  return runChunks((n + kChunk - 1) / kChunk, threads, max_pairs,
                   [&](std::size_t c, std::vector<TrianglePair>& out, QueryStats& st) {
    const std::size_t end = std::min(n, (c + 1) * kChunk);
    for (std::size_t i = c * kChunk; i < end; ++i) {
      const double di = h.diameter[i];
      const auto ui = std::uint32_t(i);
      // The larger triangle of each pair is the one with the larger (diameter, index).
      const bool go = scanCandidates(
          h, h.boxes[i], di,
          [&](std::uint32_t j, double dj) { return dj > di ? 1 : (dj == di ? (j > ui ? 1 : 0) : -1); },
          [&](std::uint32_t j) {
            if (sharesVertex(ui, j)) return true;
            ++st.triangle_tests;
            if (!detail::trianglesIntersect(options.predicate, v[t[i][0]], v[t[i][1]], v[t[i][2]], v[t[j][0]],
                                            v[t[j][1]], v[t[j][2]]))
              return true;
            out.push_back(ui < j ? TrianglePair{ui, j} : TrianglePair{j, ui});
            return !(max_pairs > 0 && out.size() >= max_pairs);
          },
          st);
      if (!go) return;
    }
  });
}

}  // namespace cpu

template <class S>
QueryResult intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options) {
  resolveBackend(options.backend, a.numTriangles() + b.numTriangles());  // throws for Cuda
  return cpu::intersectMeshes(a, b, options);
}

template <class S>
QueryResult intersectSelf(const HashedMesh<S>& mesh, const QueryOptions& options) {
  resolveBackend(options.backend, mesh.numTriangles());
  return cpu::intersectSelf(mesh, options);
}

template QueryResult intersectMeshes(const HashedMesh<float>&, const HashedMesh<float>&,
                                     const QueryOptions&);
template QueryResult intersectMeshes(const HashedMesh<double>&, const HashedMesh<double>&,
                                     const QueryOptions&);
template QueryResult intersectSelf(const HashedMesh<float>&, const QueryOptions&);
template QueryResult intersectSelf(const HashedMesh<double>&, const QueryOptions&);

}  // namespace kdet_fcl
