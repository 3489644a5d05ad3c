# The durations (us) of the kernels in each "== scene setting" block of an ncu CSV (gzip),
# medians per kernel name (its last 40 characters). Usage: ncu_kernels.py FILE.csv.gz
import sys,csv,collections,statistics,gzip
lines=gzip.open(sys.argv[1],'rt').read().split('\n')
def flush(name,cur):
    if not name: return
    rows=list(csv.reader([l for l in cur if l.startswith('"')]))
    if not rows: return
    h=rows[0]
    ki=h.index('Kernel Name'); mi=h.index('Metric Name'); vi=h.index('Metric Value')
    t=collections.OrderedDict()
    for r in rows[1:]:
        if r[mi]=='gpu__time_duration.sum':
            t.setdefault(r[ki].split('(')[0][-40:],[]).append(float(r[vi].replace(',',''))/1000)
    print(name)
    for k,v in t.items(): print('   %-42s n=%3d med=%7.1f min=%7.1f max=%7.1f'%(k,len(v),statistics.median(v),min(v),max(v)))
name=None;cur=[]
for l in lines:
    if l.startswith('== '):
        flush(name,cur); name=l; cur=[]
    else: cur.append(l)
flush(name,cur)
