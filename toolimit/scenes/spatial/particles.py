"""Batched granular material: B instances x N equal spheres, position-based dynamics with friction.

The scheme is the particle solver of Macklin, Mueller, Chentanez, Kim, "Unified particle physics
for real-time applications", ACM TOG 33(4), 2014 (SIGGRAPH; its "Algorithm 1" simulation loop),
restricted to rigid, non-rotating spheres of one radius r:

* each sub-step of length h: v += g h; predicted x* = x + h v;
* contact constraints, one pass per sub-step ("small steps" rather than iterations), in groups
  solved one after the other (Gauss-Seidel between groups): sphere-sphere, ground plane z = 0,
  static oriented boxes (walls), then the kinematic tool (boxes and capsules) last, so that the
  tool always wins;
* sphere-sphere contacts are solved Jacobi-style for all pairs at once, each sphere's summed
  correction divided by its number of contacts and scaled by an over-relaxation factor omega (the
  paper's constraint averaging with SOR), with the paper's height-dependent **mass scaling**
  m*_i = m exp(-k z_i) for contacts (its "shock propagation" for stacks), so piles converge in one
  pass per sub-step;
* **Coulomb friction by position** (the paper's friction model): the tangential displacement of a
  sphere relative to the surface over the sub-step, dx_t, is cancelled when |dx_t| < mu_s d
  (static; d is the penetration resolved), otherwise reduced by mu_k d (kinetic). A sphere at rest
  on a slope of angle theta stays while tan(theta) < mu_s; once sliding it accelerates while
  tan(theta) > mu_k. With mu_s = 0.6, mu_k = 0.5 a loaded blade keeps its sand below 26.6 degrees
  (atan mu_k) and spills above 31 degrees (atan mu_s) (tests/scenes/test_particles.py);
* v = (x* - x) / h, then **particle sleeping** (the last line of the paper's Algorithm 1): a sphere
  whose sub-step speed is below ``sleep_speed`` (1 cm/s) keeps its position. This removes the
  residual jitter of the one-pass Jacobi solve, so piles at rest stay exactly at rest. Only the
  position update is skipped: the solver carries the sub-step's velocity, so a sphere that
  accelerates slowly (a slide just past the friction angle, an unsupported sphere: g h = 4 cm/s at
  240 Hz) wakes within a few sub-steps; a slow push can hide at most ``sleep_speed * h`` (0.04 mm)
  of penetration. Sleepers report zero velocity.
* **island sleeping** (as in rigid-body engines): when every sphere of the batch has slept for
  ``freeze_after_substeps`` sub-steps (24: 0.1 s at 240 Hz) and the tool's bounds reach no
  sphere, the sub-step is skipped: the sand is exactly at rest. Only accelerations below
  ``sleep_speed / (freeze_after_substeps h)`` (0.1 m/s^2) could have woken it later; a sphere
  starting to slide past the friction angle accelerates at 0.85 m/s^2 or more;
* ``ParticleWorld.place_tool`` puts the tool down without velocity: overlapped spheres are pushed
  out by position-only passes (the paper's pre-stabilisation of initial overlaps).

The spheres do not rotate (like sand grains with strong rolling resistance: the paper's PhysX scene
gave its spheres an angular damping of 500 for the same reason).

Broad phase: sphere-sphere and sphere-wall candidate pairs come from Verlet lists (pairs closer
than the contact distance plus ``pair_margin``); the rows of a sphere that has moved more than
``pair_margin / 2`` since they were built are rebuilt, so no contact is missed; tool candidates
are the spheres whose relative segment's bounding box meets the tool's, then each box's, in the
tool frame.

**No tunnelling.** The tool moves at constant velocity within each sub-step (straight line for the
head point, geodesic rotation); spheres against the tool are solved in the tool frame, where the
sphere's centre moves from its start-of-sub-step to its end-of-sub-step position. Against every
box (tool boxes and walls):

* if that relative segment crosses the box itself (slab test), the sphere is pushed out through the
  face it entered by, whatever its depth, so it cannot pass through a thin blade or wall at any
  speed (tested with the blade moving 8 cm, two diameters, per sub-step);
* otherwise the ordinary closest-point contact of a sphere with a box (rounded edges) applies.

Tool capsules (handles) use the closest-point contact only: crossing one needs a relative motion of
r + capsule radius per sub-step (8.6 m/s at 240 Hz for the spade handle).

Frames and units: world frame, metres, seconds, z up, ground z = 0, gravity -z. Array axis 0 is
the instance (batch).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from toolimit.scenes.spatial.shapes import segment_closest_points
from toolimit.scenes.spatial.tool_geometry import ToolShapes
from toolimit.scenes.spatial.tool_motion import interpolate_poses

#: Standard gravity, m/s^2.
GRAVITY = 9.81


@dataclass(frozen=True)
class GranularMaterial:
    """Physical and numerical constants of the sphere material.

    Attributes:
        radius: sphere radius, m.
        mu_static, mu_kinetic: Coulomb coefficients for every contact (sphere, ground, walls,
            tool); atan(0.6) = 31 degrees is close to dry sand's angle of repose.
        sleep_speed: speed (m/s) under which a sphere sleeps (see the module docstring).
        mass_scaling: k (1/m) of the height-dependent mass scaling m* = m exp(-k z).
        relaxation: omega of the averaged Jacobi sphere-sphere solve.
        pair_margin: Verlet-list skin (m).
        freeze_after_substeps: island sleeping: after this many consecutive sub-steps in which every
            sphere slept, a batch the tool does not reach is not simulated (module docstring);
            None turns it off.
    """

    radius: float = 0.02
    mu_static: float = 0.6
    mu_kinetic: float = 0.5
    sleep_speed: float = 0.01
    mass_scaling: float = 10.0
    relaxation: float = 1.5
    pair_margin: float = 0.02
    freeze_after_substeps: int | None = 24

    def __post_init__(self) -> None:
        for name in ("radius", "sleep_speed", "pair_margin"):
            if not getattr(self, name) > 0:
                raise ValueError(f"GranularMaterial.{name} must be positive, got {getattr(self, name)!r}")
        if not 0 <= self.mu_kinetic <= self.mu_static:
            raise ValueError(f"need 0 <= mu_kinetic <= mu_static, got {self.mu_kinetic!r}, {self.mu_static!r}")
        if not 0 < self.relaxation < 2:
            raise ValueError(f"GranularMaterial.relaxation must be in (0, 2), got {self.relaxation!r}")
        if self.freeze_after_substeps is not None and self.freeze_after_substeps < 1:
            raise ValueError(f"freeze_after_substeps must be None or >= 1, got {self.freeze_after_substeps!r}")


@dataclass(frozen=True)
class StaticBoxes:
    """Fixed oriented boxes shared by all instances (walls), world frame.

    Attributes:
        centers: (K, 3) m. rotations: (K, 3, 3) box axes as columns. half_extents: (K, 3) m.
    """

    centers: np.ndarray
    rotations: np.ndarray
    half_extents: np.ndarray


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products (...,) of vectors (..., 3): einsum is several times faster than sum(a * b, -1)."""
    return np.einsum("...i,...i->...", a, b)


