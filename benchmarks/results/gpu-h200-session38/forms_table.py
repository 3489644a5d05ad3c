#!/usr/bin/env python3
"""Session 38's kdet_bench forms side by side, from the bench.json files of device calls 1 and 2
(extracted from callN/out.tgz into /tmp/s38cN). Per deforming or UNC/cloth scene and form: kDet
GPU total, GPU BVH total (ms per frame, as bench.json's summary) and their ratio, as ranges over
the form's runs.
  python3 forms_table.py /tmp/s38c1 /tmp/s38c2"""
import json
import sys

c1, c2 = sys.argv[1], sys.argv[2]
forms = [
    ("updateVertices, new results", [c1 + "/copy1", c1 + "/copy2"]),
    ("commitVertices, new results", [c1 + "/commit1", c1 + "/commit2", c2 + "/fresh1", c2 + "/fresh2"]),
    ("commitVertices, kept results", [c2 + "/kept1", c2 + "/kept2"]),
]
rows = {}
order = []
for name, runs in forms:
    for r in runs:
        d = json.load(open(r + "/bench.json"))
        for s in d["scenes"]:
            S = s["summary"]
            g, b = S["kdet_gpu"]["total_ms"], S["gpu_bvh"]["total_ms"]
            u = S["kdet_gpu"]["update_ms"]
            if s["name"] not in rows:
                rows[s["name"]] = {}
                order.append(s["name"])
            rows[s["name"]].setdefault(name, []).append((g, b, b / g, u))


def rng(v, f="%.3f"):
    lo, hi = min(v), max(v)
    return (f % lo) if f % lo == f % hi else (f % lo) + "–" + (f % hi)


print("| scene | " + " | ".join(n + ": kDet / BVH / ratio" for n, _ in forms) + " |")
print("|---|" + "---|" * len(forms))
for sc in order:
    cells = []
    for n, _ in forms:
        v = rows[sc].get(n, [])
        if not v:
            cells.append("")
            continue
        cells.append("%s / %s / %s×" % (rng([x[0] for x in v]), rng([x[1] for x in v]),
                                       rng([x[2] for x in v], "%.2f")))
    print("| " + sc + " | " + " | ".join(cells) + " |")
