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
from toolimit.tools.registry import tool_record, tool_records

TASKS_DIR = Path(__file__).resolve().parent / "tasks"


def environments() -> list[tuple[str, str]]:
    """(tool, world) of every registered tool with a scene and a default robot in that world (its
    record's ``default_robots``): the pairs that have a shipped task and a registered id."""
    return [
        (record.name, world) for record in tool_records() for world in record.scenes if world in record.default_robots
    ]


def default_robot(tool: str, world: str) -> str:
    """The robot of the shipped task of (tool, world) (the tool record's ``default_robots``: the
    Panda in 3D, the planar 3-link arm in the vertical x-z plane); InputError for a pair without
    one."""
    if (tool, world) not in environments():
        known = ", ".join(f"{t}/{w}" for t, w in environments())
        raise InputError(f"no environment for the {tool!r} in world {world!r}; known: {known}")
    return tool_record(tool).default_robots[world]


def shipped_task_path(tool: str, world: str, robot: str | None = None) -> Path:
    """Where the shipped task of (tool, world, robot) lives (it may not exist)."""
    return TASKS_DIR / f"{tool}_{world}_{robot or default_robot(tool, world)}.npz"


def shipped_tasks() -> list[tuple[str, str, str]]:
    """(tool, world, robot) of every shipped task."""
    return sorted(tuple(path.stem.split("_")) for path in TASKS_DIR.glob("*_*_*.npz"))  # type: ignore[misc]


def shipped_task(tool: str, world: str, robot: str | None = None) -> LearningTask:
    """The shipped task; InputError listing the shipped ones if there is none for these names."""
    default = default_robot(tool, world)  # InputError for a pair without an environment
    name = robot or default
    path = shipped_task_path(tool, world, name)
    if not path.is_file():
        known = ", ".join("/".join(names) for names in shipped_tasks())
        raise InputError(
            f"no shipped task for the {tool} in {world} with robot {name}; shipped: {known}; "
            "build your own with `toolimit run` and pass task=DIR/task.npz"
        )
    return LearningTask.load(path)
