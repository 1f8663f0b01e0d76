#!/usr/bin/env python3
"""Convert ViSP's SIMULATED RGB-D castle sequence (Debian visp-images-data, mbt-depth/Castle-simu)
into the sequence format of DATASET.md, with ground truth: 40 rendered grey 640x480 frames of
the castle of mbt-depth/castel (plus a textured ViSP cube and other props that are not part of
the tracked model), a rendered depth image per frame, ViSP's untextured CAD model of the castle
(Models/chateau.cao: floor + tower, 5 polygons) and the exact pose of every frame.

  apt-get install visp-images-data python3-opencv     # Debian's; or unpack the .deb anywhere
  /usr/bin/python3 bench/heldout/visp_castle_simu.py \\
      /usr/share/visp-images-data/ViSP-images/mbt-depth/Castle-simu OUT/visp_castle_simu
  unseen track OUT/visp_castle_simu --init gt --out p.csv && unseen eval OUT/visp_castle_simu p.csv

What the source holds (as read by ViSP's testGenericTracker.cpp, checked against the data):
  * Images/Image_%04d.pgm       8-bit GREY 640x480 (P5), frames 1..40, written as 3-channel BGR
                                PNG with frame id = source number - 1.
  * Depth/Depth_%04d.bin        uint32 LE height (480), uint32 LE width (640), then height*width
                                uint16 LE, row-major; 0 = no surface (empty background). Unit
                                0.000030518 m (ViSP's depth_scale, ~1/32768): with it, depth at the
                                model's visible surface matches the ground truth to -0.16 mm median.
                                It is z-depth (not range along the ray) and is rendered from a
                                SEPARATE depth camera: same intrinsics, X_depth = X_color + (-0.05, 0, 0)
                                (ViSP's depth_M_color, hard-coded in its test; a 5 cm baseline
                                reproduces the data best). It is registered here to the grey camera.
  * CameraPose/Camera_%03d.txt  4x4 row-major cMo in metres: the castle's object frame (the frame
                                of chateau.cao) in the grey camera, one per frame. ViSP's test
                                initialises from it and scores against it.
  * Config/chateau.xml, chateau_depth.xml  px = py = 700, u0 = 320, v0 = 240, no distortion.
  * Models/chateau.cao (+ chateau_parts/floor, tower): V1 .cao in metres; differs from castel's
    (no front door or slope, floor 5 mm shorter). chateau.wrl is the rendered scene and cube.cao a
    cube ViSP's test adds to the tracked model at a fixed offset; neither is used here.
"""
import json
import os
import re
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import visp_castel as vc  # noqa: E402  (.cao parsing, PLY writing, depth registration)

DEPTH_SCALE_M = 0.000030518               # raw unit -> metres (ViSP testGenericTracker.cpp)
DEPTH_M_COLOR = np.array([[1, 0, 0, -0.05],  # X_depth = DEPTH_M_COLOR * X_color
                          [0, 1, 0, 0],
                          [0, 0, 1, 0],
                          [0, 0, 0, 1]], float)


def frame_numbers(src):
    nums = sorted(int(m.group(1)) for m in (re.match(r'Image_(\d+)\.pgm$', f)
                                            for f in os.listdir(os.path.join(src, 'Images'))) if m)
    if not nums:
        sys.exit('%s/Images: no Image_*.pgm frames' % src)
    return nums


def read_cmo(src, num):
    T = np.loadtxt(os.path.join(src, 'CameraPose', 'Camera_%03d.txt' % num))
    if T.shape != (4, 4) or not np.allclose(T[3], [0, 0, 0, 1]):
        sys.exit('CameraPose/Camera_%03d.txt: not a 4x4 rigid transform' % num)
    if not np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-5):
        sys.exit('CameraPose/Camera_%03d.txt: the rotation is not orthonormal' % num)
    return T


def write_frames(src, out, nums):
    """rgb/, depth/ (registered to the grey camera, uint16 mm) and scene_camera.json."""
    Kc = vc.read_visp_cam_xml(os.path.join(src, 'Config', 'chateau.xml'))
    Kd = vc.read_visp_cam_xml(os.path.join(src, 'Config', 'chateau_depth.xml'))
    cam_K = [Kc[0], 0, Kc[2], 0, Kc[1], Kc[3], 0, 0, 1]
    cams = {}
    for i, num in enumerate(nums):
        grey = cv2.imread(os.path.join(src, 'Images', 'Image_%04d.pgm' % num), cv2.IMREAD_GRAYSCALE)
        cv2.imwrite(os.path.join(out, 'cam0', 'rgb', '%06d.png' % i), cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR))
        raw = vc.read_depth_bin(os.path.join(src, 'Depth', 'Depth_%04d.bin' % num))
        depth = vc.register_depth(raw, Kd, Kc, DEPTH_M_COLOR, grey.shape, coeffs=None, scale=DEPTH_SCALE_M)
        cv2.imwrite(os.path.join(out, 'cam0', 'depth', '%06d.png' % i), depth)
        cams[str(i)] = {'cam_K': cam_K, 'depth_scale': 1.0}
    with open(os.path.join(out, 'cam0', 'scene_camera.json'), 'w') as f:
        json.dump(cams, f, indent=1)


