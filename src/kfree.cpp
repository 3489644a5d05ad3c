// The k-free analysis of Definition 3.1, through the hierarchy and by the direct definition.

#include "kdet_fcl/kfree.h"

#include <cmath>

#include "cpu/hierarchical_hash.h"
#include "cpu/parallel.h"
#include "cpu/scan.h"
#include "kdet_fcl/detail/triangle_distance.h"

namespace kdet_fcl {
namespace {

/// Whether triangle j counts for triangle i: larger (d_j >= d_i), not i itself, and within
/// distance d_i/4 of i (it meets i grown by a sphere of diameter d_i/2). Both analyses call this
/// one function, so they agree bit for bit.
template <class S>
bool countsFor(const TriangleMesh<S>& m, const std::vector<double>& d, std::uint32_t i,
               std::uint32_t j) {
  if (j == i || d[j] < d[i]) return false;
  const Triangle& a = m.triangles[i];
  const Triangle& b = m.triangles[j];
  const auto& v = m.vertices;
  const double r = d[i] / 4;
  return detail::triangleDistanceSquared(v[a[0]], v[a[1]], v[a[2]], v[b[0]], v[b[1]], v[b[2]]) <=
         r * r;
}

KFreeStats summarize(std::vector<std::uint32_t>&& counts, const std::vector<std::uint32_t>& adj,
                     int height, bool keep) {
  KFreeStats st;
  st.triangles = counts.size();
  st.height = height;
  if (counts.empty()) return st;
  double sum = 0, sum_adj = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    sum += counts[i];
    sum_adj += adj[i];
    if (counts[i] > st.max_count) st.max_count = counts[i];
  }
  const double n = double(counts.size());
  st.mean = sum / n;
  double var = 0;
  for (std::uint32_t c : counts) var += (c - st.mean) * (c - st.mean);
  st.sd = std::sqrt(var / n);
  st.k = st.max_count + 1;
  st.adjacent_mean = sum_adj / n;
  st.adjacent_share = sum > 0 ? sum_adj / sum : 0;
  if (keep) st.counts = std::move(counts);
  return st;
}

}  // namespace

template <class S>
KFreeStats analyzeKFree(const TriangleMesh<S>& mesh, const KFreeOptions& options) {
  mesh.validateForQueries(false, "analyzeKFree");
  detail::HierarchicalHash<S> h;
  h.build(mesh, options.threads);
  const std::size_t n = mesh.triangles.size();
  std::vector<std::uint32_t> counts(n, 0), adj(n, 0);
  cpu::parallelFor(n, 512, options.threads, [&](std::size_t b, std::size_t e) {
    QueryStats st;
    for (std::size_t i = b; i < e; ++i) {
      const auto ui = std::uint32_t(i);
      // Grow the box by the sphere radius d/4, with a hair of slack so that rounding in the
      // distance can never make a counted triangle miss the candidate search.
      const double r = h.diameter[i] / 4;
      const detail::Aabb<double> q = detail::inflate(h.boxes[i], r * (1 + 1e-9) + 1e-300);
      cpu::scanCandidates(
          h, q, h.diameter[i], [&](std::uint32_t j, double dj) { return dj >= h.diameter[i] ? (j != ui ? 1 : 0) : -1; },
          [&](std::uint32_t j) {
            if (countsFor(mesh, h.diameter, ui, j)) {
              ++counts[i];
              if (mesh.sharesVertex(ui, j)) ++adj[i];
            }
            return true;
          },
          st);
    }
  });
  return summarize(std::move(counts), adj, n ? h.top_level + 1 : 0, options.keep_counts);
}

template <class S>
KFreeStats analyzeKFreeBruteForce(const TriangleMesh<S>& mesh, const KFreeOptions& options) {
  mesh.validateForQueries(false, "analyzeKFreeBruteForce");
  detail::HierarchicalHash<S> h;  // only for the diameters and the height
  h.build(mesh, options.threads);
  const std::size_t n = mesh.triangles.size();
  std::vector<std::uint32_t> counts(n, 0), adj(n, 0);
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = 0; j < n; ++j)
      if (countsFor(mesh, h.diameter, i, j)) {
        ++counts[i];
        if (mesh.sharesVertex(i, j)) ++adj[i];
      }
  return summarize(std::move(counts), adj, n ? h.top_level + 1 : 0, options.keep_counts);
}

template KFreeStats analyzeKFree(const TriangleMesh<float>&, const KFreeOptions&);
template KFreeStats analyzeKFree(const TriangleMesh<double>&, const KFreeOptions&);
template KFreeStats analyzeKFreeBruteForce(const TriangleMesh<float>&, const KFreeOptions&);
template KFreeStats analyzeKFreeBruteForce(const TriangleMesh<double>&, const KFreeOptions&);

}  // namespace kdet_fcl
