// The FCL adapter: kdet_fcl::collide/selfCollide/distance with FCL's signatures and semantics
// (include/kdet_fcl/fcl_collide.h), and the structure cache of plain BVHModels.

#include "kdet_fcl/fcl_collide.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "kdet_fcl/fcl_mesh.h"  // BVH_model.h with the includes it needs
#include <fcl/math/bv/AABB.h>
#include <fcl/math/bv/OBB.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/math/bv/RSS.h>
#include <fcl/math/bv/kDOP.h>
#include <fcl/math/bv/kIOS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include "cpu/hierarchical_hash.h"
#include "cpu/parallel.h"
#include "fcl/checksum.h"
#include "fcl/mesh_cache.h"
#include "fcl/prepare_fcl_query.h"
#include "fcl/triangle_contact.h"
#include "kdet_fcl/detail/pose.h"
#include "kdet_fcl/errors.h"
#include "kdet_fcl/fcl_mesh.h"

namespace kdet_fcl {

// ---- Process-wide settings ----
namespace {
std::atomic<CacheValidation> g_validation{CacheValidation::Checksum};
std::mutex g_options_mutex;
QueryOptions g_options;
}  // namespace

void setCacheValidation(CacheValidation policy) { g_validation.store(policy); }
CacheValidation cacheValidation() { return g_validation.load(); }

void setCollideOptions(const QueryOptions& options) {
  std::lock_guard<std::mutex> lock(g_options_mutex);
  g_options = options;
  g_options.max_pairs = 0;
}

QueryOptions collideOptions() {
  std::lock_guard<std::mutex> lock(g_options_mutex);
  return g_options;
}

namespace detail {

namespace {

template <class S, class BV>
void fillView(const fcl::CollisionGeometry<S>* g, FclMeshView<S>& v) {
  const auto* m = static_cast<const fcl::BVHModel<BV>*>(g);
  v.vertices = m->vertices;
  v.triangles = m->tri_indices;
  v.num_vertices = m->num_vertices;
  v.num_tris = m->num_tris;
  v.build_state = m->build_state;
  v.triangles_model = m->getModelType() == fcl::BVH_MODEL_TRIANGLES;
}

/// The checksums of a model's vertices and of its triangles (apart, so that a deformation, whose
/// triangles stay, can be told from a new mesh).
struct ModelChecksums {
  std::uint64_t vertices = 0, triangles = 0;
};

/// (A large model's arrays in the vertex passes' threads. On the H200 machine's Xeon the checksum
/// of 3.6 MB took 146-180 µs on one thread and 86-90 on four; on a 2-thread VM the second thread
/// did not pay below 8 MB: benchmarks/results/cpu-interpose/checksum_probe.cpp.)
template <class S>
ModelChecksums checksumsOf(const FclMeshView<S>& v) {
  const std::size_t vertex_bytes = sizeof(fcl::Vector3<S>) * std::size_t(v.num_vertices);
  const std::size_t triangle_bytes = sizeof(fcl::Triangle) * std::size_t(v.num_tris);
  // (The options, behind their mutex, are read only where an array is large enough to split.)
  const int threads = std::max(vertex_bytes, triangle_bytes) >= cpu::kParallelVertexBytes
                          ? collideOptions().threads
                          : 1;
  return {checksumBytes(v.vertices, vertex_bytes, 1, cpu::vertexPassThreads(vertex_bytes, threads)),
          checksumBytes(v.triangles, triangle_bytes, 2,
                        cpu::vertexPassThreads(triangle_bytes, threads))};
}

template <class S>
TriangleMesh<S> toTriangleMesh(const FclMeshView<S>& v) {
  TriangleMesh<S> m;
  m.vertices.resize(std::size_t(v.num_vertices));
  for (int i = 0; i < v.num_vertices; ++i)
    m.vertices[i] = {v.vertices[i][0], v.vertices[i][1], v.vertices[i][2]};
  m.triangles.resize(std::size_t(v.num_tris));
  for (int t = 0; t < v.num_tris; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::size_t id = v.triangles[t][k];
      // Out-of-range ids become an id validateForQueries() rejects, with the triangle's index.
      m.triangles[t][k] = id < 0xFFFFFFFFull ? std::uint32_t(id) : 0xFFFFFFFFu;
    }
  return m;
}

}  // namespace

template <class S>
bool viewOf(const fcl::CollisionGeometry<S>* g, FclMeshView<S>& v) {
  if (g == nullptr || g->getObjectType() != fcl::OT_BVH) return false;
  switch (g->getNodeType()) {
    case fcl::BV_AABB: fillView<S, fcl::AABB<S>>(g, v); break;
    case fcl::BV_OBB: fillView<S, fcl::OBB<S>>(g, v); break;
    case fcl::BV_RSS: fillView<S, fcl::RSS<S>>(g, v); break;
    case fcl::BV_kIOS: fillView<S, fcl::kIOS<S>>(g, v); break;
    case fcl::BV_OBBRSS:
      fillView<S, fcl::OBBRSS<S>>(g, v);
      v.kdet_mesh = dynamic_cast<const Mesh<S>*>(g);
      break;
    case fcl::BV_KDOP16: fillView<S, fcl::KDOP<S, 16>>(g, v); break;
    case fcl::BV_KDOP18: fillView<S, fcl::KDOP<S, 18>>(g, v); break;
    case fcl::BV_KDOP24: fillView<S, fcl::KDOP<S, 24>>(g, v); break;
    default: return false;
  }
  return true;
}

template <class S>
void syncEntry(FclMeshEntry<S>& e, const FclMeshView<S>& v) {
  if (v.build_state != fcl::BVH_BUILD_STATE_PROCESSED &&
      v.build_state != fcl::BVH_BUILD_STATE_UPDATED)
    throw InvalidInputError(
        "kdet_fcl: a BVHModel that is not built (call endModel, endUpdateModel or "
        "endReplaceModel before querying it)");
  const bool dirty = e.dirty.exchange(false);
  // Same triangle array and counts (FCL's update family swaps the vertex array with the previous
  // frame's, so the vertex pointer alone may change).
  const bool same_triangles = e.hashed && e.triangles == v.triangles &&
                              e.num_vertices == v.num_vertices && e.num_tris == v.num_tris;
  const bool same_shape = same_triangles && e.vertices == v.vertices;
  ModelChecksums sums;
  bool unchanged;
  bool vertices_only = false;  // a deformation: the triangles are the ones hashed
  if (v.kdet_mesh != nullptr) {
    unchanged = same_shape && !dirty && e.mesh_version == v.kdet_mesh->version();
    vertices_only = same_triangles && e.mesh_topology == v.kdet_mesh->topologyVersion();
  } else if (g_validation.load(std::memory_order_relaxed) == CacheValidation::Checksum) {
    sums = checksumsOf(v);
    unchanged = same_shape && !dirty && e.vertex_checksum == sums.vertices &&
                e.triangle_checksum == sums.triangles;
    vertices_only = same_triangles && e.triangle_checksum == sums.triangles;
  } else {
    unchanged = same_shape && !dirty;
  }
  if (unchanged) return;
  try {
    if (vertices_only) {
      // The new positions straight into the hash's write buffer, checked there; the triangles
      // (validated when they were hashed) are neither copied nor checked again, and keep the
      // mesh's topology version, so the CUDA backend keeps its copy of them.
      // (A large model's in the vertex passes' threads: cpu::vertexPassThreads.)
      Vec3<S>* w = e.hashed->vertexWriteBuffer();
      const auto n = static_cast<std::size_t>(v.num_vertices);
      const int t = cpu::vertexPassThreads(n * sizeof(Vec3<S>), collideOptions().threads);
      cpu::parallelFor(n, cpu::shareOf(n, t), t, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i)
          w[i] = {v.vertices[i][0], v.vertices[i][1], v.vertices[i][2]};
      });
      try {
        e.hashed->commitVertices();
      } catch (const InvalidInputError&) {
        // The message a new mesh would give.
        toTriangleMesh(v).validateForQueries(false, "kdet_fcl: BVHModel");
        throw;
      }
    } else {
      TriangleMesh<S> mesh = toTriangleMesh(v);
      mesh.validateForQueries(false, "kdet_fcl: BVHModel");
      if (e.hashed) {
        e.hashed->setMesh(std::move(mesh));
      } else {
        e.hashed = std::make_unique<HashedMesh<S>>(std::move(mesh), Transform<S>::identity(),
                                                   collideOptions().threads);
      }
    }
  } catch (...) {
    if (dirty) e.dirty.store(true);
    throw;
  }
  e.twin.reset();
  e.vertices = v.vertices;
  e.triangles = v.triangles;
  e.num_vertices = v.num_vertices;
  e.num_tris = v.num_tris;
  if (v.kdet_mesh != nullptr) {
    e.mesh_version = v.kdet_mesh->version();
    e.mesh_topology = v.kdet_mesh->topologyVersion();
  } else {
    if (g_validation.load() != CacheValidation::Checksum) sums = checksumsOf(v);
    e.vertex_checksum = sums.vertices;
    e.triangle_checksum = sums.triangles;
  }
}

