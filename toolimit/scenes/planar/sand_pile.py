"""The spade world's building blocks: ground, deposit walls, goal box, sand circles, settled pile.

Units: metres, kilograms, seconds; plane coordinates (x, y) = world (x, z).

Settling a pile from scratch takes seconds of simulated time, too slow for alignment's thousands of
resets. The pile is therefore settled once per geometry (cached in memory), stored relative to the
tray centre, and each instance then adds its own small seeded jitter (see the spade scene).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import pymunk

#: Fixed seed of the one-off settling layout (part of the scene geometry, not of an instance).
_LAYOUT_SEED = 20220101


@dataclass(frozen=True)
class SandMaterial:
    """Physical constants of the sand circles and static geometry (SI units)."""

    radius: float = 0.0125  # m
    mass: float = 0.005  # kg per circle
    friction: float = 0.9  # Coulomb coefficient (pymunk multiplies both shapes' values)
    elasticity: float = 0.0


def configure_space(space: pymunk.Space, iterations: int, sleeping: bool = True) -> None:
    """Gravity and solver settings in metres (pymunk's defaults assume pixels).

    Collision slop 0.5 mm. With ``sleeping``, bodies slower than 1 cm/s for 0.25 s fall asleep, so
    a resting pile costs nothing; a moving kinematic tool wakes what it touches.
    """
    space.gravity = (0.0, -9.81)
    space.iterations = iterations
    space.collision_slop = 0.0005
    space.sleep_time_threshold = 0.25 if sleeping else float("inf")
    space.idle_speed_threshold = 0.01


def add_walls(
    space: pymunk.Space,
    centre_x: float,
    inner_half_width: float,
    wall_height: float,
    wall_thickness: float,
    friction: float,
    mass: float | None = None,
) -> pymunk.Body:
    """Two walls standing on the ground at ``centre_x +- (inner_half_width + t/2)``, metres; returns their body.

    Without ``mass``, a static tray (walls of the space's static body). With it, a dynamic open box
    of ``mass`` kg (two walls, no floor, no rotation) whose body origin is the box centre on the
    ground and whose rounded walls rest on the ground: a kinematic tool cannot pass through it, it
    pushes the box (sliding on the ground) instead.
    """
    radius = wall_thickness / 2.0
    if mass is None:
        body, origin_x, bottom = space.static_body, centre_x, 0.0
    else:
        body = pymunk.Body(mass, float("inf"))
        body.position = (centre_x, 0.0)
        space.add(body)
        origin_x, bottom = 0.0, radius
    for side in (-1.0, 1.0):
        x = origin_x + side * (inner_half_width + radius)
        wall = pymunk.Segment(body, (x, bottom), (x, wall_height), radius)
        wall.friction = friction
        space.add(wall)
    return body


def add_ground(space: pymunk.Space, friction: float, half_extent: float = 50.0) -> None:
    """A static ground whose top surface is plane y (= world z) = 0, over |x| < half_extent."""
    thickness = 0.05
    ground = pymunk.Segment(space.static_body, (-half_extent, -thickness), (half_extent, -thickness), thickness)
    ground.friction = friction
    space.add(ground)


def add_circles(space: pymunk.Space, positions: np.ndarray, material: SandMaterial) -> list[pymunk.Body]:
    """Dynamic sand circles at plane positions (N, 2), metres; returns their bodies in order."""
    bodies = []
    moment = pymunk.moment_for_circle(material.mass, 0.0, material.radius)
    for x, y in positions:
        body = pymunk.Body(material.mass, moment)
        body.position = (float(x), float(y))
        circle = pymunk.Circle(body, material.radius)
        circle.friction = material.friction
        circle.elasticity = material.elasticity
        space.add(body, circle)
        bodies.append(body)
    return bodies


def settle(space: pymunk.Space, bodies: list[pymunk.Body], max_time: float, dt: float) -> None:
    """Step until every circle sleeps (or ``max_time`` seconds of simulated time have passed)."""
    for _ in range(int(round(max_time / dt))):
        space.step(dt)
        if all(body.is_sleeping for body in bodies):
            return


@lru_cache(maxsize=8)
def settled_pile(
    count: int,
    inner_half_width: float,
    wall_height: float,
    wall_thickness: float,
    material: SandMaterial,
    dt: float,
    iterations: int,
) -> np.ndarray:
    """(count, 2) plane positions of a settled pile relative to the tray centre on the ground, m.

    Circles start on a staggered grid filling the tray row by row and fall under gravity.
    """
    rng = np.random.default_rng(_LAYOUT_SEED)
    spacing = 2.05 * material.radius
    per_row = max(1, int((2.0 * inner_half_width - spacing) // spacing))
    rows = np.arange(count) // per_row
    columns = np.arange(count) % per_row
    x = -inner_half_width + spacing * (columns + 0.5 + 0.5 * (rows % 2)) + 0.0
    x = np.minimum(x, inner_half_width - material.radius)
    y = material.radius + rows * spacing * 0.95 + 0.002
    start = np.stack([x + rng.uniform(-0.001, 0.001, count), y], axis=1)

    space = pymunk.Space()
    configure_space(space, iterations)
    add_ground(space, material.friction)
    add_walls(space, 0.0, inner_half_width, wall_height, wall_thickness, material.friction)
    bodies = add_circles(space, start, material)
    settle(space, bodies, max_time=5.0, dt=dt)
    return np.array([tuple(body.position) for body in bodies])
