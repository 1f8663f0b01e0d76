#!/usr/bin/env python3
"""Convert ViSP's real RGB-D "castel" sequence (Debian visp-images-data, mbt-depth/castel)
into the sequence format of DATASET.md: 30 grey 640x480 frames of a castle model larger
than the view, SR300 depth registered to the colour camera, ViSP's untextured CAD model
(chateau.cao and its parts) and first pose (init_pose.txt). No ground truth: judge a track by
its statuses and `unseen overlay`.

  apt-get install visp-images-data python3-opencv     # Debian's; or unpack the .deb anywhere
  /usr/bin/python3 bench/heldout/visp_castel.py \
      /usr/share/visp-images-data/ViSP-images/mbt-depth/castel OUT/visp_castel [--no-depth-distortion]
  unseen track OUT/visp_castel --init "$(cat OUT/visp_castel/init_pose.txt)" --out p.csv

What the source holds:
  * castel/image_%04d.pgm       8-bit GREY 640x480 (P5), written as 3-channel BGR PNG.
  * castel/depth_image_%04d.bin uint32 LE height, uint32 LE width, then height*width uint16 LE
                                raw depth, row-major (ViSP vpIoTools::readBinaryValueLE).
  * Depth unit 0.000124986647 m (Intel SR300; ViSP's test/tutorial for this sequence).
    ViSP deprojects with RealSense's inverse Brown-Conrady model and the coefficients below;
    chateau_depth.xml gives the same fx,fy,ppx,ppy but no distortion.
  * depth_M_color.txt: X_depth = depth_M_color * X_color (ViSP: pose of the colour frame in the
    depth frame; the tracker sets it as Camera2's c2Mc1), so X_color = inv(depth_M_color) X_depth.
  * chateau.cao (+ loaded parts): V1 .cao, metres. chateau.0.pos: cMo as t (m) + theta-u (rad).
"""
import json, os, re, sys
import numpy as np
import cv2

DEPTH_SCALE_M = 0.000124986647            # raw unit -> metres (SR300)
# SR300 depth-stream distortion used by ViSP to deproject this sequence
# (RS2_DISTORTION_INVERSE_BROWN_CONRADY: k1 k2 p1 p2 k3).
DEPTH_COEFFS = [0.165056542, -0.0508309528, 0.00435937941, 0.00541406544, 0.250085592]


# ---------------------------------------------------------------- readers
def read_visp_cam_xml(path):
    txt = open(path).read()
    g = lambda k: float(re.search(r'<%s>\s*([-+0-9.eE]+)\s*</%s>' % (k, k), txt).group(1))
    return g('px'), g('py'), g('u0'), g('v0')


def read_depth_bin(path):
    h, w = np.fromfile(path, dtype='<u4', count=2)
    d = np.fromfile(path, dtype='<u2', offset=8)
    assert d.size == h * w, (path, h, w, d.size)
    return d.reshape(int(h), int(w))


def read_pos(path):
    v = [float(l.split()[0]) for l in open(path) if l.strip()]
    return np.array(v[:3]), np.array(v[3:6])


def rot_to_quat(R):
    """Unit quaternion (x, y, z, w), w >= 0, robust branch choice."""
    tr = np.trace(R)
    if tr > 0:
        s = 2 * np.sqrt(1 + tr)
        q = [(R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s, s / 4]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2 * np.sqrt(1 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [s / 4, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s, (R[2, 1] - R[1, 2]) / s]
    elif R[1, 1] > R[2, 2]:
        s = 2 * np.sqrt(1 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 1] + R[1, 0]) / s, s / 4, (R[1, 2] + R[2, 1]) / s, (R[0, 2] - R[2, 0]) / s]
    else:
        s = 2 * np.sqrt(1 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, s / 4, (R[1, 0] - R[0, 1]) / s]
    q = np.array(q)
    q /= np.linalg.norm(q)
    return q if q[3] >= 0 else -q


