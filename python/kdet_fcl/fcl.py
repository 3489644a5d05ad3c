"""python-fcl's API for mesh collision, with kDet deciding the mesh pairs.

Code written for python-fcl changes its import and keeps the rest:

    from kdet_fcl import fcl            # was: import fcl
    m = fcl.BVHModel(); m.beginModel(len(tris), len(verts)); m.addSubModel(verts, tris); m.endModel()
    o1 = fcl.CollisionObject(m, fcl.Transform(R, t))
    request = fcl.CollisionRequest(num_max_contacts=10**9, enable_contact=True)
    result = fcl.CollisionResult()
    n = fcl.collide(o1, o2, request, result)   # one Contact per intersecting triangle pair

What is the same as python-fcl: the classes and calls below, their arguments and defaults,
results that accumulate in the Python result, Contact's fields (o1/o2 the geometries, b1/b2
the triangle indices, pos/normal/penetration_depth), DynamicAABBTreeCollisionManager with
Python callbacks (collide and distance, three forms each), and the default callbacks' stop
rules. Mesh-mesh pairs go through kdet_fcl::collide (the C++ drop-in: exact pairs, FCL's
conventions, README "Switching from FCL"); shape pairs (Box, Sphere, Convex, Halfspace, OcTree,
...) and distances go to FCL 0.7 itself. `python3 -m kdet_fcl.as_fcl program.py` runs a
python-fcl program unmodified on this module.

What differs, where FCL 0.7 would crash, hang or answer wrongly (python-fcl passes those on):
queries it has no test for, distances to a Halfspace or Plane and collisions of two unbounded
shapes raise UnsupportedQueryError (a NotImplementedError); unsigned distances run on GJK indep
and signed ones are decided by a collision test first (libccd aborts on touching shapes);
continuousCollide runs naive sampling (FCL's rule) or conservative advancement here, on the
discrete queries, for CCDM_TRANS and CCDM_LINEAR motions (README "Python").

What kDet adds: self_collide (FCL has none), BVHModel(kdet_only=True) for deforming meshes
(updates skip FCL's refit), and fcl_collide, FCL's own answer in the same process, for
cross-checks and timing.
"""
import sys

import numpy as np

from . import _kdet_fcl as _core
from ._kdet_fcl import (  # noqa: F401
    BVHModel,
    Box,
    Capsule,
    CollisionGeometry,
    Cone,
    Convex,
    Cylinder,
    Ellipsoid,
    Halfspace,
    InvalidInputError,
    Plane,
    Sphere,
    TriangleP,
    UnsupportedQueryError,
)

try:  # FCL built with octomap (Debian's is)
    from ._kdet_fcl import OcTree  # noqa: F401
except ImportError:  # pragma: no cover
    pass


class OBJECT_TYPE:
    OT_UNKNOWN, OT_BVH, OT_GEOM, OT_OCTREE, OT_COUNT = range(5)


class NODE_TYPE:
    (BV_UNKNOWN, BV_AABB, BV_OBB, BV_RSS, BV_kIOS, BV_OBBRSS, BV_KDOP16, BV_KDOP18, BV_KDOP24,
     GEOM_BOX, GEOM_SPHERE, GEOM_ELLIPSOID, GEOM_CAPSULE, GEOM_CONE, GEOM_CYLINDER,
     GEOM_CONVEX, GEOM_PLANE, GEOM_HALFSPACE, GEOM_TRIANGLE, GEOM_OCTREE, NODE_COUNT) = range(21)


class CCDMotionType:
    CCDM_TRANS, CCDM_LINEAR, CCDM_SCREW, CCDM_SPLINE = range(4)


class CCDSolverType:
    (CCDC_NAIVE, CCDC_CONSERVATIVE_ADVANCEMENT, CCDC_RAY_SHOOTING,
     CCDC_POLYNOMIAL_SOLVER) = range(4)


class GJKSolverType:
    GST_LIBCCD, GST_INDEP = range(2)


def _quat_to_matrix(q):
    """A (w, x, y, z) quaternion (python-fcl's order), normalized, as a rotation matrix."""
    q = np.asarray(q, dtype=np.float64).reshape(-1)
    if q.shape != (4,):
        raise ValueError("a quaternion is 4 numbers (w, x, y, z)")
    n = np.linalg.norm(q)
    if not np.isfinite(n) or n == 0:
        raise ValueError("the quaternion must be finite and non-zero")
    w, x, y, z = q / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _matrix_to_quat(R):
    """The (w, x, y, z) quaternion of a rotation matrix (w >= 0)."""
    R = np.asarray(R, dtype=np.float64)
    tr = np.trace(R)
    if tr > 0:
        s = 2.0 * np.sqrt(tr + 1.0)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
    q = np.array(q)
    return -q if q[0] < 0 else q


