"""Batched granular material: B instances x N equal spheres, position-based dynamics with friction.

The scheme is the particle solver of Macklin, Mueller, Chentanez, Kim, "Unified particle physics
for real-time applications", ACM TOG 33(4), 2014 (SIGGRAPH; its "Algorithm 1" simulation loop),
restricted to rigid, non-rotating spheres of one radius r:

* each sub-step of length h: v += g h; predicted x* = x + h v;
* contact constraints, one pass per sub-step ("small steps" rather than iterations), in groups
  solved one after the other (Gauss-Seidel between groups): sphere-sphere; the ground plane z = 0
  and the static oriented boxes (walls) with friction; the kinematic tool (boxes and capsules);
  then the walls and the ground again, normal constraints only. **Static surfaces win**: a
  sphere squeezed between the moving tool and the ground or a wall ends on the static surface,
  overlapping the tool, and leaves sideways or, as the tool moves on, over it (through the face
  nearest to it, see below); no sphere centre ever lies below r or inside a wall, whatever the
  tool does (a blade below ground level included). Static friction is applied before the tool so
  that it never drags a sphere back into a tool that pushes it;
* sphere-sphere contacts are solved Jacobi-style for all pairs at once, each sphere's summed
  correction divided by its number of contacts and scaled by an over-relaxation factor omega (the
  paper's constraint averaging with SOR), with the paper's height-dependent **mass scaling**
  m*_i = m exp(-k z_i) for contacts (its "shock propagation" for stacks), so piles converge in one
  pass per sub-step;
* **Coulomb friction by position** (the paper's friction model), one pair of coefficients per
  kind of surface (sphere, tool, ground, wall): the tangential displacement of a sphere relative
  to the surface over the sub-step, dx_t, is cancelled when |dx_t| < mu_s d (static; d is the
  penetration resolved), otherwise reduced by mu_k d (kinetic). A sphere at rest on a slope of
  angle theta stays while tan(theta) < mu_s; once sliding it accelerates while tan(theta) > mu_k.
  With mu_s = 0.6, mu_k = 0.5 a loaded blade keeps its sand below 26.6 degrees (atan mu_k) and
  spills above 31 degrees (atan mu_s) (tests/scenes/test_particles.py);
* v = (x* - x) / h, capped at ``max_speed`` if set (the original PhysX scene caps its spheres at
  1 m/s), then **particle sleeping** (the last line of the paper's Algorithm 1): a sphere whose
  sub-step speed is below ``sleep_speed`` (1 cm/s) keeps its position. This removes the residual
  jitter of the one-pass Jacobi solve, so piles at rest stay exactly at rest. Only the position
  update is skipped: the solver carries the sub-step's velocity, so a sphere that accelerates
  slowly (a slide just past the friction angle, an unsupported sphere: g h = 4 cm/s at 240 Hz)
  wakes within a few sub-steps; a slow push can hide at most ``sleep_speed * h`` (0.04 mm) of
  penetration. Sleepers report zero velocity.
* **island sleeping** (as in rigid-body engines), per instance: when every sphere of an instance
  has slept for ``freeze_after_substeps`` sub-steps (24: 0.1 s at 240 Hz) and the tool's bounds
  reach none of its spheres, its sub-step is skipped: the sand is exactly at rest. Only
  accelerations below ``sleep_speed / (freeze_after_substeps h)`` (0.1 m/s^2) could have woken it
  later; a sphere starting to slide past the friction angle accelerates at 0.85 m/s^2 or more;
* ``ParticleWorld.place_tool`` puts the tool down without velocity: overlapped spheres are pushed
  out by position-only passes (the paper's pre-stabilisation of initial overlaps).

The spheres do not rotate (like sand grains with strong rolling resistance: the paper's PhysX scene
damps its spheres' rotation for the same reason).

Broad phase: each instance keeps a Verlet list of sphere pairs closer than the contact distance
plus ``pair_margin``, rebuilt (sort and sweep along x) as soon as one of its spheres has moved
more than ``pair_margin / 2`` since the last build, so no contact is missed. Walls and tool boxes
are tested against a sphere only when its sub-step segment meets their bounds grown by r (the
tool's in the tool frame).

**No tunnelling.** The tool moves at constant velocity within each sub-step (straight line for the
head point, geodesic rotation); spheres against the tool are solved in the tool frame, where the
sphere's centre moves from its start-of-sub-step to its end-of-sub-step position. Against every
box (tool boxes and walls):

* if that relative segment crosses the box itself (slab test), the sphere is pushed out through the
  face it entered by (the nearest face if it starts inside), whatever its depth, so it cannot pass
  through a thin blade or wall at any speed (tested with the blade moving 8 cm, two diameters, per
  sub-step);
* otherwise the ordinary closest-point contact of a sphere with a box (rounded edges) applies.

Tool capsules (handles) use the closest-point contact only: crossing one needs a relative motion of
r + capsule radius per sub-step (8.6 m/s at 240 Hz for the spade handle).

The loops are compiled by numba (:mod:`toolimit.scenes.spatial.particle_kernels`, cached on disk):
at 200 spheres a batch of 16 instances steps about 2,900 instance control steps per CPU second on
one core, against 600 for the former vectorised numpy version (``benchmarks/spatial_scene_speed.py``).
Results are deterministic on one machine (same inputs, same numbers).

Frames and units: world frame, metres, seconds, z up, ground z = 0, gravity -z. Array axis 0 is
the instance (batch).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numba
import numpy as np

from toolimit.scenes.spatial import particle_kernels as kernels
from toolimit.scenes.spatial.tool_geometry import ToolShapes
from toolimit.scenes.spatial.tool_motion import interpolate_poses

#: Standard gravity, m/s^2.
GRAVITY = 9.81


@dataclass(frozen=True)
class GranularMaterial:
    """Physical and numerical constants of the sphere material.

    Attributes:
        radius: sphere radius, m.
        mu_static, mu_kinetic: Coulomb coefficients of sphere-sphere contacts; atan(0.6) = 31
            degrees is close to dry sand's angle of repose.
        tool_mu_static, tool_mu_kinetic: sphere-tool contacts.
        ground_mu_static, ground_mu_kinetic: sphere-ground contacts.
        wall_mu_static, wall_mu_kinetic: sphere-wall contacts.
        sleep_speed: speed (m/s) under which a sphere sleeps (see the module docstring).
        mass_scaling: k (1/m) of the height-dependent mass scaling m* = m exp(-k z).
        relaxation: omega of the averaged Jacobi sphere-sphere solve.
        pair_margin: Verlet-list skin (m).
        freeze_after_substeps: island sleeping: after this many consecutive sub-steps in which every
            sphere of an instance slept, an instance the tool does not reach is not simulated
            (module docstring); None turns it off.
        max_speed: cap (m/s) on the velocity a sphere carries from one sub-step to the next (the
            original PhysX scene caps its spheres at 1 m/s); None for no cap.
    """

    radius: float = 0.02
    mu_static: float = 0.6
    mu_kinetic: float = 0.5
    tool_mu_static: float = 0.6
    tool_mu_kinetic: float = 0.5
    ground_mu_static: float = 0.6
    ground_mu_kinetic: float = 0.5
    wall_mu_static: float = 0.6
    wall_mu_kinetic: float = 0.5
    sleep_speed: float = 0.01
    mass_scaling: float = 10.0
    relaxation: float = 1.5
    pair_margin: float = 0.02
    freeze_after_substeps: int | None = 24
    max_speed: float | None = None

    def __post_init__(self) -> None:
        for name in ("radius", "sleep_speed", "pair_margin"):
            if not getattr(self, name) > 0:
                raise ValueError(f"GranularMaterial.{name} must be positive, got {getattr(self, name)!r}")
        for prefix in ("", "tool_", "ground_", "wall_"):
            static, kinetic = getattr(self, f"{prefix}mu_static"), getattr(self, f"{prefix}mu_kinetic")
            if not 0 <= kinetic <= static:
                raise ValueError(f"need 0 <= {prefix}mu_kinetic <= {prefix}mu_static, got {kinetic!r}, {static!r}")
        if not 0 < self.relaxation < 2:
            raise ValueError(f"GranularMaterial.relaxation must be in (0, 2), got {self.relaxation!r}")
        if self.freeze_after_substeps is not None and self.freeze_after_substeps < 1:
            raise ValueError(f"freeze_after_substeps must be None or >= 1, got {self.freeze_after_substeps!r}")
        if self.max_speed is not None and not self.max_speed > 0:
            raise ValueError(f"GranularMaterial.max_speed must be None or positive, got {self.max_speed!r}")

    def coefficients(self) -> np.ndarray:
        """The constants as the kernels' vector (indices in :mod:`particle_kernels`)."""
        values = np.zeros(kernels.N_COEFFICIENTS)
        values[kernels.RADIUS] = self.radius
        values[kernels.MU_SPHERE_S], values[kernels.MU_SPHERE_K] = self.mu_static, self.mu_kinetic
        values[kernels.MU_TOOL_S], values[kernels.MU_TOOL_K] = self.tool_mu_static, self.tool_mu_kinetic
        values[kernels.MU_GROUND_S], values[kernels.MU_GROUND_K] = self.ground_mu_static, self.ground_mu_kinetic
        values[kernels.MU_WALL_S], values[kernels.MU_WALL_K] = self.wall_mu_static, self.wall_mu_kinetic
        values[kernels.MASS_SCALING], values[kernels.RELAXATION] = self.mass_scaling, self.relaxation
        values[kernels.SLEEP_SPEED], values[kernels.PAIR_MARGIN] = self.sleep_speed, self.pair_margin
        values[kernels.MAX_SPEED] = 0.0 if self.max_speed is None else self.max_speed
        values[kernels.GRAVITY] = GRAVITY
        return values


