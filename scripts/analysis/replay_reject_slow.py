#!/usr/bin/python3
"""replay_reject_slow.py COUPLING_H5 [--max-iterations N] [--tolerance T] [--rule FIRST,WINDOW,MARGIN ...]

Replays the recorded iterations of a strong run (/iterations of coupling.h5, written with
output.iterations true) through the early rejection of coupler.json step_control.reject_slow:
from iteration FIRST on, a try whose residual, at the geometric-mean rate of its last WINDOW
iterations (at most 1), would still be above MARGIN x the tolerance at max_iterations is given
up. For each rule it prints how many tries that reached max_iterations unconverged it would
have given up and the iterations that saves, and how many tries that did converge it would
have given up (their iterations so far are lost and they are retried at dt/2). Run it on a
run made with "reject_slow": false to see the iterations as the iteration left them.
The coupler's rule (coupler/cpl_loop.h, CPL_SLOW_*) is 12,9,10. The residual is compared with
the absolute tolerance only (tolerance 1e-6 unless given; relative_tolerance is not replayed).
"""
import argparse
import sys

import h5py
import numpy as np


def tries(path):
    """(residuals of each try) in the order recorded."""
    with h5py.File(path, 'r') as f:
        if 'iterations' not in f:
            sys.exit(f'{path}: no /iterations group (coupler.json output.iterations false?)')
        it = f['iterations']
        key = it['step'][:].astype(np.int64) * 1000 + it['attempt'][:]
        res = it['residual'][:]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    ends = np.r_[starts[1:], len(key)]
    return [res[a:b] for a, b in zip(starts, ends)]


def fires(r, first, window, margin, tol, max_it):
    """The iteration (1-based) at which the rule gives up the try r, or None."""
    for k in range(first, min(len(r), max_it)):
        now, then = r[k - 1] / tol, r[k - 1 - window] / tol
        if not (now > 0 and then > 0 and np.isfinite(now) and np.isfinite(then)):
            continue
        rate = min(1.0, (now / then) ** (1.0 / window))
        if now * rate ** (max_it - k) > margin:
            return k
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[2])
    ap.add_argument('coupling_h5')
    ap.add_argument('--max-iterations', type=int, default=50)
    ap.add_argument('--tolerance', type=float, default=1e-6)
    ap.add_argument('--rule', action='append', default=None,
                    help='FIRST,WINDOW,MARGIN (repeatable; default 12,9,10 and neighbours)')
    a = ap.parse_args()
    rules = a.rule or ['12,9,10', '12,9,3', '10,6,10', '15,12,3']
    all_tries = tries(a.coupling_h5)
    total = sum(len(r) for r in all_tries)
    failing = [r for r in all_tries if len(r) >= a.max_iterations and r[-1] >= a.tolerance]
    print(f'{a.coupling_h5}: {len(all_tries)} tries, {total} iterations, {len(failing)} tries '
          f'ended at max_iterations {a.max_iterations} unconverged')
    for rule in rules:
        first, window, margin = rule.split(',')
        first, window, margin = int(first), int(window), float(margin)
        if first <= window:
            sys.exit(f'--rule {rule}: FIRST must exceed WINDOW')
        saved = lost = doomed = wasted = 0
        for r in all_tries:
            k = fires(r, first, window, margin, a.tolerance, a.max_iterations)
            if k is None:
                continue
            if len(r) >= a.max_iterations and r[-1] >= a.tolerance:
                doomed += 1
                saved += len(r) - k
            else:
                wasted += 1
                lost += k
        print(f'rule {first},{window},{margin:g}: gives up {doomed} of the {len(failing)} '
              f'failing tries (saves {saved} iterations) and {wasted} converging ones '
              f'({lost} iterations lost, plus their retries)')


if __name__ == '__main__':
    main()