def _rotation(arg):
    """A 3x3 matrix or a (w, x, y, z) quaternion as a 3x3 float64 matrix."""
    a = np.asarray(arg, dtype=np.float64)
    if a.shape == (3, 3):
        return a.copy()
    if a.shape == (4,):
        return _quat_to_matrix(a)
    raise ValueError("a rotation is a 3x3 matrix or a (w, x, y, z) quaternion")


def _translation(arg):
    t = np.asarray(arg, dtype=np.float64).squeeze()
    if t.shape != (3,):
        raise ValueError("Translation must be (3,).")
    return t.copy()


class Transform:
    """A rigid transform: Transform(), Transform(R | q | t), Transform(R | q, t)."""

    def __init__(self, *args):
        self._R = np.eye(3)
        self._t = np.zeros(3)
        if len(args) == 1:
            a = args[0]
            if isinstance(a, Transform):
                self._R, self._t = a._R.copy(), a._t.copy()
                return
            shape = np.shape(a)
            if shape in ((3, 3), (4,)):
                self._R = _rotation(a)
            elif shape == (3,):
                self._t = _translation(a)
            else:
                raise ValueError("Invalid input to Transform().")
        elif len(args) == 2:
            self._R = _rotation(args[0])
            self._t = _translation(args[1])
        elif len(args) > 2:
            raise ValueError("Too many arguments to Transform().")

    def getRotation(self):
        return self._R.copy()

    def getTranslation(self):
        return self._t.copy()

    def getQuatRotation(self):
        return _matrix_to_quat(self._R)

    def setRotation(self, R):
        self._R = _rotation(R)

    def setTranslation(self, T):
        self._t = _translation(T)

    def setQuatRotation(self, q):
        self._R = _quat_to_matrix(q)


class CollisionObject(_core._ObjectCore):
    """A geometry at a pose (python-fcl's CollisionObject)."""

    def __init__(self, geom=None, tf=None, _no_instance=False):
        if geom is None:
            raise ValueError("CollisionObject needs a geometry (BVHModel, Box, Sphere, ...)")
        tf = Transform() if tf is None else tf
        super().__init__(geom, tf._R, tf._t)
        self._geom = geom

    def getTranslation(self):
        return self._translation()

    def setTranslation(self, vec):
        self._set_transform(self._rotation(), _translation(vec))

    def getRotation(self):
        return self._rotation()

    def setRotation(self, mat):
        self._set_transform(_rotation(mat), self._translation())

    def getQuatRotation(self):
        return _matrix_to_quat(self._rotation())

    def setQuatRotation(self, q):
        self._set_transform(_quat_to_matrix(q), self._translation())

    def getTransform(self):
        return Transform(self._rotation(), self._translation())

    def setTransform(self, tf):
        self._set_transform(tf._R, tf._t)

    @property
    def geometry(self):
        return self._geom


class Contact:
    def __init__(self):
        self.o1 = None
        self.o2 = None
        self.b1 = 0
        self.b2 = 0
        self.normal = np.zeros(3)
        self.pos = np.zeros(3)
        self.penetration_depth = 0.0


class CostSource:
    def __init__(self):
        self.aabb_min = np.zeros(3)
        self.aabb_max = np.zeros(3)
        self.cost_density = 0.0
        self.total_cost = 0.0


class CollisionRequest:
    def __init__(self, num_max_contacts=1, enable_contact=False, num_max_cost_sources=1,
                 enable_cost=False, use_approximate_cost=True,
                 gjk_solver_type=GJKSolverType.GST_LIBCCD):
        self.num_max_contacts = num_max_contacts
        self.enable_contact = enable_contact
        self.num_max_cost_sources = num_max_cost_sources
        self.enable_cost = enable_cost
        self.use_approximate_cost = use_approximate_cost
        self.gjk_solver_type = gjk_solver_type


class CollisionResult:
    def __init__(self, is_collision=False):
        self.is_collision = is_collision
        self.contacts = []
        self.cost_sources = []


class ContinuousCollisionRequest:
    def __init__(self, num_max_iterations=10, toc_err=0.0001,
                 ccd_motion_type=CCDMotionType.CCDM_TRANS,
                 gjk_solver_type=GJKSolverType.GST_LIBCCD,
                 ccd_solver_type=CCDSolverType.CCDC_CONSERVATIVE_ADVANCEMENT):
        self.num_max_iterations = num_max_iterations
        self.toc_err = toc_err
        self.ccd_motion_type = ccd_motion_type
        self.gjk_solver_type = gjk_solver_type
        self.ccd_solver_type = ccd_solver_type


