"""Every ordered pair of python-fcl's geometry types through kdet_fcl.fcl: collide, distance and
signed distance (both GJK solvers) with the pair overlapping, apart and exactly touching along x;
with --ccd also continuousCollide (every motion and solver type). Each query must give a number or
raise UnsupportedQueryError: FCL 0.7 crashes, hangs or aborts on some of these (python-fcl passes
them on), which kdet_fcl.fcl refuses or answers another way.

    python3 fcl_pair_sweep.py [--quick] [--ccd] [--random N [--seed S]]

Prints one line per query and exits 1 on any other exception. A crash or a hang ends the
process: run it in a child process (test_fcl_api.py does) or under `timeout`.
--quick: one solver except at the touching poses (the tests' run).
--random N: also N random poses per pair of bounded types (a third of them on a 0.1 grid, where
exact contacts happen; half of them turned), distance, signed distance and collide, both solvers.
"""
import itertools
import sys

import numpy as np

import kdet_fcl
from kdet_fcl import fcl

sys.path.insert(0, __file__.rsplit("/", 1)[0])
import meshes as M  # noqa: E402

CUBE_V = np.array([[x, y, z] for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)])
CUBE_FLAT = np.concatenate([[4] + f for f in ([0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1],
                                              [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3])])
VOXEL = bytes([0x00, 0xC0] + [0x03, 0x00] * 14 + [0x02, 0x00])
MESH = M.sphere(0.7, 12, 8)

GEOMS = {
    "box": lambda: fcl.Box(1, 1, 1), "sphere": lambda: fcl.Sphere(0.5),
    "ellipsoid": lambda: fcl.Ellipsoid(.5, .4, .3), "capsule": lambda: fcl.Capsule(.3, 1),
    "cone": lambda: fcl.Cone(.5, 1), "cylinder": lambda: fcl.Cylinder(.5, 1),
    "convex": lambda: fcl.Convex(CUBE_V, 6, CUBE_FLAT),
    "halfspace": lambda: fcl.Halfspace(np.array([1., 0, 0]), 0.0),
    "plane": lambda: fcl.Plane(np.array([1., 0, 0]), 0.0),
    "triangle": lambda: fcl.TriangleP([0, 0, 0], [1, 0, 0], [0, 1, 0]),
    "mesh": lambda: M.fcl_mesh(*MESH), "octree": lambda: fcl.OcTree(0.1, VOXEL),
}
# How far each reaches along +x and -x from its origin (for the exactly touching pose).
PLUS = dict(box=.5, sphere=.5, ellipsoid=.5, capsule=.3, cone=.5, cylinder=.5, convex=.5,
            mesh=.7, octree=.1, halfspace=0.0, plane=0.0, triangle=1.0)
MINUS = dict(PLUS, octree=0.0, triangle=0.0)


def poses(a, b):
    return [("overlap", (0.2, 0.1, 0.05)), ("apart", (3.0, 0.2, 0.1)), ("coincident", (0, 0, 0)),
            ("touching", (-(PLUS[a] + MINUS[b]), 0.0, 0.0))]


def run(label, f):
    print(label, end=" ", flush=True)
    try:
        print("->", f(), flush=True)
        return True
    except kdet_fcl.UnsupportedQueryError as e:
        print("refused:", e, flush=True)
        return True
    except Exception as e:  # noqa: BLE001
        print("FAILED:", type(e).__name__, e, flush=True)
        return False


def main(argv):
    quick, ccd = "--quick" in argv, "--ccd" in argv
    ok, n = True, 0
    for a, b in itertools.product(GEOMS, GEOMS):
        g1, g2 = GEOMS[a](), GEOMS[b]()
        for name, t in poses(a, b):
            o1 = fcl.CollisionObject(g1, fcl.Transform(np.array(t, dtype=float)))
            o2 = fcl.CollisionObject(g2, fcl.Transform())
            for solver in ((0,) if quick and name != "touching" else (0, 1)):
                req = fcl.CollisionRequest(num_max_contacts=100, enable_contact=True,
                                           gjk_solver_type=solver)
                ok &= run("%s %s %s collide gjk=%d" % (a, b, name, solver),
                          lambda: fcl.collide(o1, o2, req, fcl.CollisionResult()))
                for signed in (False, True):
                    dreq = fcl.DistanceRequest(True, signed, solver)
                    ok &= run("%s %s %s %s gjk=%d" % (a, b, name, "sdist" if signed else "dist",
                                                       solver),
                              lambda: fcl.distance(o1, o2, dreq, fcl.DistanceResult()))
                n += 3
        if ccd:
            for motion, solver, gjk in itertools.product(range(4), range(4), range(2)):
                o1 = fcl.CollisionObject(g1, fcl.Transform(np.array([-3.0, 0, 0])))
                o2 = fcl.CollisionObject(g2, fcl.Transform())
                req = fcl.ContinuousCollisionRequest(ccd_motion_type=motion, ccd_solver_type=solver,
                                                     gjk_solver_type=gjk)
                ok &= run("%s %s ccd motion=%d solver=%d gjk=%d" % (a, b, motion, solver, gjk),
                          lambda: fcl.continuousCollide(
                              o1, fcl.Transform(np.array([3.0, 0, 0])), o2, fcl.Transform(), req,
                              fcl.ContinuousCollisionResult()))
                n += 1
    if "--random" in argv:
        rng = np.random.default_rng(int(argv[argv.index("--seed") + 1]) if "--seed" in argv else 1)
        count = int(argv[argv.index("--random") + 1])
        bounded = [g for g in GEOMS if g not in ("halfspace", "plane", "triangle")]
        for a, b in itertools.product(bounded, bounded):
            g1, g2 = GEOMS[a](), GEOMS[b]()
            for k in range(count):
                t = rng.uniform(-1.5, 1.5, 3)
                if k % 3 == 0:
                    t = np.round(t, 1)
                tf = fcl.Transform(rng.normal(size=4), t) if k % 2 else fcl.Transform(t)
                o1, o2 = fcl.CollisionObject(g1, tf), fcl.CollisionObject(g2, fcl.Transform())
                for solver in (0, 1):
                    req = fcl.CollisionRequest(gjk_solver_type=solver)
                    ok &= run("%s %s random %d collide gjk=%d" % (a, b, k, solver),
                              lambda: fcl.collide(o1, o2, req, fcl.CollisionResult()))
                    for signed in (False, True):
                        dreq = fcl.DistanceRequest(True, signed, solver)
                        ok &= run("%s %s random %d %s gjk=%d" % (
                            a, b, k, "sdist" if signed else "dist", solver),
                            lambda: fcl.distance(o1, o2, dreq, fcl.DistanceResult()))
                    n += 3
    print("%d queries: %s" % (n, "every query answered or refused" if ok else "SOME FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
