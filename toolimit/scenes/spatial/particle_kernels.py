"""Compiled (numba) kernels of the particle solver of :mod:`toolimit.scenes.spatial.particles`.

The scheme, the contact groups and their order are documented there; this module only holds the
loops, written per sphere so that numba compiles them to plain machine code (no temporaries).
Every function works on one instance ``b`` of the batched arrays at a time, in the world frame,
metres and seconds, except where a name says *local* (a box's or the tool's frame). Instances share
nothing, so :func:`advance` runs each one's sub-steps one after the other (its spheres stay in the
cache) and :func:`advance_on_threads` shares the instances out among numba's threads: the same
numbers, bit for bit, whatever their count (``tests/scenes/test_sand_threads.py``).

The wall passes test only the walls near the sand (a broad phase), and island sleeping skips a
heap at rest; where the time goes is in docs/results/performance.md#where-the-sands-time-goes.

Kernels are compiled on first use and cached on disk (``cache=True``), so only the first import on
a machine pays the compile time. They keep IEEE arithmetic (no ``fastmath``): with it, the kernels
compiled in a run and the same kernels loaded from the cache in the next run rounded differently,
and the sand, a chaotic system, amplified that into other results for the same seed (a scripted
scoop, B = 4: [21, 17, 17, 22] spheres in the box when compiled, [20, 20, 18, 23] when cached).
Measured cost of IEEE arithmetic: about 2 % (2,545 against 2,595 instance-steps per CPU second,
200 spheres, B = 16).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

# Indices into the ``coefficients`` vector (see particles.GranularMaterial.coefficients).
RADIUS, MU_SPHERE_S, MU_SPHERE_K, MU_TOOL_S, MU_TOOL_K = 0, 1, 2, 3, 4
MU_GROUND_S, MU_GROUND_K, MU_WALL_S, MU_WALL_K, MASS_SCALING, RELAXATION = 5, 6, 7, 8, 9, 10
SLEEP_SPEED, MAX_SPEED, PAIR_MARGIN, GRAVITY = 11, 12, 13, 14
N_COEFFICIENTS = 15

_jit = nb.njit(cache=True, nogil=True, fastmath=False, error_model="numpy")
#: Instances stepped on several threads (numba's ``prange``): they share nothing. Not cached: numba
#: keys its disk cache by function and signature, not by ``parallel``, so a cached threaded build
#: of :func:`_advance` would replace the single-threaded one (and be loaded for it).
_parallel = nb.njit(cache=False, nogil=True, fastmath=False, error_model="numpy", parallel=True)
#: Small helpers called per sphere and per shape are inlined by numba: a call that passes arrays
#: costs reference counting, several times the work of the helper itself (3x the whole step).
_inline = nb.njit(cache=True, nogil=True, fastmath=False, error_model="numpy", inline="always")


@_inline
def _friction(rx, ry, rz, nx, ny, nz, depth, mu_s, mu_k):  # type: ignore[no-untyped-def]
    """Coulomb friction by position: minus the tangential part of the relative displacement r if it
    is below mu_s depth (static), else the part mu_k depth of it (kinetic). Returns 3 floats."""
    along = rx * nx + ry * ny + rz * nz
    tx, ty, tz = rx - along * nx, ry - along * ny, rz - along * nz
    slip = math.sqrt(tx * tx + ty * ty + tz * tz)
    scale = 1.0 if slip < mu_s * depth else min(mu_k * depth / max(slip, 1e-15), 1.0)
    return -tx * scale, -ty * scale, -tz * scale


@_inline
def _box_contact(s, e, half, radius, mu_s, mu_k, out):  # type: ignore[no-untyped-def]
    """Contact of a sphere moving from ``s`` to ``e`` (3,) (box-local frame) with a box of half
    extents ``half`` (3,). Writes the normal push (out[0:3]) and the friction correction
    (out[3:6]) to add to ``e``; returns whether there is a contact.

    Closest-point contact with the rounded box, or, if the segment s -> e crosses the box itself
    (slab test), a push out through the face entered by (the axis where ``s`` is most outside;
    the nearest face if ``s`` is inside), whatever the depth.
    """
    # Closest point of the box to the end point.
    ox = e[0] - min(max(e[0], -half[0]), half[0])
    oy = e[1] - min(max(e[1], -half[1]), half[1])
    oz = e[2] - min(max(e[2], -half[2]), half[2])
    distance = math.sqrt(ox * ox + oy * oy + oz * oz)
    contact = distance < radius
    depth = radius - distance
    inv = 1.0 / max(distance, 1e-15)
    nx, ny, nz = ox * inv, oy * inv, oz * inv
    # Slab test of the segment against the box itself.
    t_entry, t_exit = -1e300, 1e300
    face, face_excess = 0, -1e300
    for a in range(3):
        m = e[a] - s[a]
        if abs(m) < 1e-12:
            m = 1e-12
        t_low = (-half[a] - s[a]) / m
        t_high = (half[a] - s[a]) / m
        t_entry = max(t_entry, min(t_low, t_high))
        t_exit = min(t_exit, max(t_low, t_high))
        excess = abs(s[a]) - half[a]
        if excess > face_excess:
            face, face_excess = a, excess
    if t_entry <= t_exit and t_exit >= 0.0 and t_entry <= 1.0:
        sign = 1.0 if s[face] >= 0.0 else -1.0
        nx, ny, nz = 0.0, 0.0, 0.0
        if face == 0:
            nx = sign
        elif face == 1:
            ny = sign
        else:
            nz = sign
        depth = half[face] + radius - sign * e[face]
        contact = True
    if not contact:
        return False
    depth = max(depth, 0.0)
    px, py, pz = nx * depth, ny * depth, nz * depth
    fx, fy, fz = _friction(e[0] + px - s[0], e[1] + py - s[1], e[2] + pz - s[2], nx, ny, nz, depth, mu_s, mu_k)
    out[0], out[1], out[2], out[3], out[4], out[5] = px, py, pz, fx, fy, fz
    return True


@_inline
def _in_tool_frame(b, i, previous, predicted, p0, r0, p1, r1, low, high, start, end):  # type: ignore[no-untyped-def]
    """Sphere i of instance b in the tool frame: ``previous`` with the tool at p0, r0 (the sub-step's
    start) into ``start`` (3,), ``predicted`` with the tool at p1, r1 (its end) into ``end`` (3,).
    Returns whether that segment is clear of the tool's grown bounds ``low``, ``high`` (3,), i.e.
    entirely beyond them along some axis (the tool's broad phase)."""
    clear = False
    for a in range(3):
        sa = 0.0
        ea = 0.0
        for c in range(3):
            sa += (previous[b, i, c] - p0[b, c]) * r0[b, c, a]
            ea += (predicted[b, i, c] - p1[b, c]) * r1[b, c, a]
        start[a], end[a] = sa, ea
        if min(sa, ea) >= high[a] or max(sa, ea) <= low[a]:
            clear = True
    return clear


@_inline
def _boxes_correction(start, end, centers, rotations, halves, bounds, radius, mu_s, mu_k, moved, scratch):  # type: ignore[no-untyped-def]
    """Correction ``moved`` (3,) of a sphere (start, end (3,) in the boxes' common frame) against
    oriented boxes (K, ...): pushes summed (faces meeting at an edge are orthogonal), friction
    averaged over the touching boxes. ``bounds`` (K, 2, 3): each box's axis-aligned bounds in the
    common frame grown by the radius (broad phase); ``scratch``: (18,) work space. Returns the
    number of touching boxes."""
    s, e, out, push, friction = scratch[0:3], scratch[3:6], scratch[6:12], scratch[12:15], scratch[15:18]
    push[:] = 0.0
    friction[:] = 0.0
    touching = 0
    for k in range(centers.shape[0]):
        near = True
        for a in range(3):
            if min(start[a], end[a]) >= bounds[k, 1, a] or max(start[a], end[a]) <= bounds[k, 0, a]:
                near = False
                break
        if not near:
            continue
        for a in range(3):
            sa = 0.0
            ea = 0.0
            for c in range(3):
                sa += (start[c] - centers[k, c]) * rotations[k, c, a]
                ea += (end[c] - centers[k, c]) * rotations[k, c, a]
            s[a], e[a] = sa, ea
            reach = halves[k, a] + radius
            if min(sa, ea) >= reach or max(sa, ea) <= -reach:
                near = False
                break
        if not near or not _box_contact(s, e, halves[k], radius, mu_s, mu_k, out):
            continue
        touching += 1
        for c in range(3):
            for a in range(3):
                push[c] += rotations[k, c, a] * out[a]
                friction[c] += rotations[k, c, a] * out[3 + a]
    for c in range(3):
        moved[c] = push[c] + friction[c] / max(touching, 1)
    return touching


@_inline
def _pair_pass(b, previous, predicted, pairs, n_pairs, coefficients, total, inv_mass):  # type: ignore[no-untyped-def]
    """One averaged Jacobi pass over instance b's candidate sphere pairs, with mass scaling and
    friction; updates ``predicted[b]`` in place. ``total`` (N, 4), ``inv_mass`` (N,): work space."""
    now, before, listed = predicted[b], previous[b], pairs[b]
    n = now.shape[0]
    r2 = 2.0 * coefficients[RADIUS]
    mu_s, mu_k, k_mass = coefficients[MU_SPHERE_S], coefficients[MU_SPHERE_K], coefficients[MASS_SCALING]
    total[:] = 0.0  # summed corrections (x, y, z) and number of contacts
    for i in range(n):
        inv_mass[i] = math.exp(k_mass * now[i, 2])
    for p in range(n_pairs[b]):
        i, j = listed[p, 0], listed[p, 1]
        ox = now[i, 0] - now[j, 0]
        oy = now[i, 1] - now[j, 1]
        oz = now[i, 2] - now[j, 2]
        d2 = ox * ox + oy * oy + oz * oz
        if d2 >= r2 * r2:
            continue
        distance = math.sqrt(d2)
        depth = r2 - distance
        inv = 1.0 / max(distance, 1e-15)
        nx, ny, nz = ox * inv, oy * inv, oz * inv
        rx = now[i, 0] - before[i, 0] - now[j, 0] + before[j, 0] + nx * depth
        ry = now[i, 1] - before[i, 1] - now[j, 1] + before[j, 1] + ny * depth
        rz = now[i, 2] - before[i, 2] - now[j, 2] + before[j, 2] + nz * depth
        fx, fy, fz = _friction(rx, ry, rz, nx, ny, nz, depth, mu_s, mu_k)
        cx, cy, cz = nx * depth + fx, ny * depth + fy, nz * depth + fz
        share = inv_mass[i] / (inv_mass[i] + inv_mass[j])
        rest = share - 1.0
        total[i, 0] += share * cx
        total[i, 1] += share * cy
        total[i, 2] += share * cz
        total[i, 3] += 1.0
        total[j, 0] += rest * cx
        total[j, 1] += rest * cy
        total[j, 2] += rest * cz
        total[j, 3] += 1.0
    relaxation = coefficients[RELAXATION]
    for i in range(n):
        if total[i, 3] > 0.0:
            scale = relaxation / total[i, 3]
            now[i, 0] += total[i, 0] * scale
            now[i, 1] += total[i, 1] * scale
            now[i, 2] += total[i, 2] * scale


@_jit
def _project(
    b,
    previous,
    predicted,
    pairs,
    n_pairs,
    has_tool,
    p0,
    r0,
    p1,
    r1,
    tool,
    walls,
    coefficients,
    pair_work,
    scratch,
    listed,
):  # type: ignore[no-untyped-def]
    """One pass over all contacts of instance b (Gauss-Seidel between groups): sphere pairs, the
    ground and the walls with friction, the tool (its pose p0, r0 at the sub-step's start, p1, r1
    at its end), then the walls and the ground again without friction, so that static surfaces
    win. ``tool``: the tool's shape arrays (see :func:`advance`); ``walls``: the walls' centers,
    rotations, half extents and bounds; ``pair_work`` (N, 5), ``scratch`` (31,) and ``listed`` (K,)
    int64: work space.
    Updates ``predicted[b]`` in place."""
    (
        box_centers,
        box_rotations,
        box_halves,
        box_bounds,
        capsule_starts,
        capsule_ends,
        capsule_radii,
        tool_low,
        tool_high,
    ) = tool
    n = predicted.shape[1]
    radius = coefficients[RADIUS]
    if n_pairs[b]:
        _pair_pass(b, previous, predicted, pairs, n_pairs, coefficients, pair_work[:, 0:4], pair_work[:, 4])
    start, end, moved, before, scratch = scratch[0:3], scratch[3:6], scratch[6:9], scratch[9:13], scratch[13:31]
    before[0], before[1], before[2], before[3] = np.inf, -np.inf, np.inf, -np.inf  # x, y extent of previous[b]
    for i in range(n):
        before[0] = min(before[0], previous[b, i, 0])
        before[1] = max(before[1], previous[b, i, 0])
        before[2] = min(before[2], previous[b, i, 1])
        before[3] = max(before[3], previous[b, i, 1])
    # Static surfaces with friction before the tool (so friction never drags a sphere into it) ...
    mu_s, mu_k = coefficients[MU_GROUND_S], coefficients[MU_GROUND_K]
    for i in range(n):
        depth = radius - predicted[b, i, 2]
        if depth > 0.0:
            predicted[b, i, 2] = radius
            fx, fy, fz = _friction(
                predicted[b, i, 0] - previous[b, i, 0],
                predicted[b, i, 1] - previous[b, i, 1],
                predicted[b, i, 2] - previous[b, i, 2],
                0.0,
                0.0,
                1.0,
                depth,
                mu_s,
                mu_k,
            )
            predicted[b, i, 0] += fx
            predicted[b, i, 1] += fy
    _walls_pass(
        b,
        previous,
        predicted,
        walls,
        radius,
        coefficients[MU_WALL_S],
        coefficients[MU_WALL_K],
        start,
        end,
        moved,
        scratch,
        listed,
        before,
    )
    if has_tool:
        mu_s, mu_k = coefficients[MU_TOOL_S], coefficients[MU_TOOL_K]
        for i in range(n):
            if _in_tool_frame(b, i, previous, predicted, p0, r0, p1, r1, tool_low, tool_high, start, end):
                continue
            _boxes_correction(
                start, end, box_centers, box_rotations, box_halves, box_bounds, radius, mu_s, mu_k, moved, scratch
            )
            for a in range(3):
                end[a] += moved[a]
            # Capsules (handles): closest-point contact, pushes summed, friction averaged.
            touching = 0
            ex, ey, ez, gx, gy, gz = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
            for k in range(capsule_radii.shape[0]):
                ax = capsule_ends[k, 0] - capsule_starts[k, 0]
                ay = capsule_ends[k, 1] - capsule_starts[k, 1]
                az = capsule_ends[k, 2] - capsule_starts[k, 2]
                length2 = max(ax * ax + ay * ay + az * az, 1e-18)
                t = (
                    (end[0] - capsule_starts[k, 0]) * ax
                    + (end[1] - capsule_starts[k, 1]) * ay
                    + (end[2] - capsule_starts[k, 2]) * az
                ) / length2
                t = min(max(t, 0.0), 1.0)
                ox = end[0] - capsule_starts[k, 0] - t * ax
                oy = end[1] - capsule_starts[k, 1] - t * ay
                oz = end[2] - capsule_starts[k, 2] - t * az
                distance = math.sqrt(ox * ox + oy * oy + oz * oz)
                depth = capsule_radii[k] + radius - distance
                if depth <= 0.0:
                    continue
                touching += 1
                inv = 1.0 / max(distance, 1e-15)
                nx, ny, nz = ox * inv, oy * inv, oz * inv
                fx, fy, fz = _friction(
                    end[0] + nx * depth - start[0],
                    end[1] + ny * depth - start[1],
                    end[2] + nz * depth - start[2],
                    nx,
                    ny,
                    nz,
                    depth,
                    mu_s,
                    mu_k,
                )
                ex, ey, ez = ex + nx * depth, ey + ny * depth, ez + nz * depth
                gx, gy, gz = gx + fx, gy + fy, gz + fz
            share = 1.0 / max(touching, 1)
            moved[0] += ex + gx * share
            moved[1] += ey + gy * share
            moved[2] += ez + gz * share
            for c in range(3):
                predicted[b, i, c] += r1[b, c, 0] * moved[0] + r1[b, c, 1] * moved[1] + r1[b, c, 2] * moved[2]

    # ... and their normal constraints after it: the walls, then the ground's hard limit, win.
    _walls_pass(b, previous, predicted, walls, radius, 0.0, 0.0, start, end, moved, scratch, listed, before)
    for i in range(n):
        predicted[b, i, 2] = max(predicted[b, i, 2], radius)


@_inline
def _walls_pass(b, previous, predicted, walls, radius, mu_s, mu_k, start, end, moved, scratch, listed, before):  # type: ignore[no-untyped-def]
    """Contacts of instance b's spheres with its walls (``walls``: per-instance arrays (B, K, ...);
    friction mu_s, mu_k), in place. ``listed`` (K,) int64: work space; ``before`` (4,): the x, y
    extent (x0, x1, y0, y1, m) of ``previous[b]``.

    Broad phase: the walls whose grown bounds meet the x, y extent of all the spheres' segments
    (``previous`` to ``predicted``) are listed, and only a sphere whose segment meets the bounds
    of a listed wall is solved (against every wall, as :func:`_boxes_correction` does): for the
    other walls and spheres its own bounds test fails, so the result is the same."""
    wall_centers, wall_rotations, wall_halves, wall_bounds = walls[0][b], walls[1][b], walls[2][b], walls[3][b]
    if wall_centers.shape[0] == 0:
        return
    n = predicted.shape[1]
    x0, x1, y0, y1 = before[0], before[1], before[2], before[3]
    for i in range(n):
        x0 = min(x0, predicted[b, i, 0])
        x1 = max(x1, predicted[b, i, 0])
        y0 = min(y0, predicted[b, i, 1])
        y1 = max(y1, predicted[b, i, 1])
    n_listed = 0
    for k in range(wall_centers.shape[0]):
        bounds = wall_bounds[k]
        if x0 < bounds[1, 0] and x1 > bounds[0, 0] and y0 < bounds[1, 1] and y1 > bounds[0, 1]:
            listed[n_listed] = k
            n_listed += 1
    if n_listed == 0:
        return
    for i in range(n):
        near = False
        for m in range(n_listed):
            k = listed[m]
            near = True
            for a in range(3):
                s, e = previous[b, i, a], predicted[b, i, a]
                if min(s, e) >= wall_bounds[k, 1, a] or max(s, e) <= wall_bounds[k, 0, a]:
                    near = False
                    break
            if near:
                break
        if not near:
            continue
        for a in range(3):
            start[a], end[a] = previous[b, i, a], predicted[b, i, a]
        if _boxes_correction(
            start, end, wall_centers, wall_rotations, wall_halves, wall_bounds, radius, mu_s, mu_k, moved, scratch
        ):
            for a in range(3):
                predicted[b, i, a] += moved[a]


@_jit
def _rebuild_pairs(b, positions, built_at, pairs, n_pairs, reach):  # type: ignore[no-untyped-def]
    """Verlet list of instance b: every pair closer than ``reach``, by sort and sweep along x.
    Returns False (list left incomplete) if ``pairs`` is too small."""
    n = positions.shape[1]
    order = np.argsort(positions[b, :, 0])
    count = 0
    capacity = pairs.shape[1]
    reach2 = reach * reach
    for u in range(n):
        i = order[u]
        for w in range(u + 1, n):
            j = order[w]
            dx = positions[b, j, 0] - positions[b, i, 0]
            if dx >= reach:
                break
            dy = positions[b, j, 1] - positions[b, i, 1]
            dz = positions[b, j, 2] - positions[b, i, 2]
            if dx * dx + dy * dy + dz * dz < reach2:
                if count >= capacity:
                    return False
                pairs[b, count, 0] = min(i, j)
                pairs[b, count, 1] = max(i, j)
                count += 1
    n_pairs[b] = count
    for i in range(n):
        for a in range(3):
            built_at[b, i, a] = positions[b, i, a]
    return True


@_inline
def _fresh_pairs(b, positions, built_at, pairs, n_pairs, coefficients):  # type: ignore[no-untyped-def]
    """Rebuild instance b's Verlet list if one of its spheres moved half the margin since its
    last build (so no unlisted pair can touch). Returns False (the list marked -1: rebuild) if
    ``pairs`` is too small."""
    margin = coefficients[PAIR_MARGIN]
    limit = (0.5 * margin) ** 2
    stale = n_pairs[b] < 0
    for i in range(positions.shape[1]):
        if stale:
            break
        dx = positions[b, i, 0] - built_at[b, i, 0]
        dy = positions[b, i, 1] - built_at[b, i, 1]
        dz = positions[b, i, 2] - built_at[b, i, 2]
        stale = dx * dx + dy * dy + dz * dz >= limit
    if stale and not _rebuild_pairs(b, positions, built_at, pairs, n_pairs, 2.0 * coefficients[RADIUS] + margin):
        n_pairs[b] = -1
        return False
    return True


@_jit
def update_pairs(positions, built_at, pairs, n_pairs, coefficients):  # type: ignore[no-untyped-def]
    """:func:`_fresh_pairs` for every instance, in order (stopping at the first whose ``pairs``
    proved too small). Returns False if ``pairs`` is too small."""
    for b in range(positions.shape[0]):  # noqa: SIM110 (numba: no generator into all())
        if not _fresh_pairs(b, positions, built_at, pairs, n_pairs, coefficients):
            return False
    return True


@_inline
def _sand_bounds(b, positions, bounds):  # type: ignore[no-untyped-def]
    """Instance b's spheres' axis-aligned bounds into ``bounds`` (2, 3): lower, upper (m)."""
    for a in range(3):
        bounds[0, a] = np.inf
        bounds[1, a] = -np.inf
    for i in range(positions.shape[1]):
        for a in range(3):
            bounds[0, a] = min(bounds[0, a], positions[b, i, a])
            bounds[1, a] = max(bounds[1, a], positions[b, i, a])


@_inline
def _tool_far(b, sand, p0, r0, p1, r1, tool_low, tool_high):  # type: ignore[no-untyped-def]
    """Whether the tool is surely too far from every sphere of instance b (at rest, within the
    bounds ``sand`` (2, 3) of :func:`_sand_bounds`) for :func:`_in_tool_frame` to find one not
    clear of its grown bounds during the sub-step: a bound on the whole sand, so that most
    sub-steps need no test per sphere.

    A resting sphere x has tool-frame end points at distances |x - c0|, |x - c1| from the bounds'
    centre c (world c0 at the start, c1 at the end), at most L = |p1 - p0| + |r1 - r0| |x - p0|
    apart (|r1 - r0| = sqrt(3 - trace(r0^T r1)) for rotations); the segment between them is clear
    along some axis if it stays beyond R + L of c, R the bounds' half diagonal (tested with
    margin: the nearest end point beyond R + 2 L, from the bound on the sand)."""
    low, high = sand[0], sand[1]
    trace = 0.0
    for a in range(3):
        for c in range(3):
            trace += r0[b, c, a] * r1[b, c, a]
    turn = math.sqrt(max(3.0 - trace, 0.0))
    half_diagonal = 0.0
    for a in range(3):
        half_diagonal += (0.5 * (tool_high[a] - tool_low[a])) ** 2
    half_diagonal = math.sqrt(half_diagonal)
    near0, near1, farthest, shift = 0.0, 0.0, 0.0, 0.0
    for a in range(3):
        c0, c1 = p0[b, a], p1[b, a]  # the bounds' centre, world frame
        for k in range(3):
            middle = 0.5 * (tool_low[k] + tool_high[k])
            c0 += r0[b, a, k] * middle
            c1 += r1[b, a, k] * middle
        near0 += max(low[a] - c0, 0.0, c0 - high[a]) ** 2
        near1 += max(low[a] - c1, 0.0, c1 - high[a]) ** 2
        farthest += max(abs(low[a] - p0[b, a]), abs(high[a] - p0[b, a])) ** 2
        shift += (p1[b, a] - p0[b, a]) ** 2
    apart = math.sqrt(shift) + turn * math.sqrt(farthest)
    return min(math.sqrt(near0), math.sqrt(near1)) - apart > half_diagonal + 2.0 * apart + 1e-9


@_inline
def _tool_reaches(b, positions, sand, p0, r0, p1, r1, tool_low, tool_high):  # type: ignore[no-untyped-def]
    """Whether a sphere of instance b meets the tool's grown bounds during the sub-step (the same
    answer as testing every sphere; :func:`_tool_far` on the sand's bounds ``sand`` (2, 3)
    spares the test in most sub-steps)."""
    if _tool_far(b, sand, p0, r0, p1, r1, tool_low, tool_high):
        return False
    start, end = np.empty(3), np.empty(3)
    for i in range(positions.shape[1]):
        if not _in_tool_frame(b, i, positions, positions, p0, r0, p1, r1, tool_low, tool_high, start, end):
            return True
    return False


@_inline
def _advance_instance(
    b,
    positions,
    carried,
    velocities,
    predicted,
    built_at,
    pairs,
    n_pairs,
    resting,
    progress,
    h,
    has_tool,
    path_positions,
    path_rotations,
    tool,
    walls,
    coefficients,
    freeze_after,
):  # type: ignore[no-untyped-def]
    """Sub-steps ``progress[b]`` .. S-1 of instance b (see :func:`advance`)."""
    n = positions.shape[1]
    sleep2 = (coefficients[SLEEP_SPEED] * h) ** 2
    max_speed, gravity = coefficients[MAX_SPEED], coefficients[GRAVITY]
    pair_work, scratch, sand = np.empty((n, 5)), np.empty(31), np.empty((2, 3))
    listed = np.empty(walls[0].shape[1], dtype=np.int64)
    sand_known = False  # whether ``sand`` holds the bounds of the spheres' current positions
    n_substeps = path_positions.shape[0] - 1
    for s in range(progress[b], n_substeps):
        if not _fresh_pairs(b, positions, built_at, pairs, n_pairs, coefficients):
            progress[b] = s
            return
        p0, r0, p1, r1 = path_positions[s], path_rotations[s], path_positions[s + 1], path_rotations[s + 1]
        if freeze_after > 0 and resting[b] >= freeze_after:
            if has_tool and not sand_known:
                _sand_bounds(b, positions, sand)
                sand_known = True
            if not has_tool or not _tool_reaches(b, positions, sand, p0, r0, p1, r1, tool[7], tool[8]):
                continue  # island sleeping: this instance is at rest and untouched
        sand_known = False
        for i in range(n):
            carried[b, i, 2] -= gravity * h
            for a in range(3):
                predicted[b, i, a] = positions[b, i, a] + h * carried[b, i, a]
        _project(
            b,
            positions,
            predicted,
            pairs,
            n_pairs,
            has_tool,
            p0,
            r0,
            p1,
            r1,
            tool,
            walls,
            coefficients,
            pair_work,
            scratch,
            listed,
        )
        awake_any = False
        for i in range(n):
            dx = predicted[b, i, 0] - positions[b, i, 0]
            dy = predicted[b, i, 1] - positions[b, i, 1]
            dz = predicted[b, i, 2] - positions[b, i, 2]
            speed2 = dx * dx + dy * dy + dz * dz
            awake = speed2 >= sleep2
            scale = 1.0 / h
            if max_speed > 0.0 and speed2 > (max_speed * h) ** 2:
                scale = max_speed / math.sqrt(speed2)
            carried[b, i, 0], carried[b, i, 1], carried[b, i, 2] = dx * scale, dy * scale, dz * scale
            if awake:
                awake_any = True
                for a in range(3):
                    positions[b, i, a] = predicted[b, i, a]
                    velocities[b, i, a] = carried[b, i, a]
            else:
                for a in range(3):
                    velocities[b, i, a] = 0.0
        resting[b] = 0 if awake_any else resting[b] + 1
    progress[b] = n_substeps


def _advance(
    positions,
    carried,
    velocities,
    built_at,
    pairs,
    n_pairs,
    resting,
    progress,
    h,
    has_tool,
    path_positions,
    path_rotations,
    tool,
    walls,
    coefficients,
    freeze_after,
):  # type: ignore[no-untyped-def]
    """Sub-steps of length h (s) for all instances, the tool moving along ``path_positions``
    (S+1, B, 3), ``path_rotations`` (S+1, B, 3, 3): instance b from sub-step ``progress[b]`` on
    (B,), to S, or to the sub-step at which its ``pairs`` proved too small (nothing of that
    sub-step simulated yet: grow ``pairs`` and call again). Updates the state arrays and
    ``progress`` in place. Instances are independent: each one's sub-steps run one after the
    other, in the order of the scheme.

    ``tool`` is the tuple (box centers, rotations, half extents, bounds, capsule starts, ends,
    radii, low, high) of the tool's shapes in its frame with its bounds grown by the sphere radius,
    ``walls`` the tuple (centers, rotations, half extents, bounds) of each instance's static boxes
    (B, K, ...), world frame.
    """
    predicted = np.empty_like(positions)
    for b in nb.prange(positions.shape[0]):
        _advance_instance(
            b,
            positions,
            carried,
            velocities,
            predicted,
            built_at,
            pairs,
            n_pairs,
            resting,
            progress,
            h,
            has_tool,
            path_positions,
            path_rotations,
            tool,
            walls,
            coefficients,
            freeze_after,
        )


#: :func:`_advance` on the calling thread, and on numba's threads (instances shared out among them).
advance = _jit(_advance)
advance_on_threads = _parallel(_advance)


@_jit
def place(
    positions,
    built_at,
    pairs,
    n_pairs,
    instances,
    iterations,
    tool_position,
    tool_rotation,
    tool,
    walls,
    coefficients,
):  # type: ignore[no-untyped-def]
    """``iterations`` position-only passes over all contacts of the ``instances`` (B,) bool with
    the tool still at its pose (B, 3), (B, 3, 3); ``tool`` and ``walls`` as in :func:`advance`.
    Returns False if ``pairs`` proved too small (grow it and call again)."""
    predicted = positions.copy()
    pair_work, scratch = np.empty((positions.shape[1], 5)), np.empty(31)
    listed = np.empty(walls[0].shape[1], dtype=np.int64)
    for _ in range(iterations):
        if not update_pairs(positions, built_at, pairs, n_pairs, coefficients):
            return False
        for b in range(positions.shape[0]):
            if not instances[b]:
                continue
            _project(
                b,
                positions,
                predicted,
                pairs,
                n_pairs,
                True,
                tool_position,
                tool_rotation,
                tool_position,
                tool_rotation,
                tool,
                walls,
                coefficients,
                pair_work,
                scratch,
                listed,
            )
        positions[...] = predicted
    return True


@_jit
def in_box_counts(positions, floor_centers, half_side, height):  # type: ignore[no-untyped-def]
    """(B,) float: per instance, the sphere centres (B, N, 3) within ``half_side`` (m) of the box's
    floor centre (B, 3) in x and y and between 0 and ``height`` (m) above it (the spade's goal
    region; the same comparisons as the array expression, without its temporaries)."""
    counts = np.zeros(positions.shape[0])
    for b in range(positions.shape[0]):
        for i in range(positions.shape[1]):
            dx = positions[b, i, 0] - floor_centers[b, 0]
            dy = positions[b, i, 1] - floor_centers[b, 1]
            dz = positions[b, i, 2] - floor_centers[b, 2]
            if abs(dx) < half_side and abs(dy) < half_side and dz >= 0.0 and dz <= height:
                counts[b] += 1.0
    return counts