class ContinuousCollisionResult:
    def __init__(self, is_collide=False, time_of_contact=1.0):
        self.is_collide = is_collide
        self.time_of_contact = time_of_contact


class DistanceRequest:
    def __init__(self, enable_nearest_points=False, enable_signed_distance=False,
                 gjk_solver_type=GJKSolverType.GST_LIBCCD):
        self.enable_nearest_points = enable_nearest_points
        self.enable_signed_distance = enable_signed_distance
        self.gjk_solver_type = gjk_solver_type


class DistanceResult:
    def __init__(self, min_distance_=sys.float_info.max):
        self.min_distance = min_distance_
        self.nearest_points = [None, None]
        self.o1 = None
        self.o2 = None
        self.b1 = -1
        self.b2 = -1


class CollisionData:
    def __init__(self, request=None, result=None):
        self.request = CollisionRequest() if request is None else request
        self.result = CollisionResult() if result is None else result
        self.done = False


class DistanceData:
    def __init__(self, request=None, result=None):
        self.request = DistanceRequest() if request is None else request
        self.result = DistanceResult() if result is None else result
        self.done = False


def _check_object(o, name):
    if not isinstance(o, CollisionObject):
        raise TypeError("%s must be a kdet_fcl.fcl.CollisionObject, not %s"
                        % (name, type(o).__name__))


def _fill(result, core_out, g1, g2):
    n, hit, ids, normal, pos, depth, swapped, costs = core_out
    result.is_collision = result.is_collision or bool(hit)
    for i in range(len(ids)):
        c = Contact()
        c.o1, c.o2 = (g2, g1) if swapped[i] else (g1, g2)
        c.b1, c.b2 = int(ids[i, 0]), int(ids[i, 1])
        c.normal, c.pos = normal[i], pos[i]
        c.penetration_depth = float(depth[i])
        result.contacts.append(c)
    lo, hi, density, total = costs if costs is not None else ((), (), (), ())
    for i in range(len(density)):
        c = CostSource()
        c.aabb_min, c.aabb_max = lo[i], hi[i]
        c.cost_density, c.total_cost = float(density[i]), float(total[i])
        result.cost_sources.append(c)
    return int(n)


def _collide(o1, o2, request, result, engine):
    _check_object(o1, "o1")
    _check_object(o2, "o2")
    request = CollisionRequest() if request is None else request
    result = CollisionResult() if result is None else result
    return _fill(result, _core._collide(o1, o2, request, engine), o1._geom, o2._geom)


def collide(o1, o2, request=None, result=None):
    """Collide two objects; mesh pairs are decided by kDet. Returns the contacts found (at
    most request.num_max_contacts) and appends them to result.contacts."""
    return _collide(o1, o2, request, result, "kdet")


def fcl_collide(o1, o2, request=None, result=None):
    """FCL 0.7's own fcl::collide on the same objects (cross-checks, timing)."""
    return _collide(o1, o2, request, result, "fcl")


def self_collide(o, request=None, result=None):
    """The triangle pairs inside one mesh object that intersect (pairs that share a vertex are
    not contacts); b1 < b2. FCL has no mesh self-collision."""
    _check_object(o, "o")
    request = CollisionRequest() if request is None else request
    result = CollisionResult() if result is None else result
    return _fill(result, _core._self_collide(o, request), o._geom, o._geom)


def distance(o1, o2, request=None, result=None):
    """FCL 0.7's distance (kdet_fcl::distance forwards it). Returns the distance."""
    _check_object(o1, "o1")
    _check_object(o2, "o2")
    request = DistanceRequest() if request is None else request
    result = DistanceResult() if result is None else result
    d, dmin, p0, p1, b1, b2, swapped = _core._distance(o1, o2, request)
    if result.min_distance > dmin:
        result.min_distance = dmin
        result.nearest_points = [p0, p1]
        result.o1, result.o2 = (o2._geom, o1._geom) if swapped else (o1._geom, o2._geom)
        result.b1, result.b2 = int(b1), int(b2)
    return d


