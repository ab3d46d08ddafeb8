"""Planar hammer scene (pymunk, vertical x-z plane): drive a nail into a board.

World (pymunk x = world x, pymunk y = world z; world y is ignored):

* the nail: a dynamic body (``nail_mass``, no rotation) made of a head plate (``nail_head_width``
  wide, ``nail_head_thickness`` thick) and a shank; its head top starts at parameter
  ``nail_position`` (x and z used; the board may be at any height) and protrudes ``protrusion``
  (default 50 mm) above the board surface;
* a vertical guide (pymunk GrooveJoint) that lets the nail move only straight down, by 0 to
  ``protrusion`` (the head plate then lies on the board);
* entry friction: a Coulomb-like force of at most ``friction_force`` (default 20 N) opposing the
  nail's motion (a pymunk PivotJoint with ``max_bias = 0`` and ``max_force = friction_force``: it
  cancels the nail's velocity with a bounded force, exactly dry friction). With the default 50 g
  nail it stops a nail moving at v after v^2 / (2 (F/m - g)) = 11 mm at 3 m/s, 0.1 mm at 0.3 m/s;
* the board: a block under the nail from the ground up to the board surface; geometry for views
  and footprints only, not a pymunk shape (the nail enters it along the guide, and pymunk would
  let the kinematic hammer pass through a static shape anyway).

The hammer (tool frame: origin at the head centre, z along the handle, x the striking direction)
is the projection into the plane of its head box (``ToolSpec.head_width`` 0.11 m along x,
``ToolSpec.head_length`` 0.035 m along z, ``head_depth`` along y) and of its handle (a segment of
``handle_radius`` to ``ToolSpec.length``). The tool is kinematic: a moving hammer pushes the nail
with whatever force it takes, so the nail travels as far as the hammer follows it, plus the slide
it keeps after the hammer stops (the momentum it received, braked by the friction above).

Rewards: goal reward 1 when less than ``planted_tolerance`` (1 mm) of the nail's travel is left.
Dense reward (the paper's appendix, :func:`~toolimit.scenes.base.gaussian_closeness`, b = 10, on
x-z plane distances, m): exp(-5 |p - n|^2), with p the hammer's striking face (the head's end along
the tool's x) and n the nail head's centre where the nail is now (the authors' tip and nail body
origin); in [0, 1], 0 before the first step (no hammer yet). Success: planted at some control step whose end time, measured from the start of the
first ``step`` after ``reset``, is at most ``success_window`` seconds (1 s, docs/method.md#success-criteria).
"""

from __future__ import annotations

import numpy as np
import pymunk

from toolimit.scenes.base import (
    CONTROL_FPS,
    SceneParams,
    WindowedGoalScene,
    check_reset,
    dense_hammer_reward,
    dense_tool_point,
    instance_positions,
    require_reset,
    world_position,
)
from toolimit.scenes.planar.kinematic_tool import KinematicTool, plane_point
from toolimit.tools import ToolPose, tool_spec

#: Nail positions above this height (m) are rejected.
MAX_NAIL_HEIGHT = 3.0
#: Half-length (m) of the board block along x.
BOARD_HALF_LENGTH = 0.15
#: Shank length (m) below the board surface at the start (hidden in the board).
SHANK_EMBEDDED = 0.02