# ---------------------------------------------------------------- .cao model
def load_cao(path, _acc=None):
    """Parse a ViSP .cao (V1) file and the files it load()s.
    Returns dict(points=[xyz...], polys=[[global point idx...]], names=[...], ignored=[str...])."""
    acc = _acc if _acc is not None else {'points': [], 'polys': [], 'names': [], 'ignored': []}
    base = os.path.dirname(path)
    lines = []
    for raw in open(path):
        line = raw.split('#', 1)[0].strip()
        if not line:
            continue
        m = re.match(r'load\s*\(\s*"([^"]+)"\s*\)', line)
        if m:
            load_cao(os.path.join(base, m.group(1)), acc)
            continue
        if re.fullmatch(r'V\d+', line):
            continue
        lines.append(line)

    def nums(line):  # numeric tokens, attributes like name=xxx dropped
        return [t for t in line.split() if '=' not in t]

    it = iter(lines)
    off = len(acc['points'])
    pts = []
    n = int(nums(next(it))[0])
    for _ in range(n):
        pts.append([float(x) for x in nums(next(it))[:3]])
    acc['points'] += pts
    segs = []
    n = int(nums(next(it))[0])
    for _ in range(n):
        t = nums(next(it)); segs.append((int(t[0]), int(t[1])))
    # faces from segments: chain segments into a vertex loop
    n = int(nums(next(it))[0])
    for _ in range(n):
        line = next(it); t = nums(line); k = int(t[0])
        ls = [segs[int(x)] for x in t[1:1 + k]]
        a, b = ls[0]
        # orient the first segment so that it connects to the second
        if len(ls) > 1 and a in ls[1]:
            a, b = b, a
        loop = [a, b]
        for s in ls[1:-1]:
            loop.append(s[1] if s[0] == loop[-1] else s[0])
        acc['polys'].append([off + i for i in loop])
        acc['names'].append(_name(line))
    n = int(nums(next(it))[0])
    for _ in range(n):
        line = next(it); t = nums(line); k = int(t[0])
        acc['polys'].append([off + int(x) for x in t[1:1 + k]])
        acc['names'].append(_name(line))
    for kind in ('cylinder', 'circle'):
        try:
            n = int(nums(next(it))[0])
        except StopIteration:
            n = 0
        for _ in range(n):
            acc['ignored'].append('%s in %s: %s' % (kind, os.path.basename(path), next(it)))
    return acc


def _name(line):
    m = re.search(r'name\s*=\s*(\S+)', line)
    return m.group(1) if m else ''


def newell_normal(P):
    n = np.zeros(3)
    for i in range(len(P)):
        a, b = P[i], P[(i + 1) % len(P)]
        n += [(a[1] - b[1]) * (a[2] + b[2]), (a[2] - b[2]) * (a[0] + b[0]), (a[0] - b[0]) * (a[1] + b[1])]
    return n


