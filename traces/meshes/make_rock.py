#!/usr/bin/env python3
"""Writes traces/meshes/rock.obj: a rock of many creases for the see-through test.

An icosphere subdivided twice (162 vertices, 320 triangles) with each vertex's radius
scaled by 1 + AMP * (u - 0.5), u from Python's random module seeded with SEED. Auto-smoothed
at 40 degrees (traces/rock_creased.json), its edges meet at angles from a few degrees to
beyond 90: creases of many angles, corners where three or more meet, creases that end
inside smooth regions.

    python3 traces/meshes/make_rock.py 2 3 0.35 > traces/meshes/rock.obj
"""
import math, sys, random
def icosphere(level):
    t=(1+5**0.5)/2
    v=[(-1,t,0),(1,t,0),(-1,-t,0),(1,-t,0),(0,-1,t),(0,1,t),(0,-1,-t),(0,1,-t),(t,0,-1),(t,0,1),(-t,0,-1),(-t,0,1)]
    v=[tuple(c/math.sqrt(sum(x*x for x in p)) for c in p) for p in v]
    f=[(0,11,5),(0,5,1),(0,1,7),(0,7,10),(0,10,11),(1,5,9),(5,11,4),(11,10,2),(10,7,6),(7,1,8),(3,9,4),(3,4,2),(3,2,6),(3,6,8),(3,8,9),(4,9,5),(2,4,11),(6,2,10),(8,6,7),(9,8,1)]
    for _ in range(level):
        cache={}; nf=[]
        def mid(a,b):
            k=(min(a,b),max(a,b))
            if k in cache: return cache[k]
            p=[(v[a][i]+v[b][i])/2 for i in range(3)]; n=math.sqrt(sum(x*x for x in p))
            v.append(tuple(x/n for x in p)); cache[k]=len(v)-1; return cache[k]
        for a,b,c in f:
            ab,bc,ca=mid(a,b),mid(b,c),mid(c,a)
            nf+= [(a,ab,ca),(b,bc,ab),(c,ca,bc),(ab,bc,ca)]
        f=nf
    return v,f
level=int(sys.argv[1]); seed=int(sys.argv[2]); amp=float(sys.argv[3])
random.seed(seed)
v,f=icosphere(level)
v=[tuple(c*(1+amp*(random.random()-0.5)) for c in p) for p in v]
print("# rock: icosphere level %d, radii scaled by 1 + %g * (u - 0.5), u uniform (Python random, seed %d)"%(level,amp,seed))
for p in v: print("v %.6f %.6f %.6f"%p)
for a,b,c in f: print("f %d %d %d"%(a+1,b+1,c+1))
