#pragma once
// What the session-52 probes in this folder share: an FCL-only mesh (examples/fcl_only_meshes.h)
// as a kdet_fcl mesh, and a result's (b1, b2) pairs as a set.
#include <cstdint>
#include <set>
#include <utility>

#include <fcl/fcl.h>
#include <kdet_fcl/kdet_fcl.h>

#include "fcl_only_meshes.h"  // examples/

namespace probe {

using Pairs = std::set<std::pair<long, long>>;

inline Pairs pairsOf(const fcl::CollisionResultd& r) {
  Pairs s;
  for (std::size_t i = 0; i < r.numContacts(); ++i)
    s.emplace(r.getContact(i).b1, r.getContact(i).b2);
  return s;
}

inline kdet_fcl::TriangleMesh<double> mesh(const fcl_only::Soup& s) {
  kdet_fcl::TriangleMesh<double> m;
  for (const auto& p : s.points) m.vertices.push_back({p[0], p[1], p[2]});
  for (const auto& t : s.triangles)
    m.triangles.push_back({std::uint32_t(t[0]), std::uint32_t(t[1]), std::uint32_t(t[2])});
  return m;
}

}  // namespace probe
