# Heading of a torso band per frame against frame 0 (best rigid fit), for the
# "slow turn" finding in docs/studies/25-spins-and-tears.md. Needs numpy.
#   python3 docs/studies/heading_drift.py SEQ_DIR...   (folders of binary-PLY frames)
import sys,glob,struct,numpy as np
def verts(p):
    b=open(p,'rb').read(); h=b.index(b'end_header\n')+11
    n=int([l for l in b[:h].decode().split('\n') if l.startswith('element vertex')][0].split()[2])
    return np.frombuffer(b,dtype='<f8',count=3*n,offset=h).reshape(n,3)
for d in sys.argv[1:]:
    fs=sorted(glob.glob(d+'/*.ply')); F=[verts(f) for f in fs]
    v0=F[0]; y=v0[:,1]; lo,hi=y.min(),y.max(); c=v0.mean(0)
    sel=(y>lo+0.5*(hi-lo))&(y<lo+0.75*(hi-lo))&(np.hypot(v0[:,0]-c[0],v0[:,2]-c[2])<0.15)
    def yaw(a,b):
        A=a[sel]-a[sel].mean(0); B=b[sel]-b[sel].mean(0)
        U,S,Vt=np.linalg.svd(A.T@B); R=(U@Vt).T
        if np.linalg.det(R)<0: Vt[-1]*=-1; R=(U@Vt).T
        return np.degrees(np.arctan2(R[0,2],R[2,2]))
    hs=[yaw(F[0],f) for f in F]
    steps=[yaw(F[i],F[i+1]) for i in range(len(F)-1)]
    print(d[-22:], 'sel',sel.sum(),'heading vs frame0:', ' '.join('%.0f'%h for h in hs[::2]), '| max step %.1f'%max(abs(s) for s in steps))
