import csv,re,sys
rows=list(csv.reader(open(sys.argv[1])))
hdr=None;seq=[]
for r in rows:
    if r and r[0]=='ID': hdr=r; continue
    if hdr and len(r)==len(hdr):
        seq.append(dict(zip(hdr,r)))
k={};order=[]
for d in seq:
    i=d['ID']
    if i not in k: k[i]={'name':d['Kernel Name']}; order.append(i)
    k[i][d['Metric Name']]=d['Metric Value'].replace(',','')
names=[]
for i in order:
    n=re.sub(r'\(.*','',k[i]['name'].replace('<unnamed>::','')).replace('void ','')
    n=re.sub(r'<.*','',n).split('::')[-1]
    names.append((n,float(k[i]['gpu__time_duration.sum'])/1000,k[i].get('launch__grid_size'),k[i].get('launch__registers_per_thread'),k[i].get('sm__warps_active.avg.pct_of_peak_sustained_active')))
print(len(names))  # (usage: ncu_sequence.py NCU_CSV FRAME_INDEX...)
start=[j for j,(n,*_) in enumerate(names) if n=='trianglesKernel']
print(len(start))
pick=[int(x) for x in sys.argv[2:]]
for s in [start[p] for p in pick]:
    e=next((j for j in start if j>s), len(names))
    tot=0
    for n,t,g,r,w in names[s:e]:
        if n.startswith('kdet_bvh') or 'Bvh' in n: continue
        tot+=t; print(f"  {n:40s} {t:8.1f} grid={g} regs={r} warps={w}")
    print('total',tot)
