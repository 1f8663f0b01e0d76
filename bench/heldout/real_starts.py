#!/usr/bin/env python3
"""The real RGB-D cube tracked from many first frames at 30, 15, 10 and 7.5 fps: 33 runs of
`unseen track SEQ --init gt --first-frame F`, each scored on the frames from F on. One run
from the sequence's start says little about a change that moves a single hard frame either
way; 33 starts of real footage say more.

  /usr/bin/python3 bench/heldout/real_starts.py build/tools/unseen/unseen OUT \\
      [--source ../shared/data/sequences/visp_rbt_cube] [--jobs 2] [-- TRACK_ARGS...]

OUT receives the stride sequences (made by stride_sequence.py when absent), the pose
streams and per-frame errors, and results.json; the table is printed. The sum of the 33
success rates (5 cm / 5 deg, each in [0, 1]) is the figure to compare.
"""
import argparse
import concurrent.futures
import csv
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
# (stride, first frames of the stride sequence)
STARTS = [(1, range(0, 80, 10)), (2, range(0, 36, 4)), (3, range(0, 24, 3)), (4, range(0, 16, 2))]


def sequence_for(stride, source, out):
    if stride == 1:
        return source
    path = os.path.join(out, f'stride{stride}')
    if not os.path.exists(os.path.join(path, 'sequence.json')):
        subprocess.run([sys.executable, os.path.join(HERE, 'stride_sequence.py'), source, path,
                        str(stride)], check=True, stdout=subprocess.DEVNULL)
    return path


def run(binary, seq, first, out, extra):
    stem = os.path.join(out, f'{os.path.basename(seq)}_{first}')
    poses, per_frame = stem + '.csv', stem + '_frames.csv'
    track = subprocess.run([binary, 'track', seq, '--init', 'gt', '--first-frame', str(first),
                            '--out', poses] + extra, capture_output=True, text=True)
    if track.returncode != 0:
        return {'error': track.stderr.strip()[-400:]}
    subprocess.run([binary, 'eval', seq, poses, '--per-frame', per_frame], check=True,
                   capture_output=True)
    with open(per_frame) as f:
        rows = [r for r in csv.DictReader(f) if int(r['frame']) >= first]
    if not rows:
        return {'error': f'{per_frame}: no frame from {first} on'}
    return {'frames': len(rows),
            'success_5cm5deg': sum(int(r['success_5cm5deg']) for r in rows) / len(rows),
            'lost': sum(r['status'] == 'lost' for r in rows)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('binary')
    parser.add_argument('out')
    parser.add_argument('--source', default=os.path.join(
        HERE, '..', '..', '..', 'shared', 'data', 'sequences', 'visp_rbt_cube'))
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('track_args', nargs='*', help='extra arguments of unseen track')
    args = parser.parse_args()
    source = os.path.abspath(args.source)
    if not os.path.exists(os.path.join(source, 'sequence.json')):
        sys.exit(f'{source}: no sequence.json (the real cube is not there)')
    os.makedirs(args.out, exist_ok=True)
    runs = [(stride, sequence_for(stride, source, args.out), first)
            for stride, firsts in STARTS for first in firsts]
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(
            lambda r: run(args.binary, r[1], r[2], args.out, args.track_args), runs))
    rows, total = [], 0.0
    for (stride, _, first), result in zip(runs, results):
        rows.append({'stride': stride, 'first_frame': first, **result})
        if 'error' in result:
            print(f'stride {stride} from frame {first}: {result["error"]}', file=sys.stderr)
            continue
        total += result['success_5cm5deg']
    for stride, _ in STARTS:
        cells = ' '.join(f'{r["first_frame"]}:{100 * r["success_5cm5deg"]:.0f}'
                         for r in rows if r['stride'] == stride and 'error' not in r)
        print(f'{30 / stride:4.1f} fps  {cells}')
    print(f'{len(rows)} runs, sum of success rates {total:.3f}')
    with open(os.path.join(args.out, 'results.json'), 'w') as f:
        json.dump({'binary': args.binary, 'track_args': args.track_args, 'runs': rows,
                   'sum_success_5cm5deg': total}, f, indent=1)
    return 0 if all('error' not in r for r in rows) else 1


if __name__ == '__main__':
    sys.exit(main())
