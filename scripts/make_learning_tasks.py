"""Make the learning tasks shipped in ``toolimit/learn/tasks/`` (one per registered environment).

For each (tool, world, robot): align a shipped demonstration (``data/demos``), optimise the robot's
trajectory with selection by robot execution, and save the task (scene parameters, base, reference
joints, horizon). The stages run through the ``toolimit`` command, exactly as a user would run
them; their folders go to a temporary directory (or ``--work DIR`` to keep them).

    python scripts/make_learning_tasks.py [--only spade_planar_planar3] [--work DIR]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from toolimit.cli import main as toolimit
from toolimit.learn.shipped import shipped_task_path
from toolimit.learn.task import task_from_pipeline

ROOT = Path(__file__).resolve().parents[1]

#: (tool, world, robot) -> (demonstration, extra `toolimit align` flags, extra `toolimit trajopt` flags).
RECIPES: dict[tuple[str, str, str], tuple[str, list[str], list[str]]] = {
    ("spade", "planar", "planar3"): ("spade_03", ["--candidates", "10"], ["--velocity-weight", "1e-4"]),
    ("hammer", "planar", "planar3"): ("hammer_00", ["--candidates", "10"], ["--velocity-weight", "1e-4"]),
    ("scythe", "planar", "panda"): ("scythe_00", ["--candidates", "10"], ["--velocity-weight", "1e-4"]),
    ("spade", "3d", "panda"): ("spade_01", ["--candidates", "10"], ["--velocity-weight", "1e-4", "--time-scale", "auto"]),
    ("hammer", "3d", "panda"): ("hammer_00", ["--candidates", "5"], ["--velocity-weight", "1e-4", "--time-scale", "auto"]),
    ("scythe", "3d", "panda"): ("scythe_00", ["--candidates", "5"], ["--velocity-weight", "1e-4", "--time-scale", "auto"]),
}


def make_task(tool: str, world: str, robot: str, work: Path) -> Path:
    """Run the pipeline for one recipe under ``work`` and save the task; returns its path."""
    demo, align_flags, trajopt_flags = RECIPES[(tool, world, robot)]
    alignment, trajectory = work / f"{tool}_{world}_align", work / f"{tool}_{world}_{robot}_trajopt"
    code = toolimit(["align", "--tool", tool, "--world", world, "--demo", str(ROOT / "data" / "demos" / f"{demo}.npz"),
                     "--out", str(alignment), "--seed", "0", "--quiet", *align_flags])
    if code != 0:
        raise SystemExit(f"{tool}/{world}: alignment failed (exit {code})")
    code = toolimit(["trajopt", "--robot", robot, "--tool", tool, "--alignment", str(alignment), "--select-by-robot",
                     "--out", str(trajectory), "--quiet", *trajopt_flags])
    if code != 0:
        raise SystemExit(f"{tool}/{world}/{robot}: trajectory optimisation failed (exit {code})")
    task = task_from_pipeline(alignment, trajectory)
    task.source.update(demo=f"data/demos/{demo}.npz", alignment="", trajectory="")
    path = task.save(shipped_task_path(tool, world, robot))
    print(f"{path.relative_to(ROOT)}: horizon {task.horizon} steps (reference {task.reference_steps}), "
          f"time scale {task.time_scale:g}")
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", action="append", default=None, help="tool_world_robot to make (repeatable)")
    parser.add_argument("--work", type=Path, default=None, help="keep the stages' folders here")
    args = parser.parse_args()
    recipes = [key for key in RECIPES if args.only is None or "_".join(key) in args.only]
    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        for key in recipes:
            make_task(*key, work)


if __name__ == "__main__":
    main()
