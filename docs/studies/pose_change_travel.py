# Pose change per frame and travel of variations against their source, for
# docs/studies/39-motion-matching-baseline.md. Needs numpy.
#   python3 docs/studies/pose_change_travel.py SOURCE VAR...   (y up; each a folder of binary-PLY frames
#   or a .pc2 point cache, as hmc-sample --frame-format pc2 writes)
# Pose change: the mean per-vertex distance between consecutive frames after the best rigid fit
# of one onto the other (mm), averaged over the frames: how much the body moves besides travelling.
# Travel: the horizontal displacement of the mean vertex from the first to the last frame along
# the source's own (unit) direction, divided by the source's travel: 1 goes as far as the source.
import sys, glob, struct, numpy as np

def verts(p):
    b = open(p, 'rb').read(); h = b.index(b'end_header\n') + 11
    n = int([l for l in b[:h].decode().split('\n') if l.startswith('element vertex')][0].split()[2])
    return np.frombuffer(b, dtype='<f8', count=3 * n, offset=h).reshape(n, 3)

def frames(d):
    if d.endswith('.pc2'):
        b = open(d, 'rb').read()
        n, = struct.unpack('<i', b[16:20]); t, = struct.unpack('<i', b[28:32])
        return list(np.frombuffer(b, dtype='<f4', count=3 * n * t, offset=32).reshape(t, n, 3).astype(float))
    return [verts(f) for f in sorted(glob.glob(d + '/*.ply'))]

def rigid_residual(a, b):
    # Mean distance of b's vertices to a after the best rotation and translation of b onto a.
    A = a - a.mean(0); B = b - b.mean(0)
    U, S, Vt = np.linalg.svd(B.T @ A)
    D = np.eye(3); D[2, 2] = np.sign(np.linalg.det(U @ Vt))
    R = U @ D @ Vt
    return np.linalg.norm(B @ R - A, axis=1).mean()

def pose_change_mm(F):
    return 1000 * np.mean([rigid_residual(F[i], F[i + 1]) for i in range(len(F) - 1)])

def horizontal_travel(F):
    d = F[-1].mean(0) - F[0].mean(0); d[1] = 0.0
    return d

src = frames(sys.argv[1])
ds = horizontal_travel(src); dist = np.linalg.norm(ds); u = ds / max(dist, 1e-12)
print('source %s: pose change %.1f mm/frame, travel %.2f m' % (sys.argv[1][-30:], pose_change_mm(src), dist))
pcs, trs = [], []
for d in sys.argv[2:]:
    F = frames(d)
    pc = pose_change_mm(F); tr = float(horizontal_travel(F) @ u) / max(dist, 1e-12)
    pcs.append(pc); trs.append(tr)
    print('  %s: pose change %.1f mm/frame (%.2f of the source), travel %.2f of the source' % (d[-30:], pc, pc / pose_change_mm(src), tr))
print('mean: pose change %.1f mm/frame (%.2f of the source), travel %.2f of the source (min %.2f, max %.2f)'
      % (np.mean(pcs), np.mean(pcs) / pose_change_mm(src), np.mean(trs), min(trs), max(trs)))
