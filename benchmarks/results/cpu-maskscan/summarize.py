#!/usr/bin/env python3
"""Per-run numbers of the A/B in this folder, from kdet_bench's bench.json files (not kept: 0.5 MB
each). Usage: summarize.py DIR... where each DIR is a kdet_bench --out folder."""
import json
import sys

for d in sys.argv[1:]:
    data = json.load(open(d + "/bench.json"))
    for s in data["scenes"]:
        sm = s["summary"]
        k1 = sm["kdet_cpu_1t"]["comparable_ms"]
        cells = [f"{d} {s['name']}: kDet 1T {k1:.4g} ms"]
        for peer in ("fcl_obbrss", "fcl_obb"):
            if sm.get(peer, {}).get("status") == "ok":
                p = sm[peer]["comparable_ms"]
                cells.append(f"{peer} {p:.4g} ms ({p / k1:.2f}x)")
        if s["group"] != "rigid":
            cells.append(f"kDet total (update + self + inter) 1T {sm['kdet_cpu_1t']['total_ms']:.4g} ms, "
                         f"2T {sm['kdet_cpu_2t']['total_ms']:.4g} ms")
        print(", ".join(cells))
