#!/usr/bin/env python3
"""envfield.fmm against scikit-fmm from Python: same process, same arrays, one run.

    pip install scikit-fmm            # builds from source: needs a compiler
    pip install target/wheels/envfield-*.whl   # (or: cd python && maturin develop --release)
    python3 benches/python_fmm.py            # 1024^2 (20% obstacles) and 128^3, orders 1 and 2
    python3 benches/python_fmm.py --quick    # 256^2 and 64^3

For each grid, order and function (distance, travel_time), the median wall time of repeated
calls of ``skfmm.f`` and ``envfield.fmm.f`` on the very same masked array (the obstacles are
the mask, the front starts around the centre cell), their ratio, and that both answers agree
(the same cells reached, values within 1e-9). Then four solves on four Python threads at
once against one solve (the GIL is released while envfield marches). One JSON line per case.
"""
import argparse
import json
import os
import statistics
import sys
import threading
import time

import numpy as np
import skfmm

import envfield.fmm

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fmm_vs_skfmm import scatter  # noqa: E402  the same obstacle maps as the Rust bench


def timed(f, repeat):
    times = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return statistics.median(times) * 1e3, out


def problem(shape, rng):
    mask, centre = scatter(shape, 0.2, max(1, shape[0] // 128), rng)
    phi = np.ones(shape)
    phi[centre] = -1.0
    speed = 1.0 + rng.random(shape)
    return np.ma.MaskedArray(phi, mask), speed


def agree(a, b):
    ma, mb = np.ma.getmaskarray(a), np.ma.getmaskarray(b)
    if not (ma == mb).all():
        return False
    return bool(np.allclose(np.ma.getdata(a)[~ma], np.ma.getdata(b)[~mb], rtol=1e-9, atol=1e-9))


def threads(f, n):
    def run():
        f()

    ts = [threading.Thread(target=run) for _ in range(n)]
    t = time.perf_counter()
    for th in ts:
        th.start()
    for th in ts:
        th.join()
    return (time.perf_counter() - t) * 1e3


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    rng = np.random.default_rng(7)
    shapes = [(256, 256), (64, 64, 64)] if args.quick else [(1024, 1024), (128, 128, 128)]
    rows = []
    for shape in shapes:
        phi, speed = problem(shape, rng)
        repeat = 5 if phi.size > 2e5 else 15
        for name in ("distance", "travel_time"):
            for order in (1, 2):
                extra = (speed,) if name == "travel_time" else ()
                sk = lambda: getattr(skfmm, name)(phi, *extra, order=order)  # noqa: E731
                ef = lambda: getattr(envfield.fmm, name)(phi, *extra, order=order)  # noqa: E731
                t_sk, a = timed(sk, repeat)
                t_ef, b = timed(ef, repeat)
                row = {
                    "grid": "x".join(map(str, shape)), "function": name, "order": order,
                    "skfmm_ms": round(t_sk, 2), "envfield_ms": round(t_ef, 2),
                    "speedup": round(t_sk / t_ef, 2), "same_answer": agree(a, b),
                }
                print(json.dumps(row), flush=True)
                rows.append(row)
        one, _ = timed(lambda: envfield.fmm.distance(phi), 3)
        four = statistics.median(
            threads(lambda: envfield.fmm.distance(phi), 4) for _ in range(3))
        row = {"grid": "x".join(map(str, shape)), "threads": 4, "one_solve_ms": round(one, 2),
               "four_threads_ms": round(four, 2), "ratio": round(four / one, 2),
               "cores": os.cpu_count()}
        print(json.dumps(row), flush=True)
    print("\n| grid | function | order | scikit-fmm ms | envfield ms | speedup | same answer |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %s | %d | %.1f | %.1f | %.1fx | %s |" % (
            r["grid"], r["function"], r["order"], r["skfmm_ms"], r["envfield_ms"],
            r["speedup"], "yes" if r["same_answer"] else "NO"))


if __name__ == "__main__":
    main()
