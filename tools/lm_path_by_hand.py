#!/usr/bin/env python3
"""The Levenberg–Marquardt path of a one-unknown problem, for the unit tests
of src/calib/batch/solve.rs.

A robot spinning in place (left wheel −φ, right wheel +φ, both radii r, the
laser at the base) turns θ = 2 r φ / b, so with the wheel base b the only
unknown the residual is e(b) = θ* − c/b with c = 2 r φ, and its derivative
is ∂e/∂b = c/b² (taken here analytically, not by differences). The whitening
w multiplies e and ∂e/∂b alike.

Marquardt's rule from λ = 1e-3: the step Δ = g / (H + λ H) with H = (w J)²
and g = w² J e (one unknown: diag H is H), the trial b − Δ accepted if its
cost w² e² is finite and no higher (then λ ← max(λ/10, 1e-12)), else
λ ← 10 λ; stop after an accepted step smaller than 1e-3 of the difference
step 1e-6, or when λ reaches 1e12.

With c = 0.5 (r = 0.1, φ = 2.5) and θ* = 1 the minimum is b = 0.5. From
b = 1.2 the undamped (Newton) step overshoots to b = −0.48; the damped ones
at λ = 0.001, 0.01 and 0.1 still land at b < 0 (costlier), λ = 1 gives
b = 1.2 − 1.68/2 = 0.36. Run: python3 tools/lm_path_by_hand.py
"""

import math


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def path(b, w=1.0, c=0.5, theta=1.0, max_iter=50):
    def err(b):
        return w * wrap(theta - c / b)

    def cost(b):
        try:
            return err(b) ** 2
        except ZeroDivisionError:
            return math.inf

    lam = 1e-3
    cst = cost(b)
    out = []
    for k in range(1, max_iter + 1):
        e = err(b)
        j = w * c / b**2
        h, g = j * j, j * e
        improved = False
        tried = []
        while lam < 1e12:
            delta = g / (h + lam * h)
            trial = b - delta
            ct = cost(trial)
            tried.append(lam)
            if math.isfinite(ct) and ct <= cst:
                small = abs(delta) < 1e-3 * 1e-6
                b, cst = trial, ct
                lam = max(lam / 10, 1e-12)
                improved = not small
                break
            lam *= 10
        out.append((k, tried, b, delta))
        if not improved:
            break
    return out


if __name__ == "__main__":
    for w in (1.0, 1e3):
        print(f"whitening {w}")
        for k, tried, b, delta in path(1.2, w):
            print(f"  iteration {k}: λ tried {tried}, step {delta:.6e}, b = {b!r}")