def triangulate(P, idx):
    """Fan triangulation of a polygon (keeps its winding). If the polygon is not convex and the
    fan would leave it, fall back to ear clipping (also keeps the winding). Returns (tris, method)."""
    P = np.asarray(P, float)
    n = newell_normal(P)
    fan = [(0, i, i + 1) for i in range(1, len(P) - 1)]
    def area(a, b, c):
        return np.dot(np.cross(P[b] - P[a], P[c] - P[a]), n)
    convex = all(np.dot(np.cross(P[i] - P[i - 1], P[(i + 1) % len(P)] - P[i]), n) >= -1e-12
                 for i in range(len(P)))
    if convex:
        return [tuple(idx[j] for j in t) for t in fan], 'fan'
    # ear clipping in the polygon plane
    u = P[1] - P[0]; u /= np.linalg.norm(u)
    nn = n / np.linalg.norm(n); v = np.cross(nn, u)
    Q = np.stack([(P - P[0]) @ u, (P - P[0]) @ v], 1)   # CCW in (u,v) since n = u x v
    cr = lambda o, a, b: (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    rem = list(range(len(P))); tris = []
    while len(rem) > 3:
        for k in range(len(rem)):
            i0, i1, i2 = rem[k - 1], rem[k], rem[(k + 1) % len(rem)]
            if cr(Q[i0], Q[i1], Q[i2]) <= 1e-15:
                continue
            if any(cr(Q[i0], Q[i1], Q[j]) >= 0 and cr(Q[i1], Q[i2], Q[j]) >= 0 and cr(Q[i2], Q[i0], Q[j]) >= 0
                   for j in rem if j not in (i0, i1, i2)):
                continue
            tris.append((i0, i1, i2)); rem.pop(k); break
        else:
            raise RuntimeError('ear clipping failed')
    tris.append(tuple(rem))
    return [tuple(idx[j] for j in t) for t in tris], 'ear-clipping (non-convex)'


def build_mesh(cao_path):
    m = load_cao(cao_path)
    V = np.array(m['points'], float)
    tris, info = [], []
    for poly, name in zip(m['polys'], m['names']):
        t, how = triangulate(V[poly], poly)
        tris += t
        info.append((name, len(poly), how, newell_normal(V[poly])))
    return V, np.array(tris, int), info, m['ignored']


def write_ply(path, V_mm, F, comment='ViSP chateau.cao (mbt-depth/castel), object frame kept, mm'):
    with open(path, 'w') as f:
        f.write('ply\nformat ascii 1.0\ncomment %s\n'
                'element vertex %d\nproperty float x\nproperty float y\nproperty float z\n'
                'element face %d\nproperty list uchar int vertex_indices\nend_header\n' % (comment, len(V_mm), len(F)))
        for p in V_mm:
            f.write('%.3f %.3f %.3f\n' % tuple(p))
        for t in F:
            f.write('3 %d %d %d\n' % tuple(t))


# ---------------------------------------------------------------- depth registration
def deproject(raw, Kd, scale=DEPTH_SCALE_M, coeffs=DEPTH_COEFFS):
    """Raw depth image -> Nx3 points (m) in the depth camera frame, as ViSP/librealsense do."""
    fx, fy, cx, cy = Kd
    v, u = np.nonzero(raw)
    z = raw[v, u].astype(np.float64) * scale
    x = (u - cx) / fx; y = (v - cy) / fy
    if coeffs is not None:
        k1, k2, p1, p2, k3 = coeffs
        r2 = x * x + y * y
        f = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2
        x, y = (x * f + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                y * f + 2 * p2 * x * y + p1 * (r2 + 2 * y * y))
    return np.stack([x * z, y * z, z], 1)


def register_depth(raw, Kd, Kc, depth_M_color, shape, coeffs=DEPTH_COEFFS, fill=True, scale=DEPTH_SCALE_M):
    """Depth image of the colour camera (uint16 mm, 0 = unknown)."""
    Xd = deproject(raw, Kd, scale=scale, coeffs=coeffs)
    color_M_depth = np.linalg.inv(depth_M_color)
    Xc = Xd @ color_M_depth[:3, :3].T + color_M_depth[:3, 3]
    fx, fy, cx, cy = Kc
    z = Xc[:, 2]
    ok = z > 1e-3
    Xc, z = Xc[ok], z[ok]
    u = np.round(fx * Xc[:, 0] / z + cx).astype(int)
    v = np.round(fy * Xc[:, 1] / z + cy).astype(int)
    h, w = shape
    ok = (u >= 0) & (u < w) & (v >= 0) & (v < h)
    u, v, z = u[ok], v[ok], z[ok]
    pix = v * w + u
    order = np.lexsort((z, pix))              # by pixel, then nearest first
    pix, z = pix[order], z[order]
    first = np.ones(len(pix), bool); first[1:] = pix[1:] != pix[:-1]
    out = np.zeros(h * w, np.float64)
    out[pix[first]] = z[first]
    out = out.reshape(h, w)
    mm = np.round(out * 1000.0)
    mm = np.clip(mm, 0, 65535).astype(np.uint16)
    if fill:
        mm = fill_small_holes(mm)
    return mm


def fill_small_holes(d, min_valid=4):
    """Fill 0 pixels that have >= min_valid valid 8-neighbours with the min of those neighbours
    (the nearest surface); larger holes stay 0. This closes the 1-pixel gaps left by forward
    projection from the lower-resolution depth camera (f 476 px) into the colour camera (f 615 px)."""
    big = np.where(d > 0, d, 65535).astype(np.uint16)
    mn = cv2.erode(big, np.ones((3, 3), np.uint8), borderType=cv2.BORDER_CONSTANT, borderValue=65535)
    cnt = cv2.filter2D((d > 0).astype(np.float32), -1, np.ones((3, 3), np.float32),
                       borderType=cv2.BORDER_CONSTANT)
    out = d.copy()
    m = (d == 0) & (cnt >= min_valid) & (mn < 65535)
    out[m] = mn[m]
    return out


# ---------------------------------------------------------------- main
def main(argv):
    args = [a for a in argv[1:] if not a.startswith('--')]
    if len(args) != 2:
        sys.exit(__doc__)
    src, out = args
    coeffs = None if '--no-depth-distortion' in argv else DEPTH_COEFFS
    seq = os.path.join(src, 'castel')
    Kc = read_visp_cam_xml(os.path.join(src, 'chateau.xml'))
    Kd = read_visp_cam_xml(os.path.join(src, 'chateau_depth.xml'))
    D = np.loadtxt(os.path.join(src, 'depth_M_color.txt')).reshape(4, 4)
    for sub in ('cam0/rgb', 'cam0/depth', 'models'):
        os.makedirs(os.path.join(out, sub), exist_ok=True)

    ids = sorted(int(re.match(r'image_(\d+)\.pgm', f).group(1))
                 for f in os.listdir(seq) if re.match(r'image_\d+\.pgm$', f))
    cam_K = [Kc[0], 0, Kc[2], 0, Kc[1], Kc[3], 0, 0, 1]
    cams = {}
    for i, fid in enumerate(ids):
        img = cv2.imread(os.path.join(seq, 'image_%04d.pgm' % fid), cv2.IMREAD_UNCHANGED)
        bgr = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR) if img.ndim == 2 else img
        cv2.imwrite(os.path.join(out, 'cam0/rgb/%06d.png' % i), bgr)
        raw = read_depth_bin(os.path.join(seq, 'depth_image_%04d.bin' % fid))
        reg = register_depth(raw, Kd, Kc, D, bgr.shape[:2], coeffs=coeffs)
        cv2.imwrite(os.path.join(out, 'cam0/depth/%06d.png' % i), reg)
        cams[str(i)] = {'cam_K': cam_K, 'depth_scale': 1.0}
    with open(os.path.join(out, 'cam0/scene_camera.json'), 'w') as f:
        json.dump(cams, f, indent=1)

    V, F, info, ignored = build_mesh(os.path.join(src, 'chateau.cao'))
    Vmm = V * 1000.0
    write_ply(os.path.join(out, 'models/obj_000001.ply'), Vmm, F)
    ext = Vmm.max(0) - Vmm.min(0)
    diam = max(np.linalg.norm(a - b) for a in Vmm for b in Vmm)
    with open(os.path.join(out, 'models/models_info.json'), 'w') as f:
        json.dump({'1': {'diameter': float(diam), 'min_x': float(Vmm[:, 0].min()),
                         'min_y': float(Vmm[:, 1].min()), 'min_z': float(Vmm[:, 2].min()),
                         'size_x': float(ext[0]), 'size_y': float(ext[1]), 'size_z': float(ext[2])}}, f, indent=1)

    t, tu = read_pos(os.path.join(src, 'chateau.0.pos'))
    q = rot_to_quat(cv2.Rodrigues(tu)[0])
    line = ','.join('%.9g' % x for x in list(t) + list(q))
    with open(os.path.join(out, 'init_pose.txt'), 'w') as f:
        f.write(line + '\n')

    notes = ('ViSP mbt-depth/castel (Debian visp-images-data): %d real frames, Intel SR300. '
             'rgb = the source GREY images as 3-channel BGR. depth = SR300 depth (unit %.12g m, '
             'deprojected with the SR300 inverse Brown-Conrady coefficients as ViSP does%s) registered '
             'to the colour camera with X_color = inv(depth_M_color) X_depth, z-buffered, 1-px holes '
             'filled, mm. Model = chateau.cao (floor, tower x4, front door, slope: %d polygons, an OPEN '
             'partial model: no tower top, not a closed volume), ViSP object frame, m->mm. init_pose.txt = chateau.0.pos '
             '(cMo, m). No ground truth; fps unknown (30 assumed).'
             % (len(ids), DEPTH_SCALE_M, '' if coeffs is not None else ' [disabled]', len(info)))
    with open(os.path.join(out, 'sequence.json'), 'w') as f:
        json.dump({'fps': 30, 'cameras': ['cam0'],
                   'object': {'obj_id': 1, 'model': 'models/obj_000001.ply'}, 'notes': notes}, f, indent=1)

    print('frames', len(ids), 'vertices', len(V), 'triangles', len(F))
    for name, k, how, n in info:
        print('  face %-12s %d pts  %s  normal %s' % (name, k, how, np.round(n / np.linalg.norm(n), 3)))
    if ignored:
        print('ignored (cylinders/circles):', ignored)
    else:
        print('no cylinders/circles in the model')
    print('init_pose', line)


if __name__ == '__main__':
    main(sys.argv)
