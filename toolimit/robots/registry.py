"""Robots by name: ``make_robot("panda", tool="spade")``."""

from __future__ import annotations

import functools
from collections.abc import Callable

import pinocchio as pin

from toolimit.errors import InputError
from toolimit.robots import arms
from toolimit.robots.model import ArmDescription, RobotModel, build_robot_model
from toolimit.tools import tool_spec

_BUILDERS: dict[str, Callable[[], ArmDescription]] = {
    "planar3": arms.planar3,
    "panda": arms.panda,
    "ur5": arms.ur5,
    "talos": arms.talos,
}

ROBOTS = tuple(_BUILDERS)


def make_robot(
    name: str,
    tool: str = "spade",
    tool_placement: pin.SE3 | None = None,
    base_height: float | None = None,
) -> RobotModel:
    """The robot ``name`` holding ``tool``.

    Args:
        name: one of :data:`ROBOTS`.
        tool: a tool name of :data:`toolimit.tools.TOOLS`; its length places the tool frame.
        tool_placement: tool frame relative to the joint that carries the flange (a Pinocchio
            ``Frame.placement``), replacing the default mounting (handle end at the flange, tool
            along the approach axis; see :mod:`toolimit.robots.model`).
        base_height: height of the base above the floor (m), replacing the robot's default.
    """
    if name not in _BUILDERS:
        raise InputError(f"unknown robot {name!r}; known robots: {', '.join(ROBOTS)}")
    return build_robot_model(_arm(name), tool_spec(tool), tool_placement, base_height)


@functools.cache
def _arm(name: str) -> ArmDescription:
    """The arm description, built once per process (loading a URDF takes up to a second);
    ``build_robot_model`` copies its Pinocchio model, so the cached one is never modified."""
    return _BUILDERS[name]()
