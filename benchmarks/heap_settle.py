"""The 3D spade's sand heap at reset: how still it lies, and what the spade carries from it.

Measures the heap of the code it runs with (``toolimit.scenes.spatial.spade.settled_heap``) and
records it under ``--label`` in ``benchmarks/results/heap_settle.json``, beside the other labels
(each with its commit and command), so that two heaps are compared by running this script at two
commits. With every label's figures at hand it prints the ratios of each to the first label.

* ``reference``: the authors' aligned spade motions (``spade_video1_aligned``,
  ``spade_example_aligned`` from ``../shared/data/video_demos``, converted by
  ``toolimit.trajopt.from_original_spade_tip``) replayed tool-only 10 times in their own scene
  parameters (one batch, ``default_rng(0)``): mean final goal reward and success rate, the motion
  as recorded (the scene module docstring's measurement) and speed-limited as the alignment replays
  it, and as recorded 50 times with the learner's reset noise (N(0, 0.01) m on each position
  parameter in x and y, per replay; a heap without randomness of its own replays alike without
  it), with the standard error of that mean;
* ``slump``: 16 instances in the authors' default parameters (deposit at the origin, yaw 0, box at
  (0, 1)) with the spade far away for 150 control steps: the largest displacement of a sphere from
  its reset position after 25, 50, 100 and 150 steps (mm), the mean one after 150, the spheres
  moved more than 1 cm, those outside the deposit's 0.4 m square (at reset and after 150 steps),
  the first step at which every sphere of an instance sleeps (0: not within the 150 steps), and the CPU time of the 150 steps;
* ``stages`` (``--demos``): stages ii and iii of ``toolimit run --tool spade --robot panda`` with the
  ``full`` reproduction's settings (seed 0) into ``--out``/<label>/<demo>, then the figure's
  ``tool_only`` and ``trajopt`` cells (20 episodes, ``toolimit.experiments.measure``) and the
  stages' wall times. ``--stages-of LABEL`` measures the cells on the stages another label made
  (found finished in ``--out``/LABEL, not run again): the heap's effect on the same trajectory.

Usage (each part is saved as soon as it is measured; ``--demos`` may be spread over calls):

    python benchmarks/heap_settle.py --label deposit
    python benchmarks/heap_settle.py --label deposit --skip-scene --out runs/heap --demos spade_00,spade_video1_aligned
    python benchmarks/heap_settle.py --label deposit_on_pen_stages --stages-of pen --skip-scene --out runs/heap --demos spade_00
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from toolimit.artifacts import save_json
from toolimit.demos.npz_format import original_scene_params
from toolimit.experiments.cells import Experiment
from toolimit.experiments.measure import measure_tool_only, measure_trajopt
from toolimit.experiments.reproduce import preset
from toolimit.learn.simulator import PARAM_NOISE_STD
from toolimit.learn.task import task_from_pipeline
from toolimit.pipeline.run import STAGES, run_stages
from toolimit.scenes.replay import replay
from toolimit.scenes.spatial.spade import DEPOSIT_INNER, SpatialSpadeScene
from toolimit.tools import ToolPose
from toolimit.trajopt import from_original_spade_tip, load_pose_targets
from toolimit.trajopt.result import TRAJECTORY_NPZ

from provenance import command, commit

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("TOOLIMIT_SHARED", ROOT.parent / "shared")) / "data" / "video_demos"
RESULTS = ROOT / "benchmarks" / "results" / "heap_settle.json"
AUTHORS_MOTIONS = ("spade_video1_aligned", "spade_example_aligned")
#: The authors' default spade parameters (pyphysx_envs ``SpadeTaskScene._default_params``).
AUTHORS_DEFAULT = {"sand_position": np.zeros(3), "sand_yaw": 0.0, "goal_position": np.array([0.0, 1.0, 0.0])}
FAR_AWAY = ToolPose(np.array([3.0, 3.0, 1.0]), np.eye(3))
SLUMP_STEPS = 150
SLUMP_REPORTED = (25, 50, 100, 150)
REPLAYS = 10
NOISY_REPLAYS = 50


def authors_motion(name: str) -> tuple[ToolPose, dict[str, Any]]:
    """The authors' aligned spade poses (tool frame, world) and their scene parameters."""
    path = SHARED / f"{name}.npz"
    data = np.load(path)
    targets = from_original_spade_tip(load_pose_targets(path))
    params = original_scene_params(dict(data))
    return ToolPose(targets.positions, targets.rotations), params