def continuousCollide(o1, tf1_end, o2, tf2_end, request=None, result=None):
    """Continuous collision from the objects' poses to tf1_end/tf2_end: CCDC_NAIVE samples poses
    by FCL's rule, CCDC_CONSERVATIVE_ADVANCEMENT (the default) advances by distance and never
    reports a time after the first touch; both run here on the discrete queries (FCL 0.7's own
    crashes or misses contacts on most pairs). CCDM_TRANS and CCDM_LINEAR motions. Returns the
    time of contact in [0, 1] (1: none), as python-fcl does."""
    _check_object(o1, "o1")
    _check_object(o2, "o2")
    for tf, name in ((tf1_end, "tf1_end"), (tf2_end, "tf2_end")):
        if not isinstance(tf, Transform):
            raise TypeError("%s must be a kdet_fcl.fcl.Transform, not %s"
                            % (name, type(tf).__name__))
    request = ContinuousCollisionRequest() if request is None else request
    result = ContinuousCollisionResult() if result is None else result
    toc, hit, time_of_contact = _core._continuous_collide(
        o1, tf1_end._R, tf1_end._t, o2, tf2_end._R, tf2_end._t, request)
    result.is_collide = result.is_collide or bool(hit)
    result.time_of_contact = min(time_of_contact, result.time_of_contact)
    return toc


def defaultCollisionCallback(o1, o2, cdata):
    """python-fcl's default manager callback, on kDet: collide the pair into cdata.result and
    stop once more than num_max_contacts contacts are there (python-fcl's rule)."""
    if cdata.done:
        return True
    collide(o1, o2, cdata.request, cdata.result)
    request, result = cdata.request, cdata.result
    if (not request.enable_cost and result.is_collision
            and len(result.contacts) > request.num_max_contacts):
        cdata.done = True
    return cdata.done


def defaultDistanceCallback(o1, o2, cdata):
    if cdata.done:
        return True, cdata.result.min_distance
    distance(o1, o2, cdata.request, cdata.result)
    d = cdata.result.min_distance
    return (True, d) if d <= 0 else (cdata.done, d)


class DynamicAABBTreeCollisionManager(_core._ManagerCore):
    """FCL's DynamicAABBTree broadphase; callbacks are Python callables
    f(o1, o2, cdata) -> bool (True stops), such as defaultCollisionCallback."""

    def __init__(self):
        super().__init__()
        self._objs = []

    def registerObjects(self, other_objs):
        other_objs = list(other_objs)
        for o in other_objs:
            _check_object(o, "a registered object")
        self._register(other_objs)
        self._objs.extend(other_objs)

    def registerObject(self, obj):
        self.registerObjects([obj])

    def unregisterObject(self, obj):
        if obj in self._objs:
            self._unregister(obj)
            self._objs.remove(obj)

    def update(self, arg=None):
        if arg is None:
            self._update([])
        elif hasattr(arg, "__len__"):
            self._update(list(arg))
        else:
            self._update([arg])

    def getObjects(self):
        return list(self._objs)

    def clear(self):
        super().clear()
        self._objs = []

    def collide(self, *args):
        """collide(cdata, callback); collide(obj, cdata, callback);
        collide(other_manager, cdata, callback). A callback returns True to stop."""
        self._dispatch("collide", args, self._collide, self._collide_object,
                       self._collide_manager)

    def distance(self, *args):
        """distance(ddata, callback); distance(obj, ddata, callback);
        distance(other_manager, ddata, callback). A callback returns (stop, distance)."""
        self._dispatch("distance", args, self._distance, self._distance_object,
                       self._distance_manager)

    def _dispatch(self, name, args, all_pairs, with_object, with_manager):
        if len(args) == 2 and callable(args[1]):
            all_pairs(args[0], args[1])
        elif len(args) == 3 and isinstance(args[0], DynamicAABBTreeCollisionManager):
            with_manager(args[0], args[1], args[2])
        elif len(args) == 3 and isinstance(args[0], CollisionObject) and callable(args[2]):
            with_object(args[0], args[1], args[2])
        else:
            raise ValueError("%s(data, callback), %s(obj, data, callback) or "
                             "%s(manager, data, callback)" % (name, name, name))


__all__ = [
    "CollisionObject", "CollisionGeometry", "Transform", "TriangleP", "Box", "Sphere",
    "Ellipsoid", "Capsule", "Cone", "Convex", "Cylinder", "Halfspace", "Plane", "BVHModel",
    "DynamicAABBTreeCollisionManager", "collide", "continuousCollide", "distance",
    "defaultCollisionCallback", "defaultDistanceCallback", "OBJECT_TYPE", "NODE_TYPE",
    "CCDMotionType", "CCDSolverType", "GJKSolverType", "Contact", "CostSource",
    "CollisionRequest", "CollisionResult", "ContinuousCollisionRequest",
    "ContinuousCollisionResult", "DistanceRequest", "DistanceResult", "CollisionData",
    "DistanceData", "self_collide", "fcl_collide", "InvalidInputError", "UnsupportedQueryError",
] + (["OcTree"] if "OcTree" in globals() else [])
