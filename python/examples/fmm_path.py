#!/usr/bin/env python3
"""Travel time through a floor plan with scikit-fmm's API, and the shortest way back from
anywhere: envfield.fmm.travel_time and envfield.fmm.path, drawn as a PNG.

    python3 python/examples/fmm_path.py --out docs/python_path.png

A 400 x 600 plan (5 cm cells: 20 x 30 m) of rooms joined by doors, walls as the mask, a slow
carpet in one room (half speed); the front starts at a goal in the lower right room. Paths from
six starts come back down the field to it. Only NumPy and the standard library (the PNG is
written with zlib).
"""
import argparse
import struct
import time
import zlib

import numpy as np

from envfield import fmm


def floor_plan(rows=400, cols=600):
    walls = np.zeros((rows, cols), bool)
    walls[:4, :] = walls[-4:, :] = walls[:, :4] = walls[:, -4:] = True
    walls[196:204, :] = True                       # the corridor wall across
    for c in (150, 300, 450):
        walls[:, c - 3:c + 3] = True                # walls between rooms
    for c0 in (60, 210, 360, 510):                  # a door from each room to the other half
        walls[196:204, c0:c0 + 18] = False
    for r0 in (90, 290):                            # doors between neighbouring rooms
        for c in (150, 300, 450):
            walls[r0:r0 + 18, c - 3:c + 3] = False
    walls[300:360, 520:528] = True                  # a cabinet
    walls[60:150, 340:352] = True                   # a long table
    return walls


def viridis(t):
    """Viridis at t in [0, 1] (five of its colours, linearly between)."""
    stops = np.array([[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98],
                      [253, 231, 37]], float)
    x = np.clip(t, 0, 1) * (len(stops) - 1)
    i = np.minimum(x.astype(int), len(stops) - 2)
    f = (x - i)[..., None]
    return (stops[i] * (1 - f) + stops[i + 1] * f).astype(np.uint8)


def write_png(path, rgb):
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[r].tobytes() for r in range(h))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="fmm_path.png")
    args = parser.parse_args()
    walls = floor_plan()
    phi = np.ones(walls.shape)
    phi[340, 560] = -1.0                             # the goal
    speed = np.ones(walls.shape)
    speed[230:380, 170:280] = 0.5                    # a carpet: half speed
    t0 = time.perf_counter()
    t = fmm.travel_time(np.ma.MaskedArray(phi, walls), speed, dx=0.05)
    t1 = time.perf_counter()
    starts = [(30, 30), (150, 100), (30, 560), (370, 30), (120, 400), (300, 220)]
    paths = [fmm.path(t, s, dx=0.05) for s in starts]
    t2 = time.perf_counter()
    print("travel time on %dx%d: %.1f ms; %d paths: %.1f ms; longest %.1f s of walking"
          % (*walls.shape, 1e3 * (t1 - t0), len(paths), 1e3 * (t2 - t1), t.max()))

    scale = 2
    img = viridis(np.ma.getdata(t) / t.max())
    img[walls] = (30, 30, 30)
    img = img.repeat(scale, 0).repeat(scale, 1)
    for p in paths:
        # Draw each step as a short run of dots, a few pixels wide.
        dense = np.concatenate([np.linspace(a, b, 8, endpoint=False)
                                for a, b in zip(p[:-1], p[1:])] + [p[-1:]])
        for y, x in dense * scale:
            img[int(y) - 1:int(y) + 2, int(x) - 1:int(x) + 2] = (255, 255, 255)
    gy, gx = 340 * scale, 560 * scale
    img[gy - 5:gy + 6, gx - 5:gx + 6] = (230, 40, 40)
    for y, x in starts:
        img[y * scale - 4:y * scale + 5, x * scale - 4:x * scale + 5] = (255, 255, 255)
    write_png(args.out, img)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
