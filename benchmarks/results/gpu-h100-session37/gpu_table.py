#!/usr/bin/env python3
"""Prints kdet_bench's GPU table (the layout of writeGpuTable in kdet_bench.cpp) from a bench.json,
for runs whose bench.md did not come back from the device (call 8). Per scene: mean triangles over
the steady frames (frames after the build frame), whether an object deforms or fractures, kDet
GPU and GPU BVH totals (ms per frame, means over the steady frames of per-frame medians, as
bench.json's summary), their ratio, FCL OBBRSS's total and FCL total / kDet GPU comparable, and
the two phases of each GPU method (update, query).
  python3 gpu_table.py call8/part1/bench.json"""
import json
import sys

d = json.load(open(sys.argv[1]))
print("GPU:", d["meta"]["gpu"], "| command:", d["meta"]["command"])
print()
print("| Scene | # polys | deforming | kDet GPU update / query / total | GPU BVH update / query / "
      "total | vs GPU BVH | FCL total | vs FCL | pairs agree |")
print("| --- | ---: | --- | --- | --- | ---: | ---: | ---: | --- |")
for s in d["scenes"]:
    S = s["summary"]
    g, b, f = S["kdet_gpu"], S["gpu_bvh"], S["fcl_obbrss"]
    steady = s["frames"][1:] or s["frames"]
    tris = sum(fr["triangles"] for fr in steady) // len(steady)
    deform = any(o["motion"] in ("deform", "fracture") for o in s["objects"])
    agree = all(a["agreed"] or a["settled_against_kdet"] == 0 for a in s["agreement"].values())
    fcl = f.get("total_ms")
    star = "*" if f.get("self_as_pair") else ""
    print(f"| {s['name']} | {tris} | {'yes' if deform else 'no'} | "
          f"{g['update_ms']:.3f} / {g['query_ms']:.3f} / {g['total_ms']:.3f} | "
          f"{b['update_ms']:.3f} / {b['query_ms']:.3f} / {b['total_ms']:.3f} | "
          f"{b['total_ms'] / g['total_ms']:.2f}× | "
          + (f"{fcl:.1f}{star} | {fcl / g['comparable_ms']:.0f}×" if fcl else "n/a | ") +
          f" | {'yes' if agree else 'NO'} |")