template bool viewOf(const fcl::CollisionGeometry<float>*, FclMeshView<float>&);
template bool viewOf(const fcl::CollisionGeometry<double>*, FclMeshView<double>&);
template void syncEntry(FclMeshEntry<float>&, const FclMeshView<float>&);
template void syncEntry(FclMeshEntry<double>&, const FclMeshView<double>&);

}  // namespace detail

namespace {

using detail::FclMeshEntry;
using detail::FclMeshView;

// ---- The cache of plain BVHModels ----

template <class S>
struct Cache {
  std::mutex mutex;
  std::unordered_map<const void*, std::shared_ptr<FclMeshEntry<S>>> entries;
  static Cache& get() {
    static Cache c;
    return c;
  }
};

template <class S>
std::shared_ptr<FclMeshEntry<S>> entryFor(const fcl::CollisionGeometry<S>* g,
                                          const FclMeshView<S>& v) {
  if (v.kdet_mesh != nullptr) return detail::MeshAccess<S>::entry(*v.kdet_mesh);
  Cache<S>& c = Cache<S>::get();
  std::lock_guard<std::mutex> lock(c.mutex);
  auto& slot = c.entries[g];
  if (!slot) slot = std::make_shared<FclMeshEntry<S>>();
  return slot;
}

// ---- Poses and checks ----

template <class S>
void requireFinite(const fcl::Transform3<S>& tf, const char* what) {
  const auto& m = tf.matrix();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j)
      if (!std::isfinite(m(i, j)))
        throw InvalidInputError(std::string("kdet_fcl::") + what + ": non-finite pose");
}

