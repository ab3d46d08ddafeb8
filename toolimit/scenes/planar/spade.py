"""Planar spade scene (pymunk, vertical x-z plane): scoop sand from a deposit into a goal box.

World (pymunk x = world x, pymunk y = world z; world y is ignored):

* static ground, top surface at z = 0;
* the sand deposit: an open-top tray (two walls, inner width ``2 * deposit_half_width``, walls
  ``deposit_wall_height`` tall) centred at parameter ``sand_position`` x, holding ``sand_count``
  sand circles (radius ``sand.radius``, Coulomb friction) settled into a pile (once per geometry,
  see sand_pile); each instance shifts every circle by its own seeded jitter (standard deviation
  ``sand_jitter``, upward only in z). With ``sleeping`` the pile starts asleep: it costs nothing
  until the tool touches it, and woken circles resolve their millimetre overlaps then;
* the goal box: two walls ``goal_wall_height`` tall, inner width ``2 * goal_half_width``, centred
  at parameter ``goal_position`` x (both positions may be (B, 3), one per instance: each instance
  has its own pymunk space, so this costs nothing). It is a dynamic body (``goal_box_mass``, sliding on the ground
  with friction, no rotation), so the tool cannot carry or push sand through its walls: a spade that
  runs into it shoves the box. The deposit's walls are static (sand pushed out of the deposit earns
  nothing, and the deposit stays where alignment put it).

The spade (tool frame of toolimit.tools: origin at the blade tip, z along the blade towards the
handle, x the blade's face normal on the side that carries sand) is the projection into the plane
of three segments, ``blade_radius`` thick so that nothing tunnels: the blade from the tip along z
(``ToolSpec.head_length``), a heel lip of ``lip_height`` along x at the blade's end (a dustpan: sand
slides back against it while carried) and the handle up to ``ToolSpec.length``. A blade whose x
axis points out of the plane loses its lip and carries only what friction holds on a flat stick.
The spade is kinematic: it moves through the static deposit walls and ground (pymunk does not
collide kinematic with static bodies) and pushes sand and the goal box with whatever force it
takes.

Rewards: goal reward = number of circles inside the goal box (between its walls where the box is
now, below their top).
Dense reward (the paper's appendix, :func:`~toolimit.scenes.base.gaussian_closeness`, b = 10, on
x-z plane distances, m): the mean over circles of exp(-5 |c - g|^2) + 0.05 exp(-5 |p - d|^2), with
c a circle centre, g the goal box's floor centre (where the box is now), p the spade's handle end
and d the deposit's floor centre (the authors' points); in [0, 1.05]. Before the first step there is no spade and the tool term is 0.
Success (docs/method.md#success-criteria): at least ``success_count`` (10) circles in the box for at least half of the
control steps since the reset.
"""

from __future__ import annotations

import numpy as np
import pymunk
import pymunk.batch

from toolimit.scenes.base import (
    CONTROL_FPS,
    SceneBase,
    SceneParams,
    SuccessTracker,
    check_reset,
    dense_spade_reward,
    dense_tool_point,
    instance_positions,
    parameter_violation,
    require_counts,
    require_reset,
    world_position,
)
from toolimit.scenes.planar.kinematic_tool import KinematicTool, plane_point
from toolimit.scenes.planar.sand_pile import (
    SandMaterial,
    add_circles,
    add_ground,
    add_walls,
    configure_space,
    settled_pile,
)
from toolimit.tools import ToolPose, tool_spec

#: Thickness of tray and box walls, m.
WALL_THICKNESS = 0.02
#: Minimum free gap between the deposit's and the goal box's outer walls, m.
ELEMENT_CLEARANCE = 0.02


def spade_outline(head_length: float, length: float, lip_height: float) -> np.ndarray:
    """(4, 3) tool-frame points (m) of the spade's segments: tip, heel, lip top, handle end.

    Segments: blade = tip-heel, lip = heel-lip top (along tool x), handle = heel-handle end.
    """
    return np.array([[0.0, 0.0, 0.0], [0.0, 0.0, head_length], [lip_height, 0.0, head_length], [0.0, 0.0, length]])


