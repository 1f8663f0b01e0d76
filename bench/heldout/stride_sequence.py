#!/usr/bin/env python3
"""A sequence (DATASET.md) filmed K times faster: every K-th frame of SOURCE, renumbered
from 0, at fps / K. Real footage keeps its sensor, blur and lighting and gains the motion
between frames a faster hand or a slower camera would give (K = 2: the real RGB-D cube at
15 fps). Frames, depth and masks are symbolic links to SOURCE's; the models folder too.

  /usr/bin/python3 bench/heldout/stride_sequence.py \\
      ../shared/data/sequences/visp_rbt_cube OUT/visp_stride2 2
  unseen track OUT/visp_stride2 --init gt --out p.csv && unseen eval OUT/visp_stride2 p.csv
"""
import json
import os
import sys


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f'{path}: cannot read it as JSON ({e})')


def save(path, data):
    with open(path, 'w') as f:
        json.dump(data, f)


def link(src, dst):
    if not os.path.lexists(dst):
        os.symlink(src, dst)


def main(source, out, stride):
    source = os.path.abspath(source)
    seq_path = os.path.join(source, 'sequence.json')
    if os.path.exists(seq_path):
        sequence = load(seq_path)
        cameras = sequence['cameras']
    else:  # a plain BOP scene folder: one camera
        sequence, cameras = None, ['.']
    os.makedirs(out, exist_ok=True)
    kept = None
    for cam in cameras:
        cam_src = os.path.join(source, cam)
        cam_out = os.path.join(out, cam)
        os.makedirs(cam_out, exist_ok=True)
        scene_camera = load(os.path.join(cam_src, 'scene_camera.json'))
        ids = sorted(int(i) for i in scene_camera)
        if kept is None:
            kept = ids[::stride]
        elif ids[::stride] != kept:
            sys.exit(f'{cam_src}: frame ids differ from the first camera\'s')
        renumber = {old: new for new, old in enumerate(kept)}
        save(os.path.join(cam_out, 'scene_camera.json'),
             {str(renumber[i]): scene_camera[str(i)] for i in kept})
        gt_path = os.path.join(cam_src, 'scene_gt.json')
        if os.path.exists(gt_path):
            gt = load(gt_path)
            save(os.path.join(cam_out, 'scene_gt.json'),
                 {str(renumber[i]): gt[str(i)] for i in kept if str(i) in gt})
        for folder in sorted(os.listdir(cam_src)):
            folder_src = os.path.join(cam_src, folder)
            if not os.path.isdir(folder_src):
                continue
            os.makedirs(os.path.join(cam_out, folder), exist_ok=True)
            for name in sorted(os.listdir(folder_src)):
                stem, ext = os.path.splitext(name)
                head, _, tail = stem.partition('_')  # mask files: FRAME_INSTANCE
                if not head.isdigit() or int(head) not in renumber:
                    continue
                new = f'{renumber[int(head)]:06d}' + ('_' + tail if tail else '') + ext
                link(os.path.join(folder_src, name), os.path.join(cam_out, folder, new))
    if sequence is not None:
        sequence['fps'] = sequence.get('fps', 30) / stride
        sequence['notes'] = (f'every {stride}th frame of {source}; ' + sequence.get('notes', ''))
        save(os.path.join(out, 'sequence.json'), sequence)
        link(os.path.join(source, 'models'), os.path.join(out, 'models'))
    print(f'{out}: {len(kept)} frames')


if __name__ == '__main__':
    if len(sys.argv) != 4 or not sys.argv[3].isdigit() or int(sys.argv[3]) < 1:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]))
