#!/usr/bin/env python3
"""Plans a walk, a sit-down and a lie-down in a room from Python and saves every pose as .npz.

    python3 python/examples/walk_and_sit.py                       # a generated room
    python3 python/examples/walk_and_sit.py --scene room.glb      # your own scene (OBJ, PLY, glTF)
    python3 python/examples/walk_and_sit.py --scene out/cat/scene.obj --out plans.npz

A room furnished with real furniture (Sweet Home 3D's catalogue, GPL, fetched):
    bash scripts/fetch_sweethome3d.sh
    cargo run --release --example accessible -- --catalogue --seed 20000 --no-field --out out/cat

The .npz holds, for the walk, the sit-down and the lie-down (where the region has a bed or sofa
a body lies on): ``<kind>_path`` (steps, 3) torso locations,
``<kind>_poses`` (frames, 22, 3) joints in metres, ``<kind>_supported`` and
``<kind>_collision_free`` (frames,) per-pose checks against the scene, and ``joints``.
"""
import argparse
import time

import numpy as np

from envfield import rooms


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", help="OBJ, PLY, glTF or GLB file (default: a generated room)")
    parser.add_argument("--up", help="the scene's up axis, when not what its format says")
    parser.add_argument("--units", help="m, cm, mm or metres per unit")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--planner", default="ours_exact",
                        help="ours_exact, rrt, rrtstar, prm, line or navmesh")
    parser.add_argument("--out", default="plans.npz")
    args = parser.parse_args()

    if args.scene:
        scene = rooms.Scene.read(args.scene, up=args.up, units=args.units)
        for w in scene.warnings:
            print("warning:", w)
    else:
        scene = rooms.Scene.generated(seed=args.seed)
    t = time.perf_counter()
    region = scene.region(seed=args.seed)
    print("region: %d voxels of %.2f m, %d sit-downs, %d lie-downs, %.1f s"
          % (len(region.points), region.voxel, len(region.sit_downs), len(region.lie_downs),
             time.perf_counter() - t))

    # A walk between the two standing places farthest apart across the floor (torsos in the
    # lowest layer of the region, at standing height).
    pts = region.points
    standing = pts[np.abs(pts[:, 2] - np.median(pts[:, 2])) < region.voxel]
    start = standing[np.argmin(standing[:, 0] + standing[:, 1])]
    goal = standing[np.argmax(standing[:, 0] + standing[:, 1])]
    plans = {"walk": region.walk(start, goal, planner=args.planner, seed=args.seed)}
    if region.sit_downs:
        plans["sit"] = region.sit_down(0, planner=args.planner, seed=args.seed)
    else:
        print("no seat in this scene's region: no sit-down planned")
    if region.lie_downs:
        plans["lie"] = region.lie_down(0, planner=args.planner, seed=args.seed)
    else:
        print("no bed or sofa a body lies on in this scene's region: no lie-down planned")

    arrays = {"joints": np.array(rooms.JOINTS)}
    for kind, plan in plans.items():
        valid = plan.supported & plan.collision_free
        print("%s (%s): reached %s in %.3f s, %d steps, %d poses, %.1f%% valid, path %.3f of "
              "the shortest" % (kind, plan.planner, plan.reached, plan.seconds, len(plan.path),
                                len(plan.poses), 100 * valid.mean(), plan.path_ratio))
        arrays.update({kind + "_path": plan.path, kind + "_poses": plan.poses,
                       kind + "_supported": plan.supported,
                       kind + "_collision_free": plan.collision_free})
    np.savez(args.out, **arrays)
    print("saved", args.out)


if __name__ == "__main__":
    main()