class PlanarSpadeScene(SceneBase):
    """B instances of the planar spade world; see the module docstring for geometry and rewards.

    Args:
        control_dt: see :class:`~toolimit.scenes.base.SceneBase`.
        substeps: physics sub-steps per control step (10 at 24 Hz = 240 Hz).
        sand_count: number of sand circles.
        sand: radius (m), mass (kg), friction, elasticity of the circles.
        sand_jitter: standard deviation (m) of each instance's per-circle shift of the settled pile.
        deposit_half_width, deposit_wall_height: tray inner half-width and wall height, m.
        goal_half_width, goal_wall_height: goal box inner half-width and wall height, m.
        goal_box_mass: mass of the goal box, kg.
        blade_radius: half-thickness of the spade's segments, m.
        lip_height: heel lip length along the tool's x axis, m.
        success_count: circles in the box that count as a successful step.
        solver_iterations: pymunk solver iterations.
        sleeping: let circles at rest sleep (pymunk's sleeping): the pile starts asleep and costs no
            time until the tool touches it; False keeps every circle simulated (for checks).
    """

    tool = "spade"
    world = "planar"

    def __init__(
        self,
        control_dt: float = 1.0 / CONTROL_FPS,
        substeps: int = 10,
        sand_count: int = 40,
        sand: SandMaterial = SandMaterial(),
        sand_jitter: float = 0.001,
        deposit_half_width: float = 0.18,
        deposit_wall_height: float = 0.04,
        goal_half_width: float = 0.175,
        goal_wall_height: float = 0.10,
        goal_box_mass: float = 2.0,
        blade_radius: float = 0.008,
        lip_height: float = 0.05,
        success_count: int = 10,
        solver_iterations: int = 10,
        sleeping: bool = True,
    ):
        super().__init__(control_dt, substeps)
        require_counts(sand_count=sand_count)
        self.sand_count = int(sand_count)
        self.sand = sand
        self.sand_jitter = float(sand_jitter)
        self.deposit_half_width = float(deposit_half_width)
        self.deposit_wall_height = float(deposit_wall_height)
        self.goal_half_width = float(goal_half_width)
        self.goal_wall_height = float(goal_wall_height)
        self.goal_box_mass = float(goal_box_mass)
        self.blade_radius = float(blade_radius)
        self.success_count = int(success_count)
        self.solver_iterations = int(solver_iterations)
        self.sleeping = bool(sleeping)
        spec = tool_spec("spade")
        self._outline = spade_outline(spec.head_length, spec.length, lip_height)
        self.parameters = (
            world_position("sand_position", "centre of the sand deposit tray on the ground (x used)", axes=(0,)),
            world_position("goal_position", "centre of the open goal box on the ground (x used)", axes=(0,)),
        )
        # The state of the B instances, built by reset.
        self.sand_x = np.zeros(0)  # (B,) deposit centres, m
        self.goal_x = np.zeros(0)  # (B,) goal box centres at reset, m
        self._spaces: list[pymunk.Space] = []
        self._sand_bodies: list[list[pymunk.Body]] = []
        self._boxes: list[pymunk.Body] = []
        self._tool = KinematicTool(self._spaces, "xz", reference_axis=2)
        self._segments: list[list[pymunk.Segment]] = []
        self._segment_points = np.zeros((0, 4, 2))
        self._buffer = pymunk.batch.Buffer()
        self._body_ids: list[np.ndarray] = []
        self._sand = np.zeros((0, self.sand_count, 2))  # (B, N, 2) circle centres, plane x-z, m
        self._box_x = np.zeros(0)  # (B,) goal box centres, m
        self.success_tracker = SuccessTracker(0)

    # ----------------------------------------------------------------------------------- parameters
    def invalid_reason(self, params: SceneParams) -> str | None:
        """Why ``params`` cannot make a scene: against the specs (|x| > 5 m), deposit and box overlap."""
        violation = parameter_violation(self.parameters, params)
        if violation is not None:
            return violation
        xs = {name: float(np.asarray(params[name], dtype=float)[0]) for name in ("sand_position", "goal_position")}
        gap = abs(xs["sand_position"] - xs["goal_position"]) - (
            self.deposit_half_width + self.goal_half_width + 2 * WALL_THICKNESS
        )
        if gap < ELEMENT_CLEARANCE:
            return (
                f"sand deposit (x = {xs['sand_position']:.3f} m) and goal box (x = {xs['goal_position']:.3f} m) "
                f"overlap: the gap between their walls is {gap:.3f} m < {ELEMENT_CLEARANCE} m"
            )
        return None

    # ----------------------------------------------------------------------------------- reset/step
    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """Build ``batch_size`` instances; each jitters the settled pile with ``rng``."""
        batch_size = check_reset(self, params, batch_size)
        self.sand_x = instance_positions(params, "sand_position", batch_size)[:, 0]
        self.goal_x = instance_positions(params, "goal_position", batch_size)[:, 0]
        dt = self.control_dt / self.substeps
        pile = settled_pile(
            self.sand_count,
            self.deposit_half_width,
            self.deposit_wall_height,
            WALL_THICKNESS,
            self.sand,
            dt,
            self.solver_iterations,
        )
        self._spaces, self._sand_bodies, self._boxes = [], [], []
        for sand_x, goal_x in zip(self.sand_x, self.goal_x):
            space = pymunk.Space()
            configure_space(space, self.solver_iterations, self.sleeping)
            add_ground(space, self.sand.friction)
            add_walls(
                space,
                sand_x,
                self.deposit_half_width,
                self.deposit_wall_height,
                WALL_THICKNESS,
                self.sand.friction,
            )
            box = add_walls(
                space,
                goal_x,
                self.goal_half_width,
                self.goal_wall_height,
                WALL_THICKNESS,
                self.sand.friction,
                mass=self.goal_box_mass,
            )
            jitter = rng.normal(0.0, self.sand_jitter, pile.shape)
            jitter[:, 1] = np.abs(jitter[:, 1])  # lift rather than push circles into the ground
            positions = pile + jitter + np.array([sand_x, 0.0])
            bodies = add_circles(space, positions, self.sand)
            if self.sleeping:
                for body in [box, *bodies]:  # at rest until touched: the tool (or a woken body) wakes it
                    body.sleep()
            self._sand_bodies.append(bodies)
            self._boxes.append(box)
            self._spaces.append(space)
        self.batch_size = batch_size
        self._tool = KinematicTool(self._spaces, "xz", reference_axis=2)
        self._segments = []
        self._segment_points = np.zeros((batch_size, 4, 2))
        for body in self._tool.bodies:
            segments = [pymunk.Segment(body, (0, 0), (0, 0), self.blade_radius) for _ in range(3)]
            for segment in segments:
                segment.friction = self.sand.friction
            self._segments.append(segments)
        self._buffer = pymunk.batch.Buffer()
        self._body_ids = [
            np.array([body.id for body in [*bodies, box]], dtype=np.uintp)
            for bodies, box in zip(self._sand_bodies, self._boxes)
        ]
        self._sand, self._box_x = self._read_bodies()
        self.success_tracker = SuccessTracker(batch_size)

    def step(self, tool_pose: ToolPose) -> None:
        """Move the spade to ``tool_pose`` over ``control_dt`` (velocity-driven) and simulate."""
        require_reset(self)
        first = not self._tool.placed
        self._tool.begin_step(tool_pose, self.control_dt)
        self._update_outline(self._tool.local_points(self._outline))
        if first:  # the tool enters the world only now, at its first pose
            for space, segments in zip(self._spaces, self._segments):
                space.add(*segments)
        dt = self.control_dt / self.substeps
        for space in self._spaces:
            for _ in range(self.substeps):
                space.step(dt)
        self._tool.end_step()
        self._sand, self._box_x = self._read_bodies()
        self.success_tracker.record(self.goal_reward() >= self.success_count)

    def _update_outline(self, local: np.ndarray) -> None:
        """Reshape the segments to the projected outline (B, 4, 2) where it changed by > 0.1 mm."""
        changed = np.abs(local - self._segment_points).max(axis=(1, 2)) > 1e-4
        for b in np.flatnonzero(changed):
            tip, heel, lip, handle = (plane_point(p) for p in local[b])
            blade, lip_segment, handle_segment = self._segments[b]
            blade.unsafe_set_endpoints(tip, heel)
            lip_segment.unsafe_set_endpoints(heel, lip)
            handle_segment.unsafe_set_endpoints(heel, handle)
        self._segment_points[changed] = local[changed]

    def _read_bodies(self) -> tuple[np.ndarray, np.ndarray]:
        """(B, N, 2) plane positions (world x, z) of the sand circles and (B,) goal box centre x, m.

        Reads all bodies of a space in one call (pymunk.batch); sleeping bodies change the order,
        so rows are matched to bodies by id.
        """
        state = np.empty((self.batch_size, self.sand_count + 1, 2))
        fields = pymunk.batch.BodyFields.BODY_ID | pymunk.batch.BodyFields.POSITION
        for b, space in enumerate(self._spaces):
            self._buffer.clear()
            pymunk.batch.get_space_bodies(space, fields, self._buffer)
            ids = np.frombuffer(self._buffer.int_buf(), dtype=np.uintp)
            positions = np.frombuffer(self._buffer.float_buf(), dtype=float).reshape(-1, 2)
            order = np.argsort(ids)
            rows = order[np.minimum(np.searchsorted(ids, self._body_ids[b], sorter=order), len(ids) - 1)]
            if not np.array_equal(ids[rows], self._body_ids[b]):
                raise RuntimeError("pymunk.batch did not report every sand circle and the goal box")
            state[b] = positions[rows]
        return state[:, :-1], state[:, -1, 0]

    # ----------------------------------------------------------------------------------- rewards
    def _in_goal_box(self) -> np.ndarray:
        """(B, N) bool: circle centres between the goal box walls and below their top."""
        x, z = self._sand[..., 0], self._sand[..., 1]
        return (np.abs(x - self._box_x[:, None]) < self.goal_half_width) & (z < self.goal_wall_height)

    def goal_reward(self) -> np.ndarray:
        """(B,) number of sand circles in the goal box."""
        require_reset(self)
        return self._in_goal_box().sum(axis=1).astype(float)

    def dense_reward(self) -> np.ndarray:
        """(B,) the paper appendix's shaping: sand close to the box, spade close to the deposit
        (module docstring), in [0, 1.05]."""
        require_reset(self)
        goal = np.stack([self._box_x, np.zeros(self.batch_size)], -1)  # (B, 2) plane x-z, m
        tool = self._tool.plane_point(dense_tool_point("spade"))
        deposit = np.stack([self.sand_x, np.zeros(self.batch_size)], -1)  # (B, 2) plane x-z, m
        return dense_spade_reward(self._sand, goal[:, None, :], tool, deposit)

    def is_success(self) -> np.ndarray:
        """(B,) >= success_count circles in the box for at least half of the steps since reset."""
        require_reset(self)
        return self.success_tracker.is_success()

    # ----------------------------------------------------------------------------------- views
    def footprints(self, params: SceneParams) -> np.ndarray:
        """(2, 5) deposit and goal box rectangles (x, y, half-length, half-width, yaw), m/rad, where
        they stand at reset. The planar world spans the y axis, so the half-width is large (10 m)."""
        sand_x, goal_x = (
            float(np.asarray(params[name], dtype=float)[0]) for name in ("sand_position", "goal_position")
        )
        return np.array(
            [
                [sand_x, 0.0, self.deposit_half_width + WALL_THICKNESS, 10.0, 0.0],
                [goal_x, 0.0, self.goal_half_width + WALL_THICKNESS, 10.0, 0.0],
            ]
        )

    def snapshot(self) -> dict[str, np.ndarray]:
        """Instance 0: ``sand`` (N, 3) world centres (y = 0), ``sand_radius`` (), ``walls`` (4, 2, 3)
        wall bottom/top points, ``tool_segments`` (3, 2, 3) blade/lip/handle end points (if placed)."""
        require_reset(self)
        sand = np.zeros((self.sand_count, 3))
        sand[:, [0, 2]] = self._sand[0]
        walls = []
        for centre, half, height in (
            (self.sand_x[0], self.deposit_half_width, self.deposit_wall_height),
            (self._box_x[0], self.goal_half_width, self.goal_wall_height),
        ):
            for side in (-1, 1):
                x = centre + side * (half + WALL_THICKNESS / 2)
                walls.append([[x, 0.0, 0.0], [x, 0.0, height]])
        snapshot = {"sand": sand, "sand_radius": np.array(self.sand.radius), "walls": np.array(walls)}
        if self._tool.placed:
            tip, heel, lip, handle = self._tool.world_points(self._outline)[0]
            snapshot["tool_segments"] = np.array([[tip, heel], [heel, lip], [heel, handle]])
        return snapshot
