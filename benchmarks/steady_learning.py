"""Is the Panda spade chain steady? ``toolimit run`` on the demonstrations and seeds a user would try.

The runs (each ``run_pipeline`` with the 3D defaults and ``--seed``, i.e. what
``toolimit run --tool spade --robot panda --demo DEMO --seed S`` does):
- ``real_aligned``: the authors' real spade recording as the aligned file
  (``../shared/data/video_demos/spade_video1_aligned.npz``), seeds 0, 1, 2;
- ``real_points``: the same recording as a user would first write it, a demonstration of head and
  handle-end points (``p_handle = p_tip - R_tip (0, -0.161, 0.369)``, the shared data's README),
  saved in the project's format and given as that file, seeds 0, 1, 2;
- ``spade_00`` .. ``spade_04``: the shipped synthetic demonstrations, seed 0.

Every run resumes where it stopped (its folder under ``--out``), so the grid can be run one run at a
time (``--only NAME``) and spread over sessions. Prints one line per run (deterministic and
stochastic success and spheres over 20 episodes, the PPO steps and whether early stopping ended
them, the wall time of the stages run in that call and the machine's load) and writes
``benchmarks/results/steady_learning.json``. Usage:

    python benchmarks/steady_learning.py --out runs/steady                 # every run, in order
    python benchmarks/steady_learning.py --out runs/steady --only real_points_s1
    python benchmarks/steady_learning.py --out runs/steady --only spade_00_s0 --relearn

``--relearn`` learns again on the run's alignment and trajectory (after a change to the learning
alone); its wall time is then the earlier stages' plus the new learning and evaluation.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from toolimit.artifacts import save_json
from toolimit.demos import ToolDemo
from toolimit.demos.npz_format import SPADE_TIP_TO_HANDLE, save_demo
from toolimit.learn.task import TASK_NPZ, LearningTask
from toolimit.learn.training import CLONING_JSON
from toolimit.pipeline import PipelineSettings, run_pipeline

from provenance import commit

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data" / "video_demos"
REAL = SHARED / "spade_video1_aligned.npz"
RESULTS = ROOT / "benchmarks" / "results" / "steady_learning.json"

#: (name, demonstration, seed): the grid of the learning issue's "done when".
RUNS: tuple[tuple[str, str, int], ...] = (
    *((f"real_aligned_s{seed}", "real_aligned", seed) for seed in (0, 1, 2)),
    *((f"real_points_s{seed}", "real_points", seed) for seed in (0, 1, 2)),
    *((f"spade_0{k}_s0", f"spade_0{k}", 0) for k in range(5)),
)


def real_as_points(out: Path) -> Path:
    """The real recording written as head and handle-end points (the shared data's README), in
    the project's demonstration format: the file a user would make first."""
    path = out / "spade_video1_points.npz"
    if not path.is_file():
        arrays = np.load(REAL)
        tip = np.asarray(arrays["tip_position"], dtype=float)  # (T, 3) m, world frame
        rotation = Rotation.from_quat(arrays["tip_quaternion_wxyz"], scalar_first=True).as_matrix()  # (T, 3, 3)
        handle = tip - rotation @ SPADE_TIP_TO_HANDLE
        save_demo(ToolDemo(head=tip, handle=handle, fps=float(arrays["fps"]), tool="spade"), path)
    return path


def demo_path(demo: str, out: Path) -> Path:
    """The file of a demonstration name."""
    if demo == "real_aligned":
        return REAL
    if demo == "real_points":
        return real_as_points(out)
    return ROOT / "data" / "demos" / f"{demo}.npz"


def forget_learning(folder: Path) -> None:
    """Remove a run's learning and what followed it, and their times, keeping alignment and trajectory."""
    for stage in ("learning", "policy_rollout", "export"):
        shutil.rmtree(folder / stage, ignore_errors=True)
    (folder / "evaluation.json").unlink(missing_ok=True)
    run = folder / "run.json"
    if run.is_file():
        times = json.loads(run.read_text())["stage_times_s"]
        kept = {stage: time for stage, time in times.items() if stage in ("alignment", "trajectory")}
        save_json(run, {"stage_times_s": kept})


def run_one(name: str, demo: str, seed: int, out: Path) -> dict:
    """Run (or resume) one chain; its row."""
    load = os.getloadavg()[0]
    result = run_pipeline(
        demo_path(demo, out),
        out / name,
        tool="spade",
        robot="panda",
        world="3d",
        settings=PipelineSettings.for_world("3d").with_seed(seed),
        on_stage=lambda stage, line: print(f"[{name}] {stage}: {line}", flush=True),
    )
    record = result.evaluation
    learning = json.loads((out / name / "learning" / "learning.json").read_text())
    trajectory = json.loads((out / name / "trajectory" / "selection.json").read_text())
    return {
        "name": name,
        "demo": demo,
        "seed": seed,
        "success_rate": record["success_rate"],
        "goal_reward_mean": record["goal_reward_mean"],
        "stochastic_success_rate": record["stochastic"]["success_rate"],
        "stochastic_goal_reward_mean": record["stochastic"]["goal_reward_mean"],
        "env_steps": record["env_steps"],
        "ppo_env_steps": learning["ppo_env_steps"],
        "stopped_early": (learning.get("early_stop") or {}).get("stopped_at_ppo_env_steps") is not None,
        "wall_time_s": record["wall_time_s"],
        "stage_times_s": record["stage_times_s"],
        "selected_candidate": trajectory.get("kept", trajectory["best"]),
        "learnt_candidate": int(LearningTask.load(out / name / "learning" / TASK_NPZ).source["candidate"]),
        "shortlist": trajectory.get("shortlist"),
        "clone_check": json.loads((out / name / "learning" / CLONING_JSON).read_text()).get("clone_check"),
        "load_at_start": load,
        "commit": commit(short=True),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("runs/steady"), help="one folder per run")
    parser.add_argument("--only", default=None, help="one run's name (see RUNS)")
    parser.add_argument("--relearn", action="store_true", help="learn again on the runs' alignment and trajectory")
    args = parser.parse_args()
    if not REAL.is_file():
        print(f"{REAL}: not found (the shared data sits beside the checkout)", file=sys.stderr)
        return 2
    names = [name for name, _, _ in RUNS]
    if args.only is not None and args.only not in names:
        print(f"--only: unknown run {args.only!r}; known: {', '.join(names)}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    rows = json.loads(RESULTS.read_text())["runs"] if RESULTS.is_file() else {}
    for name, demo, seed in RUNS:
        if args.only in (None, name):
            if args.relearn:
                forget_learning(args.out / name)
            rows[name] = run_one(name, demo, seed, args.out)
            save_json(RESULTS, {"runs": rows})
    for row in (rows[name] for name in names if name in rows):
        print(
            f"{row['name']:16s} success {row['success_rate']:.2f} ({row['goal_reward_mean']:.1f} spheres), "
            f"stochastic {row['stochastic_success_rate']:.2f} ({row['stochastic_goal_reward_mean']:.1f}), "
            f"{row['ppo_env_steps']:,} PPO steps{' (stopped early)' if row['stopped_early'] else ''}, "
            f"{row['wall_time_s'] / 60:.1f} min"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
