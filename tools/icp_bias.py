#!/usr/bin/env python3
"""Scale and heading bias of ICP motions against a simulator truth file.

Usage: icp_bias.py MOTIONS.csv TRUTH.json [--offset S]

MOTIONS.csv is `odocal icp --motions` output (base frame, m and rad); TRUTH.json
is `odocal simulate --truth` output (world_from_base at 't', s). Scan stamps and
truth times share one clock in simulated bags (both start at 0); --offset is
added to the truth times otherwise. Independent of odocal: numpy only.

Prints, over the valid pairs: Σdx ICP / Σdx true (pairs moving > 5 mm),
Σdθ ICP / Σdθ true over turning pairs (|dθ| > 1 mrad), mean signed errors
and their standard errors, and the mean |error| per pair.
"""
import json
import sys

import numpy as np


def main():
    args = sys.argv[1:]
    offset = 0.0
    if "--offset" in args:
        i = args.index("--offset")
        offset = float(args[i + 1])
        del args[i : i + 2]
    m = np.genfromtxt(args[0], delimiter=",", names=True)
    tr = json.load(open(args[1]))["trajectory"]
    T = np.array([p["t"] for p in tr]) + offset
    X = np.array([p["x"] for p in tr])
    Y = np.array([p["y"] for p in tr])
    H = np.unwrap(np.array([p["theta"] for p in tr]))

    def at(t):
        return np.interp(t, T, X), np.interp(t, T, Y), np.interp(t, T, H)

    v = (m["valid"] == 1) & (m["t0"] >= T[0]) & (m["t1"] <= T[-1])
    xa, ya, ha = at(m["t0"][v])
    xb, yb, hb = at(m["t1"][v])
    dxw, dyw = xb - xa, yb - ya
    dx = np.cos(ha) * dxw + np.sin(ha) * dyw
    dy = -np.sin(ha) * dxw + np.cos(ha) * dyw
    dth = hb - ha
    mx, my, mt = m["dx"][v], m["dy"][v], m["dtheta"][v]
    mov = np.abs(dx) > 0.005
    turn = np.abs(dth) > 0.001
    se = lambda e: e.std(ddof=1) / np.sqrt(len(e))
    out = {
        "pairs": int(len(m)),
        "valid": int(v.sum()),
        "moving": int(mov.sum()),
        "turning": int(turn.sum()),
        "dx_ratio": float(mx[mov].sum() / dx[mov].sum()),
        "dtheta_ratio": float(mt[turn].sum() / dth[turn].sum()),
        "dtheta_ratio_all": float(mt.sum() / dth.sum()),
        "dx_err_mean": float((mx - dx).mean()),
        "dx_err_se": float(se(mx - dx)),
        "dy_err_mean": float((my - dy).mean()),
        "dtheta_err_mean": float((mt - dth).mean()),
        "dtheta_err_se": float(se(mt - dth)),
        "trans_err_mm": float(1e3 * np.hypot(mx - dx, my - dy).mean()),
        "rot_err_deg": float(np.degrees(np.abs(mt - dth)).mean()),
    }
    for k, val in out.items():
        print(f"{k:18s} {val:.6g}" if isinstance(val, float) else f"{k:18s} {val}")


if __name__ == "__main__":
    main()
