#!/usr/bin/env python3
"""Medians of ncu's kernel durations per frame (us), from this folder's ncu CSVs of gpu_bench's
cloth ball: a frame starts at its counting build's countFillKernel, and is the two frames' joint
query where its scan (selfCandidatesWarpKernel) took more than 200 us, else the frame alone.
Usage: ncu_frames.py FILE.csv.gz..."""
import collections, csv, gzip, re, statistics, sys

for path in sys.argv[1:]:
    rows = list(csv.reader(gzip.open(path, "rt")))
    hdr, seq = None, []
    for r in rows:
        if r and r[0] == "ID":
            hdr = r
            continue
        if hdr and len(r) == len(hdr):
            d = dict(zip(hdr, r))
            if d["Metric Name"] == "gpu__time_duration.sum":
                n = re.sub(r"\(.*", "", d["Kernel Name"]).replace("void ", "")
                n = re.sub(r"<.*", "", n).split("::")[-1]
                seq.append((n, float(d["Metric Value"].replace(",", "")) / 1000))
    frames, cur = [], []
    for n, v in seq:
        if n == "countFillKernel" and cur:
            frames.append(cur)
            cur = []
        cur.append((n, v))
    frames.append(cur)
    agg = collections.defaultdict(lambda: collections.defaultdict(list))
    for f in frames:
        t = collections.defaultdict(float)
        for n, v in f:
            t[n] += v
        if "selfCandidatesWarpKernel" not in t or "countFillKernel" not in t:
            continue
        kind = "two frames" if t["selfCandidatesWarpKernel"] > 200 else "frame"
        for n in t:
            agg[kind][n].append(t[n])
    for kind, ks in agg.items():
        print("%s, %s (%d): %s" % (path, kind, len(ks["countFillKernel"]), ", ".join(
            "%s %.1f" % (n.replace("Kernel", ""), statistics.median(v)) for n, v in sorted(ks.items()))))