template <class S>
Transform<S> toKdet(const fcl::Transform3<S>& tf) {
  Transform<S> t;
  const auto R = tf.linear();
  const auto p = tf.translation();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) t.R[i][j] = R(i, j);
    t.t[i] = p[i];
  }
  return t;
}

template <class S>
bool samePose(const Transform<S>& a, const Transform<S>& b) {
  return std::memcmp(&a, &b, sizeof(Transform<S>)) == 0;
}

/// Before a query goes to FCL: a BVHModel must be built (FCL's traversals read its hierarchy and
/// crash on one between beginModel and endModel, inside an update, or empty, which endModel
/// refuses) and hold triangles (FCL 0.7 segfaults in every collide and distance of a point cloud,
/// BVH_MODEL_POINTCLOUD: UnsupportedQueryError), and a kdet_fcl::Mesh in KdetOnly mode gets FCL's
/// BVH refitted.
template <class S>
void prepareForFcl(const fcl::CollisionGeometry<S>* g, const char* what) {
  FclMeshView<S> v;
  if (!detail::viewOf(g, v)) return;
  if (v.build_state != fcl::BVH_BUILD_STATE_PROCESSED &&
      v.build_state != fcl::BVH_BUILD_STATE_UPDATED)
    throw InvalidInputError(
        std::string("kdet_fcl::") + what +
        (v.num_vertices == 0 && v.num_tris == 0
             ? ": an empty BVHModel (no triangles: FCL's endModel refuses it)"
             : ": a BVHModel that is not built (call endModel, endUpdateModel or "
               "endReplaceModel before querying it)"));
  if (!v.triangles_model)
    throw UnsupportedQueryError(std::string("kdet_fcl::") + what +
                                ": a point-cloud BVHModel (vertices without triangles): FCL 0.7 "
                                "has no collision or distance query for it (it crashes)");
  if (v.kdet_mesh == nullptr) return;
  if (!detail::MeshAccess<S>::fclStale(*v.kdet_mesh)) return;
  std::lock_guard<std::mutex> lock(detail::MeshAccess<S>::entry(*v.kdet_mesh)->mutex);
  // The Mesh is the caller's (non-const) object; refitting changes only FCL's BVs.
  const_cast<Mesh<S>*>(v.kdet_mesh)->refitFcl();
}

template <class S>
fcl::Vector3<S> toWorld(const Transform<double>& pose, const Vec3<double>& p) {
  const Vec3<double> w = pose.apply(p);
  return fcl::Vector3<S>(S(w.x), S(w.y), S(w.z));
}

