"""The 3D hammer world: drive a nail into a board with a kinematic hammer.

World frame: metres, z up, ground at z = 0. The nail is a square head plate on a shank; it slides
on a 1-DoF vertical guide. Its **head top** starts at the parameter ``nail_position`` (x, y, z),
with the head plate's underside ``protrusion`` (default 50 mm) above the board's top surface; the
board is a block standing on the ground under the nail. The nail is *planted* when less than
``planted_tolerance`` (1 mm) is left between the plate's underside and the board.

Impact model (the hammer is kinematic, i.e. infinitely heavy). Each control step (1/24 s) is split
into ``substeps``; over each the hammer head box moves at constant velocity. Points sampled on the
head box's surface are tested against the plate's top plane **along their swept segments**, so a
4 m/s strike (17 mm per sub-step) cannot pass through the 10 mm plate. A point that was at or above
the plate top at the start of the sub-step and is below it at the end, crossing it inside the
plate's square, pushes the nail down to that point and gives it the point's downward speed times
``1 + restitution`` (an infinitely heavy striker; ``restitution = 0`` by default: the nail moves
with the face). Between pushes the nail decelerates under a constant Coulomb-like resistance of
the wood, ``entry_deceleration`` a (m/s^2), so a strike that stops at contact with speed v drives
the nail ``v^2 / (2 a)`` further (a = 100 m/s^2: 2 m/s -> 20 mm, 3 m/s -> 45 mm, a 0.3 m/s tap
-> 0.45 mm). The nail stops on the board (travel range 0 .. protrusion <= guide_travel). The hammer
is not stopped by the nail or the board (a kinematic tool), and the shank is not a collision body.

Dense reward (the paper's appendix, :func:`~toolimit.scenes.base.gaussian_closeness`, b = 10):
exp(-5 |p - n|^2), with p the hammer's striking face (the head's end along the tool's x) and n the
nail head's centre where the nail is now (the authors' tip and nail body origin), world frame, m;
in [0, 1]. Before the first step there is no
hammer (no pose) and the reward is 0.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import (
    CONTROL_FPS,
    SceneParams,
    WindowedGoalScene,
    check_reset,
    dense_hammer_reward,
    dense_tool_point,
    instance_positions,
    require_positive,
    require_reset,
    world_position,
)
from toolimit.scenes.spatial.tool_geometry import tool_boxes
from toolimit.scenes.spatial.tool_motion import SweptTool, tool_snapshot
from toolimit.tools import ToolPose

#: Height of the nail head plate's underside above the board at reset, m: the nail's travel (default).
PROTRUSION = 0.05


def box_surface_points(half_extents: np.ndarray, per_edge: int = 5) -> np.ndarray:
    """(P, 3) points on the surface of a box centred at 0 with ``half_extents`` (3,), metres.

    A ``per_edge`` x ``per_edge`` grid on each face (edges and corners included), duplicates
    removed: enough for the lowest point of a tilted face to be found within a few millimetres.
    """
    grid = np.linspace(-1.0, 1.0, per_edge)
    points = []
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        u, v = np.meshgrid(grid, grid, indexing="ij")
        for sign in (-1.0, 1.0):
            face = np.zeros((u.size, 3))
            face[:, axis] = sign
            face[:, others[0]] = u.ravel()
            face[:, others[1]] = v.ravel()
            points.append(face)
    unit = np.unique(np.round(np.concatenate(points), 12), axis=0)
    return unit * np.asarray(half_extents, dtype=float)


class SpatialHammerScene(WindowedGoalScene):
    """Batched 3D nail-hammering scene (see the module docstring for the physics).

    Args:
        protrusion: initial height of the head plate's underside above the board, m (the travel).
        guide_travel: length of the nail's vertical guide, m; ``protrusion`` must not exceed it.
        plate_half_size: half side of the square head plate, m.
        plate_thickness: head plate thickness, m.
        shank_radius, shank_length: the shank (for views only), m.
        board_half_size: half side of the square board under the nail, m.
        entry_deceleration: deceleration of the moving nail by the wood, m/s^2.
        restitution: e; the struck nail leaves at (1 + e) times the face's downward speed.
        planted_tolerance: the nail is planted when less than this is left, m.
        success_window, substeps, control_dt: see :class:`~toolimit.scenes.base.WindowedGoalScene`;
            the nail must be planted within ``success_window`` s of the tool's placement (the first
            ``step``, time 0).
    """

    tool = "hammer"
    world = "3d"

    def __init__(
        self,
        protrusion: float = PROTRUSION,
        guide_travel: float = 0.10,
        plate_half_size: float = 0.03,
        plate_thickness: float = 0.01,
        shank_radius: float = 0.003,
        shank_length: float = 0.10,
        board_half_size: float = 0.15,
        entry_deceleration: float = 100.0,
        restitution: float = 0.0,
        planted_tolerance: float = 0.001,
        success_window: float = 1.0,
        substeps: int = 10,
        control_dt: float = 1.0 / CONTROL_FPS,
    ) -> None:
        super().__init__(control_dt, substeps, success_window)
        require_positive(
            protrusion=protrusion,
            guide_travel=guide_travel,
            plate_half_size=plate_half_size,
            plate_thickness=plate_thickness,
            shank_radius=shank_radius,
            shank_length=shank_length,
            board_half_size=board_half_size,
            entry_deceleration=entry_deceleration,
            planted_tolerance=planted_tolerance,
            success_window=success_window,
        )
        if protrusion > guide_travel:
            raise ValueError(f"protrusion ({protrusion} m) exceeds the guide travel ({guide_travel} m)")
        if not 0.0 <= restitution <= 1.0:
            raise ValueError(f"restitution must be in [0, 1], got {restitution!r}")
        self.protrusion = float(protrusion)
        self.guide_travel = float(guide_travel)
        self.plate_half_size = float(plate_half_size)
        self.plate_thickness = float(plate_thickness)
        self.shank_radius = float(shank_radius)
        self.shank_length = float(shank_length)
        self.board_half_size = float(board_half_size)
        self.entry_deceleration = float(entry_deceleration)
        self.restitution = float(restitution)
        self.planted_tolerance = float(planted_tolerance)
        head = tool_boxes("hammer")[0]
        #: (P, 3) points on the hammer head box's surface (tool_geometry's head box), tool frame, m.
        self.head_points = head.center + box_surface_points(head.half_extents) @ head.rotation.T
        self._dense_point = dense_tool_point("hammer")  # (3,) tool frame, m: the striking face
        lowest_head_top = self.plate_thickness + self.protrusion
        self.parameters = (
            world_position(
                "nail_position",
                f"initial top of the nail head (the board's top is {lowest_head_top * 1000:.0f} mm below it)",
                low_z=lowest_head_top,
                high_z=1.5,
                bound_reason="the board under the nail must stand on the ground",
            ),
        )
        # The state of the B instances, built by reset.
        self._nail_xy = np.zeros((0, 2))  # (B, 2) the nails' x, y, m
        self._start_top = np.zeros(0)  # (B,) z of the head tops at reset, m
        self.nail_top = np.zeros(0)  # (B,) z of the head top, m
        self.nail_speed = np.zeros(0)  # (B,) downward speed, m/s
        self._tool = SweptTool(0)

    # ----------------------------------------------------------------------------- parameters
    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """Build B nails at ``params["nail_position"]`` ((3,) or (B, 3), per instance); the hammer
        is absent until ``step``.

        The scene has no randomness; ``rng`` is accepted for the protocol.
        """
        batch_size = check_reset(self, params, batch_size)
        position = instance_positions(params, "nail_position", batch_size)
        self.start_instances(batch_size)  # the clock starts at the tool's placement
        self._nail_xy = position[:, :2].copy()
        self._start_top = position[:, 2].copy()
        self.nail_top = self._start_top.copy()
        self.nail_speed = np.zeros(batch_size)
        self._tool = SweptTool(batch_size)

    # ---------------------------------------------------------------------------- geometry
    @property
    def board_top(self) -> np.ndarray:
        """(B,) z of the boards' top surfaces, m."""
        return self._start_top - self.plate_thickness - self.protrusion

    @property
    def lowest_top(self) -> np.ndarray:
        """(B,) z of the nail head tops when the plates rest on the boards, m."""
        return self._start_top - self.protrusion

    def remaining_depth(self) -> np.ndarray:
        """(B,) distance still to drive the nail, m (0 = head plate on the board)."""
        return self.nail_top - self.lowest_top

    # -------------------------------------------------------------------------------- physics
    def step(self, tool_pose: ToolPose) -> None:
        """Move the hammer to ``tool_pose`` over ``control_dt`` and simulate the nail."""
        require_reset(self)
        motion = self._tool.move(tool_pose, self.substeps)
        if motion is None:  # placed: the clock starts
            return
        positions, rotations = motion
        # (S+1, B, P, 3) head surface points in the world frame.
        points = positions[:, :, None, :] + np.einsum("sbij,pj->sbpi", rotations, self.head_points)
        if self._may_interact(points):
            dt = self.control_dt / self.substeps
            for k in range(self.substeps):
                self._substep(points[k], points[k + 1], dt)
        else:
            self.goal_timer.advance(self.control_dt)

    def _may_interact(self, points: np.ndarray) -> bool:
        """Whether any nail moves or may be struck by head points (S+1, B, P, 3) in this step.

        Conservative: a push needs a point below the nail top at the end of a sub-step, within the
        plate's square widened by the largest x-y move of a point in one sub-step. When false,
        sub-stepping would change nothing but the clock.
        """
        if np.any(self.nail_speed > 0.0):
            return True
        reach = self.plate_half_size + np.max(np.abs(np.diff(points[..., :2], axis=0)), initial=0.0)
        low = points[..., 2] < self.nail_top[None, :, None]
        near = np.all(np.abs(points[..., :2] - self._nail_xy[:, None]) <= reach, axis=-1)
        return bool(np.any(low & near))

    def _substep(self, start: np.ndarray, end: np.ndarray, dt: float) -> None:
        """Advance the nails by ``dt`` while head points move from ``start`` to ``end`` (B, P, 3)."""
        top_before = self.nail_top.copy()
        # Free motion: constant deceleration until the nail stops.
        speed = self.nail_speed
        glide_time = np.minimum(dt, speed / self.entry_deceleration)
        glide = speed * glide_time - 0.5 * self.entry_deceleration * glide_time**2
        top = self.nail_top - glide
        speed = np.maximum(speed - self.entry_deceleration * dt, 0.0)
        # Swept test of every head point against the plate's top plane.
        z0, z1 = start[..., 2], end[..., 2]
        descending = z0 > z1
        crossing = descending & (z0 >= top_before[:, None] - 1e-9) & (z1 < top[:, None])
        fraction = np.clip((z0 - top[:, None]) / np.where(descending, z0 - z1, 1.0), 0.0, 1.0)
        xy = start[..., :2] + fraction[..., None] * (end[..., :2] - start[..., :2])
        inside = np.all(np.abs(xy - self._nail_xy[:, None]) <= self.plate_half_size, axis=-1)
        contact = crossing & inside  # (B, P)
        hit = np.any(contact, axis=1)
        pushed_top = np.min(np.where(contact, z1, np.inf), axis=1)
        face_speed = np.max(np.where(contact, (z0 - z1) / dt, 0.0), axis=1)
        top = np.where(hit, np.minimum(top, pushed_top), top)
        speed = np.where(hit, np.maximum(speed, (1.0 + self.restitution) * face_speed), speed)
        # The board stops the nail.
        on_board = top <= self.lowest_top
        self.nail_top = np.maximum(top, self.lowest_top)
        self.nail_speed = np.where(on_board, 0.0, speed)
        self.goal_timer.advance(dt)
        self.goal_timer.record(self.remaining_depth() < self.planted_tolerance)

    # -------------------------------------------------------------------------------- rewards
    def goal_reward(self) -> np.ndarray:
        """(B,) 1.0 where less than ``planted_tolerance`` of the nail is left, else 0.0."""
        return (self.remaining_depth() < self.planted_tolerance).astype(float)

    def dense_reward(self) -> np.ndarray:
        """(B,) the paper appendix's closeness of the hammer's striking face to the nail head's
        centre (module docstring), in [0, 1]; 0 before the tool is placed."""
        centre = self.nail_top - self.plate_thickness / 2.0
        nail_head = np.column_stack([self._nail_xy, centre])
        if self._tool.position is None or self._tool.rotation is None:
            return dense_hammer_reward(None, nail_head)
        return dense_hammer_reward(self._tool.position + self._tool.rotation @ self._dense_point, nail_head)

    # ---------------------------------------------------------------------------------- views
    def footprints(self, params: SceneParams) -> np.ndarray:
        """(1, 5) the board: centre x, y, half-length, half-width (m), yaw (rad)."""
        x, y = np.asarray(params["nail_position"], dtype=float)[:2]
        return np.array([[x, y, self.board_half_size, self.board_half_size, 0.0]])

    def snapshot(self) -> dict[str, np.ndarray]:
        """Instance 0 for views: world-frame boxes (centre, half extents), nail state, tool pose.

        Keys: ``nail_top`` (3,) head top; ``plate_center``/``plate_half_extents``,
        ``shank_center``/``shank_half_extents``, ``board_center``/``board_half_extents`` (3,) m;
        ``remaining_depth`` () m; ``tool_position`` (3,), ``tool_rotation`` (3, 3) (NaN before the
        first step); ``time`` () s.
        """
        x, y = self._nail_xy[0]
        top = self.nail_top[0]
        plate_half = np.array([self.plate_half_size, self.plate_half_size, self.plate_thickness / 2])
        shank_half = np.array([self.shank_radius, self.shank_radius, self.shank_length / 2])
        board_half = np.array([self.board_half_size, self.board_half_size, self.board_top[0] / 2])
        return {
            "nail_top": np.array([x, y, top]),
            "plate_center": np.array([x, y, top - self.plate_thickness / 2]),
            "plate_half_extents": plate_half,
            "shank_center": np.array([x, y, top - self.plate_thickness - self.shank_length / 2]),
            "shank_half_extents": shank_half,
            "board_center": np.array([x, y, self.board_top[0] / 2]),
            "board_half_extents": board_half,
            "remaining_depth": np.array(self.remaining_depth()[0]),
            **tool_snapshot(self._tool.position, self._tool.rotation),
            "time": np.array(self.goal_timer.time),
        }
