// kdet_fcl::guardedCollide and guardedDistance (include/kdet_fcl/fcl_guarded.h): FCL 0.7's
// collide and distance with the pairs and poses where it crashes, hangs or has no answer refused
// or answered another way (the sweep: benchmarks/results/python-compat/).
#include "kdet_fcl/fcl_guarded.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <new>
#include <string>

#include "kdet_fcl/fcl_collide.h"
#include "kdet_fcl/fcl_mesh.h"
#include "prepare_fcl_query.h"
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision-inl.h>
#include <fcl/narrowphase/distance-inl.h>

namespace kdet_fcl {
namespace {

using Geometry = fcl::CollisionGeometryd;

std::string nodeName(fcl::NODE_TYPE t) {
  switch (t) {
    case fcl::GEOM_BOX: return "Box";
    case fcl::GEOM_SPHERE: return "Sphere";
    case fcl::GEOM_ELLIPSOID: return "Ellipsoid";
    case fcl::GEOM_CAPSULE: return "Capsule";
    case fcl::GEOM_CONE: return "Cone";
    case fcl::GEOM_CYLINDER: return "Cylinder";
    case fcl::GEOM_CONVEX: return "Convex";
    case fcl::GEOM_PLANE: return "Plane";
    case fcl::GEOM_HALFSPACE: return "Halfspace";
    case fcl::GEOM_TRIANGLE: return "TriangleP";
    case fcl::GEOM_OCTREE: return "OcTree";
    default: return t >= fcl::BV_AABB && t <= fcl::BV_KDOP24 ? "BVHModel" : "geometry";
  }
}

bool unbounded(fcl::NODE_TYPE t) { return t == fcl::GEOM_HALFSPACE || t == fcl::GEOM_PLANE; }

std::string pairName(const Geometry* a, const Geometry* b) {
  return nodeName(a->getNodeType()) + " and " + nodeName(b->getNodeType());
}

/// Whether FCL's table of a solver's functions has one for a pair of these node and object types
/// (looked up as FCL does).
template <class Table>
bool inTable(const Table& table, fcl::NODE_TYPE na, fcl::OBJECT_TYPE oa, fcl::NODE_TYPE nb,
             fcl::OBJECT_TYPE ob) {
  if (oa == fcl::OT_GEOM && ob == fcl::OT_BVH) return table[nb][na];
  return table[na][nb];
}
template <class Table>
bool inTable(const Table& table, const Geometry* a, const Geometry* b) {
  return inTable(table, a->getNodeType(), a->getObjectType(), b->getNodeType(),
                 b->getObjectType());
}

/// FCL 0.7's answer, with its exceptions (such as "Error with configuration" from the signed
/// distance of coincident cylinders) as UnsupportedQueryError.
template <class F>
auto fromFcl(F f, const Geometry* a, const Geometry* b) {
  try {
    return f();
  } catch (const Error&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    throw UnsupportedQueryError("FCL 0.7 failed on " + pairName(a, b) + ": " + e.what());
  }
}

void requireGeometries(const Geometry* a, const Geometry* b, const char* what) {
  if (a == nullptr || b == nullptr) throw InvalidInputError(std::string(what) + ": null geometry");
}

/// Whether FCL 0.7 lists a distance for a pair of these types (either solver's table: they list
/// the same pairs; for float geometries too: the tables are registered by node type alike).
bool hasDistance(fcl::NODE_TYPE na, fcl::OBJECT_TYPE oa, fcl::NODE_TYPE nb, fcl::OBJECT_TYPE ob) {
  return inTable(fcl::getDistanceFunctionLookTable<fcl::detail::GJKSolver_indep<double>>()
                     .distance_matrix, na, oa, nb, ob);
}

/// Checks that FCL 0.7 has a distance for a and b that neither crashes nor answers wrongly.
void checkDistance(const Geometry* a, const Geometry* b) {
  if (!hasDistance(a->getNodeType(), a->getObjectType(), b->getNodeType(), b->getObjectType()))
    throw UnsupportedQueryError("FCL 0.7 has no distance for " + pairName(a, b));  // DBL_MAX
  if (detail::distanceToUnboundedShape(a->getNodeType(), a->getObjectType(), b->getNodeType(),
                                       b->getObjectType()))
    throw UnsupportedQueryError("distance: FCL 0.7 crashes on " + pairName(a, b) +
                                " with GST_LIBCCD and answers wrongly with GST_INDEP");
}

/// Two spheres' signed distance in closed form; the nearest points on the line of the centres,
/// in world coordinates as FCL gives them; coincident centres take +x.
double sphereSphereSigned(const fcl::Sphered& s1, const fcl::Transform3d& t1,
                          const fcl::Sphered& s2, const fcl::Transform3d& t2,
                          fcl::DistanceResultd& result) {
  const fcl::Vector3d c1 = t1.translation(), c2 = t2.translation();
  const double len = (c2 - c1).norm();
  const fcl::Vector3d u = len > 0 ? fcl::Vector3d((c2 - c1) / len) : fcl::Vector3d::UnitX();
  const double d = len - s1.radius - s2.radius;
  result.update(d, &s1, &s2, fcl::DistanceResultd::NONE, fcl::DistanceResultd::NONE,
                c1 + s1.radius * u, c2 - s2.radius * u);
  return d;
}

}  // namespace

namespace detail {

bool libccdCollideCrashes(fcl::NODE_TYPE a, fcl::NODE_TYPE b) {
  return (a == fcl::GEOM_CONVEX && b == fcl::GEOM_PLANE) ||
         (a == fcl::GEOM_PLANE && b == fcl::GEOM_CONVEX);
}

bool distanceToUnboundedShape(fcl::NODE_TYPE a, fcl::OBJECT_TYPE a_object, fcl::NODE_TYPE b,
                              fcl::OBJECT_TYPE b_object) {
  return (unbounded(a) || unbounded(b)) && hasDistance(a, a_object, b, b_object);
}

}  // namespace detail

fcl::GJKSolverType guardedCollideSolver(const Geometry* a, const Geometry* b,
                                        fcl::GJKSolverType requested) {
  requireGeometries(a, b, "guardedCollide");
  const bool listed =
      requested == fcl::GST_INDEP
          ? inTable(fcl::getCollisionFunctionLookTable<fcl::detail::GJKSolver_indep<double>>()
                        .collision_matrix, a, b)
          : inTable(fcl::getCollisionFunctionLookTable<fcl::detail::GJKSolver_libccd<double>>()
                        .collision_matrix, a, b);
  const fcl::NODE_TYPE na = a->getNodeType(), nb = b->getNodeType();
  if (!listed)  // FCL prints a warning and answers "no collision"
    throw UnsupportedQueryError(
        "FCL 0.7 has no collision test for " + pairName(a, b) +
        (na == fcl::GEOM_TRIANGLE || nb == fcl::GEOM_TRIANGLE
             ? " (a TriangleP collides with nothing: use a one-triangle BVHModel)"
             : ""));
  if (unbounded(na) && unbounded(nb))
    throw UnsupportedQueryError("collide: FCL 0.7 answers " + pairName(a, b) +
                                " wrongly (overlapping ones are reported apart when contacts are "
                                "asked for)");
  if (detail::libccdCollideCrashes(na, nb)) return fcl::GST_INDEP;  // libccd's test crashes
  return requested;
}

std::size_t guardedCollide(const Geometry* a, const fcl::Transform3d& ta, const Geometry* b,
                           const fcl::Transform3d& tb, const fcl::CollisionRequestd& request,
                           fcl::CollisionResultd& result, CollideEngine engine) {
  fcl::CollisionRequestd r = request;
  r.gjk_solver_type = guardedCollideSolver(a, b, request.gjk_solver_type);
  if (engine == CollideEngine::Kdet)
    return fromFcl([&] { return kdet_fcl::collide(a, ta, b, tb, r, result); }, a, b);
  detail::prepareFclQuery(a, ta, b, tb, "guardedCollide");
  return fromFcl([&] { return fcl::collide(a, ta, b, tb, r, result); }, a, b);
}

double guardedDistance(const Geometry* a, const fcl::Transform3d& ta, const Geometry* b,
                       const fcl::Transform3d& tb, const fcl::DistanceRequestd& request,
                       fcl::DistanceResultd& result) {
  requireGeometries(a, b, "guardedDistance");
  checkDistance(a, b);
  fcl::DistanceRequestd r = request;
  r.enable_signed_distance = false;
  r.gjk_solver_type = fcl::GST_INDEP;
  auto unsignedDistance = [&] {
    return fromFcl([&] { return kdet_fcl::distance(a, ta, b, tb, r, result); }, a, b);
  };
  // FCL's distance of two meshes has no sign (0 where they intersect): the unsigned one.
  if (!request.enable_signed_distance ||
      (a->getObjectType() == fcl::OT_BVH && b->getObjectType() == fcl::OT_BVH))
    return unsignedDistance();
  if (a->getNodeType() == fcl::GEOM_SPHERE && b->getNodeType() == fcl::GEOM_SPHERE) {
    detail::prepareFclQuery(a, ta, b, tb, "guardedDistance");  // the poses' check
    return sphereSphereSigned(static_cast<const fcl::Sphered&>(*a), ta,
                              static_cast<const fcl::Sphered&>(*b), tb, result);
  }
  fcl::CollisionRequestd crequest(std::numeric_limits<int>::max(), true);
  crequest.gjk_solver_type = guardedCollideSolver(a, b, fcl::GST_LIBCCD);
  fcl::CollisionResultd contacts;
  if (fromFcl([&] { return kdet_fcl::collide(a, ta, b, tb, crequest, contacts); }, a, b) == 0) {
    const double d = unsignedDistance();
    if (d >= 0) return d;
    // The collision test finds them apart, GST_INDEP's GJK in contact: they touch within FCL's
    // tolerance (about 1e-6). The distance is 0; there are no nearest points to give.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    result = fcl::DistanceResultd();
    result.update(0.0, a, b, fcl::DistanceResultd::NONE, fcl::DistanceResultd::NONE,
                  fcl::Vector3d::Constant(nan), fcl::Vector3d::Constant(nan));
    return 0.0;
  }
  std::size_t deepest = 0;
  for (std::size_t i = 1; i < contacts.numContacts(); ++i)
    if (contacts.getContact(i).penetration_depth > contacts.getContact(deepest).penetration_depth)
      deepest = i;
  const fcl::Contactd& contact = contacts.getContact(deepest);
  const double size = std::max(a->aabb_radius, b->aabb_radius);
  const fcl::Vector3d p = contact.pos;
  if (!(contact.penetration_depth > 1e-9 * size)) {
    result.update(0.0, a, b, fcl::DistanceResultd::NONE, fcl::DistanceResultd::NONE, p, p);
    return 0.0;
  }
  if (a->getObjectType() != fcl::OT_GEOM || b->getObjectType() != fcl::OT_GEOM) {
    // A mesh or an octree with a shape: FCL's own rule (minus a contact's penetration depth, both
    // nearest points at it), which FCL takes from one contact and asserts deeper than 0.
    result.update(-contact.penetration_depth, a, b, contact.b1, contact.b2, p, p);
    return -contact.penetration_depth;
  }
  r.enable_signed_distance = true;
  r.gjk_solver_type = fcl::GST_LIBCCD;
  return fromFcl([&] { return kdet_fcl::distance(a, ta, b, tb, r, result); }, a, b);
}

}  // namespace kdet_fcl