template <class S>
fcl::Vector3<S> rotateToWorld(const Transform<double>& pose, const Vec3<double>& n) {
  Vec3<double> w;
  for (int i = 0; i < 3; ++i) w[i] = pose.R[i][0] * n.x + pose.R[i][1] * n.y + pose.R[i][2] * n.z;
  return fcl::Vector3<S>(S(w.x), S(w.y), S(w.z));
}

template <class S>
Vec3<double> toD(const Vec3<S>& p) {
  return {double(p.x), double(p.y), double(p.z)};
}

/// FCL's cost source for an intersecting pair: the overlap of the triangles' world boxes.
template <class S>
fcl::CostSource<S> costSource(const Vec3<double> P[3], const Vec3<double> Q[3], S density) {
  fcl::AABB<S> a(fcl::Vector3<S>(S(P[0].x), S(P[0].y), S(P[0].z)),
                 fcl::Vector3<S>(S(P[1].x), S(P[1].y), S(P[1].z)),
                 fcl::Vector3<S>(S(P[2].x), S(P[2].y), S(P[2].z)));
  fcl::AABB<S> b(fcl::Vector3<S>(S(Q[0].x), S(Q[0].y), S(Q[0].z)),
                 fcl::Vector3<S>(S(Q[1].x), S(Q[1].y), S(Q[1].z)),
                 fcl::Vector3<S>(S(Q[2].x), S(Q[2].y), S(Q[2].z)));
  fcl::AABB<S> overlap;
  a.overlap(b, overlap);
  return fcl::CostSource<S>(overlap, density);
}

/// A contact without contact values: FCL leaves pos/normal/depth uninitialised; zeros here.
template <class S>
fcl::Contact<S> plainContact(const fcl::CollisionGeometry<S>* g1,
                             const fcl::CollisionGeometry<S>* g2, const TrianglePair& p) {
  return fcl::Contact<S>(g1, g2, int(p.a), int(p.b), fcl::Vector3<S>::Zero(),
                         fcl::Vector3<S>::Zero(), S(0));
}

/// Turns kDet's pairs into FCL contacts/cost sources. `va`/`vb` are the coordinates the exact
/// test used (A mapped into B's frame, and B), `to_world` maps B's frame to the world.
template <class S>
void emitPairs(const std::vector<TrianglePair>& pairs, const Vec3<S>* va, const Triangle* ta,
               const Vec3<S>* vb, const Triangle* tb, const Transform<double>& to_world,
               const fcl::CollisionGeometry<S>* g1, const fcl::CollisionGeometry<S>* g2,
               bool occupied, const fcl::CollisionRequest<S>& req, fcl::CollisionResult<S>& res) {
  const S density = g1->cost_density * g2->cost_density;
  for (const TrianglePair& pr : pairs) {
    const bool add = occupied && res.numContacts() < req.num_max_contacts;
    if (!add && !req.enable_cost) break;
    if (!req.enable_contact && !req.enable_cost) {
      res.addContact(plainContact(g1, g2, pr));
      continue;
    }
    Vec3<double> P[3], Q[3];
    for (int k = 0; k < 3; ++k) {
      P[k] = toD(va[ta[pr.a][k]]);
      Q[k] = toD(vb[tb[pr.b][k]]);
    }
    if (add) {
      if (req.enable_contact) {
        const detail::TriangleContact c = detail::triangleContact(P, Q);
        res.addContact(fcl::Contact<S>(g1, g2, int(pr.a), int(pr.b), toWorld<S>(to_world, c.pos),
                                       rotateToWorld<S>(to_world, c.normal), S(c.depth)));
      } else {
        res.addContact(plainContact(g1, g2, pr));
      }
    }
    if (req.enable_cost) {
      Vec3<double> Pw[3], Qw[3];
      for (int k = 0; k < 3; ++k) {
        Pw[k] = to_world.apply(P[k]);
        Qw[k] = to_world.apply(Q[k]);
      }
      res.addCostSource(costSource<S>(Pw, Qw, density), req.num_max_cost_sources);
    }
  }
}

/// Whether the pair adds anything, FCL's leaf rule: contacts need both occupied; cost sources
/// need enable_cost and neither free.
template <class S>
bool pairMatters(const fcl::CollisionGeometry<S>* g1, const fcl::CollisionGeometry<S>* g2,
                 const fcl::CollisionRequest<S>& req, bool& occupied) {
  occupied = g1->isOccupied() && g2->isOccupied();
  return occupied || (req.enable_cost && !g1->isFree() && !g2->isFree());
}

