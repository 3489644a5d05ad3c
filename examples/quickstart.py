#!/usr/bin/env python3
"""kdet_fcl from Python in one page: a cloth falling onto a sphere, its self-collision, and the
same query through python-fcl's API. Run after scripts/run.sh:

    PYTHONPATH=build/python /usr/bin/python3 examples/quickstart.py
"""
import numpy as np

import kdet_fcl
from kdet_fcl import fcl


def grid(n, size):
    """An n x n cloth of 2 n^2 triangles in the z = 0 plane."""
    xs = np.linspace(-size / 2, size / 2, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    b, c, d = a + n + 1, a + 1, a + n + 2
    return v, np.concatenate([np.stack([a, b, c], 1), np.stack([c, b, d], 1)])


cloth_v, cloth_t = grid(120, 2.0)          # 28,800 triangles
ball_v, ball_t = kdet_fcl.make_sphere(0.5, 96, 36)  # 6,720 triangles (the library's scenes)
cloth = kdet_fcl.Mesh(cloth_v, cloth_t)
sphere = kdet_fcl.Mesh(ball_v, ball_t)
print(cloth, sphere)

for frame in range(4):                     # the cloth falls and sags: a deformation per frame
    v = cloth_v.copy()
    v[:, 2] = 0.8 - 0.15 * frame - 0.3 * np.exp(-4 * (v[:, 0] ** 2 + v[:, 1] ** 2))
    cloth.update_vertices(v)               # re-hashed by the next query
    pairs = kdet_fcl.intersect(cloth, sphere)
    print("frame %d: %d intersecting (cloth, sphere) triangle pairs" % (frame, len(pairs)))

sphere.set_pose(np.eye(3), [0.0, 0.0, 0.05])  # a rigid motion: no re-hash
print("after moving the sphere:", len(kdet_fcl.intersect(cloth, sphere)), "pairs;",
      "self-collisions of the cloth:", len(kdet_fcl.intersect_self(cloth)))
if kdet_fcl.cuda_available():
    print("on the GPU:", len(kdet_fcl.intersect(cloth, sphere, backend="cuda")), "pairs")

# The same pair through python-fcl's API (code written for python-fcl changes its import only).
models = []
for v, t in ((v, cloth_t), (ball_v, ball_t)):
    m = fcl.BVHModel()
    m.beginModel(len(t), len(v))
    m.addSubModel(v, t)
    m.endModel()
    models.append(m)
o1 = fcl.CollisionObject(models[0])
o2 = fcl.CollisionObject(models[1], fcl.Transform([0.0, 0.0, 0.05]))
request = fcl.CollisionRequest(num_max_contacts=10 ** 9, enable_contact=True)
result = fcl.CollisionResult()
n = fcl.collide(o1, o2, request, result)
c = result.contacts[0]
print("fcl.collide: %d contacts; the first: triangles (%d, %d) at %s" % (n, c.b1, c.b2, np.round(c.pos, 3)))
same = fcl.fcl_collide(o1, o2, request, fcl.CollisionResult())
print("FCL 0.7 itself finds %d" % same)

try:
    kdet_fcl.Mesh(cloth_v, cloth_t + len(cloth_v))   # indices past the vertices
except kdet_fcl.InvalidInputError as e:
    print("bad input is an exception:", e)
