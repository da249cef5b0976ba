# How much of a transfer's error against a reference performance is timing?
# For docs/studies/30-animated-characters.md. Needs numpy.
#   python3 docs/studies/reference_timing.py REST.ply REFERENCE_DIR PREDICTION_DIR... [--retimed OUT]
# Per prediction (folders of binary-PLY frames, the reference's topology), the RMS
# pose error (each frame rigidly aligned, Procrustes without scale, as transfer-eval)
# against the reference, for the prediction and for REST held still:
#   time-normalised: frame i of n against the reference at i (m-1)/(n-1) (transfer-eval --time-normalise)
#   dtw:             along the monotone frame alignment of least summed squared error
#   nearest:         each frame against its nearest reference frame (no timing at all)
#   python3 docs/studies/reference_timing.py --nearest QUERY_DIR TRAINING_DIR...
# prints, per training folder, the RMS over QUERY's frames of the pose error to the nearest of its
# frames: how far a motion lies from what a model was trained on.
# --retimed OUT copies the reference's frames onto the first prediction's frame numbers twice, for
# `render --separate-rows`: OUT/time-normalised (the nearest frame in time) and OUT/dtw (the frame
# the alignment pairs it with).
import sys, glob, os, shutil, numpy as np

def verts(p):
    b = open(p, 'rb').read(); h = b.index(b'end_header\n') + 11
    n = int([l for l in b[:h].decode().split('\n') if l.startswith('element vertex')][0].split()[2])
    return np.frombuffer(b, dtype='<f8', count=3 * n, offset=h).reshape(n, 3)

def frames(d):
    return [verts(f) for f in sorted(glob.glob(d + '/*.ply'))]

def pose_err(a, b):
    A = a - a.mean(0); B = b - b.mean(0)
    U, S, Vt = np.linalg.svd(A.T @ B)
    d = np.sign(np.linalg.det(U @ Vt))
    R = U @ np.diag([1, 1, d]) @ Vt
    return np.sqrt(((A @ R - B) ** 2).sum(1).mean())

def time_normalised(P, R):
    n, m = len(P), len(R); e = []
    for i, p in enumerate(P):
        u = i * (m - 1) / (n - 1) if n > 1 else 0.0
        a = min(int(np.floor(u)), m - 1); b = min(a + 1, m - 1); t = u - a
        e.append(pose_err(p, R[a] * (1 - t) + R[b] * t))
    return np.sqrt(np.mean(np.square(e)))

def dtw(C):
    # (RMS along the least-cost path, the path's first reference frame per prediction frame)
    n, m = C.shape; D = np.full((n + 1, m + 1), np.inf); L = np.zeros((n + 1, m + 1)); D[0, 0] = 0
    B = {}
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            k = min(((D[i - 1, j - 1], L[i - 1, j - 1], (i - 1, j - 1)), (D[i - 1, j], L[i - 1, j], (i - 1, j)),
                     (D[i, j - 1], L[i, j - 1], (i, j - 1))))
            D[i, j] = k[0] + C[i - 1, j - 1]; L[i, j] = k[1] + 1; B[i, j] = k[2]
    match = [0] * n; node = (n, m)
    while node != (0, 0) and node in B:
        match[node[0] - 1] = node[1] - 1; node = B[node]
    return np.sqrt(D[n, m] / L[n, m]), match

def retime(src_files, picks, out):
    shutil.rmtree(out, ignore_errors=True); os.makedirs(out)
    for i, j in enumerate(picks):
        shutil.copy(src_files[j], os.path.join(out, '%06d.ply' % i))

args = sys.argv[1:]; retimed = None
if args[0] == '--nearest':
    Q = frames(args[1])
    for d in args[2:]:
        T = frames(d)
        e = [min(pose_err(q, t) for t in T) for q in Q]
        print('%-40s nearest RMS %.1f cm, largest %.1f' % (d[-40:], 100 * np.sqrt(np.mean(np.square(e))), 100 * max(e)))
    sys.exit(0)
if '--retimed' in args:
    k = args.index('--retimed'); retimed = args[k + 1]; del args[k:k + 2]
rest = verts(args[0]); R = frames(args[1]); ref_files = sorted(glob.glob(args[1] + '/*.ply'))
for d in args[2:]:
    P = frames(d)
    C = np.array([[pose_err(p, r) ** 2 for r in R] for p in P])
    Cs = np.array([pose_err(rest, r) ** 2 for r in R])
    aligned, match = dtw(C)
    if retimed:
        n, m = len(P), len(R)
        retime(ref_files, [round(i * (m - 1) / (n - 1)) for i in range(n)], retimed + '/time-normalised')
        retime(ref_files, match, retimed + '/dtw'); retimed = None
    print('%-60s frames %d/%d  time-normalised %.1f (still %.1f)  dtw %.1f (still %.1f)  nearest %.1f (still %.1f) cm' % (
        d[-60:], len(P), len(R),
        100 * time_normalised(P, R), 100 * time_normalised([rest] * len(P), R),
        100 * aligned, 100 * np.sqrt(Cs.mean()),
        100 * np.sqrt(C.min(1).mean()), 100 * np.sqrt(Cs.min())))
