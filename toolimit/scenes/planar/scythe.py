"""Planar scythe scene (horizontal x-y plane): cut a patch of grass stalks, the 3D scene's twin.

World (pymunk x, y = world x, y; heights z are kept): ``stalk_count`` (10) grass stalks, points
standing on the ground, placed uniformly at random (each instance with its own generator draws) in
the authors' ``patch_size`` rectangle (0.4 m along world x, 0.1 m along y) centred at parameter
``grass_position``, as in the 3D scene.

The scythe's blade is a kinematic pymunk body (see kinematic_tool) moving at constant velocity and
angular velocity over each control step. The scythe's demonstration is not flattened for this
plane (the cut depends on the blade's height), so the scene receives 3D tool poses and cuts by the
same rule as the 3D scene, the authors' (:mod:`toolimit.scenes.scythe_cut`: the edge within 2 cm
of a stalk's bottom 0.1 m, at most 0.1 m high, its normal within 30 degrees of the direction to
the stalk, approaching at about 1 m/s), tested at the ``substeps`` instants of the constant-velocity
3D motion between control poses: a planar twin that cuts exactly what the 3D scene cuts.

Rewards: goal reward = number of stalks cut. Dense reward (the paper's appendix,
:func:`~toolimit.scenes.base.gaussian_closeness`, b = 10, on x-y plane distances, m):
0.1 exp(-5 |p - g|^2), with p the tool frame origin (the head point: the authors' tip) and g the
grass patch's centre (the authors' mean over their one patch); in [0, 0.1], 0 before the first
step (no scythe yet). Success: every
stalk cut by the end of a control step ending at most ``success_window`` seconds (1 s, docs/method.md#success-criteria)
after the start of the first ``step`` after ``reset``.
"""

from __future__ import annotations

import numpy as np
import pymunk

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
from toolimit.scenes.planar.kinematic_tool import KinematicTool
from toolimit.scenes.scythe_cut import MAX_CUT_HEIGHT, PATCH_SIZE, ScytheCutRule, scythe_cut_rule
from toolimit.scenes.spatial.tool_motion import interpolate_poses
from toolimit.tools import ToolPose


