#pragma once
/// \file
/// The k-free analysis of the kDet paper (Definition 3.1).
///
/// For a triangle t with minimum-enclosing-sphere diameter d, its neighbour count is the number
/// of *other* triangles t_j with d_j >= d that intersect t grown by a sphere of diameter d/2, i.e.
/// whose distance to t is at most d/4. t is k-free for every k > count, so the mesh's minimum k
/// is (largest count) + 1.

#include <cstdint>
#include <vector>

#include "kdet_fcl/triangle_mesh.h"

namespace kdet_fcl {

/// Per-mesh summary of the k-free analysis.
struct KFreeStats {
  std::size_t triangles = 0;
  std::uint32_t k = 0;           ///< minimum k for which the mesh is k-free (max count + 1)
  double mean = 0;               ///< mean neighbour count per triangle
  double sd = 0;                 ///< population standard deviation of the counts
  std::uint32_t max_count = 0;   ///< largest neighbour count (k - 1)
  double adjacent_mean = 0;      ///< mean count of neighbours that share a vertex with t
  double adjacent_share = 0;     ///< adjacent neighbours / all neighbours (0 when none)
  int height = 0;                ///< hierarchy height (levels from finest to coarsest)
  std::vector<std::uint32_t> counts;  ///< per-triangle neighbour counts (when requested)
};

struct KFreeOptions {
  bool keep_counts = false;  ///< fill KFreeStats::counts
  int threads = 0;           ///< 0: hardware concurrency
};

/// The analysis through the hierarchical hash (linear time for k-free meshes). Validates the
/// mesh (InvalidInputError). An empty mesh gives all zeros.
template <class S>
KFreeStats analyzeKFree(const TriangleMesh<S>& mesh, const KFreeOptions& options = {});

/// The same numbers by the direct O(n^2) definition (a referee for tests).
template <class S>
KFreeStats analyzeKFreeBruteForce(const TriangleMesh<S>& mesh, const KFreeOptions& options = {});

}  // namespace kdet_fcl
