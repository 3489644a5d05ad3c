#!/usr/bin/python3
"""DART (Debian's python3-dartpy 6.12, a robotics library built on FCL 0.7), unmodified, with and
without kDet underneath (libkdet_fcl_interpose.so under LD_PRELOAD).

Two free bodies loaded from URDF, each with a mesh collision shape (a 48 x 24 sphere and a
64 x 24 torus, written here as OBJ files), are posed at 12 seeded poses; DART's
FCLCollisionDetector collides them (every contact: CollisionOption(True, 100000)). Per pose the
probe records DART's contacts and their (sphere triangle, torus triangle) pairs, and the median
time of 200 group.collide calls.

  dartpy_probe.py run OUT.json        DART's results (run it plain and under LD_PRELOAD)
  dartpy_probe.py compare A.json B.json
                                      both pair sets against the exact pairs: every triangle pair
                                      whose boxes overlap, decided by exact orientation tests
                                      (Python fractions) on the world vertices DART used

PROBE_CONTACTS=fcl makes DART take FCL's contact points (ContactPointComputationMethod FCL)
instead of computing its own. Either way DART merges contacts whose points coincide, so its
contact list is not the pair set: "not reported" counts exact pairs absent from DART's list
(merged by DART, or missed below it); "not intersecting" counts reported pairs that the exact
test rejects.
"""
import json
import math
import os
import random
import sys
import tempfile
import time
from fractions import Fraction


def sphere(radius, nu, nv):
    verts = [(0.0, 0.0, radius)]
    for j in range(1, nv):
        th = math.pi * j / nv
        for i in range(nu):
            ph = 2 * math.pi * i / nu
            verts.append((radius * math.sin(th) * math.cos(ph),
                          radius * math.sin(th) * math.sin(ph), radius * math.cos(th)))
    verts.append((0.0, 0.0, -radius))
    tris = [(0, 1 + i, 1 + (i + 1) % nu) for i in range(nu)]
    for j in range(nv - 2):
        for i in range(nu):
            a, b = 1 + j * nu + i, 1 + j * nu + (i + 1) % nu
            tris += [(a, a + nu, b + nu), (a, b + nu, b)]
    s = 1 + (nv - 2) * nu
    tris += [(s + i, len(verts) - 1, s + (i + 1) % nu) for i in range(nu)]
    return verts, tris


def torus(big, small, nu, nv):
    verts = []
    for i in range(nu):
        ph = 2 * math.pi * i / nu
        for j in range(nv):
            th = 2 * math.pi * j / nv
            rr = big + small * math.cos(th)
            verts.append((rr * math.cos(ph), rr * math.sin(ph), small * math.sin(th)))
    tris = []
    for i in range(nu):
        for j in range(nv):
            a, b = i * nv + j, i * nv + (j + 1) % nv
            c, d = ((i + 1) % nu) * nv + j, ((i + 1) % nu) * nv + (j + 1) % nv
            tris += [(a, c, d), (a, d, b)]
    return verts, tris


MESHES = {"sphere": sphere(0.62, 48, 24), "torus": torus(0.9, 0.3, 64, 24)}


def poses():
    rng = random.Random(53)
    out = []
    for _ in range(12):
        rot = [rng.uniform(-1.5, 1.5) for _ in range(3)]
        pos = [rng.uniform(-0.35, 0.35), rng.uniform(-0.35, 0.35), rng.uniform(-0.3, 0.3)]
        out.append(rot + pos)
    return out


