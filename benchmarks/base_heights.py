"""Robot base heights on the authors' real spade recording: the Panda and the UR5 at the project's
former heights (Panda on the floor, UR5 on a 0.4 m pedestal) and at the authors' (the spade scene
0.2 m above the Panda's base, the UR5 on the floor; ``method/utils.py get_default_robot_z``).

Aligns the recording once (the 3D spade scene, ``--candidates`` K, seed 0), then tracks every
candidate with each robot at each height and replays it in its scene (10 replays): prints the best
robot replay's spheres, how many candidates earn, the median over candidates, and the kept
trajectory's median position and rotation errors.

    python benchmarks/base_heights.py --out runs/base_heights \
        --json benchmarks/results/base_heights.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from talos_selection import RECORDING, aligned_recording, selection_row

from toolimit.robots import make_robot

#: (robot, base height above the scene's floor in m, label)
VARIANTS = (
    ("panda", 0.0, "former: on the floor"),
    ("panda", -0.2, "authors': scene 0.2 m above the base"),
    ("ur5", 0.4, "former: 0.4 m pedestal"),
    ("ur5", 0.0, "authors': on the floor"),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--recording", type=Path, default=RECORDING)
    parser.add_argument("--json")
    parser.add_argument("--candidates", type=int, default=40)
    parser.add_argument("--starts", type=int, default=2)
    args = parser.parse_args()
    world, candidates, first = aligned_recording(args.recording, Path(args.out), args.candidates)
    rows: list[dict] = [first]
    print(json.dumps(first), flush=True)
    for name, height, label in VARIANTS:
        started = time.perf_counter()
        robot = make_robot(name, tool="spade", base_height=height)
        selected, kept = selection_row(robot, candidates, world, args.starts)
        row: dict = {"robot": name, "base_height_m": height, "variant": label, **selected}
        if kept is not None:
            row["median_rotation_error_rad"] = float(np.median(kept.rotation_error))
        row["wall_time_s"] = round(time.perf_counter() - started, 1)
        print(json.dumps(row), flush=True)
        rows.append(row)
    if args.json:
        settings = {key: str(value) if isinstance(value, Path) else value for key, value in vars(args).items()}
        Path(args.json).write_text(json.dumps({"settings": settings, "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
