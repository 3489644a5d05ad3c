#!/usr/bin/env python3
"""python-fcl-style code on kDet against FCL 0.7, in one process (benchmarks/RESULTS.md, section
"Python"). Both columns go through the same binding and the same Python contact objects:
`kdet_fcl.fcl.collide` (kDet) and `kdet_fcl.fcl.fcl_collide` (FCL's own fcl::collide, the call
python-fcl makes). Medians over --repeats calls after a warm-up call; progress on stderr; a
Markdown table on stdout (--json FILE writes the numbers too).

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/python_bench.py [--repeats 15] [--quick]
"""
import argparse
import json
import os
import platform
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python", "tests"))
import meshes as M  # noqa: E402

import kdet_fcl  # noqa: E402
from kdet_fcl import fcl  # noqa: E402

ALL = 10 ** 9
GPU = kdet_fcl.cuda_available()  # adds the CUDA backend's rows


def log(msg):
    print("[python_bench] " + msg, file=sys.stderr, flush=True)


def timed(fn, repeats):
    fn()  # warm-up: hashes and trees built, caches filled
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        out.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(out)


def pair_count(engine, o1, o2, request):
    res = fcl.CollisionResult()
    engine(o1, o2, request, res)
    return {(c.b1, c.b2) for c in res.contacts}


def rigid_rows(name, va, ta, vb, tb, R, t, repeats):
    a, b = M.fcl_mesh(va, ta), M.fcl_mesh(vb, tb)
    o1, o2 = fcl.CollisionObject(a), fcl.CollisionObject(b, fcl.Transform(R, t))
    rows = []
    for what, request in [("every pair, contacts", fcl.CollisionRequest(ALL, True)),
                          ("first contact", fcl.CollisionRequest())]:
        mine, ref = pair_count(fcl.collide, o1, o2, request), pair_count(fcl.fcl_collide, o1, o2, request)
        if what.startswith("every") and mine != ref:
            log("NOTE: %s: kDet %d pairs, FCL %d (FCL's traversal or rounding; the C++ tests "
                "settle such differences exactly)" % (name, len(mine), len(ref)))
        log("%s, %s ..." % (name, what))
        tk = timed(lambda: fcl.collide(o1, o2, request, fcl.CollisionResult()), repeats)
        tf = timed(lambda: fcl.fcl_collide(o1, o2, request, fcl.CollisionResult()), repeats)
        rows.append(dict(scene=name, query=what, triangles=len(ta) + len(tb), pairs=len(mine),
                         fcl_pairs=len(ref), kdet_ms=tk, fcl_ms=tf))
    # The NumPy API on the same pair: no contact objects, pairs as one array.
    ma, mb = kdet_fcl.Mesh(va, ta), kdet_fcl.Mesh(vb, tb, rotation=R, translation=t)
    log("%s, kdet_fcl.intersect ..." % name)
    tk = timed(lambda: kdet_fcl.intersect(ma, mb), repeats)
    rows.append(dict(scene=name, query="every pair, kdet_fcl.intersect (NumPy pairs)",
                     triangles=len(ta) + len(tb), pairs=len(kdet_fcl.intersect(ma, mb)),
                     fcl_pairs=None, kdet_ms=tk, fcl_ms=None))
    if GPU:
        log("%s, kdet_fcl.intersect on the GPU ..." % name)
        tk = timed(lambda: kdet_fcl.intersect(ma, mb, backend="cuda"), repeats)
        rows.append(dict(scene=name, query="every pair, kdet_fcl.intersect, backend=\"cuda\"",
                         triangles=len(ta) + len(tb),
                         pairs=len(kdet_fcl.intersect(ma, mb, backend="cuda")), fcl_pairs=None,
                         kdet_ms=tk, fcl_ms=None))
    return rows