def run(out_path):
    import dartpy as dart
    folder = tempfile.mkdtemp(prefix="dartpy_probe_")
    skels = {}
    loader = dart.utils.DartLoader()
    for name, (verts, tris) in MESHES.items():
        with open(os.path.join(folder, name + ".obj"), "w") as f:
            for v in verts:
                f.write("v %.17g %.17g %.17g\n" % v)
            for t in tris:
                f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))
        urdf = ('<robot name="%s"><link name="%s"><collision><geometry><mesh filename="file://%s"/>'
                '</geometry></collision></link></robot>' % (name, name, os.path.join(folder, name + ".obj")))
        skels[name] = loader.parseSkeletonString(urdf, dart.common.Uri("file://" + folder + "/"))
    det = dart.collision.FCLCollisionDetector()
    if os.environ.get("PROBE_CONTACTS") == "fcl":
        det.setContactPointComputationMethod(dart.collision.FCLCollisionDetector.FCL)
    group = det.createCollisionGroup()
    for s in skels.values():
        group.addShapeFramesOf(s)
    option = dart.collision.CollisionOption(True, 100000)
    results = []
    for k, pose in enumerate(poses()):
        skels["torus"].setPositions(pose)
        result = dart.collision.CollisionResult()
        group.collide(option, result)
        pairs = set()
        for c in result.getContacts():
            n1 = c.collisionObject1.getShapeFrame().getName()
            pairs.add((c.triID1, c.triID2) if n1.startswith("sphere") else (c.triID2, c.triID1))
        times = []
        for _ in range(200):
            r = dart.collision.CollisionResult()
            t0 = time.perf_counter()
            group.collide(option, r)
            times.append(time.perf_counter() - t0)
        times.sort()
        world = {}
        for name, s in skels.items():
            m = s.getBodyNode(0).getWorldTransform().matrix()
            world[name] = [[float(m[i][j]) for j in range(4)] for i in range(3)]
        results.append({"pose": pose, "contacts": result.getNumContacts(), "pairs": sorted(pairs),
                        "median_ms": 1e3 * times[len(times) // 2], "world": world})
        print("pose %2d: %4d contacts, %4d triangle pairs, %.3f ms" %
              (k, result.getNumContacts(), len(pairs), results[-1]["median_ms"]), flush=True)
    with open(out_path, "w") as f:
        json.dump(results, f)


# ---- exact triangle-triangle intersection (closed triangles), by orientation signs ----
def orient3d(a, b, c, d):
    # A float filter first (a generous static bound); fractions where it cannot decide.
    bx, by, bz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    cx, cy, cz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    dx, dy, dz = d[0] - a[0], d[1] - a[1], d[2] - a[2]
    det = bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx)
    perm = (abs(bx) * (abs(cy * dz) + abs(cz * dy)) + abs(by) * (abs(cx * dz) + abs(cz * dx)) +
            abs(bz) * (abs(cx * dy) + abs(cy * dx)))
    if abs(det) > 1e-14 * perm:
        return (det > 0) - (det < 0)
    A = [Fraction(x) for x in a]
    B, C, D = ([Fraction(x) - A[i] for i, x in enumerate(p)] for p in (b, c, d))
    e = (B[0] * (C[1] * D[2] - C[2] * D[1]) - B[1] * (C[0] * D[2] - C[2] * D[0]) +
         B[2] * (C[0] * D[1] - C[1] * D[0]))
    return (e > 0) - (e < 0)


def orient2d(a, b, c):
    e = (Fraction(b[0]) - Fraction(a[0])) * (Fraction(c[1]) - Fraction(a[1])) - \
        (Fraction(b[1]) - Fraction(a[1])) * (Fraction(c[0]) - Fraction(a[0]))
    return (e > 0) - (e < 0)


def on_segment_2d(a, b, p):  # p collinear with a, b
    return (min(a[0], b[0]) <= p[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= p[1] <= max(a[1], b[1]))


def segments_meet_2d(a, b, c, d):
    o1, o2, o3, o4 = orient2d(a, b, c), orient2d(a, b, d), orient2d(c, d, a), orient2d(c, d, b)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return ((o1 == 0 and on_segment_2d(a, b, c)) or (o2 == 0 and on_segment_2d(a, b, d)) or
            (o3 == 0 and on_segment_2d(c, d, a)) or (o4 == 0 and on_segment_2d(c, d, b)))


def inside_2d(p, t):
    s = [orient2d(t[i], t[(i + 1) % 3], p) for i in range(3)]
    return all(x >= 0 for x in s) or all(x <= 0 for x in s)


def segment_meets_triangle(a, b, t):
    sa, sb = orient3d(t[0], t[1], t[2], a), orient3d(t[0], t[1], t[2], b)
    if sa * sb > 0:
        return False
    if sa == 0 and sb == 0:  # coplanar: drop the axis of the normal's largest component
        n = [Fraction(0)] * 3
        T = [[Fraction(x) for x in p] for p in t]
        u = [T[1][i] - T[0][i] for i in range(3)]
        v = [T[2][i] - T[0][i] for i in range(3)]
        n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        axis = max(range(3), key=lambda i: abs(n[i]))
        keep = [i for i in range(3) if i != axis]
        pr = lambda p: (p[keep[0]], p[keep[1]])
        A, B, P = pr(a), pr(b), [pr(p) for p in t]
        return (inside_2d(A, P) or inside_2d(B, P) or
                any(segments_meet_2d(A, B, P[i], P[(i + 1) % 3]) for i in range(3)))
    s = [orient3d(a, b, t[i], t[(i + 1) % 3]) for i in range(3)]
    return all(x >= 0 for x in s) or all(x <= 0 for x in s)


def triangles_meet(p, q):
    return (any(segment_meets_triangle(p[i], p[(i + 1) % 3], q) for i in range(3)) or
            any(segment_meets_triangle(q[i], q[(i + 1) % 3], p) for i in range(3)))


def world_triangles(name, world):
    verts, tris = MESHES[name]
    w = [[m[0] * v[0] + m[1] * v[1] + m[2] * v[2] + m[3] for m in world] for v in verts]
    return [[w[i] for i in t] for t in tris]


def exact_pairs(entry):
    A = world_triangles("sphere", entry["world"]["sphere"])
    B = world_triangles("torus", entry["world"]["torus"])
    box = lambda t: ([min(p[i] for p in t) for i in range(3)], [max(p[i] for p in t) for i in range(3)])
    bb = [box(t) for t in B]
    out = set()
    for i, ta in enumerate(A):
        lo, hi = box(ta)
        for j, (blo, bhi) in enumerate(bb):
            if all(lo[k] <= bhi[k] and blo[k] <= hi[k] for k in range(3)) and triangles_meet(ta, B[j]):
                out.add((i, j))
    return out


def compare(path_a, path_b):
    runs = [json.load(open(p)) for p in (path_a, path_b)]
    names = [os.path.basename(p) for p in (path_a, path_b)]
    print("pose | exact pairs | " + " | ".join("%s: contacts, pairs, not reported, not intersecting, ms" % n
                                               for n in names))
    totals = [[0, 0, 0] for _ in runs]
    for k in range(len(runs[0])):
        for r in runs[1:]:
            if r[k]["world"] != runs[0][k]["world"]:
                sys.exit("the runs' world transforms differ at pose %d" % k)
        truth = exact_pairs(runs[0][k])
        cells = []
        for n, r in enumerate(runs):
            got = set(map(tuple, r[k]["pairs"]))
            missed, extra = len(truth - got), len(got - truth)
            totals[n][0] += missed
            totals[n][1] += extra
            totals[n][2] += r[k]["median_ms"]
            cells.append("%d, %d, %d, %d, %.3f" % (r[k]["contacts"], len(got), missed, extra,
                                                   r[k]["median_ms"]))
        print("%d | %d | %s" % (k, len(truth), " | ".join(cells)), flush=True)
    for n, t in enumerate(totals):
        print("%s: %d exact pairs not reported, %d pairs not intersecting over the poses; "
              "sum of the medians %.3f ms" %
              (names[n], t[0], t[1], t[2]))
    return 0 if all(t[0] == 0 and t[1] == 0 for t in totals[1:]) else 1


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "run":
        run(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3]))
    else:
        sys.exit(__doc__)
