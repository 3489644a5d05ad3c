import csv,sys,re,statistics,collections
rows=list(csv.reader(open(sys.argv[1])))
hdr=None;seq=[]
for r in rows:
    if r and r[0]=='ID': hdr=r; continue
    if hdr and len(r)==len(hdr):
        d=dict(zip(hdr,r))
        if d['Metric Name']=='gpu__time_duration.sum':
            n=re.sub(r'\(.*','',d['Kernel Name']).replace('void ','').replace('<unnamed>::','')
            bvh=n.startswith('kdet_bvh')
            n=re.sub(r'<.*','',n).split('::')[-1]
            if bvh: n='kdet_bvh '+n
            seq.append((n,float(d['Metric Value'].replace(',',''))/1000))
# split kDet frames: a frame starts at trianglesKernel (kDet build)
frames=[];cur=None
for n,v in seq:
    if n=='trianglesKernel':
        if cur: frames.append(cur)
        cur=[]
    if cur is not None: cur.append((n,v))
if cur: frames.append(cur)
# classify
build_names={'trianglesKernel','gridKernel','countKernel','DeviceScanInitKernel','DeviceScanKernel','fillKernel','DeviceRadixSortHistogramKernel','DeviceRadixSortExclusiveSumKernel','DeviceRadixSortOnesweepKernel','entriesKernel','headsKernel','cellsKernel','upperLevelsKernel'}
agg=collections.defaultdict(list)
for f in frames[2:]:
    # build = until first candidates kernel
    b=collections.defaultdict(float); q=collections.defaultdict(float); inb=True
    for n,v in f:
        if 'Candidates' in n or 'CellPairs' in n: inb=False
        if n.startswith('kdet_bvh'): continue
        (b if inb else q)[('sort' if 'RadixSort' in n else 'scan' if 'Scan' in n else n)]+=v
    for k,v in b.items(): agg['B '+k].append(v)
    for k,v in q.items(): agg['Q '+k].append(v)
    agg['B total'].append(sum(b.values())); agg['Q total'].append(sum(q.values()))
    agg['N kernels (kDet, per frame)'].append(sum(1 for n, _ in f if not n.startswith('kdet_bvh')))
for k,v in sorted(agg.items()):
    print(f"{k:45s} n={len(v):3d} med={statistics.median(v):8.1f} min={min(v):8.1f} max={max(v):8.1f}")
