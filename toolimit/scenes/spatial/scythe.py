"""The 3D scythe world: mow a patch of grass stalks with a kinematic scythe.

World frame: metres, z up, ground at z = 0. The patch is a rectangle ``patch_size`` (length along
the patch's own x, width along its y) centred at the parameter ``grass_position`` and turned by
``grass_yaw`` about z. Each instance scatters ``n_stalks`` thin vertical stalks (square section
``stalk_width``, height ``stalk_height``) uniformly in it with its own random generator.

The cutting edge is the segment along the tool x axis spanned by the blade box of
:mod:`~toolimit.scenes.spatial.tool_geometry` (from the head point, 0.45 m), on the tool axis line
y = z = 0. Its cutting direction is the tool's +y axis: perpendicular to the edge and to the snath,
the direction in which a swung scythe's edge moves. A stalk is **cut** (the paper's
definition) when the edge crosses it below ``max_cut_height`` with the edge point's velocity along
the cutting direction above ``min_cut_speed``. Crossings are found exactly along the motion: each
control step (1/24 s) is split into ``substeps``; over each, the blade end points move linearly and
the signed area between the edge and a stalk (in the x-y plane) is a quadratic in time whose roots
in [0, 1] are the crossing instants. No sweep can pass a stalk unnoticed, whatever its speed.
An edge exactly parallel to the stalks (a vertical blade) has no x-y extent and cuts nothing.

Dense reward (the paper's appendix, :func:`~toolimit.scenes.base.gaussian_closeness`, b = 10):
0.1 times the mean over all stalks (the appendix's grass patches, cut or not) of
exp(-5 |p - s|^2), with p the tool frame origin (the blade root) and s a stalk's point at half the
cutting height (half of ``min(max_cut_height, stalk_height)``, the part the edge must cross),
world frame, m; in [0, 0.1]. Before the first step there is no scythe (no pose) and it is 0.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import (
    CONTROL_FPS,
    ParameterSpec,
    SceneParams,
    WindowedGoalScene,
    check_reset,
    dense_scythe_reward,
    require_counts,
    require_positive,
    require_reset,
    world_position,
)
from toolimit.scenes.spatial.tool_geometry import tool_boxes
from toolimit.scenes.spatial.tool_motion import SweptTool, tool_snapshot
from toolimit.tools import ToolPose, rotation_z


def _cross2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z component of the cross product of x-y vectors (..., 2)."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def edge_crossings(
    root_start: np.ndarray,
    tip_start: np.ndarray,
    root_end: np.ndarray,
    tip_end: np.ndarray,
    stalks_xy: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Instants at which a linearly moving edge crosses vertical lines, in the x-y plane.

    Args:
        root_start, tip_start, root_end, tip_end: (B, 3) edge end points at the start and the end
            of the interval, world frame, m.
        stalks_xy: (B, N, 2) positions of the vertical lines, m.

    Returns:
        fraction (B, N, 2): crossing instants as fractions of the interval (NaN: no crossing).
        along (B, N, 2): position of the crossing on the edge, 0 at the root, 1 at the tip.
        height (B, N, 2): z of the edge point at the crossing, m.
    """
    direction0 = (tip_start - root_start)[:, None, :]
    direction_change = ((tip_end - root_end) - (tip_start - root_start))[:, None, :]
    root_motion = (root_end - root_start)[:, None, :]
    offset = stalks_xy - root_start[:, None, :2]
    # cross(D0 + f dD, E0 - f dA) = a0 + a1 f + a2 f^2
    a2 = -_cross2(direction_change[..., :2], root_motion[..., :2])
    a1 = _cross2(direction_change[..., :2], offset) - _cross2(direction0[..., :2], root_motion[..., :2])
    a0 = _cross2(direction0[..., :2], offset)
    a2 = np.broadcast_to(a2, a1.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        # Numerically stable roots (also right when a2 = 0, a pure translation): q / a2, a0 / q.
        disc = a1**2 - 4.0 * a2 * a0
        q = -0.5 * (a1 + np.where(a1 >= 0.0, 1.0, -1.0) * np.sqrt(np.where(disc >= 0.0, disc, np.nan)))
        fraction = np.stack([q / a2, a0 / q], axis=-1)
    fraction = np.where((fraction >= 0.0) & (fraction <= 1.0), fraction, np.nan)
    f = fraction[..., None]  # (B, N, 2, 1)
    root = root_start[:, None, None, :] + f * root_motion[:, :, None, :]
    direction = direction0[:, :, None, :] + f * direction_change[:, :, None, :]
    length2 = np.sum(direction[..., :2] ** 2, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        along = np.sum((stalks_xy[:, :, None, :] - root[..., :2]) * direction[..., :2], axis=-1) / length2
    height = root[..., 2] + along * direction[..., 2]
    return fraction, along, height


class SpatialScytheScene(WindowedGoalScene):
    """Batched 3D grass-mowing scene (see the module docstring for the cutting model).

    Args:
        n_stalks: stalks per patch.
        patch_size: (length, width) of the patch, m.
        stalk_width: side of a stalk's square section, m.
        stalk_height: stalk height, m.
        max_cut_height: z_max, a stalk is cut only below this height, m.
        min_cut_speed: v_min, minimum edge speed along the cutting direction, m/s.
        success_window, substeps, control_dt: see :class:`~toolimit.scenes.base.WindowedGoalScene`;
            every stalk must be cut within ``success_window`` s of the tool's placement (the first
            ``step``, time 0).
    """

    tool = "scythe"
    world = "3d"

    def __init__(
        self,
        n_stalks: int = 30,
        patch_size: tuple[float, float] = (0.4, 0.3),
        stalk_width: float = 0.005,
        stalk_height: float = 0.3,
        max_cut_height: float = 0.1,
        min_cut_speed: float = 1.0,
        success_window: float = 1.0,
        substeps: int = 10,
        control_dt: float = 1.0 / CONTROL_FPS,
    ) -> None:
        super().__init__(control_dt, substeps, success_window)
        require_positive(
            patch_length=patch_size[0],
            patch_width=patch_size[1],
            stalk_width=stalk_width,
            stalk_height=stalk_height,
            max_cut_height=max_cut_height,
            min_cut_speed=min_cut_speed,
            success_window=success_window,
        )
        require_counts(n_stalks=n_stalks)
        self.n_stalks = int(n_stalks)
        self.patch_size = (float(patch_size[0]), float(patch_size[1]))
        self.stalk_width = float(stalk_width)
        self.stalk_height = float(stalk_height)
        self.max_cut_height = float(max_cut_height)
        self.min_cut_speed = float(min_cut_speed)
        blade = tool_boxes("scythe")[0]
        extent = np.abs(blade.rotation[0]) @ blade.half_extents  # half extent along tool x, m
        #: (2, 3) edge root and tip in the tool frame, m.
        self.edge = np.array([[blade.center[0] - extent, 0.0, 0.0], [blade.center[0] + extent, 0.0, 0.0]])
        self.blade_length = 2.0 * extent
        self.parameters = (
            world_position(
                "grass_position",
                "centre of the grass patch on the ground",
                bound_reason="the patch lies on the ground, z = 0",
            ),
            ParameterSpec(
                "grass_yaw", "uniform", low=-np.pi, high=np.pi, unit="rad", description="patch orientation about z"
            ),
        )
        # The state of the B instances, built by reset.
        self.grass_position = np.zeros(3)  # patch centre, world, m
        self.grass_yaw = 0.0  # rad
        self.stalks_xy = np.zeros((0, self.n_stalks, 2))  # (B, N, 2) stalk positions on the ground, world x-y, m
        self.cut = np.zeros((0, self.n_stalks), dtype=bool)  # (B, N)
        self.cut_time = np.zeros((0, self.n_stalks))  # (B, N) s since the tool was placed
        self._tool = SweptTool(0)

    # ----------------------------------------------------------------------------- parameters
    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """Scatter B patches of stalks (each from ``rng``); the scythe is absent until ``step``."""
        b = check_reset(self, params, batch_size)
        self.start_instances(b)  # the clock starts at the tool's placement
        self.grass_position = np.asarray(params["grass_position"], dtype=float).copy()
        self.grass_yaw = float(np.asarray(params["grass_yaw"], dtype=float))
        half = np.array(self.patch_size) / 2
        local = rng.uniform(-half, half, size=(b, self.n_stalks, 2))
        turn = rotation_z(self.grass_yaw)[:2, :2]
        #: (B, N, 2) stalk positions on the ground, world x-y, m.
        self.stalks_xy = self.grass_position[:2] + local @ turn.T
        self.cut = np.zeros((b, self.n_stalks), dtype=bool)
        self.cut_time = np.full((b, self.n_stalks), np.inf)
        self._tool = SweptTool(b)

    # -------------------------------------------------------------------------------- physics
    def step(self, tool_pose: ToolPose) -> None:
        """Move the scythe to ``tool_pose`` over ``control_dt`` and cut the stalks it crosses."""
        require_reset(self)
        motion = self._tool.move(tool_pose, self.substeps)
        if motion is None:  # placed: the clock starts
            return
        s, b = self.substeps, self.batch_size
        positions, rotations = motion
        edges = positions[:, :, None, :] + np.einsum("sbij,ej->sbei", rotations, self.edge)  # (S+1, B, 2, 3)
        cutting_direction = rotations[..., :, 1]  # (S+1, B, 3) tool y in the world frame
        dt = self.control_dt / s
        # All sub-steps at once (a cut does not change the motion): flatten (S, B) to S * B.
        crossing = self._first_crossing(
            edges[:-1].reshape(s * b, 2, 3),
            edges[1:].reshape(s * b, 2, 3),
            cutting_direction[:-1].reshape(s * b, 3),
            cutting_direction[1:].reshape(s * b, 3),
            np.broadcast_to(self.stalks_xy, (s, b) + self.stalks_xy.shape[1:]).reshape(s * b, -1, 2),
            dt,
        ).reshape(s, b, -1)
        # Time of the first cutting crossing, s since placement: sub-step k, fraction f -> (k + f) dt.
        first = np.min(crossing + np.arange(s)[:, None, None], axis=0) * dt + self.goal_timer.time
        newly = np.isfinite(first) & ~self.cut
        self.cut_time = np.where(newly, first, self.cut_time)
        self.cut |= newly
        self.goal_timer.record(self.cut.all(axis=1), at=self.cut_time.max(axis=1))  # when the last stalk fell
        self.goal_timer.advance(self.control_dt)

    def _first_crossing(
        self,
        edge0: np.ndarray,
        edge1: np.ndarray,
        dir0: np.ndarray,
        dir1: np.ndarray,
        stalks_xy: np.ndarray,
        dt: float,
    ) -> np.ndarray:
        """(M, N) fraction of the interval at which the edge first cuts each stalk (inf: never).

        ``edge0``/``edge1`` (M, 2, 3): edge root and tip at the start and end of M intervals of
        ``dt`` seconds; ``dir0``/``dir1`` (M, 3) cutting directions; ``stalks_xy`` (M, N, 2).
        """
        fraction, along, height = edge_crossings(edge0[:, 0], edge0[:, 1], edge1[:, 0], edge1[:, 1], stalks_xy)
        margin = self.stalk_width / 2 / self.blade_length
        on_edge = (along >= -margin) & (along <= 1.0 + margin)
        low_enough = (height >= 0.0) & (height <= min(self.max_cut_height, self.stalk_height))
        f = np.nan_to_num(fraction)[..., None]  # (M, N, 2, 1)
        u = np.nan_to_num(along)[..., None]
        root_motion = (edge1[:, 0] - edge0[:, 0])[:, None, None, :]
        tip_motion = (edge1[:, 1] - edge0[:, 1])[:, None, None, :]
        direction = (1.0 - f) * dir0[:, None, None, :] + f * dir1[:, None, None, :]
        direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
        speed = np.sum(((1.0 - u) * root_motion + u * tip_motion) * direction, axis=-1) / dt  # (M, N, 2) m/s
        cutting = np.isfinite(fraction) & on_edge & low_enough & (speed > self.min_cut_speed)
        return np.min(np.where(cutting, fraction, np.inf), axis=-1)

    # -------------------------------------------------------------------------------- rewards
    def goal_reward(self) -> np.ndarray:
        """(B,) number of stalks cut."""
        return self.cut.sum(axis=1).astype(float)

    def dense_reward(self) -> np.ndarray:
        """(B,) the paper appendix's closeness of the blade root to the stalks at half the cutting
        height (module docstring), in [0, 0.1]; 0 before the tool is placed."""
        height = np.full(self.stalks_xy.shape[:2] + (1,), min(self.max_cut_height, self.stalk_height) / 2)
        targets = np.concatenate([self.stalks_xy, height], axis=-1)  # (B, N, 3)
        return dense_scythe_reward(self._tool.position, targets)

    # ---------------------------------------------------------------------------------- views
    def footprints(self, params: SceneParams) -> np.ndarray:
        """(1, 5) the patch: centre x, y, half-length, half-width (m), yaw (rad)."""
        x, y = np.asarray(params["grass_position"], dtype=float)[:2]
        yaw = float(np.asarray(params["grass_yaw"], dtype=float))
        return np.array([[x, y, self.patch_size[0] / 2, self.patch_size[1] / 2, yaw]])

    def snapshot(self) -> dict[str, np.ndarray]:
        """Instance 0 for views.

        Keys: ``stalk_base`` (N, 3) stalk bottoms (z = 0), ``stalk_half_extents`` (3,),
        ``stalk_cut`` (N,) bool, ``patch_center`` (3,), ``patch_half_extents`` (2,) m,
        ``patch_yaw`` () rad, ``blade`` (2, 3) edge root and tip in the world (NaN before the
        first step), ``tool_position`` (3,), ``tool_rotation`` (3, 3), ``time`` () s.
        """
        tool = tool_snapshot(self._tool.position, self._tool.rotation)
        base = np.column_stack([self.stalks_xy[0], np.zeros(self.n_stalks)])
        blade = tool["tool_position"] + self.edge @ tool["tool_rotation"].T  # NaN before the first step
        return {
            "stalk_base": base,
            "stalk_half_extents": np.array([self.stalk_width / 2, self.stalk_width / 2, self.stalk_height / 2]),
            "stalk_cut": self.cut[0].copy(),
            "patch_center": self.grass_position.copy(),
            "patch_half_extents": np.array(self.patch_size) / 2,
            "patch_yaw": np.array(self.grass_yaw),
            "blade": blade,
            **tool,
            "time": np.array(self.goal_timer.time),
        }
