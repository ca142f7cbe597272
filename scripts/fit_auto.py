#!/usr/bin/python3
"""Fits the error and cost models of `--warp auto --fill auto` (warp/src/auto_choice.cpp) to a
`reprise bench fruc` run: fruc.csv (PSNR and ms per frame and setting) joined with
fruc_predictors.csv (the survey of each frame). Prints the kModels table to paste.

    build/tools/reprise bench fruc --scenes pan,fence,crossing,specular,fast,cut --out OUT
    scripts/fit_auto.py OUT WIDTH HEIGHT

Per mode and warp, the mean squared error of display values at warp distance t is modelled as
floor + alpha (1 - exp(-lambda v)) + beta sigma + kappa[fill] d (v, sigma, d: motion, spread and
disoccluded fraction times t), the saturating form of Sitthi-amorn et al. 2008; lambda by a grid
search, the rest by least squares relative to each frame's error, kept non-negative. Cost: mean
ns per output pixel of each warp + fill."""
import csv
import math
import sys

import numpy as np

WARPS = ["reverse", "splat", "grid"]
FILLS = ["none", "pullpush", "andreev"]


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
    rows = {}
    with open(out + "/fruc.csv") as f:
        for r in csv.DictReader(f):
            if r["method"] not in ("interpolate", "extrapolate"):
                continue
            warp, _, fill = r["setting"].partition("+")
            if warp not in WARPS or fill not in FILLS:
                continue
            key = (r["scene"], int(r["frame"]), r["method"])
            if key not in features or not math.isfinite(float(r["psnr"])):
                continue
            rows.setdefault((r["method"], warp), []).append(
                (features[key], FILLS.index(fill), 10 ** (-float(r["psnr"]) / 10),
                 float(r["ms"])))
    print("constexpr Model kModels[2] = {")
    for mode in ("interpolate", "extrapolate"):
        errors, costs = [], []
        for warp in WARPS:
            data = rows.get((mode, warp), [])
            if not data:
                sys.exit(f"no rows for {mode} {warp}")
            v = np.array([d[0][0] for d in data])
            s = np.array([d[0][1] for d in data])
            dis = np.array([d[0][2] for d in data])
            fill = np.array([d[1] for d in data])
            mse = np.array([d[2] for d in data])
            weight = 1.0 / mse
            best = None
            for lam in np.geomspace(0.01, 10.0, 40):
                cols = [np.ones_like(v), 1 - np.exp(-lam * v), s] + [
                    dis * (fill == k) for k in range(3)]
                a = np.stack(cols, 1) * weight[:, None]
                x = nonnegative_lstsq(a, mse * weight)
                pred = np.stack(cols, 1) @ x
                err = np.mean(np.abs(10 * np.log10(np.maximum(pred, 1e-10) / mse)))
                if best is None or err < best[0]:
                    best = (err, lam, x)
            err, lam, x = best
            print(f"    // {mode} {warp}: {len(data)} frames, mean |error| of the predicted "
                  f"PSNR {err:.2f} dB", file=sys.stderr)
            errors.append(f"{{{x[0]:.3e}f, {x[1]:.3e}f, {lam:.3f}f, {x[2]:.3e}f, "
                          f"{{{x[3]:.3e}f, {x[4]:.3e}f, {x[5]:.3e}f}}}}")
            row = []
            for k in range(3):
                ms = [d[3] for d in data if d[1] == k]
                row.append(1e6 * float(np.mean(ms)) / pixels)
            costs.append("{" + ", ".join(f"{c:.1f}f" for c in row) + "}")
        print(f"    // {mode}")
        print("    {{" + ",\n      ".join(errors) + "},")
        print("     {" + ", ".join(costs) + "},")
        print("     1.0f},")
    print("};")


if __name__ == "__main__":
    main()
