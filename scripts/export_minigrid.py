#!/usr/bin/env python3
"""Export layouts of the real Minigrid package to envfield's maze text format.

    pip install minigrid        # 3.2.0 was used for data/minigrid/
    python3 scripts/export_minigrid.py data/minigrid

One file per environment, 200 layouts each (seeds 0..199), each with the environment's own
agent start (S) and goal (G). Walls and lava are obstacles; doors (open, closed or locked)
and every other object are free cells, since an agent can pass them by opening or picking
up (LavaCrossing is left out: with the same seed it lays lava where SimpleCrossing lays
walls, the same layout). The layouts come from Minigrid's generators, which envfield never trains on: they are
evaluation data only.
"""

import os
import sys

import gymnasium as gym
import minigrid  # noqa: F401  (registers the MiniGrid-* environments)
from minigrid.core.world_object import Lava, Wall

ENVS = [
    "MiniGrid-SimpleCrossingS9N1-v0",
    "MiniGrid-SimpleCrossingS9N2-v0",
    "MiniGrid-SimpleCrossingS9N3-v0",
    "MiniGrid-SimpleCrossingS11N5-v0",
    "MiniGrid-FourRooms-v0",
    "MiniGrid-MultiRoom-N4-S5-v1",
    "MiniGrid-MultiRoom-N6-v0",
]
LAYOUTS = 200


def layout(env_id, seed):
    env = gym.make(env_id)
    env.reset(seed=seed)
    u = env.unwrapped
    rows = []
    goal = None
    for y in range(u.height):
        row = []
        for x in range(u.width):
            obj = u.grid.get(x, y)
            if isinstance(obj, (Wall, Lava)):
                row.append("#")
            else:
                if obj is not None and obj.type == "goal":
                    goal = (x, y)
                row.append(".")
        rows.append(row)
    ax, ay = u.agent_pos
    rows[ay][ax] = "S"
    if goal is not None and goal != (ax, ay):
        rows[goal[1]][goal[0]] = "G"
    env.close()
    return "\n".join("".join(r) for r in rows)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "data/minigrid"
    os.makedirs(out, exist_ok=True)
    version = getattr(minigrid, "__version__", "unknown")
    for env_id in ENVS:
        name = env_id.removeprefix("MiniGrid-").removesuffix("-v0").removesuffix("-v1")
        mazes = [layout(env_id, s) for s in range(LAYOUTS)]
        path = os.path.join(out, f"{name}.txt")
        tmp = path + ".tmp"
        with open(tmp, "w") as f:
            f.write(f"; {env_id}, minigrid {version}, seeds 0..{LAYOUTS - 1}: S the agent, G the goal\n")
            f.write("\n\n".join(mazes) + "\n")
        os.replace(tmp, path)
        print(f"{path}: {len(mazes)} layouts")


if __name__ == "__main__":
    main()