def deforming_rows(n, frames, repeats):
    """A cloth waving over a sphere: each frame new vertices, then every pair."""
    vc, tc = M.cloth(n, 2.0)
    vs, ts = M.sphere(0.5, 64, 32)
    shapes = []
    for k in range(frames):
        ph = 2 * np.pi * k / frames
        v = vc.copy()
        v[:, 2] = 0.45 + 0.12 * np.sin(3 * v[:, 0] + ph) * np.cos(2 * v[:, 1] - ph) - 0.1 * (k % 2)
        shapes.append(v)
    request = fcl.CollisionRequest(ALL, False)
    rows = []
    fcl_frame = None
    for label, kdet_only in [("fcl.BVHModel()", False), ("fcl.BVHModel(kdet_only=True)", True)]:
        cloth_k, cloth_f = M.fcl_mesh(vc, tc, kdet_only=kdet_only), M.fcl_mesh(vc, tc)
        ball = M.fcl_mesh(vs, ts)
        ok, of = fcl.CollisionObject(cloth_k), fcl.CollisionObject(cloth_f)
        ob = fcl.CollisionObject(ball)
        state = {"i": 0}

        def frame(model, obj, engine):
            v = shapes[state["i"] % frames]
            state["i"] += 1
            model.beginUpdateModel()
            model.updateSubModel(v)
            model.endUpdateModel()
            return engine(obj, ob, request, fcl.CollisionResult())

        log("cloth %dk over a sphere, deforming, %s ..." % (2 * n * n // 1000, label))
        tk = timed(lambda: frame(cloth_k, ok, fcl.collide), repeats)
        if not kdet_only:  # FCL's frame (refit + collide) is the peer of every row here
            fcl_frame = timed(lambda: frame(cloth_f, of, fcl.fcl_collide), repeats)
        tf = fcl_frame
        rows.append(dict(scene="cloth %dk over a 4k sphere, deforming" % (2 * n * n // 1000),
                         query="update + every pair, " + label, triangles=len(tc) + len(ts),
                         pairs=None, fcl_pairs=None, kdet_ms=tk, fcl_ms=tf))
    m, b = kdet_fcl.Mesh(vc, tc), kdet_fcl.Mesh(vs, ts)
    state = {"i": 0}

    def core_frame(backend):
        m.update_vertices(shapes[state["i"] % frames])
        state["i"] += 1
        return kdet_fcl.intersect(m, b, backend=backend)
    for backend in ("cpu", "cuda") if GPU else ("cpu",):
        log("the same, kdet_fcl.Mesh.update_vertices + intersect, %s ..." % backend)
        label = "update + every pair, kdet_fcl.Mesh (NumPy)" + (
            ", backend=\"cuda\"" if backend == "cuda" else "")
        rows.append(dict(scene="cloth %dk over a 4k sphere, deforming" % (2 * n * n // 1000),
                         query=label, triangles=len(tc) + len(ts), pairs=None, fcl_pairs=None,
                         kdet_ms=timed(lambda: core_frame(backend), repeats), fcl_ms=fcl_frame))
    return rows


def self_rows(n, repeats):
    v, t = M.folded_cloth(n)
    m = kdet_fcl.Mesh(v, t)
    log("self-collision of a %dk folded cloth ..." % (len(t) // 1000))
    state = {"k": 0}

    def deform(backend):  # a new frame each call: not answered from the kept result
        state["k"] += 1
        m.update_vertices(v * (1.0 + 1e-6 * (state["k"] % 7)))
        return kdet_fcl.intersect_self(m, backend=backend)
    rows = []
    for backend in ("cpu", "cuda") if GPU else ("cpu",):
        rows.append(dict(scene="folded cloth %dk, self-collision" % (len(t) // 1000),
                         query="update + self pairs, kdet_fcl.Mesh (FCL: none)" + (
                             ", backend=\"cuda\"" if backend == "cuda" else ""),
                         triangles=len(t), pairs=len(kdet_fcl.intersect_self(m, backend=backend)),
                         fcl_pairs=None, kdet_ms=timed(lambda: deform(backend), repeats),
                         fcl_ms=None))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--quick", action="store_true", help="small meshes only (a smoke run)")
    ap.add_argument("--json", help="write the rows to this file")
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error("--repeats must be >= 1")
    rows = []
    vs, ts = M.sphere(0.6, 48, 25)      # 2.3k triangles
    vt, tt = M.torus(1.0, 0.3, 64, 24)  # 3.1k
    rows += rigid_rows("sphere 2.3k / torus 3.1k, rigid", vs, ts, vt, tt,
                       M.rotation([1, 1, 0], 0.4), (0.9, 0.1, 0.05), args.repeats)
    if not args.quick:
        vc, tc = M.cloth(200, 2.0)             # 80k
        vb, tb = M.sphere(0.5, 128, 79)        # 20k
        rows += rigid_rows("sheet 80k / sphere 20k, rigid", vc, tc, vb, tb, np.eye(3),
                           (0.0, 0.0, 0.45), args.repeats)
        rows += deforming_rows(150, 6, args.repeats)
        rows += self_rows(150, args.repeats)
    else:
        rows += deforming_rows(30, 4, args.repeats)
        rows += self_rows(30, args.repeats)

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    gpu = ("; GPU: device %d: %s" % (kdet_fcl.cuda_device(),
                                     kdet_fcl.cuda_device_description(kdet_fcl.cuda_device()))
           if GPU else "")
    print("CPU: %s, %d hardware threads%s; Python %s; medians of %d calls after a warm-up call\n"
          % (cpu, os.cpu_count() or 0, gpu, platform.python_version(), args.repeats))
    print("| scene | query | triangles | pairs (kDet / FCL) | kDet ms | FCL ms | FCL / kDet |")
    print("|---|---|---:|---|---:|---:|---:|")
    for r in rows:
        pairs = "" if r["pairs"] is None else (
            str(r["pairs"]) + ("" if r["fcl_pairs"] is None else " / %d" % r["fcl_pairs"]))
        fcl_ms = "n/a" if r["fcl_ms"] is None else "%.3f" % r["fcl_ms"]
        ratio = "" if r["fcl_ms"] is None else "%.2fx" % (r["fcl_ms"] / r["kdet_ms"])
        print("| %s | %s | %d | %s | %.3f | %s | %s |" % (r["scene"], r["query"], r["triangles"],
                                                        pairs, r["kdet_ms"], fcl_ms, ratio))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(dict(cpu=cpu, threads=os.cpu_count(), gpu=gpu[8:], repeats=args.repeats,
                           rows=rows), f, indent=1)


if __name__ == "__main__":
    main()
