#!/usr/bin/env python3
"""ViSP's real grey 'mbt/cube' footage as a sequence (DATASET.md): an 84 mm printed cube on a
desk filmed by a hand-held camera, 218 frames of 640x480, with ViSP's untextured cube model
(its 8 corners) and the first frame's pose (ViSP's cube.0.pos). There is no ground truth:
judge a track by `unseen overlay` and by its statuses.

  apt-get install visp-images-data python3-opencv     # Debian's; or unpack the .deb anywhere
  /usr/bin/python3 bench/heldout/visp_mbt_cube.py \\
      /usr/share/visp-images-data/ViSP-images/mbt OUT/visp_mbt_cube
  unseen track OUT/visp_mbt_cube --init "$(cat OUT/visp_mbt_cube/init_pose.txt)" --out p.csv
"""
import json
import os
import sys

import cv2
import numpy as np


def main(source, out):
    os.makedirs(os.path.join(out, 'cam0', 'rgb'), exist_ok=True)
    os.makedirs(os.path.join(out, 'models'), exist_ok=True)
    frames = sorted(f for f in os.listdir(os.path.join(source, 'cube')) if f.endswith('.pgm'))
    if not frames:
        sys.exit(f'{source}/cube: no .pgm frames')
    # Intrinsics of ViSP's mbt/cube.xml (no distortion).
    k = [547.7367575, 0, 338.7036994, 0, 542.0744058, 234.5083345, 0, 0, 1]
    cameras = {}
    for i, name in enumerate(frames):
        grey = cv2.imread(os.path.join(source, 'cube', name), cv2.IMREAD_GRAYSCALE)
        cv2.imwrite(os.path.join(out, 'cam0', 'rgb', f'{i:06d}.png'),
                    cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR))
        cameras[str(i)] = {'cam_K': k, 'depth_scale': 1.0}
    with open(os.path.join(out, 'cam0', 'scene_camera.json'), 'w') as f:
        json.dump(cameras, f)
    # cube.cao's corners (mm) and quads, split in two and wound outwards.
    corners = np.array([[0, 0, 0], [-84, 0, 0], [-84, 84, 0], [0, 84, 0],
                        [0, 0, 84], [-84, 0, 84], [-84, 84, 84], [0, 84, 84]], float)
    quads = [[0, 4, 5, 1], [1, 5, 6, 2], [6, 7, 3, 2], [3, 7, 4, 0], [0, 1, 2, 3], [7, 6, 5, 4]]
    centre = corners.mean(0)
    triangles = []
    for q in quads:
        for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]]):
            normal = np.cross(corners[t[1]] - corners[t[0]], corners[t[2]] - corners[t[0]])
            if normal.dot(corners[t].mean(0) - centre) < 0:
                t = [t[0], t[2], t[1]]
            triangles.append(t)
    with open(os.path.join(out, 'models', 'obj_000001.ply'), 'w') as f:
        f.write('ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n'
                'property float z\nelement face %d\nproperty list uchar int vertex_indices\n'
                'end_header\n' % len(triangles))
        for p in corners:
            f.write('%g %g %g\n' % tuple(p))
        for t in triangles:
            f.write('3 %d %d %d\n' % tuple(t))
    with open(os.path.join(out, 'sequence.json'), 'w') as f:
        json.dump({'fps': 30, 'cameras': ['cam0'],
                   'object': {'obj_id': 1, 'model': 'models/obj_000001.ply'},
                   'notes': "ViSP mbt/cube: real grey footage, untextured 84 mm cube model, "
                            "no ground truth; first pose in init_pose.txt"}, f, indent=1)
    # cube.0.pos: camera-from-object translation (m) and theta-u rotation (rad).
    with open(os.path.join(source, 'cube.0.pos')) as f:
        v = [float(line.split()[0]) for line in f if line.strip()]
    rotation, _ = cv2.Rodrigues(np.array(v[3:6]))
    w = np.sqrt(max(0.0, 1.0 + np.trace(rotation))) / 2.0
    q = [(rotation[2, 1] - rotation[1, 2]) / (4 * w), (rotation[0, 2] - rotation[2, 0]) / (4 * w),
         (rotation[1, 0] - rotation[0, 1]) / (4 * w), w]
    with open(os.path.join(out, 'init_pose.txt'), 'w') as f:
        f.write(','.join('%.9g' % x for x in v[:3] + q) + '\n')


if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
