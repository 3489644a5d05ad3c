#pragma once
/// \file
/// Plain triangle-mesh data: vertices plus index triples. Indexed meshes and triangle soups
/// (three fresh vertices per triangle) are both fine.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "kdet_fcl/vec3.h"

namespace kdet_fcl {

/// Three vertex indices of one triangle.
using Triangle = std::array<std::uint32_t, 3>;

/// A triangle mesh in its own (local) frame.
template <class S>
struct TriangleMesh {
  std::vector<Vec3<S>> vertices;
  std::vector<Triangle> triangles;

  std::size_t numTriangles() const { return triangles.size(); }
  std::size_t numVertices() const { return vertices.size(); }

  /// Throws InvalidInputError naming the first problem: a NaN or infinite coordinate (with the
  /// vertex index), an index out of range (with the triangle index), more than 2^32-2 triangles
  /// or vertices, or (when `require_triangles`) no triangles at all. Degenerate triangles
  /// (zero area, repeated indices) are valid. (What the mesh readers and writers check.)
  void validate(bool require_triangles = false, const std::string& what = "mesh") const;

  /// validate(), and also a largest coordinate magnitude outside [2^-247, 2^330] (about
  /// [4.4e-75, 2.2e99]; 0, every vertex at the origin, is fine), naming the vertex that has it:
  /// what a mesh must meet to be hashed or queried (HashedMesh, its vertex updates, the brute
  /// force, the k-free analysis, kdet_fcl::collide's meshes). Outside it the hierarchy's levels
  /// no longer bound a triangle's cells and the exact predicates lose their guarantee
  /// (docs/numerics.md). Every float mesh is inside the range.
  void validateForQueries(bool require_triangles = false, const std::string& what = "mesh") const;

  /// Whether triangles i and j share a vertex: the same index, or equal coordinates (so that
  /// triangle soups work). Such pairs are adjacent, not colliding: the self-collision rule of
  /// intersectSelf, bruteForceIntersectSelf and the k-free analysis.
  bool sharesVertex(std::uint32_t i, std::uint32_t j) const {
    const Triangle& a = triangles[i];
    const Triangle& b = triangles[j];
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q)
        if (a[p] == b[q] || vertices[a[p]] == vertices[b[q]]) return true;
    return false;
  }

  /// Convenience: append a triangle with three new vertices (triangle-soup style).
  void addTriangle(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c) {
    const auto i = static_cast<std::uint32_t>(vertices.size());
    vertices.push_back(a);
    vertices.push_back(b);
    vertices.push_back(c);
    triangles.push_back({i, i + 1, i + 2});
  }
};

extern template struct TriangleMesh<float>;
extern template struct TriangleMesh<double>;

}  // namespace kdet_fcl
