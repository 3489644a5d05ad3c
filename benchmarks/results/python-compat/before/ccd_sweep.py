"""The continuous-collision sweep of the session-55 record (before the guards). Run by drive.sh."""
import itertools, sys
import numpy as np
from kdet_fcl import fcl
exec(open("geoms.py").read())  # the geometry makers, shared with disc_sweep.py
start = int(sys.argv[1]) if len(sys.argv) > 1 else 0
names = list(geoms)
combos = [(a, b, m, s, g) for a, b in itertools.product(names, names) for m in range(4) for s in range(4) for g in range(2)]
for idx in range(start, len(combos)):
            a, b, motion, solver, gjk = combos[idx]
            if True:
                o1 = fcl.CollisionObject(geoms[a](), fcl.Transform(np.array([-3., 0, 0])))
                o2 = fcl.CollisionObject(geoms[b](), fcl.Transform())
                req = fcl.ContinuousCollisionRequest(ccd_motion_type=motion, ccd_solver_type=solver, gjk_solver_type=gjk)
                res = fcl.ContinuousCollisionResult()
                print(idx, a, b, motion, solver, gjk, end=" ", flush=True)
                try:
                    toc = fcl.continuousCollide(o1, fcl.Transform(np.array([3., 0, 0])), o2, fcl.Transform(), req, res)
                    print("toc", toc, res.is_collide, res.time_of_contact, flush=True)
                except Exception as e:
                    print("EXC", type(e).__name__, e, flush=True)