class PlanarScytheScene(WindowedGoalScene):
    """B instances of the planar scythe world; see the module docstring for the cut test.

    Args:
        control_dt, success_window: see :class:`~toolimit.scenes.base.WindowedGoalScene`; every
            stalk must be cut within ``success_window`` s of the first step's start.
        substeps: cut-test instants per control step (10 at 24 Hz = 240 Hz).
        stalk_count: stalks in the patch. patch_size: (length along x, width along y), m.
        stalk_width: side of a stalk, m. max_cut_height: highest edge point that cuts, m.
    """

    tool = "scythe"
    world = "planar"

    def __init__(
        self,
        control_dt: float = 1.0 / CONTROL_FPS,
        substeps: int = 10,
        stalk_count: int = 10,
        patch_size: tuple[float, float] = PATCH_SIZE,
        stalk_width: float = 0.005,
        max_cut_height: float = MAX_CUT_HEIGHT,
        success_window: float = 1.0,
    ):
        super().__init__(control_dt, substeps, success_window)
        require_counts(stalk_count=stalk_count)
        require_positive(
            patch_length=patch_size[0],
            patch_width=patch_size[1],
            stalk_width=stalk_width,
            max_cut_height=max_cut_height,
        )
        self.stalk_count = int(stalk_count)
        self.patch_size = (float(patch_size[0]), float(patch_size[1]))
        self.stalk_width = float(stalk_width)
        self.max_cut_height = float(max_cut_height)
        #: The cut test (edge, normal and thresholds), the 3D scene's.
        self.rule: ScytheCutRule = scythe_cut_rule(self.stalk_width, self.max_cut_height)
        self._blade_points = self.rule.edge  # (2, 3) tool frame
        self.parameters = (
            world_position(
                "grass_position",
                f"centre of the {self.patch_size[0]:.2f} x {self.patch_size[1]:.2f} m grass patch on the ground (x, y used)",
                axes=(0, 1),
            ),
        )
        # The state of the B instances, built by reset.
        self.grass_centre = np.zeros((0, 2))  # (B, 2) patch centres, world x-y, m
        self.stalks = np.zeros((0, self.stalk_count, 2))  # (B, M, 2) stalk positions, m
        self.cut = np.zeros((0, self.stalk_count), dtype=bool)  # (B, M)
        self._spaces: list[pymunk.Space] = []
        self._tool = KinematicTool(self._spaces, "xy", reference_axis=0)

    # ----------------------------------------------------------------------------------- parameters
    # ----------------------------------------------------------------------------------- reset/step
    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """Build ``batch_size`` instances at ``params["grass_position"]`` ((3,) or (B, 3), per
        instance), each with its own stalk placement drawn from ``rng``."""
        batch_size = check_reset(self, params, batch_size)
        self.grass_centre = instance_positions(params, "grass_position", batch_size)[:, :2]
        half = np.array(self.patch_size) / 2.0
        self.stalks = self.grass_centre[:, None] + rng.uniform(
            -half, half, size=(batch_size, self.stalk_count, 2)
        )  # (B, M, 2)
        self.cut = np.zeros((batch_size, self.stalk_count), dtype=bool)
        self._spaces = [pymunk.Space() for _ in range(batch_size)]
        self._tool = KinematicTool(self._spaces, "xy", reference_axis=0)
        self.start_instances(batch_size)  # the clock starts with the first step

    def step(self, tool_pose: ToolPose) -> None:
        """Move the blade to ``tool_pose`` over ``control_dt`` and cut what it sweeps."""
        require_reset(self)
        previous = self._tool.pose  # None before the first step
        self._tool.begin_step(tool_pose, self.control_dt)
        if previous is not None and self._tool.pose is not None:
            fractions = np.arange(self.substeps + 1) / self.substeps
            positions, rotations = interpolate_poses(*previous, *self._tool.pose, fractions)
            cuts = self.rule.cuts(positions, rotations, self.stalks, self.control_dt / self.substeps)
            self.cut |= cuts.any(axis=0)
        for space in self._spaces:  # kinematic bodies integrate exactly over one step
            space.step(self.control_dt)
        self._tool.end_step()
        self.goal_timer.advance(self.control_dt)
        self.goal_timer.record(self.cut.all(axis=1))

    # ----------------------------------------------------------------------------------- rewards
    def goal_reward(self) -> np.ndarray:
        """(B,) number of stalks cut."""
        require_reset(self)
        return self.cut.sum(axis=1).astype(float)

    def dense_reward(self) -> np.ndarray:
        """(B,) the paper appendix's closeness of the head point to the patch's centre (module
        docstring), in [0, 0.1]; 0 before the first step."""
        require_reset(self)
        return dense_scythe_reward(self._tool.position if self._tool.placed else None, self.grass_centre)

    # ----------------------------------------------------------------------------------- views
    def footprints(self, params: SceneParams) -> np.ndarray:
        """(1, 5) the grass patch (x, y, half-length, half-width, yaw 0), m/rad."""
        x, y = np.asarray(params["grass_position"], dtype=float)[:2]
        return np.array([[x, y, self.patch_size[0] / 2.0, self.patch_size[1] / 2.0, 0.0]])

    def snapshot(self) -> dict[str, np.ndarray]:
        """Instance 0: ``stalks`` (M, 3) world foot points, ``cut`` (M,) bool, ``blade`` (2, 3) world
        root and tip (if placed)."""
        require_reset(self)
        stalks = np.zeros((self.stalk_count, 3))
        stalks[:, :2] = self.stalks[0]
        snapshot = {"stalks": stalks, "cut": self.cut[0].copy()}
        if self._tool.placed:
            snapshot["blade"] = self._tool.world_points(self._blade_points)[0]
        return snapshot