/// Whether the two meshes' local bounding boxes, placed at their poses, are disjoint by more than
/// rounding (a 15-axis separating-axis test in double, boxes grown by a relative 1e-9 so touching
/// pairs are never lost). Lets non-overlapping poses skip kDet's per-triangle scans. Uses the
/// vertex boxes HashedMesh keeps current, so it never forces a CPU re-hash (the query may run on
/// the GPU).
template <class S>
bool boxesApart(const HashedMesh<S>& a, const HashedMesh<S>& b) {
  const detail::Aabb<double>& ba = a.localBounds();
  const detail::Aabb<double>& bb = b.localBounds();
  if (a.numTriangles() == 0 || b.numTriangles() == 0) return true;
  const Transform<double> pa = detail::toDouble(a.pose()), pb = detail::toDouble(b.pose());
  double ha[3], hb[3], scale = 0;
  Vec3<double> ca, cb;
  for (int k = 0; k < 3; ++k) {
    ha[k] = 0.5 * (ba.hi[k] - ba.lo[k]);
    hb[k] = 0.5 * (bb.hi[k] - bb.lo[k]);
    ca[k] = 0.5 * (ba.hi[k] + ba.lo[k]);
    cb[k] = 0.5 * (bb.hi[k] + bb.lo[k]);
    scale += std::fabs(ba.lo[k]) + std::fabs(ba.hi[k]) + std::fabs(bb.lo[k]) + std::fabs(bb.hi[k]) +
             std::fabs(pa.t[k]) + std::fabs(pb.t[k]);
  }
  const Vec3<double> wa = pa.apply(ca), wb = pb.apply(cb), d = wb - wa;
  const double tol = 1e-9 * scale + 1e-300;
  Vec3<double> A[3], B[3];  // box axes in world
  for (int k = 0; k < 3; ++k) {
    A[k] = {pa.R[0][k], pa.R[1][k], pa.R[2][k]};
    B[k] = {pb.R[0][k], pb.R[1][k], pb.R[2][k]};
  }
  auto separated = [&](const Vec3<double>& axis) {
    const double n = std::sqrt(dot(axis, axis));
    if (!(n > 1e-12)) return false;
    double ra = 0, rb = 0;
    for (int k = 0; k < 3; ++k) {
      ra += ha[k] * std::fabs(dot(A[k], axis));
      rb += hb[k] * std::fabs(dot(B[k], axis));
    }
    return std::fabs(dot(d, axis)) > ra + rb + tol * n;
  };
  for (int k = 0; k < 3; ++k)
    if (separated(A[k]) || separated(B[k])) return true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (separated(cross(A[i], B[j]))) return true;
  return false;
}

template <class S>
std::size_t meshCollide(const fcl::CollisionGeometry<S>* g1, const FclMeshView<S>& v1,
                        const fcl::Transform3<S>& tf1, const fcl::CollisionGeometry<S>* g2,
                        const FclMeshView<S>& v2, const fcl::Transform3<S>& tf2,
                        const fcl::CollisionRequest<S>& req, fcl::CollisionResult<S>& res) {
  if (req.isSatisfied(res)) return res.numContacts();
  bool occupied = false;
  if (!pairMatters(g1, g2, req, occupied)) return res.numContacts();
  const Transform<S> p1 = toKdet(tf1), p2 = toKdet(tf2);

  const std::shared_ptr<FclMeshEntry<S>> e1 = entryFor(g1, v1);
  const std::shared_ptr<FclMeshEntry<S>> e2 = entryFor(g2, v2);
  std::unique_lock<std::mutex> l1(e1->mutex, std::defer_lock), l2(e2->mutex, std::defer_lock);
  if (e1 == e2) {
    l1.lock();
  } else {
    std::lock(l1, l2);
  }
  detail::syncEntry(*e1, v1);
  if (e1 != e2) detail::syncEntry(*e2, v2);

  HashedMesh<S>& a = *e1->hashed;
  HashedMesh<S>* b = e2->hashed.get();
  if (e1 == e2 && !samePose(p1, p2)) {
    // One mesh at two poses needs two hashes (a HashedMesh has one pose).
    if (!e1->twin || e1->twin_of != a.version()) {
      e1->twin = std::make_unique<HashedMesh<S>>(a.mesh(), Transform<S>::identity(),
                                                 collideOptions().threads);
      e1->twin_of = a.version();
    }
    b = e1->twin.get();
  }
  a.setPose(p1);   // validates: throws InvalidInputError for non-rigid rotations
  b->setPose(p2);

  if (boxesApart(a, *b)) return res.numContacts();
  QueryOptions opt = collideOptions();
  opt.max_pairs = (occupied && !req.enable_cost) ? req.num_max_contacts - res.numContacts() : 0;
  const QueryResult qr = intersectMeshes(a, *b, opt);
  if (qr.pairs.empty()) return res.numContacts();

  // The coordinates the exact test used: A mapped into B's frame (detail/pose.h), and B.
  const TriangleMesh<S>& ma = a.mesh();
  const TriangleMesh<S>& mb = b->mesh();
  const detail::RelativePose rp = detail::relativePose(a.pose(), b->pose());
  std::vector<Vec3<S>> mapped;
  const Vec3<S>* va = ma.vertices.data();
  if ((req.enable_contact || req.enable_cost) && !rp.identity) {
    mapped.resize(ma.vertices.size());
    for (std::size_t i = 0; i < mapped.size(); ++i)
      mapped[i] = detail::mapPoint(rp.a_to_b, ma.vertices[i]);
    va = mapped.data();
  }
  emitPairs(qr.pairs, va, ma.triangles.data(), mb.vertices.data(), mb.triangles.data(),
            detail::toDouble(b->pose()), g1, g2, occupied, req, res);
  return res.numContacts();
}

}  // namespace

