#!/usr/bin/env python3
"""A first pose off by a given amount, for `unseen track SEQ --init POSE`.

    /usr/bin/python3 bench/perturbed_start.py SEQ OFFSET_MM TURN_DEG SEED

Reads the ground truth of SEQ's first frame (reference camera, BOP layout of DATASET.md),
moves the object by OFFSET_MM in a random direction and turns it by TURN_DEG about a random
axis through its model origin (both drawn from SEED), and prints the pose in the world
frame as tx,ty,tz,qx,qy,qz,qw (metres): the tracker's start when the pose it is given is
that far off. Needs numpy.
"""
import json
import math
import os
import sys

import numpy as np


def first_world_from_obj(seq):
    with open(os.path.join(seq, "sequence.json")) as f:
        meta = json.load(f)
    cams = sorted(d for d in os.listdir(seq) if os.path.isfile(os.path.join(seq, d, "scene_gt.json")))
    if not cams:
        sys.exit(f"{seq}: no camera folder with a scene_gt.json")
    cam = meta.get("reference_camera") if meta.get("reference_camera") in cams else cams[0]
    with open(os.path.join(seq, cam, "scene_gt.json")) as f:
        gt = json.load(f)
    with open(os.path.join(seq, cam, "scene_camera.json")) as f:
        cameras = json.load(f)
    key = min(gt, key=int)
    obj_id = meta.get("object", {}).get("obj_id")
    entries = [g for g in gt[key] if obj_id is None or g.get("obj_id") == obj_id] or gt[key]
    cam_R_obj = np.array(entries[0]["cam_R_m2c"], float).reshape(3, 3)
    cam_t_obj = np.array(entries[0]["cam_t_m2c"], float) / 1000.0
    c = cameras[key]
    cam_R_world = np.array(c.get("cam_R_w2c", np.eye(3).ravel().tolist()), float).reshape(3, 3)
    cam_t_world = np.array(c.get("cam_t_w2c", [0.0, 0.0, 0.0]), float) / 1000.0
    # world_from_obj = (cam_from_world)^-1 cam_from_obj
    return cam_R_world.T @ cam_R_obj, cam_R_world.T @ (cam_t_obj - cam_t_world)


def rotation(axis_angle):
    angle = np.linalg.norm(axis_angle)
    if angle == 0.0:
        return np.eye(3)
    k = axis_angle / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


def quaternion(R):
    """(qx, qy, qz, qw) of a rotation matrix."""
    w = math.sqrt(max(0.0, 1.0 + R[0, 0] + R[1, 1] + R[2, 2])) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1.0 + R[0, 0] - R[1, 1] - R[2, 2])) / 2.0, R[2, 1] - R[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - R[0, 0] + R[1, 1] - R[2, 2])) / 2.0, R[0, 2] - R[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - R[0, 0] - R[1, 1] + R[2, 2])) / 2.0, R[1, 0] - R[0, 1])
    return x, y, z, w


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    seq, offset_mm, turn_deg, seed = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
    R, t = first_world_from_obj(seq)
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=3)
    axis = rng.normal(size=3)
    t = t + direction / np.linalg.norm(direction) * offset_mm / 1000.0
    R = rotation(axis / np.linalg.norm(axis) * math.radians(turn_deg)) @ R
    print("%.6f,%.6f,%.6f,%.7f,%.7f,%.7f,%.7f" % (*t, *quaternion(R)))


if __name__ == "__main__":
    main()
