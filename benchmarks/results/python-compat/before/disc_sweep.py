"""The discrete sweep of the session-55 record (before the guards): collide, FCL's collide,
distance and signed distance of every ordered pair at three poses, both solvers. Run by drive.sh."""
import itertools, sys, faulthandler
import numpy as np
from kdet_fcl import fcl
exec(open('geoms.py').read())
start = int(sys.argv[1]) if len(sys.argv) > 1 else 0
names = list(geoms)
poses = [np.array([0.2, 0.1, 0.05]), np.array([3.0, 0.2, 0.1]), np.array([0.0, 0.0, 0.0])]
combos = [(a, b, p, op, g) for a, b in itertools.product(names, names) for p in range(3) for op in ("collide", "fcl_collide", "dist", "sdist") for g in range(2)]
for idx in range(start, len(combos)):
    a, b, p, op, g = combos[idx]
    o1 = fcl.CollisionObject(geoms[a](), fcl.Transform(poses[p]))
    o2 = fcl.CollisionObject(geoms[b](), fcl.Transform())
    print(idx, a, b, p, op, g, end=" ", flush=True)
    faulthandler.dump_traceback_later(5, exit=True, file=open("/dev/null","w"))
    try:
        if op in ("collide", "fcl_collide"):
            req = fcl.CollisionRequest(num_max_contacts=100, enable_contact=True, gjk_solver_type=g)
            res = fcl.CollisionResult()
            n = getattr(fcl, op)(o1, o2, req, res)
            print("n", n, res.is_collision, flush=True)
        else:
            req = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=(op == "sdist"), gjk_solver_type=g)
            res = fcl.DistanceResult()
            d = fcl.distance(o1, o2, req, res)
            print("d", d, flush=True)
    except Exception as e:
        print("EXC", type(e).__name__, str(e)[:80], flush=True)
