#!/usr/bin/env python3
"""An account of one kernel from ncu's SASS source page.

  ncu --set full -k regex:KERNEL -s 10 -c 1 -o rep <program ...>
  ncu -i rep.ncu-rep --page source --csv --print-source sass > kernel-sass.csv
  sass_account.py kernel-sass.csv [--listing] [--top N]

Prints the kernel's warp instructions, their average active lanes and stall samples; the
opcode mix (share of warp instructions and of stall samples); the instructions with the most
stall samples; and the hottest straight-line blocks (runs of instructions executed the same
number of times), by warp instructions. --listing prints every instruction as
"offset  executions  lanes  samples  SASS", from which code regions can be read off by hand
(the regions of RESULTS-gpu.md's 2026-11-24 section were).
"""
import argparse
import collections
import csv


def load(path):
    rows = list(csv.reader(open(path, newline="")))
    header = next(i for i, r in enumerate(rows) if r and r[0] == "Address")
    names = {h: i for i, h in enumerate(rows[header])}
    out = []
    base = None
    for r in rows[header + 1:]:
        if not r or not r[0].startswith("0x"):
            continue
        addr = int(r[0], 16)
        base = addr if base is None else base

        def num(key):
            try:
                return float(r[names[key]])
            except (KeyError, ValueError):
                return 0.0

        out.append({
            "off": addr - base,
            "sass": r[names["Source"]].strip(),
            "inst": num("Instructions Executed"),
            "thread": num("Thread Instructions Executed"),
            "samples": num("Warp Stall Sampling (All Samples)"),
        })
    return out


def opcode(sass):
    words = [w for w in sass.split() if not w.startswith("@")]
    return words[0].split(".")[0] if words else "?"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("--listing", action="store_true")
    ap.add_argument("--top", type=int, default=12)
    a = ap.parse_args()
    ins = load(a.csv)
    if not ins:
        raise SystemExit(f"{a.csv}: no SASS rows (is it ncu's --page source --csv output?)")
    if a.listing:
        for i in ins:
            lanes = i["thread"] / i["inst"] if i["inst"] else 0
            print(f"{i['off']:6x} {i['inst'] / 1e3:9.0f}k {lanes:5.1f} {i['samples']:6.0f}  {i['sass']}")
        return
    inst = sum(i["inst"] for i in ins)
    samples = sum(i["samples"] for i in ins) or 1.0
    lanes = sum(i["thread"] for i in ins) / inst if inst else 0
    print(f"{len(ins)} instructions in the listing; {inst / 1e6:.1f}M warp instructions executed, "
          f"{lanes:.1f} active lanes on average; {samples:.0f} stall samples")
    mix, mix_s = collections.Counter(), collections.Counter()
    for i in ins:
        mix[opcode(i["sass"])] += i["inst"]
        mix_s[opcode(i["sass"])] += i["samples"]
    print("\nopcode     warp inst  samples")
    for op, n in mix.most_common(a.top):
        print(f"  {op:8s} {n / inst * 100:7.1f} % {mix_s[op] / samples * 100:6.1f} %")
    print("\nmost stall samples (offset, executions, samples, SASS)")
    for i in sorted(ins, key=lambda i: -i["samples"])[:a.top]:
        print(f"  {i['off']:6x} {i['inst'] / 1e3:8.0f}k {i['samples'] / samples * 100:5.1f} %  {i['sass']}")
    blocks = []
    for i in ins:
        if blocks and blocks[-1]["inst"] == i["inst"]:
            blocks[-1]["n"] += 1
            blocks[-1]["end"] = i["off"]
            blocks[-1]["samples"] += i["samples"]
        else:
            blocks.append({"start": i["off"], "end": i["off"], "inst": i["inst"], "n": 1,
                           "samples": i["samples"], "first": i["sass"]})
    print("\nhottest blocks (offsets, executions x length, share of warp instructions and samples)")
    for b in sorted(blocks, key=lambda b: -b["inst"] * b["n"])[:a.top]:
        print(f"  {b['start']:6x}-{b['end']:6x} {b['inst'] / 1e3:7.0f}k x{b['n']:4d} "
              f"{b['inst'] * b['n'] / inst * 100:5.1f} % {b['samples'] / samples * 100:5.1f} %  {b['first']}")


if __name__ == "__main__":
    main()
