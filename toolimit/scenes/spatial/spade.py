"""The 3D spade world: scoop sand from a deposit and drop it into a goal box.

World frame: metres, z up, ground z = 0. The scene is the original experiments' PhysX scene
(``docs/original_setup.md#spade-scene``; kzorina/pyphysx_envs ``SpadeTaskScene``):

* the **sand deposit** is a 0.4 m x 0.4 m three-walled pen (walls 7 cm high, 1 cm thick) whose
  centre is the parameter ``sand_position`` and whose frame is turned by ``sand_yaw`` about z; in
  that frame the walls stand at x = -+0.2 m and at y = -0.2 m, and the side y = +0.2 m is open;
* the **goal box** is an open-top square box of inner side ``GOAL_INNER`` (0.5 m) with walls
  ``GOAL_WALL_HEIGHT`` (7 cm) high, axis-aligned, centred at ``goal_position``; the ground is its
  floor. Both positions may be (B, 3), one per instance (the learner's reset noise, domain
  randomisation's boxes): each instance has its own wall set, and the goal region follows it;
* ``n_spheres`` (default 200) sand spheres of radius 2 cm start as a **heap**, built as the
  original builds it (``SpadeTaskScene.scene_setup``): dropped once into the deposit's own three
  walls from a column (N(0, 5 cm) horizontal offsets, one sphere every 0.1 m of height),
  simulated to rest and cached in the deposit's frame (:func:`settled_heap`), then placed in the
  deposit at every reset: moved to ``sand_position`` and turned by ``sand_yaw``. The original
  translates its heap only: its deposit's yaw is fixed for an environment and the heap was
  settled in the deposit already turned by it; here the yaw is a parameter of every reset (the
  alignment samples it), and a heap translated but not turned would put the sand that settled
  against the open side on a wall. The scene has no randomness of its own: every instance starts
  from the same heap (the learner's reset noise moves each instance's deposit and box);
* the sand (:data:`AUTHORS_SAND`): spheres that do not rotate (the original damps their rotation),
  sphere-sphere friction 5, sphere-spade and sphere-ground 2.5 (PhysX averages 5 with the spade's
  and the ground's 0.1), sphere-wall 3 (average of 5 and 1), speed capped at 1 m/s, 240 Hz (10
  sub-steps per 24 Hz control step);
* the spade is kinematic (:mod:`toolimit.scenes.spatial.tool_geometry`): a 0.12 m x 0.17 m blade
  with a 5 cm rim on both sides and the back; the sand follows
  :mod:`toolimit.scenes.spatial.particles`, in which the ground and the walls win against the
  spade: a sphere squeezed between them leaves sideways or over the blade.

Differences from the original, each measured (authors' aligned spade motions
``spade_video1_aligned`` / ``spade_example_aligned``, converted by
``toolimit.trajopt.from_original_spade_tip``, replayed tool-only 10 times in their own scene
parameters, mean final goal reward):

* the blade is a box with a rim, not the original mesh; its "about 0.17 m x 0.12 m" is read as
  0.17 m across and 0.12 m along the handle (the other reading carries less sand), and the rim's
  5 cm height stands for the dish of a real blade (the height that carried most on the two
  motions with the former heap; the figures are in docs/history.md#scenes);
* friction is Coulomb friction by position (particles module); its coefficients are the
  original's. They keep the load of a blade tilted as the real recordings tilt it: carrying from
  the deposit towards the box (tip above 10 cm, outside the box's square), the blade's face is at
  most 36 degrees from level in ``spade_video1_aligned`` (frames 39-58, mostly a sideways roll) and
  11 degrees in ``spade_example_aligned``; sand on the blade holds up to atan(2.5) = 68 degrees,
  and the recording empties the blade by rolling it to 103 degrees over the box (frames 84-91)
  (``tests/scenes/test_spatial_spade_invariants.py`` measures the tilt and checks a loaded blade
  at that tilt keeps its load).

Rewards. The goal reward is the number of sphere centres in the goal region: within the box's
inner square (+-0.25 m in x and y around its centre) and 0 <= z <= 0.1 m. Success (the paper):
at least 10 spheres in the box for at least half of the control steps so far.

Dense reward (the paper's appendix, :func:`~toolimit.scenes.base.gaussian_closeness`, b = 10):
the mean over spheres of exp(-5 |c - g|^2) + 0.05 exp(-5 |p - d|^2), with c a sphere centre, g the
goal box's floor centre, p the spade's handle end and d the deposit's floor centre
(``sand_position``), world frame, m: the authors' points (their boxes' and spade's body origins).
Before the first step there is no spade (``tool_pose`` None) and the tool term is 0. Range
[0, 1.05].

Parameters must keep the deposit and the box apart (their ground rectangles must not overlap) and
inside the world bound ``WORLD_HALF_SIZE`` (5 m) in x and y; both stand on the ground (the z of
their position parameters is ignored). :func:`toolimit.scenes.spatial.scoop.scripted_scoop` makes
a hand-written scoop-carry-tip spade motion for given parameters (tests, benchmarks, notebooks).
"""

