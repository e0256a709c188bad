#!/usr/bin/python3
"""contact_intervals.py RUN_DIR|REF.npz ... [--until T] — contact intervals (time spans with a
non-zero contact force on the net) of coupled runs (coupling.h5 /steps/contact_force) or of a
reference_explicit.py --save file, up to T (default 0.75 s: the first impact of case 7.2).
A run that 'keeps contact' through the first impact has one interval there."""
import sys, os
import numpy as np
import h5py
args = [a for a in sys.argv[1:]]
until = 0.75
if '--until' in args:
    i = args.index('--until'); until = float(args[i + 1]); del args[i:i + 2]
for a in args:
    if a.endswith('.npz'):
        d = np.load(a); t = d['t']; f = d['fz']
    else:
        with h5py.File(os.path.join(a, 'coupling.h5'), 'r') as h:
            t = h['steps/time'][:]; f = h['steps/contact_force'][:, 2]
    m = t <= until; t = t[m]; on = np.abs(f[m]) > 0
    iv = []; st = None
    for k in range(len(t)):
        if on[k] and st is None: st = t[k]
        if not on[k] and st is not None: iv.append((st, t[k])); st = None
    if st is not None: iv.append((st, t[-1]))
    txt = ' '.join(f'[{x:.3f},{y:.3f}]' for x, y in iv[:8]) + (' ...' if len(iv) > 8 else '')
    print(f'{os.path.basename(a.rstrip("/")):22s} {len(iv):3d} contact intervals up to {until} s, '
          f'max |F| {np.abs(f[m]).max():9.0f} N: {txt}')
