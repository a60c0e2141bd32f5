#!/usr/bin/env python3
"""Import cycles between sibling modules of src/ (crate:: and super:: paths, comments and
test modules skipped): prints the strongly connected components; none is the goal."""
import os,re,itertools,collections
root="src"
def modpath(f):
    p=f[len(root)+1:-3].split("/")
    if p[-1] in("mod","lib","main"): p=p[:-1]
    return p
edges=collections.defaultdict(set)
for d,_,fs in os.walk(root):
    for fn in fs:
        if not fn.endswith(".rs"): continue
        f=os.path.join(d,fn); me=modpath(f)
        s=open(f).read()
        # strip test modules roughly
        s=re.split(r"#\[cfg\(test\)\]", s)[0]
        s="\n".join(l for l in s.split("\n") if not l.strip().startswith("//"))
        for m in re.finditer(r"\b(crate|super)((?:::\w+)+)", s):
            parts=m.group(2).strip(":").split("::")
            if m.group(1)=="crate": tgt=parts
            else:
                base=me[:-1] if fn not in("mod.rs",) else me[:-1]
                tgt=base+parts
            # compare at every depth: siblings under common parent
            for k in range(1,min(len(me),len(tgt))+1):
                if me[:k-1]==tgt[:k-1] and me[k-1]!=tgt[k-1]:
                    edges[tuple(me[:k])].add(tuple(tgt[:k])); break
cyc=[]
for a in list(edges):
    for b in edges[a]:
        if a in edges.get(b,()): cyc.append((a,b))
print("2-cycles:",sorted(set(tuple(sorted(c)) for c in cyc)))
# longer cycles among nodes via DFS (SCCs)
import sys
sys.setrecursionlimit(10000)
idx={};low={};st=[];on=set();sccs=[];c=[0]
def sc(v):
    idx[v]=low[v]=c[0];c[0]+=1;st.append(v);on.add(v)
    for w in edges.get(v,()):
        if w not in idx: sc(w);low[v]=min(low[v],low[w])
        elif w in on: low[v]=min(low[v],idx[w])
    if low[v]==idx[v]:
        comp=[]
        while True:
            w=st.pop();on.discard(w);comp.append(w)
            if w==v:break
        if len(comp)>1: sccs.append(comp)
for v in list(edges):
    if v not in idx: sc(v)
print("SCCs:",sccs)