class PlanarHammerScene(WindowedGoalScene):
    """B instances of the planar hammer world; see the module docstring for geometry and rewards.

    Args:
        control_dt, success_window: see :class:`~toolimit.scenes.base.WindowedGoalScene`; the
            nail must be planted within ``success_window`` s of the first step's start.
        substeps: physics sub-steps per control step (20 at 24 Hz = 480 Hz).
        protrusion: nail travel from its start to fully planted, m (0 < protrusion <= 0.1).
        nail_mass: kg. friction_force: maximum entry friction force, N.
        nail_head_width, nail_head_thickness, nail_shank_width: nail dimensions, m.
        head_depth: hammer head extent along the tool's y axis, m. handle_radius: m.
        planted_tolerance: travel left (m) below which the nail counts as planted.
    """

    tool = "hammer"
    world = "planar"

    def __init__(
        self,
        control_dt: float = 1.0 / CONTROL_FPS,
        substeps: int = 20,
        protrusion: float = 0.05,
        nail_mass: float = 0.05,
        friction_force: float = 20.0,
        nail_head_width: float = 0.03,
        nail_head_thickness: float = 0.006,
        nail_shank_width: float = 0.005,
        head_depth: float = 0.03,
        handle_radius: float = 0.012,
        planted_tolerance: float = 0.001,
        success_window: float = 1.0,
    ):
        super().__init__(control_dt, substeps, success_window)
        if not 0.0 < protrusion <= 0.1:
            raise ValueError(f"protrusion must be in (0, 0.1] m, got {protrusion}")
        self.protrusion = float(protrusion)
        self.nail_mass = float(nail_mass)
        self.friction_force = float(friction_force)
        self.nail_head_width = float(nail_head_width)
        self.nail_head_thickness = float(nail_head_thickness)
        self.nail_shank_width = float(nail_shank_width)
        self.handle_radius = float(handle_radius)
        self.planted_tolerance = float(planted_tolerance)
        spec = tool_spec("hammer")
        half = np.array([spec.head_width, head_depth, spec.head_length]) / 2.0
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
        self._head_corners = corners  # (8, 3) tool frame, m
        self._handle_points = np.array([[0.0, 0.0, half[2]], [0.0, 0.0, spec.length]])  # (2, 3)
        self.parameters = (
            world_position(
                "nail_position",
                f"top of the nail head; the board surface is {self.protrusion * 1000:.0f} mm below",
                low_z=self.protrusion,
                high_z=MAX_NAIL_HEIGHT,
                axes=(0, 2),
                bound_reason="the board surface, one protrusion below the nail's top, may not be "
                "below the ground (z = 0)",
            ),
        )
        # The state of the B instances, built by reset.
        self.nail_start = np.zeros((0, 2))  # (B, 2) plane points (x, z) of the nail heads' tops at reset, m
        self._spaces: list[pymunk.Space] = []
        self._nails: list[pymunk.Body] = []
        self._tool = KinematicTool(self._spaces, "xz", reference_axis=2)
        self._tool_shapes: list[tuple[pymunk.Poly, pymunk.Segment]] = []

    # ----------------------------------------------------------------------------------- parameters
    # ----------------------------------------------------------------------------------- reset/step
    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """Build ``batch_size`` instances with the nail at ``params["nail_position"]`` ((3,) or (B, 3),
        per instance; this scene has no randomness of its own)."""
        batch_size = check_reset(self, params, batch_size)
        self.nail_start = instance_positions(params, "nail_position", batch_size)[:, [0, 2]]
        self._spaces, self._nails = [], []
        for start in self.nail_start:
            space = pymunk.Space()
            space.gravity = (0.0, -9.81)
            space.collision_slop = 0.0002
            self._nails.append(self._add_nail(space, start))
            self._spaces.append(space)
        self._tool = KinematicTool(self._spaces, "xz", reference_axis=2)
        self._tool_shapes = []
        for body in self._tool.bodies:
            head = pymunk.Poly(body, [(-0.01, -0.01), (0.01, -0.01), (0.0, 0.01)])
            handle = pymunk.Segment(body, (0, 0), (0, 0), self.handle_radius)
            for shape in (head, handle):
                shape.friction = 0.5
            self._tool_shapes.append((head, handle))
        self.start_instances(batch_size)  # the clock starts with the first step

    def _add_nail(self, space: pymunk.Space, start: np.ndarray) -> pymunk.Body:
        """The nail body with its guide and friction joints, its head top at ``start`` (x, z) (the
        body's origin), plane m."""
        body = pymunk.Body(self.nail_mass, float("inf"))
        body.position = plane_point(start)
        w, t = self.nail_head_width / 2.0, self.nail_head_thickness
        shank_bottom = -(t + self.protrusion + SHANK_EMBEDDED)
        s = self.nail_shank_width / 2.0
        head = pymunk.Poly(body, [(-w, -t), (w, -t), (w, 0.0), (-w, 0.0)])
        shank = pymunk.Poly(body, [(-s, shank_bottom), (s, shank_bottom), (s, -t), (-s, -t)])
        for shape in (head, shank):
            shape.friction = 0.5
            shape.elasticity = 0.0
        x, y = start
        guide = pymunk.GrooveJoint(space.static_body, body, (x, y), (x, y - self.protrusion), (0.0, 0.0))
        friction = pymunk.PivotJoint(space.static_body, body, (x, y), (0.0, 0.0))
        friction.max_bias = 0.0
        friction.max_force = self.friction_force
        space.add(body, head, shank, guide, friction)
        return body

    def step(self, tool_pose: ToolPose) -> None:
        """Move the hammer to ``tool_pose`` over ``control_dt`` (velocity-driven) and simulate."""
        require_reset(self)
        first = not self._tool.placed
        self._tool.begin_step(tool_pose, self.control_dt)
        head_local = self._tool.local_points(self._head_corners)
        handle_local = self._tool.local_points(self._handle_points)
        identity = pymunk.Transform.identity()
        for b, (head, handle) in enumerate(self._tool_shapes):
            head.unsafe_set_vertices([plane_point(p) for p in head_local[b]], identity)
            handle.unsafe_set_endpoints(plane_point(handle_local[b, 0]), plane_point(handle_local[b, 1]))
            if first:  # the hammer enters the world only now, at its first pose
                self._spaces[b].add(head, handle)
        dt = self.control_dt / self.substeps
        for space in self._spaces:
            for _ in range(self.substeps):
                space.step(dt)
        self._tool.end_step()
        self.goal_timer.advance(self.control_dt)
        self.goal_timer.record(self.goal_reward() > 0)

    # ----------------------------------------------------------------------------------- rewards
    def travel(self) -> np.ndarray:
        """(B,) how far each nail has been driven down from its start, m, in [0, protrusion]."""
        require_reset(self)
        y = np.array([nail.position.y for nail in self._nails])
        return np.clip(self.nail_start[:, 1] - y, 0.0, self.protrusion)

    def goal_reward(self) -> np.ndarray:
        """(B,) 1 where less than ``planted_tolerance`` of the travel is left, else 0."""
        require_reset(self)
        return (self.protrusion - self.travel() < self.planted_tolerance).astype(float)

    def dense_reward(self) -> np.ndarray:
        """(B,) the paper appendix's closeness of the hammer's striking face to the nail head's
        centre (module docstring), in [0, 1]; 0 before the first step."""
        require_reset(self)
        centre = self.nail_start[:, 1] - self.travel() - self.nail_head_thickness / 2.0
        nail_head = np.stack([self.nail_start[:, 0], centre], -1)
        return dense_hammer_reward(self._tool.plane_point(dense_tool_point("hammer")), nail_head)

    # ----------------------------------------------------------------------------------- views
    def footprints(self, params: SceneParams) -> np.ndarray:
        """(1, 5) the board under the nail (x, y, half-length, half-width, yaw), m/rad; the planar
        world spans the y axis, so the half-width is large (10 m)."""
        nail_x = float(np.asarray(params["nail_position"], dtype=float)[0])
        return np.array([[nail_x, 0.0, BOARD_HALF_LENGTH, 10.0, 0.0]])

    def snapshot(self) -> dict[str, np.ndarray]:
        """Instance 0: ``nail_top`` (3,) world head-top point, ``travel`` (), ``board`` (2, 3) the
        board block's min and max corners (y = 0), ``hammer_head`` (8, 3) world corners (if placed)."""
        require_reset(self)
        travel = self.travel()[0]
        x, z = self.nail_start[0]
        board_top = z - self.protrusion
        snapshot = {
            "nail_top": np.array([x, 0.0, z - travel]),
            "travel": np.array(travel),
            "board": np.array([[x - BOARD_HALF_LENGTH, 0.0, 0.0], [x + BOARD_HALF_LENGTH, 0.0, board_top]]),
        }
        if self._tool.placed:
            snapshot["hammer_head"] = self._tool.world_points(self._head_corners)[0]
        return snapshot