def write_gt(src, out, nums):
    """scene_gt.json (model->camera, mm; camera frame = world frame) and init_pose.txt (frame 0,
    T_world_object as tx,ty,tz,qx,qy,qz,qw in metres). Returns the first pose line."""
    gt = {}
    for i, num in enumerate(nums):
        T = read_cmo(src, num)
        gt[str(i)] = [{'obj_id': 1, 'cam_R_m2c': [float(x) for x in T[:3, :3].ravel()],
                       'cam_t_m2c': [float(x) * 1000.0 for x in T[:3, 3]]}]
    with open(os.path.join(out, 'cam0', 'scene_gt.json'), 'w') as f:
        json.dump(gt, f, indent=1)
    T = read_cmo(src, nums[0])
    line = ','.join('%.9g' % x for x in list(T[:3, 3]) + list(vc.rot_to_quat(T[:3, :3])))
    with open(os.path.join(out, 'init_pose.txt'), 'w') as f:
        f.write(line + '\n')
    return line


def write_model(src, out):
    """models/obj_000001.ply (chateau.cao, object frame kept, mm) and models_info.json."""
    V, F, info, ignored = vc.build_mesh(os.path.join(src, 'Models', 'chateau.cao'))
    Vmm = V * 1000.0
    vc.write_ply(os.path.join(out, 'models', 'obj_000001.ply'), Vmm, F,
                 comment='ViSP chateau.cao (mbt-depth/Castle-simu), object frame kept, mm')
    lo, size = Vmm.min(0), Vmm.max(0) - Vmm.min(0)
    diam = np.linalg.norm(Vmm[:, None] - Vmm[None], axis=2).max()
    with open(os.path.join(out, 'models', 'models_info.json'), 'w') as f:
        json.dump({'1': {'diameter': float(diam), 'min_x': float(lo[0]), 'min_y': float(lo[1]),
                         'min_z': float(lo[2]), 'size_x': float(size[0]), 'size_y': float(size[1]),
                         'size_z': float(size[2])}}, f, indent=1)
    return V, F, info, ignored


def write_sequence_json(out, n_frames, n_polys):
    notes = ('ViSP mbt-depth/Castle-simu (Debian visp-images-data): %d SIMULATED frames, f = 700 px, '
             'no distortion. rgb = the source GREY renders as 3-channel BGR (frame id = source number - 1). '
             'depth = the rendered z-depth (unit %.9g m) of a depth camera 5 cm to the +x of the grey '
             'camera (ViSP depth_M_color), registered to the grey camera, z-buffered, 1-px holes filled, mm. '
             'Model = Castle-simu chateau.cao (floor + open-topped tower: %d polygons, an OPEN partial '
             'model; the scene also holds a textured ViSP cube and unmodelled props), ViSP object frame, '
             'm->mm. Ground truth = CameraPose cMo (exact); init_pose.txt = frame 0. fps unknown (30 '
             'assumed).' % (n_frames, DEPTH_SCALE_M, n_polys))
    with open(os.path.join(out, 'sequence.json'), 'w') as f:
        json.dump({'fps': 30, 'cameras': ['cam0'],
                   'object': {'obj_id': 1, 'model': 'models/obj_000001.ply'}, 'notes': notes}, f, indent=1)


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    src, out = argv[1:]
    for sub in ('cam0/rgb', 'cam0/depth', 'models'):
        os.makedirs(os.path.join(out, sub), exist_ok=True)
    nums = frame_numbers(src)
    write_frames(src, out, nums)
    line = write_gt(src, out, nums)
    V, F, info, ignored = write_model(src, out)
    write_sequence_json(out, len(nums), len(info))

    print('frames', len(nums), '(source %d..%d)' % (nums[0], nums[-1]), 'vertices', len(V), 'triangles', len(F))
    for name, k, how, n in info:
        print('  face %-12s %d pts  %s  normal %s' % (name, k, how, np.round(n / np.linalg.norm(n), 3)))
    if ignored:
        print('ignored (cylinders/circles):', ignored)
    print('init_pose', line)


if __name__ == '__main__':
    main(sys.argv)
