#pragma once
// The coordinate range every mesh must keep (detail::kExactMinMagnitude, kExactMaxMagnitude in
// exact_predicates.h): TriangleMesh::validateForQueries() and HashedMesh's vertex updates share
// it.

#include <cmath>
#include <sstream>
#include <string>

#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/exact_predicates.h"

namespace kdet_fcl {
namespace detail {

/// Whether a mesh whose largest coordinate magnitude is `m` (finite) may be hashed: m is 0 (every
/// vertex at the origin) or lies in [kExactMinMagnitude, kExactMaxMagnitude].
inline bool inExactRange(double m) {
  return m == 0 || (m >= kExactMinMagnitude && m <= kExactMaxMagnitude);
}

/// The largest coordinate magnitude of a box (finite bounds).
inline double largestMagnitude(const Aabb<double>& b) {
  double m = 0;
  for (int a = 0; a < 3; ++a) m = std::fmax(m, std::fmax(std::fabs(b.lo[a]), std::fabs(b.hi[a])));
  return m;
}

/// The message of a mesh refused by inExactRange: `what`, the vertex and its coordinates.
inline std::string outOfRangeMessage(const std::string& what, std::size_t vertex, double x,
                                     double y, double z, double m) {
  std::ostringstream os;
  os.precision(17);
  os << what << ": vertex " << vertex << " (" << x << ", " << y << ", " << z
     << ") makes the mesh's largest coordinate magnitude " << m
     << (m > kExactMaxMagnitude ? ", above 2^330 (about 2.2e99)"
                                : ", below 2^-247 (about 4.4e-75)")
     << ": outside the range where kDet's hierarchy and exact predicates hold (docs/numerics.md);"
        " rescale the mesh";
  return os.str();
}

}  // namespace detail
}  // namespace kdet_fcl
