#!/usr/bin/env python3
"""Times scikit-fmm and envfield's fast marching on the very same grids, in one run.

    pip install scikit-fmm numpy
    cargo build --release --example fmm
    python3 benches/fmm_vs_skfmm.py            # all sizes
    python3 benches/fmm_vs_skfmm.py --quick    # 28^2 and 256^2 only

Grids: 28^2, 256^2, 1024^2 with 20% of the cells covered by random squares (side up to
n/128, at least 1), and 64^3, 128^3 with 20% random cubes; the source is the centre cell (kept
free). Each solver is timed on each grid and order as the median of repeated calls (envfield's
time is measured inside the `fmm` example around the solve call alone, as scikit-fmm's is
around `skfmm.distance`). Prints one JSON line per case and a table with the time ratio.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import skfmm

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLE = os.path.join(ROOT, "target", "release", "examples", "fmm")


def scatter(shape, frac, max_side, rng):
    mask = np.zeros(shape, dtype=bool)
    target = frac * mask.size
    filled = 0
    while filled < target:
        side = int(rng.integers(1, max_side + 1))
        corner = [int(rng.integers(0, d)) for d in shape]
        block = tuple(slice(c, c + side) for c in corner)
        filled += int((~mask[block]).sum())
        mask[block] = True
    centre = tuple(d // 2 for d in shape)
    mask[centre] = False
    return mask, centre


def time_skfmm(mask, centre, order, repeat):
    phi = np.ones(mask.shape)
    phi[centre] = -1.0
    phi = np.ma.MaskedArray(phi, mask)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        skfmm.distance(phi, order=order)
        times.append(time.perf_counter() - t)
    return float(np.median(times)) * 1e3


def time_envfield(path, centre, order, repeat):
    goal = ",".join(str(c) for c in centre)
    out = subprocess.run(
        [EXAMPLE, path, "--goal", goal, "--order", str(order), "--repeat", str(repeat)],
        check=True, capture_output=True, text=True,
    ).stdout.strip().splitlines()[-1]
    return json.loads(out)["median_ms"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if not os.path.exists(EXAMPLE):
        sys.exit(f"{EXAMPLE} not found: run `cargo build --release --example fmm` first")
    rng = np.random.default_rng(args.seed)
    cases = [((28, 28), 500), ((256, 256), 30), ((1024, 1024), 9), ((64, 64, 64), 9), ((128, 128, 128), 3)]
    if args.quick:
        cases = cases[:2]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for shape, repeat in cases:
            mask, centre = scatter(shape, 0.2, max(1, shape[0] // 128), rng)
            path = os.path.join(tmp, "grid.npy")
            np.save(path, mask)
            for order in (1, 2):
                ours = time_envfield(path, centre, order, repeat)
                theirs = time_skfmm(mask, centre, order, repeat)
                row = {"shape": "x".join(map(str, shape)), "order": order,
                       "skfmm_ms": round(theirs, 4), "envfield_ms": round(ours, 4),
                       "speedup": round(theirs / ours, 2)}
                print(json.dumps(row), flush=True)
                rows.append(row)
    print(f"\nscikit-fmm {skfmm.__version__}, numpy {np.__version__}")
    print(f"{'grid':>12} {'order':>5} {'scikit-fmm ms':>14} {'envfield ms':>12} {'speedup':>8}")
    for r in rows:
        print(f"{r['shape']:>12} {r['order']:>5} {r['skfmm_ms']:>14.3f} {r['envfield_ms']:>12.3f} {r['speedup']:>7.2f}x")


if __name__ == "__main__":
    main()
