"""The learning tasks shipped with the package, so that every registered environment works from a
fresh install without running the pipeline first.

``toolimit/learn/tasks/<tool>_<world>_<robot>.npz``, written by ``scripts/make_learning_tasks.py``
(alignment of a shipped demonstration, trajectory optimisation with selection by robot execution,
the horizon measured by :func:`toolimit.learn.task.success_horizon`).
"""

from __future__ import annotations

from pathlib import Path

from toolimit.errors import InputError
from toolimit.learn.task import LearningTask

TASKS_DIR = Path(__file__).resolve().parent / "tasks"
#: The robot of each (tool, world) when none is asked for: the Panda in 3D, the planar 3-link arm in
#: the vertical x-z plane. The planar scythe's world is the horizontal x-y plane, which an arm moving
#: in a vertical plane cannot sweep: the Panda holds that scythe.
DEFAULT_ROBOTS = {(tool, "3d"): "panda" for tool in ("spade", "hammer", "scythe")} | {
    ("spade", "planar"): "planar3",
    ("hammer", "planar"): "planar3",
    ("scythe", "planar"): "panda",
}


def shipped_task_path(tool: str, world: str, robot: str | None = None) -> Path:
    """Where the shipped task of (tool, world, robot) lives (it may not exist)."""
    return TASKS_DIR / f"{tool}_{world}_{robot or DEFAULT_ROBOTS[(tool, world)]}.npz"


def shipped_tasks() -> list[tuple[str, str, str]]:
    """(tool, world, robot) of every shipped task."""
    return sorted(tuple(path.stem.split("_")) for path in TASKS_DIR.glob("*_*_*.npz"))  # type: ignore[misc]


def shipped_task(tool: str, world: str, robot: str | None = None) -> LearningTask:
    """The shipped task; InputError listing the shipped ones if there is none for these names."""
    if (tool, world) not in DEFAULT_ROBOTS:
        raise InputError(
            f"no environment for the {tool!r} in world {world!r}; "
            f"known: {', '.join(f'{t}/{w}' for t, w in DEFAULT_ROBOTS)}"
        )
    path = shipped_task_path(tool, world, robot)
    if not path.is_file():
        known = ", ".join("/".join(names) for names in shipped_tasks())
        name = robot or DEFAULT_ROBOTS[(tool, world)]
        raise InputError(
            f"no shipped task for the {tool} in {world} with robot {name}; shipped: {known}; "
            "build your own with `toolimit run` and pass task=DIR/task.npz"
        )
    return LearningTask.load(path)