@dataclass(frozen=True)
class StaticBoxes:
    """Fixed oriented boxes (walls), world frame: shared by all instances, or one set per instance
    (a leading batch axis B: the spade's goal box placed per instance).

    Attributes:
        centers: (K, 3) or (B, K, 3) m. rotations: (K, 3, 3) or (B, K, 3, 3) box axes as columns.
        half_extents: (K, 3) or (B, K, 3) m.
    """

    centers: np.ndarray
    rotations: np.ndarray
    half_extents: np.ndarray


def _box_bounds(centers: np.ndarray, rotations: np.ndarray, half_extents: np.ndarray, radius: float) -> np.ndarray:
    """(..., K, 2, 3) axis-aligned lower and upper bounds of oriented boxes (..., K, ...) grown by
    ``radius``, in the frame their centres and rotations are given in (m)."""
    reach = np.einsum("...ij,...j->...i", np.abs(rotations), half_extents) + radius
    return np.stack([centers - reach, centers + reach], axis=-2)


def checked_threads(threads: int) -> int:
    """``threads`` if it is an integer in 1..numba's ``NUMBA_NUM_THREADS``; else ValueError."""
    if not isinstance(threads, numbers.Integral) or not 1 <= threads <= numba.config.NUMBA_NUM_THREADS:
        raise ValueError(f"threads must be an integer in 1..{numba.config.NUMBA_NUM_THREADS}, got {threads!r}")
    return int(threads)


