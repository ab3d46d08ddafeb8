"""Robots by name: ``make_robot("panda", tool="spade")``; a new one: ``register_robot(name, builder)``."""

from __future__ import annotations

import functools
from collections.abc import Callable

import pinocchio as pin

from toolimit.errors import InputError
from toolimit.live_names import LiveNames
from toolimit.robots import arms
from toolimit.robots.model import ArmDescription, RobotModel, build_robot_model
from toolimit.tools import tool_spec

_BUILDERS: dict[str, Callable[[], ArmDescription]] = {
    "planar3": arms.planar3,
    "panda": arms.panda,
    "ur5": arms.ur5,
    "talos": arms.talos,
}

#: The registered robot names (a live view: a robot registered later appears in it).
ROBOTS = LiveNames("ROBOTS", lambda: tuple(_BUILDERS))


def register_robot(name: str, builder: Callable[[], ArmDescription]) -> None:
    """Make ``name`` a robot of :func:`make_robot`: ``builder()`` returns its
    :class:`~toolimit.robots.model.ArmDescription` (active joints, flange and mount rotation, rest
    pose, base height and base coordinates; see :mod:`toolimit.robots.arms` for examples), called
    once, on the robot's first use. InputError for a name already taken or a builder that is not
    callable."""
    if not isinstance(name, str) or not name:
        raise InputError(f"robot name: expected a non-empty string, got {name!r}")
    if name in _BUILDERS:
        raise InputError(f"robot {name!r} is already registered")
    if not callable(builder):
        raise InputError(f"robot {name!r}: the builder must be callable, got {type(builder).__name__}")
    _BUILDERS[name] = builder


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
        base_height: height of the base above the floor (m), replacing the robot's default for
            ``tool`` (:meth:`~toolimit.robots.model.ArmDescription.base_height_for`).
    """
    if name not in _BUILDERS:
        raise InputError(f"unknown robot {name!r}; known robots: {', '.join(ROBOTS)}")
    return build_robot_model(_arm(name), tool_spec(tool), tool_placement, base_height)


@functools.cache
def _arm(name: str) -> ArmDescription:
    """The arm description, built once per process (loading a URDF takes up to a second);
    ``build_robot_model`` copies its Pinocchio model, so the cached one is never modified."""
    arm = _BUILDERS[name]()
    if not isinstance(arm, ArmDescription):
        raise InputError(f"robot {name!r}: its builder returned a {type(arm).__name__}, not an ArmDescription")
    if arm.name != name:
        raise InputError(f"robot {name!r}: its builder's ArmDescription is named {arm.name!r}")
    return arm
