"""Make the learning tasks shipped in ``toolimit/learn/tasks/`` (one per registered environment).

For each (tool, world, robot): align a shipped demonstration (``data/demos``), optimise the robot's
trajectory with selection by robot execution, and save the task (scene parameters, base, reference
joints, horizon). The stages are the pipeline's own functions (:mod:`toolimit.pipeline`) with their
default settings but for the few below; their folders go to a temporary directory (or ``--work DIR``
to keep them).

    python scripts/make_learning_tasks.py [--only spade_planar_planar3] [--work DIR]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from toolimit.align.config import AlignmentConfig
from toolimit.learn.shipped import shipped_task_path
from toolimit.learn.task import task_from_pipeline
from toolimit.pipeline import AlignSettings, TrajoptSettings, align_stage, trajopt_stage

ROOT = Path(__file__).resolve().parents[1]

#: (tool, world, robot) -> (demonstration, alignment candidates, time scales the robot's selection tries).
RECIPES: dict[tuple[str, str, str], tuple[str, int, tuple[float, ...]]] = {
    ("spade", "planar", "planar3"): ("spade_03", 10, (1.0,)),
    ("hammer", "planar", "planar3"): ("hammer_00", 10, (1.0,)),
    ("scythe", "planar", "panda"): ("scythe_00", 10, (1.0,)),
    # the pipeline's 3D defaults: 40 candidates at real time (a slowed episode loses the sand);
    # spade_00, whose tool alone succeeds with the deposit's heap (spade_01's earns 2 spheres)
    ("spade", "3d", "panda"): ("spade_00", 40, (1.0,)),
    # the hammer and the scythe at real time: a slowed episode misses their first-second window
    ("hammer", "3d", "panda"): ("hammer_00", 5, (1.0,)),
    # 20 scythe candidates: about half earn their first stalk by the roll's turn at a keypoint, and
    # of 10 none had a Panda replay that cut (README, the timed tools)
    ("scythe", "3d", "panda"): ("scythe_00", 20, (1.0,)),
}


def make_task(tool: str, world: str, robot: str, work: Path) -> Path:
    """Run stages ii and iii for one recipe under ``work`` and save the task; returns its path."""
    demo, candidates, time_scales = RECIPES[(tool, world, robot)]
    alignment, trajectory = work / f"{tool}_{world}_align", work / f"{tool}_{world}_{robot}_trajopt"
    align_settings = AlignSettings(search=AlignmentConfig(candidates=candidates), seed=0)
    align_stage(ROOT / "data" / "demos" / f"{demo}.npz", tool, world, alignment, align_settings, progress=False)
    trajopt_stage(alignment, robot, trajectory, TrajoptSettings(time_scales=time_scales), progress=False)
    task = task_from_pipeline(alignment, trajectory)
    task.source.update(demo=f"data/demos/{demo}.npz", alignment="", trajectory="")
    path = task.save(shipped_task_path(tool, world, robot))
    print(
        f"{path.relative_to(ROOT)}: horizon {task.horizon} steps (reference {task.reference_steps}), "
        f"time scale {task.time_scale:g}"
    )
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
