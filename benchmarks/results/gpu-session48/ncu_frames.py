#!/usr/bin/env python3
"""Session 48: ncu's kernel durations (call 6) per frame of precision_probe.cpp.

Usage: ncu_frames.py FILE.csv.gz LAST   (LAST: the frames to summarise, from the end)
Each re-hash of the deforming cloth starts with trianglesKernel, so the kernels are cut into
frames there (the first frame also holds the sphere's first build). Prints the build kinds in
order (C: counting build without read-back, S: sort build, I: inter scan, s: self scan, with
their microseconds), then the last LAST frames' kernel sums and their medians by part.
"""
import collections
import csv
import gzip
import re
import statistics
import sys

PARTS = {
    'build': {'trianglesKernel', 'gridKernel', 'countKernel', 'DeviceScanInitKernel',
              'DeviceScanKernel', 'countClearKernel', 'countFillKernel', 'countCellsKernel',
              'scatterKernel', 'upperLevelsKernel', 'fillKernel', 'entriesKernel', 'headsKernel',
              'cellsKernel', 'DeviceRadixSortHistogramKernel',
              'DeviceRadixSortExclusiveSumKernel', 'DeviceRadixSortOnesweepKernel'},
    'inter candidates': {'interCandidatesWarpKernel'},
    'self candidates': {'selfCandidatesWarpKernel', 'selfCellPairsKernel'},
    'filter + exact': {'planeFilterQueuedKernel', 'interExactKernel', 'selfExactKernel'},
    'order': {'orderPairsKernel'},
}


def kernels(path):
    lines = gzip.open(path, 'rt').read().splitlines()
    start = next(i for i, l in enumerate(lines) if l.startswith('"ID"'))
    rows = list(csv.reader(lines[start:]))
    hdr = rows[0]
    name, value = hdr.index('Kernel Name'), hdr.index('Metric Value')
    for r in rows[1:]:
        if len(r) != len(hdr):
            continue
        n = r[name].replace('<unnamed>::', '').replace('void ', '').split('(')[0]
        yield re.sub(r'<.*', '', n).split('::')[-1], float(r[value].replace(',', '')) / 1000


def main():
    seq = list(kernels(sys.argv[1]))
    last = int(sys.argv[2])
    tags = {'countFillKernel': 'C', 'fillKernel': 'S', 'interCandidatesWarpKernel': 'I',
            'selfCandidatesWarpKernel': 's'}
    print('order:', ' '.join(f'{tags[n]}{d:.0f}' for n, d in seq if n in tags))
    frames, cur = [], []
    for n, d in seq:
        if n == 'trianglesKernel' and cur:
            frames.append(cur)
            cur = []
        cur.append((n, d))
    frames.append(cur)
    frames = frames[-last:]
    print('kernel us per frame:', [round(sum(d for _, d in f)) for f in frames],
          'median', round(statistics.median(sum(d for _, d in f) for f in frames), 1))
    for part, names in PARTS.items():
        per = [sum(d for n, d in f if n in names) for f in frames]
        print(f'  {part}: median {statistics.median(per):.1f}')


if __name__ == '__main__':
    main()
