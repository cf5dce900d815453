#!/usr/bin/env python3
"""P / E_eff against the box's volumetric strain 1 - V / V_jam, for `bpm
compact` output folders given as arguments (run from their parent folder):
each run's series (compaction.json) interpolated between the rows on each
side of the strain; V_jam is the box at the end of the jam stage. Prints a
markdown table, one column per folder ('-' where a run stopped first)."""
import json, sys
def at_strains(name, targets):
    d=json.load(open(f'{name}/compaction.json'))
    r=d['runs'][0]; e=d['e_eff']; s=r['series']; st=r['states']
    vjam=[x for x in st if x['stage']=='jam'][-1]['box_volume']
    out=[]
    V=s['box_volume']; P=s['pressure']
    for t in targets:
        val=None
        for k in range(1,len(V)):
            a=1-V[k-1]/vjam; b=1-V[k]/vjam
            if a < t <= b:
                w=(t-a)/(b-a); val=(P[k-1]+w*(P[k]-P[k-1]))/e; break
        out.append(val)
    return out
targets=[0.10,0.20,0.25,0.30,0.40,0.45,0.50,0.55,0.599]
names=sys.argv[1:]
print('| box strain | ' + ' | '.join(names) + ' |')
print('| --- ' * (len(names) + 1) + '|')
cols=[at_strains(n,targets) for n in names]
for i,t in enumerate(targets):
    print(f'| {t:.2f} | ' + ' | '.join('-' if c[i] is None else f'{c[i]:.3g}' for c in cols) + ' |')
