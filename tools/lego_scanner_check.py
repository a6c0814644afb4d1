#!/usr/bin/env python3
"""Measure the LEGO robot's scanner, tracker and clocks against the arena's landmark map.

Independent of odocal: reads the course's raw text files (lego-robot/raw/robot4_*.txt and
landmarks.txt), finds the six 55 mm cylinders in every scan (range jumps, as the course's
cylinder finder), pairs them with the map by a rigid fit, and fits:

  1. the scanner: true centre range = s * r + c (range scale s, offset c, the cylinder radius
     included) and true bearing = k * (i - 330) * 2*pi/1024 (beam spacing scale k), from the
     distances between the cylinders of one scan against the map's (translation- and
     rotation-free, so neither the robot's pose nor the tracker enters);
  2. the overhead tracker's scale against the map: tracker = scale * scanner position + shift
     (Sim(2) without rotation, the map being the tracker's frame);
  3. the time offset between the wheels and the laser: the heading the landmarks give each
     scan against the wheels' heading (ticks right - left), shifted in time.

Usage: lego_scanner_check.py DATA/lego-robot
Needs numpy and scipy. Runs in ~1 minute.
"""
import itertools
import math
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

INC = 2 * math.pi / 1024  # the course's beam spacing (rad)
CENTRE = 330  # the beam the course puts at angle 0
RADIUS_MM = 27.5  # landmarks.txt: 55 mm diameter


def load(d):
    rows = lambda name, tag: [l.split() for l in open(d / 'raw' / name) if l.startswith(tag)]
    s = rows('robot4_scan.txt', 'S')
    m = rows('robot4_motors.txt', 'M')
    p = rows('robot4_reference.txt', 'P')
    scans = (np.array([float(x[1]) for x in s]), np.array([[float(v) for v in x[3:]] for x in s]))
    motors = (np.array([float(x[1]) for x in m]), np.array([float(x[2]) for x in m]),
              np.array([float(x[6]) for x in m]))
    track = (np.array([float(x[1]) for x in p]), np.array([[float(x[2]), float(x[3])] for x in p]))
    marks = np.loadtxt(d / 'landmarks.txt', usecols=(2, 3))
    return scans, motors, track, marks


def cylinders(scan, jump=100.0, min_mm=20.0):
    """(mean beam index, mean range mm) of each cylinder: a fall then a rise of the range."""
    out, run = [], None
    for i in range(1, len(scan) - 1):
        if scan[i - 1] <= min_mm or scan[i + 1] <= min_mm:
            continue
        der = (scan[i + 1] - scan[i - 1]) / 2
        if der < -jump:
            run = []
        elif der > jump and run:
            out.append((np.mean([a for a, _ in run]), np.mean([r for _, r in run])))
            run = None
        elif run is not None and scan[i] > min_mm:
            run.append((i, scan[i]))
    return out


def points(cyl, s=1.0, c=RADIUS_MM, k=1.0):
    return np.array([[(s * r + c) * math.cos(k * (i - CENTRE) * INC),
                      (s * r + c) * math.sin(k * (i - CENTRE) * INC)] for i, r in cyl])


def rigid(a, b):
    ca, cb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    r = vt.T @ u.T
    if np.linalg.det(r) < 0:
        vt[1] *= -1
        r = vt.T @ u.T
    return r, cb - r @ ca


def associate(all_cyl, marks, model, gate_mm=40.0):
    """Scans with >= 3 cylinders whose best assignment to the map fits within gate_mm."""
    out = []
    for k, cyl in enumerate(all_cyl):
        if len(cyl) < 3:
            continue
        a = points(cyl, *model)
        best = None
        for perm in itertools.permutations(range(len(marks)), len(cyl)):
            b = marks[list(perm)]
            r, t = rigid(a, b)
            e = math.sqrt(((a @ r.T + t - b) ** 2).sum(1).mean())
            if best is None or e < best[0]:
                best = (e, perm, r, t)
        if best[0] < gate_mm:
            out.append((k, cyl, best[1], best[2], best[3]))
    return out


def pair_residuals(model, assoc, marks):
    res = []
    for _, cyl, perm, _, _ in assoc:
        a, b = points(cyl, *model), marks[list(perm)]
        for i, j in itertools.combinations(range(len(cyl)), 2):
            res.append(np.hypot(*(a[i] - a[j])) - np.hypot(*(b[i] - b[j])))
    return np.array(res)


def fit(fun, x0):
    f = least_squares(fun, x0)
    cov = np.linalg.inv(f.jac.T @ f.jac) * (f.fun ** 2).sum() / (len(f.fun) - len(x0))
    return f.x, np.sqrt(np.diag(cov)), math.sqrt((f.fun ** 2).mean())


def main(d):
    (st, ranges), (mt, left, right), (pt, pxy), marks = load(Path(d))
    all_cyl = [cylinders(r) for r in ranges]
    model = [1.0, 90.0, 1.03]
    for _ in range(3):
        assoc = associate(all_cyl, marks, model)
        model, std, rms = fit(lambda p: pair_residuals(p, assoc, marks), model)
    print(f'scanner ({len(assoc)} scans with >= 3 cylinders matched to the map):')
    print(f'  range scale {model[0]:.4f} +- {std[0]:.4f}, centre offset {model[1]:.1f} +- '
          f'{std[1]:.1f} mm (range offset {model[1] - RADIUS_MM:.1f} mm beyond the radius), '
          f'beam spacing x {model[2]:.4f} +- {std[2]:.4f} (rms {rms:.1f} mm)')
    nominal = pair_residuals([1.0, RADIUS_MM, 1.0], assoc, marks)
    print(f'  as recorded (2*pi/1024, no offset): pair distances {nominal.mean():+.1f} mm on '
          f'average, rms {math.sqrt((nominal ** 2).mean()):.1f} mm')
    assoc = associate(all_cyl, marks, model)
    ts = st[[a[0] for a in assoc]]
    pos = np.array([a[4] for a in assoc])
    head = np.unwrap([math.atan2(a[3][1, 0], a[3][0, 0]) for a in assoc])
    # 2. tracker against the scanner positions the map gives (free point offset along the
    # heading, so which robot point the tracker followed does not matter).
    trk = np.c_[np.interp(ts, pt, pxy[:, 0]), np.interp(ts, pt, pxy[:, 1])]
    c = np.array([1000.0, 1000.0])

    def tracker_res(p):
        off = np.c_[np.cos(head) * p[1] - np.sin(head) * p[2], np.sin(head) * p[1] + np.cos(head) * p[2]]
        return ((trk - c) - p[0] * (pos + off - c) - p[3:5]).ravel()

    x, s, rms = fit(tracker_res, [1.0, 0.0, 0.0, 0.0, 0.0])
    print(f'tracker: scale {x[0]:.4f} +- {s[0]:.4f} against the map (rms {rms:.1f} mm)')
    # 3. heading lag: wheels' heading (right - left ticks) against the landmarks' heading.
    wheel = (right - left) * 2 * math.pi / 360
    best = None
    for lag in np.arange(-800, 401, 5.0):
        w = np.interp(ts + lag, mt, wheel)
        a = np.c_[w, np.ones_like(w)]
        coef = np.linalg.lstsq(a, head, rcond=None)[0]
        e = np.sqrt(((head - a @ coef) ** 2).mean())
        if best is None or e < best[0]:
            best = (e, lag, coef[0])
    print(f'clocks: the landmarks\' heading follows the wheels\' at wheel time = scan time '
          f'{best[1]:+.0f} ms (rms {math.degrees(best[0]):.1f} deg; r/b {best[2]:.4f})')


if __name__ == '__main__':
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
