#!/usr/bin/env python3
"""One tank on one indoor fire, closed loop (extinguish_indoor_fire against ual_sim's world, its realistic
profile: GNSS bias, gusts, thermal noise and offset, the seed's litres needed), over seeds x the six indoor
holders. Prints, per pour and in total: judged out correctly, judged out short of its water (must be 0),
out but left for a top-up, short (the tank not enough), litres into the fire per litre pumped.

    bench/bench_indoor_pour.py [--seeds 1-12] [--holders in0_w,in0_e,...] [--track-from 3] [--progress 0.97]
Writes bench/results/indoor_pour.json (with --track-from: indoor_pour_track_from_<id>.json; with --progress:
indoor_pour_topup_<percent>[_track_from_<id>].json)."""
import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'catkin_ws', 'src', 'mbzirc_agents', 'test', 'unit'))
HOLDERS = 'in0_w,in0_e,in1_w,in1_e,in2_w,in2_e'


def seed_range(text):
    a, _, b = text.partition('-')
    return list(range(int(a), int(b or a) + 1))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--seeds', default='1-12', help='first-last (default 1-12)')
    ap.add_argument('--holders', default=HOLDERS)
    ap.add_argument('--track-from', type=int, default=None,
                    help="robot id whose GNSS bias places the fire's track (default: the pouring UAV's own; 3: "
                         'the other water UAV, as when one found the fire and the other waters it)')
    ap.add_argument('--progress', type=float, default=0.0,
                    help='share of its need the fire already holds: a top-up of a fire a dry tank left nearly out '
                         '(0.97: the fire hardly warmer than its wall)')
    ap.add_argument('--out', default=os.path.join(HERE, 'results', 'indoor_pour.json'))
    args = ap.parse_args()
    if args.out == ap.get_default('out'):
        name = 'indoor_pour' + (f'_topup_{round(100 * args.progress)}' if args.progress > 0 else '')
        name += f'_track_from_{args.track_from}' if args.track_from is not None else ''
        args.out = os.path.join(HERE, 'results', name + '.json')
    from sim_ual import pour
    rows, t0 = [], time.time()
    for seed in seed_range(args.seeds):
        for holder in args.holders.split(','):
            o = pour(seed, holder=holder, track_from=args.track_from, progress=args.progress)
            verdict = ('out' if o['extinguished'] and o['progress'] >= 1.0 else
                       'FALSE_OUT' if o['extinguished'] else
                       'not_judged' if o['progress'] >= 1.0 else 'short')
            rows.append({'seed': seed, 'holder': holder, 'need': round(o['need'], 3),
                         'pumped': round(o['pumped'], 3), 'into': round(o['into'], 3),
                         'progress': round(o['progress'], 4), 'verdict': verdict, 'message': o['message']})
            print(f"seed {seed:3d} {holder}: need {o['need']:.2f} L, pumped {o['pumped']:.2f}, into {o['into']:.2f}, "
                  f"progress {o['progress']:.3f}: {verdict}", flush=True)
    n = len(rows)
    count = {v: sum(r['verdict'] == v for r in rows) for v in ('out', 'FALSE_OUT', 'not_judged', 'short')}
    eff = sum(r['into'] for r in rows) / max(1e-9, sum(r['pumped'] for r in rows))
    summary = {'pours': n, 'track_from': args.track_from, 'progress': args.progress, **count, 'litres_into_per_litre_pumped': round(eff, 3),
               'wall_s': round(time.time() - t0, 1)}
    print(f"{n} pours: out and judged out {count['out']}, judged out short of its water {count['FALSE_OUT']}, "
          f"out but left for a top-up {count['not_judged']}, short {count['short']}; "
          f"{eff:.2f} L into the fire per L pumped")
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, 'w') as f:
        json.dump({'summary': summary, 'pours': rows}, f, indent=1)


if __name__ == '__main__':
    main()
