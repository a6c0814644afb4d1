#!/usr/bin/env python3
"""The encoder-versus-tachometer table of Paryanto et al. (Table I, docs/references.md: Paryanto) fitted from first
principles with numpy, as a check on `odocal::diagnose::encoder_table`
written without looking at it.

Per wheel, with ω the tachometer's rate and m the encoder's (rad/s), two
one-parameter models of what the encoder reads:

  scale:  m = s ω                  (a wrong gear ratio or tick count)
  gain:   m = ω (1 + k |ω|)        (the effect table's encoder_gain)

Both are linear in their parameter: the scale regresses m on ω, the gain
regresses m − ω on ω|ω|, each through the origin. The readings' error is
whole-rpm rounding on both instruments, so the σ of one difference is
√(2/12) rpm. With that σ known, each model has one parameter, so
ΔBIC = BIC(scale) − BIC(gain) = (RSS_scale − RSS_gain) / σ²; with σ
unknown (profiled) the Gaussian log-likelihood at its maximum gives
ΔBIC = n ln(RSS_scale / RSS_gain). With relative errors (σ_i ∝ ω_i,
profiled) both fits are weighted by 1/ω² and the same log-ratio is taken of
the weighted sums (the Σ ln σ_i terms are the same for both models).

Prints one JSON object: {"right": {...}, "left": {...}, "sigma": σ (rad/s)}
with scale, scale_se, k, k_se, rss_scale, rss_gain, delta_bic,
delta_bic_profiled, delta_bic_relative per wheel.

Usage: encoder_table_check.py TABLE.csv
"""
import json
import sys

import numpy as np

RPM = 2.0 * np.pi / 60.0


def through_origin(x, y, w=None):
    """Weighted least squares y ≈ b x: (b, Σ w (y − b x)², Σ w x²)."""
    w = np.ones_like(x) if w is None else w
    sxx = np.sum(w * x * x)
    b = np.sum(w * x * y) / sxx
    return b, float(np.sum(w * (y - b * x) ** 2)), sxx


def wheel(tacho_rpm, enc_rpm, sigma):
    om, m = tacho_rpm * RPM, enc_rpm * RPM
    n = len(om)
    s, rss_s, sxx_s = through_origin(om, m)
    g = om * np.abs(om)
    k, rss_g, sxx_g = through_origin(g, m - om)
    # Relative errors: divide each reading's equation by ω (weights 1/ω²).
    w = 1.0 / om**2
    _, rel_s, _ = through_origin(om, m, w)
    _, rel_g, _ = through_origin(g, m - om, w)
    return {
        "scale": float(s),
        "scale_se": float(sigma / np.sqrt(sxx_s)),
        "k": float(k),
        "k_se": float(sigma / np.sqrt(sxx_g)),
        "rss_scale": rss_s,
        "rss_gain": rss_g,
        "delta_bic": (rss_s - rss_g) / sigma**2,
        "delta_bic_profiled": float(n * np.log(rss_s / rss_g)),
        "delta_bic_relative": float(n * np.log(rel_s / rel_g)),
    }


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.strip().splitlines()[-1])
    with open(sys.argv[1]) as f:
        lines = [l.strip() for l in f if l.strip() and not l.startswith("#")]
    # The header, then tachometer, right encoder, left encoder (rpm).
    rows = np.array([[float(c) for c in l.split(",")] for l in lines[1:]])
    sigma = np.sqrt(2.0 / 12.0) * RPM
    out = {
        "right": wheel(rows[:, 0], rows[:, 1], sigma),
        "left": wheel(rows[:, 0], rows[:, 2], sigma),
        "sigma": float(sigma),
    }
    json.dump(out, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
