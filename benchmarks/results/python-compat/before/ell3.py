"""Exactly touching poses (session-55 record): python3 ell3.py A B GJK SIGNED, one process each."""
import sys, numpy as np
from kdet_fcl import fcl
a, b, g, sd = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4] == "1"
exec(open('geoms.py').read())
plus = dict(box=.5, sphere=.5, ellipsoid=.5, capsule=.3, cone=.5, cylinder=.5, convex=.5, mesh=.7, octree=.1)
minus = dict(plus, octree=0.0)
x = -(plus[a] + minus[b])
o1 = fcl.CollisionObject(geoms[a](), fcl.Transform(np.array([x, 0, 0])))
o2 = fcl.CollisionObject(geoms[b](), fcl.Transform())
print(x, fcl.collide(o1, o2), flush=True)
print(fcl.distance(o1, o2, fcl.DistanceRequest(gjk_solver_type=g, enable_signed_distance=sd)), flush=True)