#: Initial capacity of each instance's Verlet list, in pairs per sphere (grown when exceeded).
_PAIRS_PER_SPHERE = 16


class ParticleWorld:
    """B instances of N spheres with ground, static boxes and a kinematic tool.

    Args:
        material: sphere constants.
        static_boxes: walls (world frame), shared or per instance (then B must match the
            ``reset`` positions'), or None.
        tool: the tool's shapes (tool frame) or None for no tool.
        threads: threads sharing out the instances at each step (numba's, at most its
            ``NUMBA_NUM_THREADS``, the cores by default); the same numbers whatever their count:
            instances share nothing.

    State (public, world frame): ``positions`` (B, N, 3) m, ``velocities`` (B, N, 3) m/s; the tool
    pose ``tool_position`` (B, 3), ``tool_rotation`` (B, 3, 3) or None before it is placed.
    """

    def __init__(
        self,
        material: GranularMaterial,
        static_boxes: StaticBoxes | None,
        tool: ToolShapes | None,
        threads: int = 1,
    ):
        self.threads = checked_threads(threads)
        self.material = material
        self.static_boxes = static_boxes
        self.tool = tool
        self._coefficients = material.coefficients()
        self._freeze_after = 0 if material.freeze_after_substeps is None else int(material.freeze_after_substeps)
        walls = (
            static_boxes
            if static_boxes is not None
            else StaticBoxes(np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros((0, 3)))
        )
        #: The walls' centers, rotations, half extents and bounds, per instance once reset.
        self._wall_arrays = (
            walls.centers,
            walls.rotations,
            walls.half_extents,
            _box_bounds(walls.centers, walls.rotations, walls.half_extents, material.radius),
        )
        self._walls: tuple[np.ndarray, ...] = ()  # the wall arrays per instance (B, K, ...), set by reset
        self.positions = np.zeros((0, 0, 3))
        self.velocities = np.zeros((0, 0, 3))
        self._carried = np.zeros((0, 0, 3))  # velocity the solver predicts with (see the module docstring)
        self.tool_position: np.ndarray | None = None
        self.tool_rotation: np.ndarray | None = None
        self._built_at = np.zeros((0, 0, 3))  # positions when each instance's Verlet list was built
        self._pairs = np.zeros((0, 0, 2), dtype=np.int64)  # (B, capacity, 2) candidate pairs i < j
        self._n_pairs = np.zeros(0, dtype=np.int64)  # (B,) listed pairs; -1: rebuild
        self._resting = np.zeros(0, dtype=np.int64)  # (B,) consecutive sub-steps with no sphere awake
        if tool is not None:
            corners = np.array(np.meshgrid([-1.0, 1.0], [-1.0, 1.0], [-1.0, 1.0])).reshape(3, -1).T  # (8, 3)
            box_corners = tool.box_centers[:, None] + (corners * tool.box_half_extents[:, None]) @ np.swapaxes(
                tool.box_rotations, -1, -2
            )
            caps = np.concatenate([tool.capsule_starts, tool.capsule_ends])
            caps_radius = np.concatenate([tool.capsule_radii, tool.capsule_radii])[:, None]
            points = np.concatenate([box_corners.reshape(-1, 3), caps - caps_radius, caps + caps_radius])
            low = points.min(axis=0) - material.radius
            high = points.max(axis=0) + material.radius
            bounds = _box_bounds(tool.box_centers, tool.box_rotations, tool.box_half_extents, material.radius)
            arrays = (
                tool.box_centers,
                tool.box_rotations,
                tool.box_half_extents,
                bounds,
                tool.capsule_starts,
                tool.capsule_ends,
                tool.capsule_radii,
                low,
                high,
            )
        else:
            arrays = (
                np.zeros((0, 3)),
                np.zeros((0, 3, 3)),
                np.zeros((0, 3)),
                np.zeros((0, 2, 3)),
                np.zeros((0, 3)),
                np.zeros((0, 3)),
                np.zeros(0),
                np.zeros(3),
                np.zeros(3),
            )
        #: Tool shapes as the kernels take them (tool frame) and the tool's bounds grown by r.
        self._tool_arrays = tuple(np.ascontiguousarray(a, dtype=float) for a in arrays)

    # ----------------------------------------------------------------------------------------- state
    def reset(self, positions: np.ndarray, velocities: np.ndarray | None = None) -> None:
        """Start from spheres at ``positions`` (B, N, 3) with ``velocities`` (B, N, 3) (default rest), no tool."""
        positions = np.asarray(positions, dtype=float)
        if positions.ndim != 3 or positions.shape[-1] != 3:
            raise ValueError(f"positions must have shape (B, N, 3), got {positions.shape}")
        velocities = np.zeros_like(positions) if velocities is None else np.asarray(velocities, dtype=float)
        if velocities.shape != positions.shape:
            raise ValueError(f"velocities must have the shape of positions {positions.shape}, got {velocities.shape}")
        b, n, _ = positions.shape
        shared = self._wall_arrays[0].ndim == 2
        if not shared and len(self._wall_arrays[0]) != b:
            raise ValueError(f"per-instance walls are for {len(self._wall_arrays[0])} instances, positions for {b}")
        self._walls = tuple(
            np.ascontiguousarray(np.broadcast_to(a, (b, *a.shape)) if shared else a, dtype=float)
            for a in self._wall_arrays
        )
        self.positions = np.ascontiguousarray(positions).copy()
        self.velocities = np.ascontiguousarray(velocities).copy()
        self._carried = self.velocities.copy()
        self.tool_position = None
        self.tool_rotation = None
        self._built_at = self.positions.copy()
        self._pairs = np.zeros((b, _PAIRS_PER_SPHERE * max(n, 1), 2), dtype=np.int64)
        self._n_pairs = np.full(b, -1, dtype=np.int64)
        self._resting = np.zeros(b, dtype=np.int64)

    @property
    def batch_size(self) -> int:
        return self.positions.shape[0]

    @property
    def n_spheres(self) -> int:
        return self.positions.shape[1]

    def kinetic_energy(self) -> np.ndarray:
        """(B,) sum of v^2 / 2 over spheres, J per kg of one sphere's mass."""
        return 0.5 * np.sum(self.velocities**2, axis=(1, 2))

    def candidate_pairs(self, instance: int) -> np.ndarray:
        """(P, 2) sphere index pairs (i < j) of instance ``instance``'s current Verlet list."""
        return self._pairs[instance, : max(int(self._n_pairs[instance]), 0)].copy()

    def _grow_pairs(self) -> None:
        """Double the Verlet lists' capacity (a kernel found one too small: its instance, marked -1,
        is rebuilt). The other instances keep their lists as they are, so that an instance's
        physics does not depend on the others in its batch (nor on how a batch is split)."""
        b, capacity, _ = self._pairs.shape
        grown = np.zeros((b, 2 * capacity, 2), dtype=np.int64)
        grown[:, :capacity] = self._pairs
        self._pairs = grown

    def update_pairs(self) -> None:
        """Bring the Verlet lists up to date (the solver does it at every sub-step)."""
        while not kernels.update_pairs(self.positions, self._built_at, self._pairs, self._n_pairs, self._coefficients):
            self._grow_pairs()

    # ------------------------------------------------------------------------------------------ tool
    def place_tool(self, position: np.ndarray, rotation: np.ndarray, iterations: int = 20) -> None:
        """Put the tool at (B, 3), (B, 3, 3) without velocity.

        In each instance where the tool overlaps spheres, they are moved out of it (a centre inside a box leaves through
        the nearest face), and the overlaps this makes are relaxed by ``iterations`` position-only
        passes over all contacts (the pre-stabilisation of Macklin et al.): positions change,
        velocities do not, as if the spheres had been there before. Static surfaces win here too.
        """
        self.tool_position = np.ascontiguousarray(position, dtype=float).copy()
        self.tool_rotation = np.ascontiguousarray(rotation, dtype=float).copy()
        if self.tool is None:
            return
        local = (self.positions - self.tool_position[:, None]) @ self.tool_rotation
        low, high = self._tool_arrays[-2:]
        touched = np.any(np.all((local > low) & (local < high), axis=-1), axis=1)  # (B,)
        if not np.any(touched):
            return  # nothing near the tool: leave the spheres exactly where they are
        self._resting[touched] = 0  # the other instances' spheres stay exactly where they are
        while not kernels.place(
            self.positions,
            self._built_at,
            self._pairs,
            self._n_pairs,
            touched,
            int(iterations),
            self.tool_position,
            self.tool_rotation,
            self._tool_arrays,
            self._walls,
            self._coefficients,
        ):
            self._grow_pairs()

    # ------------------------------------------------------------------------------------- simulation
    def advance(
        self, duration: float, substeps: int, position: np.ndarray | None = None, rotation: np.ndarray | None = None
    ) -> None:
        """Simulate ``duration`` seconds in ``substeps`` sub-steps.

        The tool (if placed) moves at constant velocity from its current pose to ``position``
        (B, 3), ``rotation`` (B, 3, 3) over the duration; without a new pose it stays still.
        """
        h = duration / substeps
        b = self.batch_size
        start_position, start_rotation = self.tool_position, self.tool_rotation
        has_tool = self.tool is not None and start_position is not None and start_rotation is not None
        if has_tool:
            assert start_position is not None and start_rotation is not None
            end_position = start_position if position is None else np.asarray(position, dtype=float)
            end_rotation = start_rotation if rotation is None else np.asarray(rotation, dtype=float)
            if position is None and rotation is None:
                path_positions = np.broadcast_to(start_position, (substeps + 1, b, 3))
                path_rotations = np.broadcast_to(start_rotation, (substeps + 1, b, 3, 3))
            else:
                path_positions, path_rotations = interpolate_poses(
                    start_position, start_rotation, end_position, end_rotation, np.linspace(0.0, 1.0, substeps + 1)
                )
            self.tool_position = np.ascontiguousarray(end_position).copy()
            self.tool_rotation = np.ascontiguousarray(end_rotation).copy()
        else:
            path_positions = np.zeros((substeps + 1, b, 3))
            path_rotations = np.broadcast_to(np.eye(3), (substeps + 1, b, 3, 3))
        path_positions = np.ascontiguousarray(path_positions, dtype=float)
        path_rotations = np.ascontiguousarray(path_rotations, dtype=float)
        progress = np.zeros(b, dtype=np.int64)  # (B,) each instance's next sub-step
        kernel = kernels.advance
        if self.threads > 1:
            kernel = kernels.advance_on_threads
            numba.set_num_threads(self.threads)
            numba.set_parallel_chunksize(1)  # instances one at a time: their costs differ
        while True:
            kernel(
                self.positions,
                self._carried,
                self.velocities,
                self._built_at,
                self._pairs,
                self._n_pairs,
                self._resting,
                progress,
                h,
                has_tool,
                path_positions,
                path_rotations,
                self._tool_arrays,
                self._walls,
                self._coefficients,
                self._freeze_after,
            )
            if np.all(progress == substeps):
                return
            self._grow_pairs()
