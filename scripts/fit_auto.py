#!/usr/bin/python3
"""Fits the error and cost models of `--warp auto --fill auto` (warp/src/auto_choice.cpp) to a
`reprise bench fruc` run: fruc.csv (PSNR and ms per frame and setting) joined with
fruc_predictors.csv (the survey of each frame). Prints the kModels table to paste.

    build/tools/reprise bench fruc --scenes pan,fence,crossing,specular,fast,courtyard,stroll --out OUT
    scripts/fit_auto.py OUT WIDTH HEIGHT

docs/results/auto-fit/ keeps the rows of the run the current table was fitted to (session 17):
`scripts/fit_auto.py docs/results/auto-fit 640 360` prints that table again.

Per mode, the reference setting (grid+pullpush) has the saturating error model of Sitthi-amorn
et al. 2008: MSE of display values = floor + alpha (1 - exp(-lambda v)) + beta sigma + kappa d
(v, sigma, d: motion, spread and disoccluded fraction times the warp distance t); floor and
lambda by a grid search, the rest by least squares relative to each frame's MSE, kept
non-negative. Every
candidate's PSNR relative to the reference's on the same frame is linear in (1, v, sigma, d),
by least squares. Cost: ns per output pixel of the warp (its cheapest fill variant's mean, as
times are noisy) and of each fill beyond it."""
import csv
import math
import sys

import numpy as np

WARPS = ["reverse", "splat", "grid"]
FILLS = ["none", "pullpush", "andreev"]
CANDIDATES = [w + "+" + f for w in WARPS for f in FILLS]
REFERENCE = "grid+pullpush"


def nonnegative_lstsq(a, b):
    active = list(range(a.shape[1]))
    x = np.zeros(a.shape[1])
    while active:
        sol, *_ = np.linalg.lstsq(a[:, active], b, rcond=None)
        if (sol >= 0).all():
            x[:] = 0
            x[active] = sol
            return x
        active.pop(int(np.argmin(sol)))
    return x


def main():
    out, width, height = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    pixels = width * height
    features = {}
    with open(out + "/fruc_predictors.csv") as f:
        for r in csv.DictReader(f):
            t = float(r["distance"])
            features[(r["scene"], int(r["frame"]), r["mode"])] = (
                float(r["motion"]) * t, float(r["spread"]) * t,
                min(1.0, float(r["disoccluded"]) * t))
    psnr, ms = {}, {}  # (mode, candidate) -> {(scene, frame): value}
    with open(out + "/fruc.csv") as f:
        for r in csv.DictReader(f):
            if r["method"] not in ("interpolate", "extrapolate") or r["setting"] not in CANDIDATES:
                continue
            key = (r["scene"], int(r["frame"]), r["method"])
            if key not in features or not math.isfinite(float(r["psnr"])):
                continue
            psnr.setdefault((r["method"], r["setting"]), {})[key] = float(r["psnr"])
            ms.setdefault((r["method"], r["setting"]), {})[key] = float(r["ms"])
    print("constexpr Model kModels[2] = {")
    for mode in ("interpolate", "extrapolate"):
        ref = psnr[(mode, REFERENCE)]
        keys = sorted(ref)
        x = np.array([features[k] for k in keys])
        v, s, d = x[:, 0], x[:, 1], x[:, 2]
        mse = np.array([10 ** (-ref[k] / 10) for k in keys])
        weight = 1.0 / mse
        best = None
        for floor in np.geomspace(1e-6, 1e-2, 25):
            for lam in np.geomspace(0.01, 10.0, 25):
                cols = np.stack([1 - np.exp(-lam * v), s, d], 1)
                c = nonnegative_lstsq(cols * weight[:, None], (mse - floor) * weight)
                pred = floor + cols @ c
                err = np.mean(np.abs(10 * np.log10(np.maximum(pred, 1e-10) / mse)))
                if best is None or err < best[0]:
                    best = (err, lam, np.concatenate([[floor], c]))
        err, lam, c = best
        print(f"    // {mode}: {len(keys)} frames; reference {REFERENCE}: mean |error| of its "
              f"predicted PSNR {err:.2f} dB", file=sys.stderr)
        reference = f"{{{c[0]:.3e}f, {c[1]:.3e}f, {lam:.3f}f, {c[2]:.3e}f, {c[3]:.3e}f}}"
        deltas, right = [], 0
        best_pred, best_true = {}, {}
        for cand in CANDIDATES:
            values = psnr[(mode, cand)]
            common = [k for k in keys if k in values]
            a = np.array([[1.0, *features[k]] for k in common])
            b = np.array([values[k] - ref[k] for k in common])
            if cand.endswith("+none"):
                # Fill none differs from pull-push only where holes stay black, which the model
                # adds itself (about 0.25 d of MSE): fitted on the hole-free predictors alone.
                coef, *_ = np.linalg.lstsq(a[:, :3], b, rcond=None)
                coef = np.append(coef, 0.0)
            else:
                coef, *_ = np.linalg.lstsq(a, b, rcond=None)
            e = np.mean(np.abs(a @ coef - b))
            print(f"    //   {cand}: mean |error| of its predicted difference {e:.2f} dB",
                  file=sys.stderr)
            deltas.append("{" + ", ".join(f"{q:.4f}f" for q in coef) + "}")
            for k, p in zip(common, a @ coef):
                if k not in best_pred or p > best_pred[k][0]:
                    best_pred[k] = (p, cand)
                if k not in best_true or values[k] - ref[k] > best_true[k][0]:
                    best_true[k] = (values[k] - ref[k], cand)
        right = sum(best_pred[k][1] == best_true[k][1] for k in keys)
        print(f"    //   the best setting predicted right on {right} of {len(keys)} frames",
              file=sys.stderr)
        costs = []
        for warp in WARPS:
            means = [1e6 * float(np.mean(list(ms[(mode, warp + "+" + f)].values()))) / pixels
                     for f in FILLS]
            base = min(means)
            costs.append("{" + ", ".join(f"{q:.1f}f" for q in [base] + [max(base, m) for m in
                                                                        means[1:]]) + "}")
        print(f"    // {mode}")
        print(f"    {{{reference},")
        print("     {" + ",\n      ".join(deltas) + "},")
        print("     {" + ", ".join(costs) + "}},")
    print("};")


if __name__ == "__main__":
    main()
