#include "kdet_fcl/triangle_mesh.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "kdet_fcl/errors.h"

namespace kdet_fcl {

template <class S>
void TriangleMesh<S>::validate(bool require_triangles, const std::string& what) const {
  constexpr std::size_t kMaxCount = std::numeric_limits<std::uint32_t>::max() - 1;
  if (vertices.size() > kMaxCount || triangles.size() > kMaxCount)
    throw InvalidInputError(what + ": too many vertices or triangles (at most 2^32-2 each)");
  if (require_triangles && triangles.empty())
    throw InvalidInputError(what + ": the mesh has no triangles");
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const Vec3<S>& p = vertices[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      std::ostringstream os;
      os << what << ": vertex " << i << " has a non-finite coordinate (" << p.x << ", " << p.y
         << ", " << p.z << ")";
      throw InvalidInputError(os.str());
    }
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

template struct TriangleMesh<float>;
template struct TriangleMesh<double>;

}  // namespace kdet_fcl