// ---- Public functions ----

template <typename S>
std::size_t collide(const fcl::CollisionGeometry<S>* o1, const fcl::Transform3<S>& tf1,
                    const fcl::CollisionGeometry<S>* o2, const fcl::Transform3<S>& tf2,
                    const fcl::CollisionRequest<S>& request, fcl::CollisionResult<S>& result) {
  if (request.num_max_contacts == 0) {
    std::cerr << "Warning: should stop early as num_max_contact is " << request.num_max_contacts
              << " !\n";
    return 0;
  }
  if (o1 == nullptr || o2 == nullptr) throw InvalidInputError("kdet_fcl::collide: null geometry");
  requireFinite(tf1, "collide");
  requireFinite(tf2, "collide");
  FclMeshView<S> v1, v2;
  const bool bvh1 = detail::viewOf(o1, v1), bvh2 = detail::viewOf(o2, v2);
  if (bvh1 && bvh2 && v1.triangles_model && v2.triangles_model)
    return meshCollide(o1, v1, tf1, o2, v2, tf2, request, result);
  // An empty BVHModel (no vertices, no triangles: FCL's type "unknown") meets nothing. FCL's own
  // traversal would read its missing hierarchy and crash.
  auto empty = [](const FclMeshView<S>& v) { return v.num_vertices == 0 && v.num_tris == 0; };
  if ((bvh1 && empty(v1)) || (bvh2 && empty(v2))) return result.numContacts();
  prepareForFcl(o1, "collide");
  prepareForFcl(o2, "collide");
  if (request.gjk_solver_type == fcl::GST_LIBCCD &&
      detail::libccdCollideCrashes(o1->getNodeType(), o2->getNodeType())) {
    fcl::CollisionRequest<S> indep = request;  // libccd's test segfaults; FCL's other one answers
    indep.gjk_solver_type = fcl::GST_INDEP;
    return fcl::collide(o1, tf1, o2, tf2, indep, result);
  }
  return fcl::collide(o1, tf1, o2, tf2, request, result);
}

/// Throws InvalidInputError for a null collision object (`what`: the call).
template <typename S>
void requireObject(const fcl::CollisionObject<S>* o, const char* what) {
  if (o == nullptr) throw InvalidInputError(std::string("kdet_fcl::") + what + ": null object");
}

template <typename S>
std::size_t collide(const fcl::CollisionObject<S>* o1, const fcl::CollisionObject<S>* o2,
                    const fcl::CollisionRequest<S>& request, fcl::CollisionResult<S>& result) {
  requireObject(o1, "collide");
  requireObject(o2, "collide");
  return kdet_fcl::collide(o1->collisionGeometry().get(), o1->getTransform(),
                 o2->collisionGeometry().get(), o2->getTransform(), request, result);
}

