"""Physical behaviour of the batched particle solver (small N, B = 1, short horizons)."""

from __future__ import annotations

import numpy as np
import pytest

from toolimit.scenes.spatial.particles import (
    GRAVITY,
    GranularMaterial,
    ParticleWorld,
    StaticBoxes,
)
from toolimit.scenes.spatial.tool_geometry import (
    SPADE_BLADE_LENGTH,
    SPADE_BLADE_WIDTH,
    SPADE_RIM_HEIGHT,
    tool_shapes,
)

DT = 1.0 / 24.0
MATERIAL = GranularMaterial()
R = MATERIAL.radius


def spade_rotation(elevation: float) -> np.ndarray:
    """Spade frame with its axis in the world y-z plane (handle towards +y), the handle end
    ``elevation`` rad above the tip, carrying face up."""
    c, s = np.cos(elevation), np.sin(elevation)
    z, x = np.array([0.0, c, s]), np.array([0.0, -s, c])
    return np.stack([x, np.cross(z, x), z], axis=1)


def pen(inner: float, height: float, thickness: float = 0.01) -> StaticBoxes:
    """Four walls around the square [-inner/2, inner/2]^2 on the ground."""
    h, t = inner / 2, thickness
    centers = np.array([[-h - t / 2, 0, height / 2], [h + t / 2, 0, height / 2],
                        [0, -h - t / 2, height / 2], [0, h + t / 2, height / 2]])
    halves = np.array([[t / 2, h + t, height / 2], [t / 2, h + t, height / 2],
                       [h, t / 2, height / 2], [h, t / 2, height / 2]])
    return StaticBoxes(centers, np.repeat(np.eye(3)[None], 4, 0), halves)


def on_blade(world: ParticleWorld) -> np.ndarray:
    """(B, N) bool: sphere centres over the spade's carrying face, inside its rim (tool frame)."""
    local = (world.positions - world.tool_position[:, None]) @ world.tool_rotation
    return ((local[..., 0] > 0) & (local[..., 0] < SPADE_RIM_HEIGHT + R) & (np.abs(local[..., 1]) < SPADE_BLADE_WIDTH / 2)
            & (local[..., 2] > 0) & (local[..., 2] < SPADE_BLADE_LENGTH))


def test_single_sphere_falls_with_g() -> None:
    world = ParticleWorld(MATERIAL, None, None)
    world.reset(np.array([[[0.1, -0.2, 1.0]]]))
    substeps = 10
    h = DT / substeps
    for k in range(1, 9):
        world.advance(DT, substeps)
        t = k * DT
        expected = 1.0 - 0.5 * GRAVITY * t * t
        # Semi-implicit Euler lags the exact parabola by g h t / 2 (first order in h).
        assert abs(world.positions[0, 0, 2] - expected) <= 0.5 * GRAVITY * h * t + 1e-9
        assert world.velocities[0, 0, 2] == pytest.approx(-GRAVITY * t, rel=1e-9)
    np.testing.assert_allclose(world.positions[0, 0, :2], [0.1, -0.2])


@pytest.mark.parametrize("freeze_after", [24, None], ids=["island-sleeping", "sleeping-only"])
def test_spheres_released_above_the_ground_settle_and_stay_at_rest(freeze_after: int | None) -> None:
    """Also without island sleeping: per-sphere sleeping alone must keep the pile still."""
    rng = np.random.default_rng(0)
    n = 20
    start = np.stack([rng.uniform(-0.08, 0.08, n), rng.uniform(-0.08, 0.08, n), 0.1 + 0.05 * np.arange(n)], -1)
    walls = pen(0.3, 0.2)
    world = ParticleWorld(GranularMaterial(freeze_after_substeps=freeze_after), walls, None)
    world.reset(start[None])
    energy = []
    for _ in range(int(3.0 / DT)):
        world.advance(DT, 10)
        energy.append(world.kinetic_energy()[0])
    assert max(energy) > 1.0, "the spheres must have fallen"
    assert energy[-1] == 0.0, "energy must decay to rest"
    settled = world.positions.copy()
    for _ in range(int(10.0 / DT)):
        world.advance(DT, 10)
    assert np.max(np.abs(world.positions - settled)) < 1e-4, "a pile at rest must not drift over 10 s"
    p = world.positions[0]
    gaps = np.linalg.norm(p[:, None] - p[None], axis=-1)[np.triu_indices(n, 1)]
    assert gaps.min() > 2 * R - 2e-3, "no two spheres overlap by more than 2 mm"
    assert p[:, 2].min() > R - 1e-3
    assert np.all(np.abs(p[:, :2]) < 0.15), "all stay inside the pen"