from __future__ import annotations

import functools

import numpy as np

from toolimit.scenes.base import (
    CONTROL_FPS,
    ParameterSpec,
    SceneBase,
    SceneParams,
    SuccessTracker,
    batched_pose,
    check_reset,
    dense_spade_reward,
    dense_tool_point,
    instance_positions,
    parameter_violation,
    world_position,
)
from toolimit.scenes.spatial.particle_kernels import in_box_counts
from toolimit.scenes.spatial.particles import (
    GranularMaterial,
    ParticleWorld,
    StaticBoxes,
    checked_threads,
)
from toolimit.scenes.spatial.tool_geometry import (
    SPADE_BLADE_LENGTH,
    SPADE_BLADE_WIDTH,
    SPADE_RIM_HEIGHT,
    tool_shapes,
)
from toolimit.scenes.spatial.tool_motion import tool_snapshot
from toolimit.tools import ToolPose, rotation_z

#: Inner side of the square sand deposit (m), its wall height and thickness (m).
DEPOSIT_INNER = 0.4
DEPOSIT_WALL_HEIGHT = 0.07
#: The deposit's walls in its frame (:func:`_walls`): its +y side is open.
DEPOSIT_WALLS = ("-x", "+x", "-y")
#: Inner side of the goal box (m), its wall height (m).
GOAL_INNER = 0.5
GOAL_WALL_HEIGHT = 0.07
#: Goal-reward region: sphere centres within the box's inner square and 0 <= z <= this height (m).
GOAL_REGION_HEIGHT = 0.1
#: Wall thickness of the deposit and the goal box (m).
WALL_THICKNESS = 0.01
#: Spheres in the box needed at a step for it to count towards success (scenes.base.SUCCESS_FRACTION of the steps).
SUCCESS_SPHERES = 10
#: The heap: spheres dropped one every HEAP_DROP_SPACING m in height from a column with
#: horizontal N(0, HEAP_DROP_SIGMA) m offsets into the deposit's three walls, simulated to rest.
HEAP_DROP_SIGMA = 0.05
HEAP_DROP_SPACING = 0.1
#: Largest sphere count of a scene.
MAX_SPHERES = 400
#: Most control steps the heap drop may take to come to rest.
HEAP_MAX_STEPS = 2400
#: The sand of the original scene (module docstring): 2 cm spheres that hardly roll (sphere-sphere
#: friction 5), PhysX-averaged sphere-spade and sphere-ground friction 2.5, sphere-wall 3, speed
#: capped at 1 m/s.
AUTHORS_SAND = GranularMaterial(
    radius=0.02,
    mu_static=5.0,
    mu_kinetic=5.0,
    tool_mu_static=2.5,
    tool_mu_kinetic=2.5,
    ground_mu_static=2.5,
    ground_mu_kinetic=2.5,
    wall_mu_static=3.0,
    wall_mu_kinetic=3.0,
    max_speed=1.0,
)