template <typename S>
std::size_t selfCollide(const fcl::CollisionGeometry<S>* g, const fcl::Transform3<S>& tf,
                        const fcl::CollisionRequest<S>& req, fcl::CollisionResult<S>& res) {
  if (req.num_max_contacts == 0) {
    std::cerr << "Warning: should stop early as num_max_contact is " << req.num_max_contacts
              << " !\n";
    return 0;
  }
  if (g == nullptr) throw InvalidInputError("kdet_fcl::selfCollide: null geometry");
  requireFinite(tf, "selfCollide");
  FclMeshView<S> v;
  if (!detail::viewOf(g, v) || !v.triangles_model) return res.numContacts();
  if (req.isSatisfied(res)) return res.numContacts();
  bool occupied = false;
  if (!pairMatters(g, g, req, occupied)) return res.numContacts();

  const std::shared_ptr<FclMeshEntry<S>> e = entryFor(g, v);
  std::lock_guard<std::mutex> lock(e->mutex);
  detail::syncEntry(*e, v);
  HashedMesh<S>& m = *e->hashed;
  m.setPose(toKdet(tf));
  QueryOptions opt = collideOptions();
  opt.max_pairs = (occupied && !req.enable_cost) ? req.num_max_contacts - res.numContacts() : 0;
  const QueryResult qr = intersectSelf(m, opt);
  const TriangleMesh<S>& mesh = m.mesh();
  emitPairs(qr.pairs, mesh.vertices.data(), mesh.triangles.data(), mesh.vertices.data(),
            mesh.triangles.data(), detail::toDouble(m.pose()), g, g, occupied, req, res);
  return res.numContacts();
}

template <typename S>
std::size_t selfCollide(const fcl::CollisionObject<S>* o, const fcl::CollisionRequest<S>& request,
                        fcl::CollisionResult<S>& result) {
  requireObject(o, "selfCollide");
  return kdet_fcl::selfCollide(o->collisionGeometry().get(), o->getTransform(), request, result);
}

template <typename S>
S distance(const fcl::CollisionGeometry<S>* o1, const fcl::Transform3<S>& tf1,
           const fcl::CollisionGeometry<S>* o2, const fcl::Transform3<S>& tf2,
           const fcl::DistanceRequest<S>& request, fcl::DistanceResult<S>& result) {
  if (o1 == nullptr || o2 == nullptr) throw InvalidInputError("kdet_fcl::distance: null geometry");
  requireFinite(tf1, "distance");
  requireFinite(tf2, "distance");
  prepareForFcl(o1, "distance");
  prepareForFcl(o2, "distance");
  if (detail::distanceToUnboundedShape(o1->getNodeType(), o1->getObjectType(), o2->getNodeType(),
                                       o2->getObjectType()))
    throw UnsupportedQueryError(
        "kdet_fcl::distance: a distance to a Halfspace or Plane, which FCL 0.7 answers with a "
        "segfault under GST_LIBCCD (its default) and wrongly under GST_INDEP");
  return fcl::distance(o1, tf1, o2, tf2, request, result);
}

template <typename S>
S distance(const fcl::CollisionObject<S>* o1, const fcl::CollisionObject<S>* o2,
           const fcl::DistanceRequest<S>& request, fcl::DistanceResult<S>& result) {
  requireObject(o1, "distance");
  requireObject(o2, "distance");
  return kdet_fcl::distance(o1->collisionGeometry().get(), o1->getTransform(),
                  o2->collisionGeometry().get(), o2->getTransform(), request, result);
}

template <typename S>
bool DefaultCollisionFunction(fcl::CollisionObject<S>* o1, fcl::CollisionObject<S>* o2,
                              void* data) {
  if (data == nullptr)
    throw InvalidInputError(
        "kdet_fcl::DefaultCollisionFunction: null data (an fcl::DefaultCollisionData)");
  auto* cdata = static_cast<fcl::DefaultCollisionData<S>*>(data);
  const fcl::CollisionRequest<S>& request = cdata->request;
  fcl::CollisionResult<S>& result = cdata->result;
  if (cdata->done) return true;
  kdet_fcl::collide(o1, o2, request, result);
  if (!request.enable_cost && result.isCollision() &&
      result.numContacts() >= request.num_max_contacts)
    cdata->done = true;
  return cdata->done;
}

template <typename S>
bool DefaultDistanceFunction(fcl::CollisionObject<S>* o1, fcl::CollisionObject<S>* o2, void* data,
                             S& dist) {
  if (data == nullptr)
    throw InvalidInputError(
        "kdet_fcl::DefaultDistanceFunction: null data (an fcl::DefaultDistanceData)");
  auto* cdata = static_cast<fcl::DefaultDistanceData<S>*>(data);
  const fcl::DistanceRequest<S>& request = cdata->request;
  fcl::DistanceResult<S>& result = cdata->result;
  if (cdata->done) {
    dist = result.min_distance;
    return true;
  }
  kdet_fcl::distance(o1, o2, request, result);
  dist = result.min_distance;
  if (dist <= 0) return true;  // in collision or in touch
  return cdata->done;
}

