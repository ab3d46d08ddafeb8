"""The 3D scythe world: mow a patch of grass stalks with a kinematic scythe, at the authors' size
(pyphysx_envs ``scenes/ScytheTaskScene.py``).

World frame: metres, z up, ground at z = 0. The patch is a rectangle ``patch_size`` (0.4 m along
world x, 0.1 m along y) centred at the parameter ``grass_position``; the authors' scene has no yaw
parameter (its yaw stays 0), nor has this one. Each instance scatters ``n_stalks`` (10) thin
vertical stalks (square section ``stalk_width`` 5 mm, height ``stalk_height`` 0.3 m) uniformly in
it with its own random generator.

A stalk is **cut** by the authors' rule (:mod:`toolimit.scenes.scythe_cut`): the blade's edge
within 2 cm of the stalk's bottom 0.1 m, at most 0.1 m above the ground, its normal (the snath's
direction towards the handle) within 30 degrees of the direction to the stalk, approaching it at
about 1 m/s or more; tested at the ``substeps`` instants of each control step (240 Hz), along the
tool's constant-velocity motion between control poses.

Dense reward (the paper's appendix, :func:`~toolimit.scenes.base.gaussian_closeness`, b = 10):
0.1 exp(-5 |p - g|^2), with p the tool frame origin (the head point: the authors' tip) and g the
patch's centre on the ground (the authors' mean over their one grass patch), world frame, m; in
[0, 0.1]. Before the first step there is no scythe (no pose) and it is 0.
"""

from __future__ import annotations

import numpy as np

from toolimit.scenes.base import (
    CONTROL_FPS,
    SceneParams,
    WindowedGoalScene,
    check_reset,
    dense_scythe_reward,
    instance_positions,
    require_counts,
    require_positive,
    require_reset,
    world_position,
)
from toolimit.scenes.scythe_cut import MAX_CUT_HEIGHT, PATCH_SIZE, ScytheCutRule, scythe_cut_rule
from toolimit.scenes.spatial.tool_motion import SweptTool, tool_snapshot
from toolimit.tools import ToolPose