def _walls(inner: float, height: float, sides: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Centres (K, 3) and half extents (K, 3) of the walls ("-x", "+x", "-y", "+y") of a square pen.

    The pen's frame: origin at the centre of its floor, walls outside the inner square, metres.
    """
    t, half = WALL_THICKNESS, inner / 2
    along = half + t  # walls along x cover the corners
    table = {
        "-x": ((-half - t / 2, 0.0, height / 2), (t / 2, along, height / 2)),
        "+x": ((half + t / 2, 0.0, height / 2), (t / 2, along, height / 2)),
        "-y": ((0.0, -half - t / 2, height / 2), (half, t / 2, height / 2)),
        "+y": ((0.0, half + t / 2, height / 2), (half, t / 2, height / 2)),
    }
    centers, halves = zip(*(table[s] for s in sides))
    return np.array(centers), np.array(halves)


@functools.lru_cache(maxsize=8)
def settled_heap(n_spheres: int, material: GranularMaterial, substeps: int = 10) -> np.ndarray:
    """(n_spheres, 3) centres of the heap at rest in the deposit, deposit frame, metres (cached).

    As the original scene builds its pile (``SpadeTaskScene.scene_setup``): spheres dropped one
    every ``HEAP_DROP_SPACING`` m in height from a column with N(0, ``HEAP_DROP_SIGMA``) horizontal
    offsets (seed 0; clipped to the deposit's inner square) into the deposit's own three walls,
    simulated until every sphere rests. The deposit's frame: origin at the centre of its floor,
    walls at x = -+DEPOSIT_INNER / 2 and y = -DEPOSIT_INNER / 2, open side +y. Spheres that roll out
    of the open side or over a wall stay where they came to rest, as in the original. The
    original's deposit is a 5 kg dynamic body set 5 cm above the ground for the drop: it falls onto
    the ground in 0.1 s, before the second sphere lands, and the 0.2 kg of sand cannot slide it
    (PhysX's averaged wall-ground friction 0.55 holds 27 N), so static walls on the ground make the
    same heap. Raises RuntimeError if the heap does not come to rest.
    """
    rng = np.random.default_rng(0)
    inside = DEPOSIT_INNER / 2 - material.radius
    start = np.column_stack(
        [
            np.clip(rng.normal(0.0, HEAP_DROP_SIGMA, (n_spheres, 2)), -inside, inside),
            material.radius + 0.01 + HEAP_DROP_SPACING * np.arange(n_spheres),
        ]
    )
    centers, halves = _walls(DEPOSIT_INNER, DEPOSIT_WALL_HEIGHT, DEPOSIT_WALLS)
    deposit = StaticBoxes(centers, np.repeat(np.eye(3)[None], len(DEPOSIT_WALLS), 0), halves)
    world = ParticleWorld(material, deposit, None)
    world.reset(start[None])
    for step in range(HEAP_MAX_STEPS):
        world.advance(1.0 / CONTROL_FPS, substeps)
        if step > CONTROL_FPS and world.kinetic_energy()[0] == 0.0:
            return world.positions[0].copy()
    raise RuntimeError(f"the heap of {n_spheres} spheres did not come to rest in {HEAP_MAX_STEPS} steps")


def _rectangles_overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two ground rectangles (cx, cy, half_length, half_width, yaw) overlap (separating axes)."""

    def corners(rect: np.ndarray) -> np.ndarray:
        cx, cy, hl, hw, yaw = rect
        local = np.array([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]])
        c, s = np.cos(yaw), np.sin(yaw)
        return local @ np.array([[c, s], [-s, c]]) + np.array([cx, cy])

    ca, cb = corners(a), corners(b)
    for yaw in (a[4], b[4]):
        for axis in (np.array([np.cos(yaw), np.sin(yaw)]), np.array([-np.sin(yaw), np.cos(yaw)])):
            pa, pb = ca @ axis, cb @ axis
            if pa.max() <= pb.min() or pb.max() <= pa.min():
                return False
    return True


class SpatialSpadeScene(SceneBase):
    """Batched 3D spade scene (see the module docstring).

    Args:
        n_spheres: number of sand spheres, 1..MAX_SPHERES (400).
        substeps: physics sub-steps per control step (10 -> 240 Hz).
        material: sphere constants (radius, friction, ...); default the original scene's sand.
        control_dt: see :class:`~toolimit.scenes.base.SceneBase`.
        threads: threads stepping the instances (:class:`ParticleWorld`; the same sand whatever
            their count).
    """

    tool = "spade"
    world = "3d"

    def __init__(
        self,
        n_spheres: int = 200,
        substeps: int = 10,
        material: GranularMaterial = AUTHORS_SAND,
        control_dt: float = 1.0 / CONTROL_FPS,
        threads: int = 1,
    ) -> None:
        if not 1 <= int(n_spheres) <= MAX_SPHERES:
            raise ValueError(f"n_spheres must be in 1..{MAX_SPHERES}, got {n_spheres!r}")
        super().__init__(control_dt, substeps)
        self.n_spheres = int(n_spheres)
        self.material = material
        self.threads = checked_threads(threads)
        self.shapes = tool_shapes("spade")
        self.parameters = (
            world_position("sand_position", "centre of the sand deposit's floor", axes=(0, 1)),
            ParameterSpec(
                "sand_yaw",
                "uniform",
                low=-np.pi,
                high=np.pi,
                unit="rad",
                description="yaw of the deposit (its open side faces its +y)",
            ),
            world_position("goal_position", "centre of the goal box's floor", axes=(0, 1)),
        )
        # The state of the B instances, built by reset.
        self.sand_position = np.zeros((0, 3))  # (B, 3) deposit floor centres, m
        self.sand_yaw = 0.0  # rad
        self.goal_position = np.zeros((0, 3))  # (B, 3) goal box floor centres, m
        self._dense_point = dense_tool_point("spade")  # (3,) tool frame, m: the handle end
        self.walls = StaticBoxes(np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros((0, 3)))
        self.success_tracker = SuccessTracker(0)
        self._world: ParticleWorld | None = None
        self._goal_reward: np.ndarray | None = None  # (B,) of the current state, once counted

    # ------------------------------------------------------------------------------- parameters
    def footprints(self, params: SceneParams) -> np.ndarray:
        """(2, 5) ground rectangles (cx, cy, half_length, half_width, yaw): deposit, goal box."""
        sand, goal = np.asarray(params["sand_position"], float), np.asarray(params["goal_position"], float)
        deposit_half = DEPOSIT_INNER / 2 + WALL_THICKNESS
        goal_half = GOAL_INNER / 2 + WALL_THICKNESS
        return np.array(
            [
                [sand[0], sand[1], deposit_half, deposit_half, float(params["sand_yaw"])],
                [goal[0], goal[1], goal_half, goal_half, 0.0],
            ]
        )

    def invalid_reason(self, params: SceneParams) -> str | None:
        """Why ``params`` cannot make this scene (against the specs, overlap), or None."""
        violation = parameter_violation(self.parameters, params)
        if violation is not None:
            return violation
        deposit, goal = self.footprints(params)
        if _rectangles_overlap(deposit, goal):
            return "the sand deposit and the goal box overlap"
        return None

    # --------------------------------------------------------------------------------- lifecycle
    def reset(self, params: SceneParams, rng: np.random.Generator, batch_size: int = 1) -> None:
        """B instances: walls at ``params`` (each position (3,) or (B, 3), per instance), the cached
        heap in each deposit (placed and turned with it); no spade yet. The scene has no randomness
        of its own; ``rng`` is accepted for the protocol."""
        batch_size = check_reset(self, params, batch_size)
        b = self.batch_size = batch_size
        on_ground = np.array([1.0, 1.0, 0.0])
        self.sand_position = instance_positions(params, "sand_position", b) * on_ground
        self.sand_yaw = float(params["sand_yaw"])
        self.goal_position = instance_positions(params, "goal_position", b) * on_ground
        deposit_rotation = rotation_z(self.sand_yaw)
        deposit_centers, deposit_halves = _walls(DEPOSIT_INNER, DEPOSIT_WALL_HEIGHT, DEPOSIT_WALLS)
        goal_centers, goal_halves = _walls(GOAL_INNER, GOAL_WALL_HEIGHT, ("-x", "+x", "-y", "+y"))
        # one wall set per instance: the deposit's walls then the goal box's
        self.walls = StaticBoxes(
            centers=np.concatenate(
                [
                    self.sand_position[:, None] + deposit_centers @ deposit_rotation.T,
                    self.goal_position[:, None] + goal_centers,
                ],
                axis=1,
            ),
            rotations=np.broadcast_to(
                np.concatenate([np.repeat(deposit_rotation[None], 3, 0), np.repeat(np.eye(3)[None], 4, 0)]),
                (b, 7, 3, 3),
            ),
            half_extents=np.broadcast_to(np.concatenate([deposit_halves, goal_halves]), (b, 7, 3)),
        )
        heap = settled_heap(self.n_spheres, self.material, self.substeps)
        self._world = ParticleWorld(self.material, self.walls, self.shapes, self.threads)
        self._world.reset(self.sand_position[:, None] + heap @ deposit_rotation.T)
        self._goal_reward = None
        #: Steps that ended with >= SUCCESS_SPHERES in the box.
        self.success_tracker = SuccessTracker(b)

    def _require_reset(self) -> ParticleWorld:
        if self._world is None:
            raise RuntimeError("call reset() before using the scene")
        return self._world

    def step(self, tool_pose: ToolPose) -> None:
        """Move the spade to ``tool_pose`` ((3,)/(3,3) or (B,3)/(B,3,3)) over ``control_dt`` and simulate.

        The first step after ``reset`` places the spade there without velocity.
        """
        world = self._require_reset()
        position, rotation = batched_pose(tool_pose, self.batch_size)
        self._goal_reward = None
        if world.tool_position is None:
            world.place_tool(position, rotation)
            world.advance(self.control_dt, self.substeps)
        else:
            world.advance(self.control_dt, self.substeps, position, rotation)
        self.success_tracker.record(self.goal_reward() >= SUCCESS_SPHERES)

    # ----------------------------------------------------------------------------------- rewards
    @property
    def sphere_positions(self) -> np.ndarray:
        """(B, N, 3) sphere centres, world frame, m (a copy)."""
        return self._require_reset().positions.copy()

    @property
    def sphere_velocities(self) -> np.ndarray:
        """(B, N, 3) sphere velocities, world frame, m/s (a copy; zero for sleeping spheres)."""
        return self._require_reset().velocities.copy()

    @property
    def tool_pose(self) -> ToolPose | None:
        """The spade's current pose ((B, 3), (B, 3, 3) world frame), None before the first step."""
        world = self._require_reset()
        if world.tool_position is None or world.tool_rotation is None:
            return None
        return ToolPose(world.tool_position.copy(), world.tool_rotation.copy())

    def spheres_in_box(self) -> np.ndarray:
        """(B, N) bool: sphere centres inside the goal box."""
        offset = self._require_reset().positions - self.goal_position[:, None]
        half = GOAL_INNER / 2
        return (
            (np.abs(offset[..., 0]) < half)
            & (np.abs(offset[..., 1]) < half)
            & (offset[..., 2] >= 0.0)
            & (offset[..., 2] <= GOAL_REGION_HEIGHT)
        )

    def spheres_on_spade(self) -> np.ndarray:
        """(B, N) bool: sphere centres above the blade's carrying face, within its rim (tool frame)."""
        world = self._require_reset()
        if world.tool_position is None or world.tool_rotation is None:
            return np.zeros((self.batch_size, self.n_spheres), dtype=bool)
        local = np.einsum("bnj,bja->bna", world.positions - world.tool_position[:, None], world.tool_rotation)
        return (
            (local[..., 0] > 0.0)
            & (local[..., 0] < SPADE_RIM_HEIGHT + self.material.radius)
            & (np.abs(local[..., 1]) < SPADE_BLADE_WIDTH / 2)
            & (local[..., 2] > 0.0)
            & (local[..., 2] < SPADE_BLADE_LENGTH)
        )

    def static_penetration(self) -> np.ndarray:
        """(B,) deepest penetration (m) of a sphere into the ground or a wall, 0 if none.

        The solver keeps it at 0 (static surfaces win, module docstring); a diagnostic for tests
        and benchmarks.
        """
        positions = self._require_reset().positions
        walls = self.walls  # (B, K, ...) per instance
        local = np.einsum("bnkj,bkja->bnka", positions[:, :, None] - walls.centers[:, None], walls.rotations)
        outside = np.linalg.norm(np.maximum(np.abs(local) - walls.half_extents[:, None], 0.0), axis=-1)
        radius = self.material.radius
        deepest = np.maximum(radius - positions[..., 2], radius - outside.min(axis=-1))
        return np.maximum(deepest.max(axis=1), 0.0)

    def goal_reward(self) -> np.ndarray:
        """(B,) number of spheres in the goal box (counted once per state: the step's success
        record and the learner both ask)."""
        if self._goal_reward is None:
            world = self._require_reset()
            self._goal_reward = in_box_counts(world.positions, self.goal_position, GOAL_INNER / 2, GOAL_REGION_HEIGHT)
        return self._goal_reward.copy()

    def dense_reward(self) -> np.ndarray:
        """(B,) the paper appendix's shaping: sand close to the box, spade close to the deposit
        (module docstring), in [0, 1.05]."""
        world = self._require_reset()
        tool = None if world.tool_rotation is None else world.tool_position + world.tool_rotation @ self._dense_point
        return dense_spade_reward(world.positions, self.goal_position[:, None], tool, self.sand_position)

    def is_success(self) -> np.ndarray:
        """(B,) bool: >= 10 spheres in the box during at least half of the steps so far."""
        self._require_reset()
        return self.success_tracker.is_success()

    # ------------------------------------------------------------------------------------- views
    def snapshot(self) -> dict[str, np.ndarray]:
        """Instance 0: ``sphere_positions`` (N, 3) m, ``sphere_radius`` (), ``wall_centers`` (K, 3),
        ``wall_rotations`` (K, 3, 3), ``wall_half_extents`` (K, 3) (deposit walls then goal walls),
        ``sand_position`` (3,), ``sand_yaw`` (), ``goal_position`` (3,), ``goal_inner`` (),
        ``goal_wall_height`` (), ``tool_position`` (3,), ``tool_rotation`` (3, 3) (NaN before the
        first step), ``in_box`` () count; world frame, metres."""
        world = self._require_reset()
        return {
            "sphere_positions": world.positions[0].copy(),
            "sphere_radius": np.array(self.material.radius),
            "wall_centers": self.walls.centers[0].copy(),
            "wall_rotations": self.walls.rotations[0].copy(),
            "wall_half_extents": self.walls.half_extents[0].copy(),
            "sand_position": self.sand_position[0].copy(),
            "sand_yaw": np.array(self.sand_yaw),
            "goal_position": self.goal_position[0].copy(),
            "goal_inner": np.array(GOAL_INNER),
            "goal_wall_height": np.array(GOAL_WALL_HEIGHT),
            **tool_snapshot(world.tool_position, world.tool_rotation),
            "in_box": np.array(self.goal_reward()[0]),
        }