template <typename S>
bool isKdetMesh(const fcl::CollisionGeometry<S>* geometry) {
  FclMeshView<S> v;
  return detail::viewOf(geometry, v) && v.triangles_model;
}

template <typename S>
void notifyDeformed(const fcl::CollisionGeometry<S>* geometry) {
  FclMeshView<S> v;
  if (!detail::viewOf(geometry, v)) return;
  if (v.kdet_mesh != nullptr) {
    std::lock_guard<std::mutex> lock(detail::MeshAccess<S>::entry(*v.kdet_mesh)->mutex);
    const_cast<Mesh<S>*>(v.kdet_mesh)->notifyDeformed();
    return;
  }
  Cache<S>& c = Cache<S>::get();
  std::lock_guard<std::mutex> lock(c.mutex);
  auto it = c.entries.find(geometry);
  if (it != c.entries.end()) it->second->dirty.store(true);
}

template <typename S>
void forget(const fcl::CollisionGeometry<S>* geometry) {
  Cache<S>& c = Cache<S>::get();
  std::lock_guard<std::mutex> lock(c.mutex);
  c.entries.erase(geometry);
}

void clearCache() {
  {
    std::lock_guard<std::mutex> lock(Cache<float>::get().mutex);
    Cache<float>::get().entries.clear();
  }
  std::lock_guard<std::mutex> lock(Cache<double>::get().mutex);
  Cache<double>::get().entries.clear();
}

std::size_t cacheSize() {
  std::size_t n = 0;
  {
    std::lock_guard<std::mutex> lock(Cache<float>::get().mutex);
    n += Cache<float>::get().entries.size();
  }
  std::lock_guard<std::mutex> lock(Cache<double>::get().mutex);
  return n + Cache<double>::get().entries.size();
}

#define KDET_FCL_INSTANTIATE(S)                                                                  \
  template std::size_t collide(const fcl::CollisionObject<S>*, const fcl::CollisionObject<S>*,  \
                               const fcl::CollisionRequest<S>&, fcl::CollisionResult<S>&);      \
  template std::size_t collide(const fcl::CollisionGeometry<S>*, const fcl::Transform3<S>&,     \
                               const fcl::CollisionGeometry<S>*, const fcl::Transform3<S>&,     \
                               const fcl::CollisionRequest<S>&, fcl::CollisionResult<S>&);      \
  template std::size_t selfCollide(const fcl::CollisionObject<S>*,                               \
                                   const fcl::CollisionRequest<S>&, fcl::CollisionResult<S>&);  \
  template std::size_t selfCollide(const fcl::CollisionGeometry<S>*, const fcl::Transform3<S>&, \
                                   const fcl::CollisionRequest<S>&, fcl::CollisionResult<S>&);  \
  template S distance(const fcl::CollisionObject<S>*, const fcl::CollisionObject<S>*,           \
                      const fcl::DistanceRequest<S>&, fcl::DistanceResult<S>&);                 \
  template S distance(const fcl::CollisionGeometry<S>*, const fcl::Transform3<S>&,              \
                      const fcl::CollisionGeometry<S>*, const fcl::Transform3<S>&,              \
                      const fcl::DistanceRequest<S>&, fcl::DistanceResult<S>&);                 \
  template bool DefaultCollisionFunction(fcl::CollisionObject<S>*, fcl::CollisionObject<S>*,    \
                                         void*);                                                 \
  template bool DefaultDistanceFunction(fcl::CollisionObject<S>*, fcl::CollisionObject<S>*,     \
                                        void*, S&);                                              \
  template bool isKdetMesh(const fcl::CollisionGeometry<S>*);                                    \
  template void notifyDeformed(const fcl::CollisionGeometry<S>*);                                \
  template void forget(const fcl::CollisionGeometry<S>*);

namespace detail {

void prepareFclQuery(const fcl::CollisionGeometryd* a, const fcl::Transform3d& ta,
                     const fcl::CollisionGeometryd* b, const fcl::Transform3d& tb,
                     const char* what) {
  if (a == nullptr || b == nullptr)
    throw InvalidInputError(std::string("kdet_fcl::") + what + ": null geometry");
  requireFinite(ta, what);
  requireFinite(tb, what);
  prepareForFcl(a, what);
  prepareForFcl(b, what);
}

}  // namespace detail

KDET_FCL_INSTANTIATE(float)
KDET_FCL_INSTANTIATE(double)
#undef KDET_FCL_INSTANTIATE

}  // namespace kdet_fcl
