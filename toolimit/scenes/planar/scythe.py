"""Planar scythe scene (horizontal x-y plane): cut a patch of grass stalks with a fast low sweep.

World (pymunk x, y = world x, y; heights z are checked separately): ``stalk_count`` grass stalks,
points standing on the ground, placed uniformly at random (each instance with its own generator
draws) in a disc of diameter ``patch_diameter`` centred at parameter ``grass_position``.

The scythe (tool frame: origin at the blade root, x along the cutting edge, z towards the handle)
cuts with its blade, the segment from the head along tool x of length ``ToolSpec.head_width``
(0.45 m), projected into the plane. The blade is a kinematic pymunk body (see kinematic_tool); over
each control step it moves at constant velocity and angular velocity and the cut test runs on
``substeps`` sub-intervals of that motion. A stalk is cut in a sub-interval when

* the blade sweeps across it: in the blade's own frame the stalk's signed distance to the blade
  line changes sign (or is within ``stalk_radius``) and the crossing lies between the blade's root
  and tip (a swept-segment test, so nothing tunnels at 4 m/s);
* the blade's height at the crossing point (interpolated in 3D) is between the ground and
  ``max_cut_height`` (0.1 m);
* the blade's speed across the stalk, perpendicular to the cutting edge in the plane, is at least
  ``min_cut_speed`` (1 m/s), in either direction.

Rewards: goal reward = number of stalks cut. Dense reward (the paper's appendix,
:func:`~toolimit.scenes.base.gaussian_closeness`, b = 10, on x-y plane distances, m): 0.1 times
the mean over all stalks (the appendix's grass patches, cut or not) of exp(-5 |p - s|^2), with p
the tool frame origin (the blade root) and s a stalk's point (its base and any point up the stalk
coincide in this plane); in [0, 0.1], 0 before the first step (no scythe yet). Success: every
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
    require_counts,
    require_positive,
    require_reset,
    world_position,
)
from toolimit.scenes.planar.kinematic_tool import KinematicTool
from toolimit.tools import ToolPose, tool_spec


class PlanarScytheScene(WindowedGoalScene):
    """B instances of the planar scythe world; see the module docstring for the cut test.

    Args:
        control_dt, success_window: see :class:`~toolimit.scenes.base.WindowedGoalScene`; every
            stalk must be cut within ``success_window`` s of the first step's start.
        substeps: cut-test sub-intervals per control step (10 at 24 Hz = 240 Hz).
        stalk_count: stalks in the patch. patch_diameter: m. stalk_radius: m.
        max_cut_height: highest blade height (m) that cuts. min_cut_speed: slowest cut, m/s.
    """

    tool = "scythe"
    world = "planar"

    def __init__(
        self,
        control_dt: float = 1.0 / CONTROL_FPS,
        substeps: int = 10,
        stalk_count: int = 30,
        patch_diameter: float = 0.4,
        stalk_radius: float = 0.003,
        max_cut_height: float = 0.1,
        min_cut_speed: float = 1.0,
        success_window: float = 1.0,
    ):
        super().__init__(control_dt, substeps, success_window)
        require_counts(stalk_count=stalk_count)
        require_positive(patch_diameter=patch_diameter)
        self.stalk_count = int(stalk_count)
        self.patch_diameter = float(patch_diameter)
        self.stalk_radius = float(stalk_radius)
        self.max_cut_height = float(max_cut_height)
        self.min_cut_speed = float(min_cut_speed)
        self._blade_points = np.array([[0.0, 0.0, 0.0], [tool_spec("scythe").head_width, 0.0, 0.0]])  # tool frame
        self.parameters = (
            world_position(
                "grass_position",
                f"centre of the {self.patch_diameter:.2f} m grass patch on the ground (x, y used)",
                axes=(0, 1),
            ),
        )
        # The state of the B instances, built by reset.
        self.grass_centre = np.zeros(2)  # patch centre, world x-y, m
        self.stalks = np.zeros((0, self.stalk_count, 2))  # (B, M, 2) stalk positions, m
        self.cut = np.zeros((0, self.stalk_count), dtype=bool)  # (B, M)
        self._spaces: list[pymunk.Space] = []
        self._tool = KinematicTool(self._spaces, "xy", reference_axis=0)

    # ----------------------------------------------------------------------------------- parameters
    # ----------------------------------------------------------------------------------- reset/step
    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """Build ``batch_size`` instances, each with its own stalk placement drawn from ``rng``."""
        batch_size = check_reset(self, params, batch_size)
        self.grass_centre = np.asarray(params["grass_position"], dtype=float)[:2].copy()
        # Instance by instance, so instance b's stalks do not depend on the batch size.
        uniform = np.array([rng.uniform(0.0, 1.0, (2, self.stalk_count)) for _ in range(batch_size)])  # (B, 2, M)
        radius = self.patch_diameter / 2.0 * np.sqrt(uniform[:, 0])  # uniform density over the disc
        angle = 2.0 * np.pi * uniform[:, 1]
        self.stalks = self.grass_centre + np.stack([radius * np.cos(angle), radius * np.sin(angle)], -1)  # (B, M, 2)
        self.cut = np.zeros((batch_size, self.stalk_count), dtype=bool)
        self._spaces = [pymunk.Space() for _ in range(batch_size)]
        self._tool = KinematicTool(self._spaces, "xy", reference_axis=0)
        self.start_instances(batch_size)  # the clock starts with the first step

    def step(self, tool_pose: ToolPose) -> None:
        """Move the blade to ``tool_pose`` over ``control_dt`` and cut what it sweeps."""
        require_reset(self)
        previous = self._tool.pose  # None before the first step
        start_position, start_angle = self._tool.position.copy(), self._tool.angle.copy()
        self._tool.begin_step(tool_pose, self.control_dt)
        if previous is not None and self._tool.pose is not None:
            self._cut_swept_stalks(previous, self._tool.pose, start_position, start_angle)
        for space in self._spaces:  # kinematic bodies integrate exactly over one step
            space.step(self.control_dt)
        self._tool.end_step()
        self.goal_timer.advance(self.control_dt)
        self.goal_timer.record(self.cut.all(axis=1))

    def _cut_swept_stalks(
        self,
        previous: tuple[np.ndarray, np.ndarray],
        current: tuple[np.ndarray, np.ndarray],
        start_position: np.ndarray,
        start_angle: np.ndarray,
    ) -> None:
        """Mark stalks swept by the blade over this step, from its ``previous`` to its ``current`` 3D
        pose ((B, 3) m, (B, 3, 3)) (see the module docstring)."""
        fractions = np.linspace(0.0, 1.0, self.substeps + 1)[:, None]  # (S+1, 1)
        velocity = np.array([tuple(body.velocity) for body in self._tool.bodies])  # (B, 2) m/s
        angular_velocity = np.array([body.angular_velocity for body in self._tool.bodies])  # (B,) rad/s
        t = fractions * self.control_dt
        root = start_position[None] + t[..., None] * velocity[None]  # (S+1, B, 2)
        angle = start_angle[None] + t * angular_velocity[None]  # (S+1, B)
        blade_length = self._tool.local_points(self._blade_points)[:, 1, 0]  # (B,) in-plane length, m
        edge = np.stack([np.cos(angle), np.sin(angle)], -1)  # (S+1, B, 2)
        normal = np.stack([-edge[..., 1], edge[..., 0]], -1)
        offset = self.stalks[None] - root[:, :, None, :]  # (S+1, B, M, 2)
        along = np.einsum("sbmk,sbk->sbm", offset, edge)
        across = np.einsum("sbmk,sbk->sbm", offset, normal)
        a0, a1, s0, s1 = across[:-1], across[1:], along[:-1], along[1:]
        crossed = (a0 * a1 <= 0.0) | (np.minimum(np.abs(a0), np.abs(a1)) <= self.stalk_radius)
        weight = np.clip(np.abs(a0) / np.maximum(np.abs(a0) + np.abs(a1), 1e-12), 0.0, 1.0)  # crossing time
        s_cross = s0 + weight * (s1 - s0)
        on_blade = (s_cross >= 0.0) & (s_cross <= blade_length[None, :, None])
        speed = np.abs(a1 - a0) / (self.control_dt / self.substeps)
        # Blade height at the crossing: 3D root and tip heights interpolated in time and along the blade.
        (p0, r0), (p1, r1) = previous, current
        tip0 = p0[:, 2] + r0[:, 2, 0] * self._blade_points[1, 0]
        tip1 = p1[:, 2] + r1[:, 2, 0] * self._blade_points[1, 0]
        time = fractions[:-1, :, None] + weight / self.substeps  # (S, B, M) fraction of the step
        root_z = p0[:, 2][None, :, None] + time * (p1 - p0)[:, 2][None, :, None]
        tip_z = tip0[None, :, None] + time * (tip1 - tip0)[None, :, None]
        along_fraction = np.clip(s_cross / np.maximum(blade_length[None, :, None], 1e-9), 0.0, 1.0)
        height = root_z + along_fraction * (tip_z - root_z)
        low = (height >= 0.0) & (height <= self.max_cut_height)
        cuts = crossed & on_blade & low & (speed >= self.min_cut_speed)
        self.cut |= cuts.any(axis=0)

    # ----------------------------------------------------------------------------------- rewards
    def goal_reward(self) -> np.ndarray:
        """(B,) number of stalks cut."""
        require_reset(self)
        return self.cut.sum(axis=1).astype(float)

    def dense_reward(self) -> np.ndarray:
        """(B,) the paper appendix's closeness of the blade root to the stalks (module docstring),
        in [0, 0.1]; 0 before the first step."""
        require_reset(self)
        return dense_scythe_reward(self._tool.position if self._tool.placed else None, self.stalks)

    # ----------------------------------------------------------------------------------- views
    def footprints(self, params: SceneParams) -> np.ndarray:
        """(1, 5) the grass patch's bounding square (x, y, half-length, half-width, yaw), m/rad."""
        x, y = np.asarray(params["grass_position"], dtype=float)[:2]
        half = self.patch_diameter / 2.0
        return np.array([[x, y, half, half, 0.0]])

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