@pytest.mark.parametrize("substeps", [10, 2])
def test_blade_at_4_m_s_pushes_spheres_and_none_tunnels(substeps: int) -> None:
    """A vertical blade sweeps a row of spheres at 4 m/s; even with 2 sub-steps per control step
    (the blade moves 8 cm, twice a sphere's diameter, per sub-step) none ends up behind it."""
    n = 6
    start = np.stack([np.linspace(0.05, 0.40, n), np.linspace(-0.06, 0.06, n), np.full(n, R)], -1)[None]
    world = ParticleWorld(MATERIAL, None, tool_shapes("spade"))
    world.reset(start)
    rotation = np.eye(3)[None]  # face normal +x, handle up (+z)
    speed = 4.0
    world.place_tool(np.array([[-0.1, 0.0, 0.004]]), rotation)
    for k in range(1, 8):
        world.advance(DT, substeps, np.array([[-0.1 + speed * DT * k, 0.0, 0.004]]), rotation)
        local = (world.positions - world.tool_position[:, None]) @ world.tool_rotation
        over_blade = (np.abs(local[..., 1]) < SPADE_BLADE_WIDTH / 2) & (local[..., 2] > 0)
        over_blade &= local[..., 2] < SPADE_BLADE_LENGTH
        behind = over_blade & (local[..., 0] < R - 1e-3)
        assert not np.any(behind), f"a sphere is inside or behind the blade at step {k}: {local[behind]}"
    # Spheres crowded in front of the blade may leave around its sides; none passes through it.
    beside = np.abs(local[0, :, 1]) >= SPADE_BLADE_WIDTH / 2
    assert np.all(beside | (world.positions[0, :, 0] > -0.1 + speed * DT * 7)), "spheres over the blade are ahead"
    assert np.sum(~beside) >= 4


def test_spheres_thrown_at_a_wall_at_4_and_6_m_s_do_not_pass() -> None:
    walls = pen(0.6, 0.8)  # inner x in [-0.3, 0.3], walls 1 cm thick
    y = np.linspace(-0.2, 0.2, 5)
    start = np.concatenate([np.stack([np.full(5, 0.1), y, np.full(5, 0.4)], -1),
                            np.stack([np.full(5, -0.1), y, np.full(5, 0.5)], -1)])[None]
    velocity = np.zeros_like(start)
    velocity[0, :5, 0], velocity[0, 5:, 0] = 4.0, -6.0
    world = ParticleWorld(MATERIAL, walls, None)
    world.reset(start, velocity)
    for _ in range(12):
        world.advance(DT, 10)
        assert np.all(np.abs(world.positions[0, :, 0]) <= 0.3 - R + 1e-3), "a sphere entered or crossed a wall"


def loaded_spade(head: np.ndarray, rotation: np.ndarray) -> ParticleWorld:
    """A spade at ``head`` (3,), ``rotation`` (3, 3) with 6 spheres resting on its carrying face."""
    ys, zs = np.meshgrid([-0.045, 0.0, 0.045], [0.03, 0.075], indexing="ij")
    local = np.stack([np.full(ys.size, R), ys.ravel(), zs.ravel()], -1)
    world = ParticleWorld(MATERIAL, None, tool_shapes("spade"))
    world.reset((head + local @ rotation.T)[None])
    world.place_tool(head[None], rotation[None])
    assert np.all(on_blade(world))
    return world


@pytest.mark.parametrize(("elevation_deg", "keeps"), [(20.0, True), (36.0, False)])
def test_blade_keeps_sand_below_the_friction_angle_and_spills_above(elevation_deg: float, keeps: bool) -> None:
    """The blade is tilted tip down (the open tip downhill) over 1 s, then held for 2 s. Coulomb
    friction puts the spill angle between atan(mu_k) = 26.6 and atan(mu_s) = 31 degrees."""
    head = np.array([0.0, 0.0, 0.6])
    world = loaded_spade(head, spade_rotation(0.0))
    for k in range(1, 25):
        world.advance(DT, 10, head[None], spade_rotation(np.radians(elevation_deg) * k / 24)[None])
    for _ in range(48):
        world.advance(DT, 10)
    count = int(on_blade(world).sum())
    assert count == (6 if keeps else 0), f"{count} of 6 spheres left on the blade"


