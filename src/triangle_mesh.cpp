#include "kdet_fcl/triangle_mesh.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "coordinate_range.h"
#include "kdet_fcl/errors.h"

namespace kdet_fcl {

namespace {

/// TriangleMesh::validate's checks; with `range`, also validateForQueries' range.
template <class S>
void validateMesh(const TriangleMesh<S>& mesh, bool require_triangles, bool range,
                  const std::string& what) {
  const auto& vertices = mesh.vertices;
  const auto& triangles = mesh.triangles;
  constexpr std::size_t kMaxCount = std::numeric_limits<std::uint32_t>::max() - 1;
  if (vertices.size() > kMaxCount || triangles.size() > kMaxCount)
    throw InvalidInputError(what + ": too many vertices or triangles (at most 2^32-2 each)");
  if (require_triangles && triangles.empty())
    throw InvalidInputError(what + ": the mesh has no triangles");
  double largest = 0;  // the largest coordinate magnitude, at vertex `at`
  std::size_t at = 0;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const Vec3<S>& p = vertices[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      std::ostringstream os;
      os << what << ": vertex " << i << " has a non-finite coordinate (" << p.x << ", " << p.y
         << ", " << p.z << ")";
      throw InvalidInputError(os.str());
    }
    if (!range) continue;
    const double m = std::fmax(std::fabs(double(p.x)),
                               std::fmax(std::fabs(double(p.y)), std::fabs(double(p.z))));
    if (m > largest) largest = m, at = i;
  }
  if (range && !detail::inExactRange(largest)) {
    const Vec3<S>& p = vertices[at];
    throw InvalidInputError(detail::outOfRangeMessage(what, at, p.x, p.y, p.z, largest));
  }
  for (std::size_t i = 0; i < triangles.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (triangles[i][k] >= vertices.size()) {
        std::ostringstream os;
        os << what << ": triangle " << i << " refers to vertex " << triangles[i][k] << " but the mesh has "
           << vertices.size() << " vertices";
        throw InvalidInputError(os.str());
      }
}

}  // namespace

template <class S>
void TriangleMesh<S>::validate(bool require_triangles, const std::string& what) const {
  validateMesh(*this, require_triangles, false, what);
}

template <class S>
void TriangleMesh<S>::validateForQueries(bool require_triangles, const std::string& what) const {
  validateMesh(*this, require_triangles, true, what);
}

template struct TriangleMesh<float>;
template struct TriangleMesh<double>;

}  // namespace kdet_fcl