def with_reset_noise(params: dict[str, Any], batch: int, rng: np.random.Generator) -> dict[str, Any]:
    """``params`` with each position parameter + N(0, PARAM_NOISE_STD) m in x and y, per instance ((B, 3))."""
    noisy = dict(params)
    for name in ("sand_position", "goal_position"):
        noise = rng.normal(0.0, PARAM_NOISE_STD, (batch, 3)) * [1.0, 1.0, 0.0]
        noisy[name] = np.asarray(params[name], float)[None] + noise
    return noisy


def reference() -> dict[str, Any]:
    """Mean final goal reward and success of the authors' motions, three ways (module docstring)."""
    record: dict[str, Any] = {}
    for name in AUTHORS_MOTIONS:
        motion, params = authors_motion(name)
        ways = {
            "recorded": (params, REPLAYS, False),
            "speed_limited": (params, REPLAYS, True),
            "recorded_reset_noise": (
                with_reset_noise(params, NOISY_REPLAYS, np.random.default_rng(1)),
                NOISY_REPLAYS,
                False,
            ),
        }
        record[name] = {}
        for way, (replay_params, replays, alone) in ways.items():
            scene = SpatialSpadeScene()
            goal = replay(scene, replay_params, np.random.default_rng(0), motion, replays, tool_alone=alone)
            record[name][way] = {
                "replays": replays,
                "goal_reward": float(goal.mean()),
                "goal_reward_standard_error": float(goal.std(ddof=1) / np.sqrt(replays)),
                "success_rate": float(np.mean(scene.is_success())),
            }
    return record


def slump() -> dict[str, Any]:
    """How the heap moves at rest with no tool (module docstring)."""
    scene = SpatialSpadeScene()
    scene.reset(AUTHORS_DEFAULT, np.random.default_rng(0), batch_size=16)
    start = scene.sphere_positions  # (B, N, 3), the deposit at the origin, yaw 0
    largest, asleep = {}, np.zeros(scene.batch_size, dtype=int)  # asleep: first step every sphere sleeps, 0 none
    cpu = time.process_time()
    for step in range(1, SLUMP_STEPS + 1):
        scene.step(FAR_AWAY)
        asleep[(asleep == 0) & ~np.any(scene.sphere_velocities, axis=(1, 2))] = step
        if step in SLUMP_REPORTED:
            moved = np.linalg.norm(scene.sphere_positions - start, axis=-1)
            largest[str(step)] = float(1000 * moved.max())
    cpu = time.process_time() - cpu
    end = scene.sphere_positions
    moved = np.linalg.norm(end - start, axis=-1)

    def outside(points: np.ndarray) -> float:
        return float(np.mean(np.sum(np.any(np.abs(points[..., :2]) > DEPOSIT_INNER / 2, axis=-1), axis=1)))

    return {
        "instances": 16,
        "largest_displacement_mm": largest,
        "mean_displacement_mm": float(1000 * moved.mean()),
        "spheres_moved_over_1cm": float(np.mean(np.sum(moved > 0.01, axis=1))),
        "spheres_outside_deposit_at_reset": outside(start),
        "spheres_outside_deposit_after": outside(end),
        "first_step_all_asleep": asleep.tolist(),
        "cpu_s": cpu,
    }


def demo_path(name: str) -> Path:
    """A shipped demonstration (``spade_0k``) or an authors' recording by its stem."""
    return SHARED / f"{name}.npz" if name in AUTHORS_MOTIONS else ROOT / "data" / "demos" / f"{name}.npz"


def stages(name: str, folder: Path, run: bool) -> dict[str, Any]:
    """Stages ii-iii with the full preset's settings in ``folder`` (made when ``run``, else found
    there) and the tool_only and trajopt cells (module docstring)."""
    experiment = Experiment("spade", "3d", "panda", demo_path(name))
    settings = preset("full").settings(experiment, seed=0)
    if run:
        run_stages(experiment.demo, folder, "spade", "panda", "3d", settings, progress=False, stages=STAGES[:2])
    task = task_from_pipeline(folder / "alignment", folder / "trajectory", seed=settings.learning.seed)
    episodes, seed = settings.evaluation.episodes, settings.evaluation.seed
    cells = {
        "tool_only": measure_tool_only(experiment, task, episodes, seed),
        "trajopt": measure_trajopt(experiment, task, episodes, seed),
    }
    record: dict[str, Any] = {
        method: {"goal_reward": cell.goal_reward, "success_rate": cell.success_rate} for method, cell in cells.items()
    }
    record["candidate"] = int(task.source["candidate"])
    record["stage_times_s"] = json.loads((folder / "run.json").read_text())["stage_times_s"]
    return record


