#!/usr/bin/env python3
"""A capped query's cost by thread count (kdet_fcl.intersect with max_pairs=1 and without),
on an 80k-triangle sheet cut by a 20k-triangle sphere, and on a near miss (a 20k-triangle
sphere inside an 80k-triangle one). Medians of repeated calls, microseconds.

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/results/gpu-session54/first_contact_probe.py
"""
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..",
                                "python", "tests"))
import meshes as M  # noqa: E402

import kdet_fcl  # noqa: E402

vc, tc = M.cloth(200, 2.0)
vb, tb = M.sphere(0.5, 128, 79)
vo, to = M.sphere(0.5, 250, 161)
sheet, ball = kdet_fcl.Mesh(vc, tc), kdet_fcl.Mesh(vb, tb, translation=(0, 0, 0.45))
outer, inner = kdet_fcl.Mesh(vo, to), kdet_fcl.Mesh(vb * 0.99, tb)


def med(f, n):
    f()
    t = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return statistics.median(t) * 1e6


print("threads | sheet/sphere first contact | every pair | near miss, capped | near miss, every pair (us)")
for th in (1, 2, 4, 16):
    print("%7d | %8.1f | %8.1f | %8.1f | %8.1f" % (
        th, med(lambda: kdet_fcl.intersect(sheet, ball, max_pairs=1, threads=th), 300),
        med(lambda: kdet_fcl.intersect(sheet, ball, threads=th), 50),
        med(lambda: kdet_fcl.intersect(outer, inner, max_pairs=1, threads=th), 15),
        med(lambda: kdet_fcl.intersect(outer, inner, threads=th), 15)))