def _friction(relative: np.ndarray, normal: np.ndarray, depth: np.ndarray, material: GranularMaterial) -> np.ndarray:
    """Position correction (..., 3) that applies Coulomb friction to a relative displacement.

    relative: (..., 3) displacement of the sphere relative to the surface over the sub-step, m;
    normal: (..., 3) unit contact normal; depth: (...,) penetration resolved, m (>= 0).
    Returns minus the tangential displacement (static) or its part cancelled by kinetic friction.
    """
    tangential = relative - _dot(relative, normal)[..., None] * normal
    slip = np.sqrt(_dot(tangential, tangential))
    static = slip < material.mu_static * depth
    scale = np.where(static, 1.0, np.minimum(material.mu_kinetic * depth / np.maximum(slip, 1e-15), 1.0))
    return -tangential * scale[..., None]


def _box_contacts(
    start_local: np.ndarray,
    end_local: np.ndarray,
    half_extents: np.ndarray,
    material: GranularMaterial,
    swept: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position corrections of spheres against boxes, in each box's local frame.

    start_local, end_local: (..., 3) sphere centres at the sub-step's start and end, each in the
    box's frame at that instant (so their difference is the motion relative to the box);
    half_extents: (..., 3) broadcastable. Returns the normal push-out (..., 3) and the friction
    correction (..., 3) to add to ``end_local`` (zero without contact), and a (...,) bool mask.
    ``swept``: also catch segments that cross the box (see the module docstring).
    """
    radius = material.radius
    closest = np.clip(end_local, -half_extents, half_extents)
    offset = end_local - closest
    distance = np.sqrt(_dot(offset, offset))
    contact = distance < radius
    normal = offset / np.maximum(distance, 1e-15)[..., None]
    depth = radius - distance
    if swept:
        # Slab test of the segment start -> end against the box itself: entry parameter per axis.
        motion = end_local - start_local
        motion = np.where(np.abs(motion) < 1e-12, 1e-12, motion)
        t_low = (-half_extents - start_local) / motion
        t_high = (half_extents - start_local) / motion
        t_entry_axis = np.minimum(t_low, t_high)
        t_entry = np.max(t_entry_axis, axis=-1)
        t_exit = np.min(np.maximum(t_low, t_high), axis=-1)
        crossed = (t_entry <= t_exit) & (t_exit >= 0.0) & (t_entry <= 1.0)
        # The face entered by: the axis where the start is most outside (deepest-face axis if inside).
        face = np.argmax(np.abs(start_local) - half_extents, axis=-1)[..., None] == np.arange(3)  # one-hot
        face_normal = np.where(start_local >= 0.0, 1.0, -1.0) * face
        face_depth = _dot(face_normal, (half_extents + radius) * face_normal - end_local)
        normal = np.where(crossed[..., None], face_normal, normal)
        depth = np.where(crossed, face_depth, depth)
        contact = contact | crossed
    depth = np.where(contact, np.maximum(depth, 0.0), 0.0)
    push = normal * depth[..., None]
    friction = np.where(contact[..., None], _friction(end_local + push - start_local, normal, depth, material), 0.0)
    return push, friction, contact


def _scatter_box_contacts(
    start_local: np.ndarray,
    end_local: np.ndarray,
    half_extents: np.ndarray,
    to_frame: np.ndarray | None,
    sphere: np.ndarray,
    n_total: int,
    material: GranularMaterial,
    swept: bool,
) -> np.ndarray:
    """Correction (n_total, 3) of sphere centres from P candidate sphere-box pairs.

    start_local, end_local, half_extents: (P, 3) as in :func:`_box_contacts`; to_frame: (P, 3, 3)
    box axes (columns) in the frame the correction is wanted in, or None if they are that frame's
    axes; sphere: (P,) flat sphere index of each pair. Normal pushes are summed over a sphere's
    boxes (faces meeting at an edge are orthogonal), friction corrections averaged.
    """
    push, friction, contact = _box_contacts(start_local, end_local, half_extents, material, swept)
    if to_frame is not None:
        back = np.swapaxes(to_frame, -1, -2)
        push, friction = (push[:, None] @ back)[:, 0], (friction[:, None] @ back)[:, 0]
    count = np.maximum(np.bincount(sphere, contact, minlength=n_total), 1.0)
    correction = np.empty((n_total, 3))
    for axis in range(3):
        correction[:, axis] = np.bincount(sphere, push[:, axis], minlength=n_total) + np.bincount(
            sphere, friction[:, axis], minlength=n_total
        ) / count
    return correction


class ParticleWorld:
    """B instances of N spheres with ground, static boxes and a kinematic tool.

    Args:
        material: sphere constants.
        static_boxes: walls shared by all instances (world frame), or None.
        tool: the tool's shapes (tool frame) or None for no tool.

    State (public, world frame): ``positions`` (B, N, 3) m, ``velocities`` (B, N, 3) m/s; the tool
    pose ``tool_position`` (B, 3), ``tool_rotation`` (B, 3, 3) or None before it is placed.
    """

    def __init__(self, material: GranularMaterial, static_boxes: StaticBoxes | None, tool: ToolShapes | None):
        self.material = material
        self.static_boxes = static_boxes
        self.tool = tool
        self.positions = np.zeros((0, 0, 3))
        self.velocities = np.zeros((0, 0, 3))
        self._carried = np.zeros((0, 0, 3))  # velocity the solver predicts with (see _substep)
        self.tool_position: np.ndarray | None = None
        self.tool_rotation: np.ndarray | None = None
        self._built_at: np.ndarray | None = None  # (B N, 3) positions when each sphere's rows were built
        self._pair_i = np.zeros(0, dtype=np.intp)
        self._pair_j = np.zeros(0, dtype=np.intp)
        self._pair_index = np.zeros(0, dtype=np.intp)  # _pair_i then _pair_j
        self._upper = np.zeros((0, 0), dtype=bool)  # strict upper triangle of an N x N matrix
        self._wall_sphere = np.zeros(0, dtype=np.intp)  # candidate (sphere, static box) pairs
        self._wall_box = np.zeros(0, dtype=np.intp)
        self._resting_substeps = 0  # consecutive sub-steps in which no sphere was awake
        if tool is not None:
            corners = np.array(np.meshgrid([-1.0, 1.0], [-1.0, 1.0], [-1.0, 1.0])).reshape(3, -1).T  # (8, 3)
            box_corners = tool.box_centers[:, None] + (corners * tool.box_half_extents[:, None]) @ np.swapaxes(
                tool.box_rotations, -1, -2
            )
            caps = np.concatenate([tool.capsule_starts, tool.capsule_ends])
            caps_radius = np.concatenate([tool.capsule_radii, tool.capsule_radii])[:, None]
            points = np.concatenate([box_corners.reshape(-1, 3), caps - caps_radius, caps + caps_radius])
            #: Bounds (3,) of the whole tool in its frame, grown by the sphere radius, for the broad phase.
            self._tool_low = points.min(axis=0) - material.radius
            self._tool_high = points.max(axis=0) + material.radius
            self._tool_boxes_aligned = bool(np.all(tool.box_rotations == np.eye(3)))

    # ----------------------------------------------------------------------------------------- state
    def reset(self, positions: np.ndarray, velocities: np.ndarray | None = None) -> None:
        """Start from spheres at ``positions`` (B, N, 3) with ``velocities`` (B, N, 3) (default rest), no tool."""
        positions = np.asarray(positions, dtype=float)
        if positions.ndim != 3 or positions.shape[-1] != 3:
            raise ValueError(f"positions must have shape (B, N, 3), got {positions.shape}")
        velocities = np.zeros_like(positions) if velocities is None else np.asarray(velocities, dtype=float)
        if velocities.shape != positions.shape:
            raise ValueError(f"velocities must have the shape of positions {positions.shape}, got {velocities.shape}")
        self.positions = positions.copy()
        self.velocities = velocities.copy()
        self._carried = velocities.copy()
        self.tool_position = None
        self.tool_rotation = None
        self._built_at = None
        self._resting_substeps = 0

    @property
    def batch_size(self) -> int:
        return self.positions.shape[0]

    @property
    def n_spheres(self) -> int:
        return self.positions.shape[1]

    def kinetic_energy(self) -> np.ndarray:
        """(B,) sum of v^2 / 2 over spheres, J per kg of one sphere's mass."""
        return 0.5 * np.sum(self.velocities**2, axis=(1, 2))

    # ------------------------------------------------------------------------------------------ tool
    def place_tool(self, position: np.ndarray, rotation: np.ndarray, iterations: int = 20) -> None:
        """Put the tool at (B, 3), (B, 3, 3) without velocity.

        If the tool overlaps spheres, they are moved out of it (a centre inside a box leaves through
        the nearest face), and the overlaps this makes are relaxed by ``iterations`` position-only
        passes over all contacts (the pre-stabilisation of Macklin et al.): positions change,
        velocities do not, as if the spheres had been there before.
        """
        self.tool_position = np.asarray(position, dtype=float).copy()
        self.tool_rotation = np.asarray(rotation, dtype=float).copy()
        if self.tool is None:
            return
        local = (self.positions - self.tool_position[:, None]) @ self.tool_rotation
        if not np.any(self._tool_contacts(local, local)):
            return  # nothing touches the tool: leave the spheres exactly where they are
        self._resting_substeps = 0
        still = (self.tool_position, self.tool_rotation, self.tool_position, self.tool_rotation)
        for _ in range(iterations):
            self._update_pairs()
            self.positions = self._project(self.positions, self.positions, still)

    def _tool_contacts(self, start: np.ndarray, end: np.ndarray) -> np.ndarray:
        """Correction (B, N, 3) of sphere centres against the tool, tool frame.

        start, end: (B, N, 3) sphere centres in the tool frame at the sub-step's start and end, so
        ``end - start`` is the motion relative to the tool. Broad phase: spheres whose segment's
        bounding box meets the tool's; then every candidate against each box (swept) whose grown
        bounds its segment meets, then against the capsules.
        """
        assert self.tool is not None
        tool, material, r = self.tool, self.material, self.material.radius
        b, n, _ = end.shape
        correction = np.zeros((b * n, 3))
        start, end = start.reshape(-1, 3), end.reshape(-1, 3)
        low, high = np.minimum(start, end), np.maximum(start, end)
        (candidates,) = np.nonzero(np.all((low < self._tool_high) & (high > self._tool_low), axis=-1))
        if not candidates.size:
            return correction.reshape(b, n, 3)
        start, end = start[candidates], end[candidates]  # (M, 3)
        box_start = start[:, None] - tool.box_centers  # (M, K, 3)
        box_end = end[:, None] - tool.box_centers
        if not self._tool_boxes_aligned:
            box_start = (box_start[..., None, :] @ tool.box_rotations)[..., 0, :]
            box_end = (box_end[..., None, :] @ tool.box_rotations)[..., 0, :]
        reach = tool.box_half_extents + r
        near = np.all((np.minimum(box_start, box_end) < reach) & (np.maximum(box_start, box_end) > -reach), axis=-1)
        sphere, box = np.nonzero(near)
        moved = np.zeros((candidates.size, 3))
        if sphere.size:
            moved = _scatter_box_contacts(
                box_start[sphere, box], box_end[sphere, box], tool.box_half_extents[box],
                None if self._tool_boxes_aligned else tool.box_rotations[box], sphere, candidates.size, material,
                swept=True,
            )
        if len(tool.capsule_radii):
            moved = moved + self._capsule_contacts(start, end + moved, material)
        correction[candidates] = moved
        return correction.reshape(b, n, 3)

    def _capsule_contacts(self, start: np.ndarray, end: np.ndarray, material: GranularMaterial) -> np.ndarray:
        """Correction (M, 3) of sphere centres (M, 3) (tool frame, sub-step start and end) against the tool capsules."""
        assert self.tool is not None
        tool, r = self.tool, material.radius
        closest, _ = segment_closest_points(end[:, None], tool.capsule_starts, tool.capsule_ends)  # (M, C, 3)
        offset = end[:, None] - closest
        distance = np.sqrt(_dot(offset, offset))
        depth = tool.capsule_radii + r - distance
        contact = depth > 0.0
        if not np.any(contact):
            return np.zeros_like(end)
        depth = np.where(contact, depth, 0.0)
        normal = offset / np.maximum(distance, 1e-15)[..., None]
        push = normal * depth[..., None]
        friction = _friction(end[:, None] + push - start[:, None], normal, depth, material)
        return np.sum(push, axis=1) + np.sum(friction, axis=1) / np.maximum(np.sum(contact, axis=1), 1)[:, None]

    # ------------------------------------------------------------------------------------- simulation
    def advance(
        self, duration: float, substeps: int, position: np.ndarray | None = None, rotation: np.ndarray | None = None
    ) -> None:
        """Simulate ``duration`` seconds in ``substeps`` sub-steps.

        The tool (if placed) moves at constant velocity from its current pose to ``position``
        (B, 3), ``rotation`` (B, 3, 3) over the duration; without a new pose it stays still.
        """
        h = duration / substeps
        if self.tool is None or self.tool_position is None:
            for _ in range(substeps):
                self._substep(h, None)
            return
        end_position = self.tool_position if position is None else np.asarray(position, dtype=float)
        end_rotation = self.tool_rotation if rotation is None else np.asarray(rotation, dtype=float)
        path_positions, path_rotations = interpolate_poses(
            self.tool_position, self.tool_rotation, end_position, end_rotation, np.linspace(0.0, 1.0, substeps + 1)
        )
        self.tool_position, self.tool_rotation = end_position.copy(), end_rotation.copy()
        for s in range(substeps):
            self._substep(h, (path_positions[s], path_rotations[s], path_positions[s + 1], path_rotations[s + 1]))

    def _update_pairs(self) -> None:
        """Keep the Verlet lists of candidate sphere-sphere and sphere-wall pairs valid.

        Every sphere has a reference position (where its row was last built); lists are decided on
        reference positions: a pair is listed when its references are closer than contact +
        margin. While every sphere stays within margin / 2 of its reference, an unlisted pair
        cannot touch. So the spheres that moved farther get their current position as reference
        and their rows rebuilt (all rows when many moved).
        """
        flat = self.positions.reshape(-1, 3)
        if self._built_at is None or self._built_at.shape != flat.shape:
            self._rebuild_pairs()
            return
        moved = flat - self._built_at
        (stale,) = np.nonzero(_dot(moved, moved) >= (0.5 * self.material.pair_margin) ** 2)
        if not stale.size:
            return
        if stale.size > flat.shape[0] // 4:
            self._rebuild_pairs()
            return
        n = self.positions.shape[1]
        self._built_at[stale] = flat[stale]
        reference = self._built_at
        is_stale = np.zeros(flat.shape[0], dtype=bool)
        is_stale[stale] = True
        keep = ~(is_stale[self._pair_i] | is_stale[self._pair_j])
        # Rows of the stale spheres against every sphere of their instance (each pair once).
        others = (stale // n)[:, None] * n + np.arange(n)  # (S, N) flat indices
        offset = reference[stale][:, None] - reference[others]
        reach = 2.0 * self.material.radius + self.material.pair_margin
        close = (_dot(offset, offset) < reach * reach) & (~is_stale[others] | (others > stale[:, None]))
        row, column = np.nonzero(close)
        self._pair_i = np.concatenate([self._pair_i[keep], stale[row]])
        self._pair_j = np.concatenate([self._pair_j[keep], others[row, column]])
        self._pair_index = np.concatenate([self._pair_i, self._pair_j])
        if self.static_boxes is not None and len(self.static_boxes.centers):
            keep = ~is_stale[self._wall_sphere]
            box, sphere = self._wall_candidates(flat[stale])
            self._wall_box = np.concatenate([self._wall_box[keep], box])
            self._wall_sphere = np.concatenate([self._wall_sphere[keep], stale[sphere]])

    def _rebuild_pairs(self) -> None:
        """Build both Verlet lists from scratch."""
        n = self.positions.shape[1]
        reach = 2.0 * self.material.radius + self.material.pair_margin
        # Squared distances |a|^2 + |b|^2 - 2 a.b (in place, about the instance's mean for precision).
        centred = self.positions - self.positions.mean(axis=1, keepdims=True)
        squared = _dot(centred, centred)
        distance2 = centred @ np.swapaxes(centred, 1, 2)
        distance2 *= -2.0
        distance2 += squared[:, :, None]
        distance2 += squared[:, None, :]
        if self._upper.shape != (n, n):
            self._upper = np.triu(np.ones((n, n), dtype=bool), k=1)
        close = distance2 < reach * reach
        close &= self._upper
        batch, i, j = np.nonzero(close)
        self._pair_i = batch * n + i
        self._pair_j = batch * n + j
        self._pair_index = np.concatenate([self._pair_i, self._pair_j])
        flat = self.positions.reshape(-1, 3)
        if self.static_boxes is not None and len(self.static_boxes.centers):
            self._wall_box, self._wall_sphere = self._wall_candidates(flat)
        self._built_at = flat.copy()

    def _wall_candidates(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(box index, point index) of the points (P, 3) within contact + margin of a static box's bounds."""
        boxes = self.static_boxes
        local = (points[None] - boxes.centers[:, None]) @ boxes.rotations  # (K, P, 3)
        reach = boxes.half_extents[:, None] + self.material.radius + self.material.pair_margin
        return np.nonzero(np.all(np.abs(local) < reach, axis=-1))

    def _pair_contacts(self, previous: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        """Predicted positions (B, N, 3) after one averaged Jacobi pass over the candidate sphere pairs.

        Candidates that do not touch get zero depth, hence zero push and zero friction.
        """
        material, r = self.material, self.material.radius
        b, n, _ = predicted.shape
        flat = predicted.reshape(-1, 3)
        i, j = self._pair_i, self._pair_j
        offset = np.take(flat, i, axis=0) - np.take(flat, j, axis=0)
        distance = np.sqrt(_dot(offset, offset))
        depth = np.maximum(2.0 * r - distance, 0.0)
        touching = depth > 0.0
        if not np.any(touching):
            return predicted
        normal = offset / np.maximum(distance, 1e-15)[:, None]
        inv_mass = np.exp(material.mass_scaling * flat[:, 2])
        inv_mass_i = np.take(inv_mass, i)
        share_i = (inv_mass_i / (inv_mass_i + np.take(inv_mass, j)))[:, None]
        push = normal * depth[:, None]
        # Relative displacement over the sub-step after the normal push, for friction.
        displacement = flat - previous.reshape(-1, 3)
        relative = np.take(displacement, i, axis=0) - np.take(displacement, j, axis=0) + push
        correction = push + _friction(relative, normal, depth, material)
        index = self._pair_index
        weights = np.concatenate([share_i * correction, (share_i - 1.0) * correction])
        count = np.maximum(np.bincount(index, np.concatenate([touching, touching]), minlength=b * n), 1.0)
        scale = material.relaxation / count
        total = np.empty_like(flat)
        for axis in range(3):
            total[:, axis] = np.bincount(index, weights[:, axis], minlength=b * n) * scale
        return (flat + total).reshape(b, n, 3)

    def _project(self, previous: np.ndarray, predicted: np.ndarray,
                 tool: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None) -> np.ndarray:
        """Predicted positions (B, N, 3) after one pass over all contacts (Gauss-Seidel between groups).

        previous: (B, N, 3) positions at the sub-step's start (friction uses the motion since);
        tool: the tool's start position, rotation, end position, rotation (B, ...) or None.
        """
        material, r = self.material, self.material.radius
        if self._pair_i.size:
            predicted = self._pair_contacts(previous, predicted)

        # Ground plane z = 0.
        depth = r - predicted[..., 2]
        on_ground = depth > 0.0
        if np.any(on_ground):
            depth = np.maximum(depth, 0.0)
            corrected = predicted.copy()
            corrected[..., 2] += depth
            friction = _friction(corrected - previous, np.array([0.0, 0.0, 1.0]), depth, material)
            predicted = np.where(on_ground[..., None], corrected + friction, predicted)

        # Static boxes (walls), shared by the instances: candidate pairs from the Verlet list.
        if self._wall_sphere.size:
            boxes = self.static_boxes
            rotations = boxes.rotations[self._wall_box]
            centers = boxes.centers[self._wall_box]
            start = ((previous.reshape(-1, 3)[self._wall_sphere] - centers)[:, None] @ rotations)[:, 0]
            end = ((predicted.reshape(-1, 3)[self._wall_sphere] - centers)[:, None] @ rotations)[:, 0]
            correction = _scatter_box_contacts(
                start, end, boxes.half_extents[self._wall_box], rotations, self._wall_sphere,
                previous.shape[0] * previous.shape[1], material, swept=True,
            )
            predicted = predicted + correction.reshape(predicted.shape)

        # Kinematic tool, in its own frame; solved last so that the tool always wins.
        if tool is not None:
            p0, r0, p1, r1 = tool
            start = (previous - p0[:, None]) @ r0
            end = (predicted - p1[:, None]) @ r1
            predicted = predicted + self._tool_contacts(start, end) @ np.swapaxes(r1, -1, -2)
        return predicted

    def _substep(self, h: float, tool: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None) -> None:
        """One sub-step of length h (s); ``tool`` = start position, rotation, end position, rotation (B, ...)."""
        freeze = self.material.freeze_after_substeps
        if freeze is not None and self._resting_substeps >= freeze and (tool is None or not self._tool_reaches(tool)):
            return  # island sleeping: the whole batch is at rest and untouched
        self._update_pairs()
        previous = self.positions
        self._carried[..., 2] -= GRAVITY * h
        predicted = self._project(previous, previous + h * self._carried, tool)
        displacement = predicted - previous
        awake = _dot(displacement, displacement) >= (self.material.sleep_speed * h) ** 2
        self.positions = np.where(awake[..., None], predicted, previous)
        # Sleeping (Macklin et al., Alg. 1 line 27) skips only the position update: the solver keeps
        # the sub-step's velocity, so a slowly accelerating sphere (a slide starting just past the
        # friction angle) builds speed and wakes; the reported velocity of a sleeper is zero.
        self._carried = displacement / h
        self.velocities = np.where(awake[..., None], self._carried, 0.0)
        self._resting_substeps = 0 if np.any(awake) else self._resting_substeps + 1

    def _tool_reaches(self, tool: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> bool:
        """Whether any (resting) sphere meets the tool's grown bounds at the sub-step's start or end,
        or between (the bounding box of its motion relative to the tool)."""
        p0, r0, p1, r1 = tool
        start = (self.positions - p0[:, None]) @ r0
        end = (self.positions - p1[:, None]) @ r1
        low, high = np.minimum(start, end), np.maximum(start, end)
        return bool(np.any(np.all((low < self._tool_high) & (high > self._tool_low), axis=-1)))