def ratios(runs: dict[str, Any]) -> None:
    """Print each label's headline figures and their ratio to the first label's."""
    labels = list(runs)
    if len(labels) < 2:
        return
    base = runs[labels[0]]
    for label in labels[1:]:
        run = runs[label]
        print(f"{label} against {labels[0]}:")
        for name in AUTHORS_MOTIONS:
            for way in ("recorded", "speed_limited", "recorded_reset_noise"):
                a, b = (r.get("reference", {}).get(name, {}).get(way) for r in (base, run))
                if a and b:
                    print(f"  {name} {way}: goal reward {b['goal_reward']:.1f} / {a['goal_reward']:.1f}")
        a, b = base.get("slump"), run.get("slump")
        if a and b:
            print(
                f"  slump largest after {SLUMP_STEPS} steps {b['largest_displacement_mm'][str(SLUMP_STEPS)]:.1f} / "
                f"{a['largest_displacement_mm'][str(SLUMP_STEPS)]:.1f} mm, CPU {b['cpu_s'] / a['cpu_s']:.2f}x"
            )
        for demo in sorted(set(base.get("stages", {})) & set(run.get("stages", {}))):
            a, b = base["stages"][demo], run["stages"][demo]
            print(
                f"  {demo}: "
                + ", ".join(
                    f"{m} {b[m]['goal_reward']:.1f} ({b[m]['success_rate']:.2f}) / {a[m]['goal_reward']:.1f} "
                    f"({a[m]['success_rate']:.2f})"
                    for m in ("tool_only", "trajopt")
                )
            )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--label", required=True, help="the heap measured (the key in the results)")
    parser.add_argument("--skip-scene", action="store_true", help="leave out the reference and the slump")
    parser.add_argument("--demos", default="", help="comma-separated: spade_00..spade_04, spade_video1_aligned")
    parser.add_argument("--out", type=Path, default=Path("runs/heap_settle"), help="stage folders (per label)")
    parser.add_argument("--results", type=Path, default=RESULTS, help="the results JSON")
    parser.add_argument("--stages-of", default=None, help="measure the cells on this label's finished stages")
    args = parser.parse_args()
    demos = [d for d in args.demos.split(",") if d]
    for name in demos:
        if not demo_path(name).is_file():
            print(f"--demos: {demo_path(name)} not found", file=sys.stderr)
            return 2
        made = args.out / str(args.stages_of) / name / "trajectory" / TRAJECTORY_NPZ
        if args.stages_of is not None and not made.is_file():
            print(f"--stages-of: {made} not found (run that label's stages first)", file=sys.stderr)
            return 2
    if not all((SHARED / f"{name}.npz").is_file() for name in AUTHORS_MOTIONS):
        print(f"{SHARED}: the authors' recordings are not there (set TOOLIMIT_SHARED)", file=sys.stderr)
        return 2
    record = json.loads(args.results.read_text()) if args.results.is_file() else {"commit": "per run", "runs": {}}
    run = record["runs"].setdefault(args.label, {})
    made_by = {  # each part records the call that measured it
        "commit": commit(short=True),
        "command": command(),
        "load_at_start": os.getloadavg()[0],
    }
    if not args.skip_scene:
        run["reference"] = reference() | made_by
        print(json.dumps(run["reference"]))
        run["slump"] = slump() | made_by
        print(json.dumps(run["slump"]))
        save_json(args.results, record)
    for name in demos:
        started = time.perf_counter()
        folder = args.out / (args.stages_of or args.label) / name
        measured = stages(name, folder, run=args.stages_of is None)
        run.setdefault("stages", {})[name] = measured | made_by | {"stages_of": args.stages_of or args.label}
        print(name, json.dumps(measured), f"{time.perf_counter() - started:.0f} s")
        save_json(args.results, record)
    ratios(record["runs"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