class SpatialScytheScene(WindowedGoalScene):
    """Batched 3D grass-mowing scene (see the module docstring for the cutting model).

    Args:
        n_stalks: stalks per patch.
        patch_size: (length along world x, width along y) of the patch, m.
        stalk_width: side of a stalk's square section, m.
        stalk_height: stalk height, m.
        max_cut_height: a stalk is cut only by an edge point at most this high, m.
        success_window, substeps, control_dt: see :class:`~toolimit.scenes.base.WindowedGoalScene`;
            every stalk must be cut within ``success_window`` s of the tool's placement (the first
            ``step``, time 0).
    """

    tool = "scythe"
    world = "3d"

    def __init__(
        self,
        n_stalks: int = 10,
        patch_size: tuple[float, float] = PATCH_SIZE,
        stalk_width: float = 0.005,
        stalk_height: float = 0.3,
        max_cut_height: float = MAX_CUT_HEIGHT,
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
            success_window=success_window,
        )
        require_counts(n_stalks=n_stalks)
        self.n_stalks = int(n_stalks)
        self.patch_size = (float(patch_size[0]), float(patch_size[1]))
        self.stalk_width = float(stalk_width)
        self.stalk_height = float(stalk_height)
        self.max_cut_height = float(max_cut_height)
        #: The cut test (edge, normal and thresholds).
        self.rule: ScytheCutRule = scythe_cut_rule(self.stalk_width, min(self.max_cut_height, self.stalk_height))
        self.edge = self.rule.edge
        self.parameters = (
            world_position(
                "grass_position",
                "centre of the grass patch on the ground",
                bound_reason="the patch lies on the ground, z = 0",
            ),
        )
        # The state of the B instances, built by reset.
        self.grass_position = np.zeros((0, 3))  # (B, 3) patch centres, world, m
        self.stalks_xy = np.zeros((0, self.n_stalks, 2))  # (B, N, 2) stalk positions on the ground, world x-y, m
        self.cut = np.zeros((0, self.n_stalks), dtype=bool)  # (B, N)
        self.cut_time = np.zeros((0, self.n_stalks))  # (B, N) s since the tool was placed
        self._tool = SweptTool(0)

    # ----------------------------------------------------------------------------- parameters
    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """Scatter B patches of stalks (each from ``rng``) at ``params["grass_position"]`` ((3,) or
        (B, 3), per instance); the scythe is absent until ``step``."""
        b = check_reset(self, params, batch_size)
        self.start_instances(b)  # the clock starts at the tool's placement
        self.grass_position = instance_positions(params, "grass_position", b)
        half = np.array(self.patch_size) / 2
        #: (B, N, 2) stalk positions on the ground, world x-y, m.
        self.stalks_xy = self.grass_position[:, None, :2] + rng.uniform(-half, half, size=(b, self.n_stalks, 2))
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
        positions, rotations = motion
        cuts = self.rule.cuts(positions, rotations, self.stalks_xy, self.control_dt / self.substeps)  # (S, B, N)
        # Time of the first cut, s since placement: the end of sub-step k is (k + 1) dt.
        steps = np.where(cuts, np.arange(1, self.substeps + 1)[:, None, None], np.inf)
        first = np.min(steps, axis=0) * (self.control_dt / self.substeps) + self.goal_timer.time
        newly = np.isfinite(first) & ~self.cut
        self.cut_time = np.where(newly, first, self.cut_time)
        self.cut |= newly
        self.goal_timer.record(self.cut.all(axis=1), at=self.cut_time.max(axis=1))  # when the last stalk fell
        self.goal_timer.advance(self.control_dt)

    # -------------------------------------------------------------------------------- rewards
    def goal_reward(self) -> np.ndarray:
        """(B,) number of stalks cut."""
        return self.cut.sum(axis=1).astype(float)

    def dense_reward(self) -> np.ndarray:
        """(B,) the paper appendix's closeness of the head point to the patch's centre on the
        ground (module docstring), in [0, 0.1]; 0 before the tool is placed."""
        centre = self.grass_position * np.array([1.0, 1.0, 0.0])  # (B, 3) on the ground
        return dense_scythe_reward(self._tool.position, centre)

    # ---------------------------------------------------------------------------------- views
    def footprints(self, params: SceneParams) -> np.ndarray:
        """(1, 5) the patch: centre x, y, half-length, half-width (m), yaw 0 (rad)."""
        x, y = np.asarray(params["grass_position"], dtype=float)[:2]
        return np.array([[x, y, self.patch_size[0] / 2, self.patch_size[1] / 2, 0.0]])

    def snapshot(self) -> dict[str, np.ndarray]:
        """Instance 0 for views.

        Keys: ``stalk_base`` (N, 3) stalk bottoms (z = 0), ``stalk_half_extents`` (3,),
        ``stalk_cut`` (N,) bool, ``patch_center`` (3,), ``patch_half_extents`` (2,) m,
        ``patch_yaw`` () rad (0), ``blade`` (2, 3) edge root and tip in the world (NaN before the
        first step), ``tool_position`` (3,), ``tool_rotation`` (3, 3), ``time`` () s.
        """
        tool = tool_snapshot(self._tool.position, self._tool.rotation)
        base = np.column_stack([self.stalks_xy[0], np.zeros(self.n_stalks)])
        blade = tool["tool_position"] + self.edge @ tool["tool_rotation"].T  # NaN before the first step
        return {
            "stalk_base": base,
            "stalk_half_extents": np.array([self.stalk_width / 2, self.stalk_width / 2, self.stalk_height / 2]),
            "stalk_cut": self.cut[0].copy(),
            "patch_center": self.grass_position[0].copy(),
            "patch_half_extents": np.array(self.patch_size) / 2,
            "patch_yaw": np.array(0.0),
            "blade": blade,
            **tool,
            "time": np.array(self.goal_timer.time),
        }
