#!/usr/bin/env python3
"""Checks that no link of a chain passed through another in a run of liedyn: for every frame of
OUT/trajectory.csv, the linking number of each two links' centre lines (the stadium curves of
their "link" shapes, read from SCENE) is 1 for neighbours in the body list and 0 for the others
near each other. The linking number is counted from the signed crossings of the two polygons
seen along a fixed generic direction; it changes only when the two wires cross.

Usage: python3 scripts/check_chain_links.py SCENE OUT/trajectory.csv
Prints the frames checked and every pair whose linking number is wrong; exit status 1 if any.
"""
import csv, json, math, sys, collections
scene=json.load(open(sys.argv[1]))
link=[b for b in scene["bodies"] if b.get("contact",{}).get("shape",{}).get("type")=="link"]
shape=link[0]["contact"]["shape"]
L,R,rr=shape["half_length"],shape["major_radius"],shape["minor_radius"]
order={b["name"]:i for i,b in enumerate(link)}
def quat_mat(w,x,y,z):
    return [[1-2*(y*y+z*z),2*(x*y-w*z),2*(x*z+w*y)],[2*(x*y+w*z),1-2*(x*x+z*z),2*(y*z-w*x)],[2*(x*z-w*y),2*(y*z+w*x),1-2*(x*x+y*y)]]
pts=[]
n=10
for side in (1,-1):
    for i in range(n+1):
        a=-math.pi/2+math.pi*i/n
        pts.append((side*(L+R*math.cos(a)), side*R*math.sin(a),0.0))
v=(0.31,0.47,0.83); nv=math.sqrt(sum(c*c for c in v)); e3=[c/nv for c in v]
e1=[e3[1],-e3[0],0.0]; n1=math.sqrt(sum(c*c for c in e1)); e1=[c/n1 for c in e1]
e2=[e3[1]*e1[2]-e3[2]*e1[1], e3[2]*e1[0]-e3[0]*e1[2], e3[0]*e1[1]-e3[1]*e1[0]]
dot=lambda a,b: a[0]*b[0]+a[1]*b[1]+a[2]*b[2]
def curve(r):
    x=[float(r['x']),float(r['y']),float(r['z'])]; M=quat_mat(*(float(r[k]) for k in ('qw','qx','qy','qz')))
    out=[]
    for p in pts:
        q=[x[i]+sum(M[i][j]*p[j] for j in range(3)) for i in range(3)]
        out.append((dot(q,e1),dot(q,e2),dot(q,e3)))
    return out
def lk(a,b):
    t2=0
    for i in range(len(a)):
        p,p1=a[i],a[(i+1)%len(a)]; r=(p1[0]-p[0],p1[1]-p[1])
        for j in range(len(b)):
            q,q1=b[j],b[(j+1)%len(b)]; s=(q1[0]-q[0],q1[1]-q[1])
            d=r[0]*s[1]-r[1]*s[0]
            if d==0: continue
            qp=(q[0]-p[0],q[1]-p[1])
            t=(qp[0]*s[1]-qp[1]*s[0])/d; u=(qp[0]*r[1]-qp[1]*r[0])/d
            if t<0 or t>=1 or u<0 or u>=1: continue
            ha=p[2]+t*(p1[2]-p[2]); hb=q[2]+u*(q1[2]-q[2])
            sg=1 if d>0 else -1
            t2+= sg if ha>hb else -sg
    return t2//2
frames=collections.defaultdict(dict)
for r in csv.DictReader(open(sys.argv[2])):
    if r['object'] in order: frames[int(r['frame'])][r['object']]=r
bad=0
for f in sorted(frames):
    names=sorted(frames[f], key=order.get); cs={k:curve(frames[f][k]) for k in names}
    for i in range(len(names)):
        for j in range(i+1,len(names)):
            a=frames[f][names[i]]; b=frames[f][names[j]]
            dist=math.dist([float(a[k]) for k in 'xyz'],[float(b[k]) for k in 'xyz'])
            if j!=i+1 and dist>2*(L+R+rr): continue
            l=abs(lk(cs[names[i]],cs[names[j]]))
            if l!=(1 if j==i+1 else 0): bad+=1; print('frame',f,names[i],names[j],l)
print('frames checked', len(frames), '; pairs wrongly linked', bad)
sys.exit(1 if bad else 0)