def test_level_blade_keeps_its_load_while_carried_at_1_m_s() -> None:
    rotation = spade_rotation(0.0)[None]
    head = np.array([0.0, 0.0, 0.6])
    world = loaded_spade(head, rotation[0])
    speed, ramp = 1.0, 0.25  # accelerate at 4 m/s^2 (below mu g), then carry tip first (-y) at 1 m/s
    for k in range(1, int(1.5 / DT) + 1):
        t = k * DT
        travelled = speed * (t - ramp / 2) if t > ramp else 0.5 * speed / ramp * t * t
        world.advance(DT, 10, (head - np.array([0.0, travelled, 0.0]))[None], rotation)
    assert travelled > 1.2
    np.testing.assert_allclose(world.velocities[0, :, 1], -speed, atol=0.05)
    assert np.all(on_blade(world))


def test_verlet_lists_always_hold_every_touching_pair() -> None:
    """White-box check of the broad phase: after the updates, every touching sphere pair is a
    candidate, while a blade stirs a falling heap."""
    rng = np.random.default_rng(4)
    n = 30
    start = np.stack([rng.uniform(-0.1, 0.1, n), rng.uniform(-0.1, 0.1, n), 0.05 + 0.045 * np.arange(n)], -1)
    walls = pen(0.3, 0.2)
    world = ParticleWorld(MATERIAL, walls, tool_shapes("spade"))
    world.reset(np.stack([start, start[::-1]]))
    rotation = np.repeat(np.eye(3)[None], 2, 0)
    world.place_tool(np.array([[-0.12, 0.0, 0.01]] * 2), rotation)
    for k in range(1, 31):
        head = np.array([[-0.12 + 0.24 * np.sin(np.pi * k / 30), 0.0, 0.01]] * 2)
        world.advance(DT, 10, head, rotation)
        world.update_pairs()
        for b in range(2):
            listed = set(map(tuple, world.candidate_pairs(b).tolist()))
            p = world.positions[b]
            gaps = np.linalg.norm(p[:, None] - p[None], axis=-1)
            for i, j in zip(*np.nonzero(np.triu(gaps < 2 * R, 1))):
                assert (i, j) in listed, f"touching pair ({i}, {j}) missing at step {k}"


def test_the_tools_far_bound_never_hides_a_sphere_it_reaches():
    """The cheap bound on the whole sand that spares the per-sphere tool test of frozen instances
    gives the per-sphere test's answer (random clouds and tool moves, near and far)."""
    from scipy.spatial.transform import Rotation

    from toolimit.scenes.spatial import particle_kernels as kernels

    world = ParticleWorld(MATERIAL, None, tool_shapes("spade"))
    low, high = world._tool_arrays[-2:]
    rng = np.random.default_rng(0)
    start, end = np.empty(3), np.empty(3)
    answers = set()
    for _ in range(300):
        positions = rng.normal(0.0, 0.05, (1, 30, 3)) + np.array([0.0, 0.0, 0.1])
        p0 = rng.normal(0.0, 0.4, (1, 3))
        p1 = p0 + rng.normal(0.0, 0.02, (1, 3))
        r0 = Rotation.random(random_state=rng).as_matrix()[None]
        r1 = (Rotation.from_rotvec(rng.normal(0.0, 0.05, 3)) * Rotation.from_matrix(r0[0])).as_matrix()[None]
        every = any(
            not kernels._in_tool_frame(0, i, positions, positions, p0, r0, p1, r1, low, high, start, end)
            for i in range(30)
        )
        sand = np.array([positions[0].min(axis=0), positions[0].max(axis=0)])
        far = kernels._tool_far(0, sand, p0, r0, p1, r1, low, high)
        assert not (far and every)
        assert kernels._tool_reaches(0, positions, sand, p0, r0, p1, r1, low, high) == every
        answers.add((far, every))
    assert {(True, False), (False, True), (False, False)} <= answers  # both ways, and the bound's slack
