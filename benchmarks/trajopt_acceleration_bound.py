"""Stage iii with and without the robot's acceleration bound: CPU time, ADMM iterations and cost J.

Aligns a shipped 3D demonstration (seed 0, the pipeline's alignment settings, the first
``--candidates`` candidates), then tracks every candidate with the robot (``toolimit trajopt``'s
settings: 8 base starts, both joint initialisations) twice in this run: within the robot's bound
(positions, velocities and, for a robot with published limits, accelerations) and with the same
bound without its acceleration limit, the reference. Prints per candidate the CPU time, the best
start's OSQP iterations and J of each; ends with ``ratio R``, the CPU time with the acceleration
bound over the time without it (single process; the alignment's workers are not timed).

    python benchmarks/trajopt_acceleration_bound.py [--tool spade] [--demo data/demos/spade_02.npz]
        [--robot panda] [--candidates 8] [--out benchmarks/results/trajopt_acceleration_bound.json]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from toolimit.pipeline.settings import AlignSettings, TrajoptSettings
from toolimit.pipeline.stages import align_stage, load_candidates
from toolimit.robots import make_robot
from toolimit.robots.motion_bound import MotionBound
from toolimit.trajopt.track import TrackOptions, track

from provenance import command, commit


def tracked(robot, candidates, options: TrackOptions) -> list[dict[str, float]]:
    """Each candidate tracked from ``default_rng([0, k])``: CPU seconds, OSQP iterations, J."""
    rows = []
    for k, candidate in enumerate(candidates):
        started = time.process_time()
        result = track(robot, candidate.targets, options, rng=np.random.default_rng([0, k]))
        assert result.statistics is not None  # a solve's result
        rows.append(
            {
                "cpu_s": time.process_time() - started,
                "osqp_iterations": result.statistics.qp_iterations,
                "cost": result.statistics.cost,
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tool", default="spade")
    parser.add_argument("--demo", type=Path, default=Path("data/demos/spade_02.npz"))
    parser.add_argument("--robot", default="panda")
    parser.add_argument("--candidates", type=int, default=8, help="candidates aligned and tracked")
    parser.add_argument("--out", type=Path, default=None, help="also write the figures to this JSON file")
    args = parser.parse_args()

    align = AlignSettings()
    align = dataclasses.replace(align, search=dataclasses.replace(align.search, candidates=args.candidates))
    with tempfile.TemporaryDirectory() as folder:
        align_stage(args.demo, args.tool, "3d", folder, align, progress=False)
        tool, _, candidates = load_candidates(folder)
    robot = make_robot(args.robot, tool=tool)
    bound = MotionBound.of(robot)
    if bound.acceleration is None:
        parser.error(f"the {args.robot} publishes no acceleration limit: nothing to compare")
    options = TrajoptSettings().track_options()
    track(robot, candidates[0].targets, options, rng=np.random.default_rng(0))  # compiled kernels warmed up
    bounded = tracked(robot, candidates, dataclasses.replace(options, bound=bound))
    reference = tracked(
        robot, candidates, dataclasses.replace(options, bound=dataclasses.replace(bound, acceleration=None))
    )

    print(f"{args.robot} tracking {len(candidates)} candidates of {args.demo}, commit {commit(short=True)}")
    print("candidate | CPU s with / without | OSQP iterations (best start) with / without | J with / without")
    for k, (a, b) in enumerate(zip(bounded, reference)):
        print(
            f"{k:9d} | {a['cpu_s']:6.2f} / {b['cpu_s']:6.2f} | {a['osqp_iterations']:8d} / {b['osqp_iterations']:8d}"
            f" | {a['cost']:.4f} / {b['cost']:.4f}"
        )
    with_bound = sum(row["cpu_s"] for row in bounded)
    without = sum(row["cpu_s"] for row in reference)
    print(f"CPU with the acceleration bound {with_bound:.1f} s, without {without:.1f} s")
    print(f"ratio {with_bound / without:.2f}")
    if args.out is not None:
        record = {
            "commit": commit(),
            "command": command(),
            "demo": str(args.demo),
            "robot": args.robot,
            "with_acceleration_bound": bounded,
            "without_acceleration_bound": reference,
            "ratio": with_bound / without,
        }
        args.out.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
