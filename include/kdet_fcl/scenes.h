#pragma once
/// \file
/// Procedural scenes (no data files needed): the default demo, tests and benchmarks use them.

#include <cstdint>

#include "kdet_fcl/triangle_mesh.h"

namespace kdet_fcl {

/// A UV sphere with `segments` around and `rings` from pole to pole (2*segments*(rings-1)
/// triangles), indexed.
template <class S>
TriangleMesh<S> makeSphere(const Vec3<S>& center, S radius, int segments, int rings);

/// A square cloth of (n x n) quads (2 n^2 triangles) draped over a sphere at the origin of radius
/// `sphere_radius`: the cloth lies at height `height` and each vertex within the sphere's
/// silhouette is pushed down onto a sphere of radius `sphere_radius * (1 - penetration)`, so it
/// cuts into the sphere, and the far border is folded back onto the cloth so that it intersects
/// itself. `time` in [0, 1] animates the drape (an analytic deformation, no physics).
template <class S>
TriangleMesh<S> makeDrapedCloth(int n, S size, S sphere_radius, S penetration, S time);

/// `count` triangles with random vertices: centres uniform in a cube of edge `extent`, sizes
/// log-uniform in [min_size, max_size]. Deterministic for a seed.
template <class S>
TriangleMesh<S> makeRandomSoup(std::size_t count, S extent, S min_size, S max_size,
                               std::uint64_t seed);

}  // namespace kdet_fcl
