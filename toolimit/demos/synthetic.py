"""Synthetic demonstrations: human-like spade, hammer and scythe motions with reconstruction noise.

Each motion is a sequence of *knots* (poses at given frames, with velocities) joined by quintic
segments: between two knots with zero acceleration at both ends the quintic is the minimum-jerk
trajectory, the model of human reaching motions (Flash and Hogan 1985); a knot with a non-zero
velocity lets one movement flow into the next (or a hammer reach the nail at speed).

Poses are written in a *local* frame (x forward, y left, z up, metres, ground at z = 0) as
``q = (hand_x, hand_y, hand_z, beta, psi)``: the handle end (the hand) and the direction of the
tool from the hand to the head, ``(cos beta cos psi, cos beta sin psi, -sin beta)``: ``beta`` is
how far the head hangs below the hand (rad), ``psi`` a small yaw of the tool out of the motion
plane. The scythe uses its own coordinates (see :func:`scythe_knots`). The finished paths are
turned by a random yaw and shifted by a random horizontal offset into the world frame.

Everything random comes from ``numpy.random.default_rng`` seeded by ``seed``; the clean motion and
the noise use two independent child streams, so ``noise=False`` gives the noisy demo's clean motion.

A tool's generator (:data:`KnotGenerator`) is named by its record's ``synthetic_motion``
(:mod:`toolimit.tools.registry`): :func:`spade_knots`, :func:`hammer_knots`, :func:`scythe_knots`
here, or any "module:function" of a registered tool.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from toolimit.demos.tool_demo import ToolDemo, frame_rate_problem
from toolimit.errors import DemoError
from toolimit.tools.registry import find_tool, load_entry_point, tool_records, tool_spec

#: Demonstration length bounds, seconds.
MIN_DURATION, MAX_DURATION = 2.5, 6.0


@dataclass(frozen=True)
class Knot:
    """A pose at a frame. ``q`` generalised coordinates; ``v_in``/``v_out`` their rates per second
    arriving at / leaving the knot (they differ only at an impact)."""

    frame: int
    q: np.ndarray
    v_in: np.ndarray
    v_out: np.ndarray


def _knot(
    frame: int, q: np.ndarray | list, v_in: np.ndarray | list | None = None, v_out: np.ndarray | list | None = None
) -> Knot:
    """A knot; velocities default to zero (a pause), ``v_out`` to ``v_in``."""
    q = np.asarray(q, dtype=float)
    v_in = np.zeros_like(q) if v_in is None else np.asarray(v_in, dtype=float)
    v_out = v_in if v_out is None else np.asarray(v_out, dtype=float)
    return Knot(frame, q, v_in, v_out)


def quintic(
    q0: np.ndarray, v0: np.ndarray, q1: np.ndarray, v1: np.ndarray, duration: float, t: np.ndarray
) -> np.ndarray:
    """(len(t), n) positions of the quintic from (q0, v0) to (q1, v1) in ``duration`` seconds with
    zero acceleration at both ends; ``t`` seconds from the start. With v0 = v1 = 0 it is the
    minimum-jerk profile ``q0 + (q1 - q0)(10 s^3 - 15 s^4 + 6 s^5)``."""
    h, T = q1 - q0, duration
    a3 = (20 * h - (8 * v1 + 12 * v0) * T) / (2 * T**3)
    a4 = (-30 * h + (14 * v1 + 16 * v0) * T) / (2 * T**4)
    a5 = (12 * h - 6 * (v1 + v0) * T) / (2 * T**5)
    t = np.asarray(t, dtype=float)[:, None]
    return q0 + v0 * t + a3 * t**3 + a4 * t**4 + a5 * t**5


def sample_knots(knots: list[Knot], fps: float) -> np.ndarray:
    """(T, n) coordinates at every frame from the first knot's frame (0) to the last one's."""
    frames = [k.frame for k in knots]
    if frames[0] != 0 or np.any(np.diff(frames) <= 0):
        raise ValueError(f"knot frames must start at 0 and increase, got {frames}")
    out = np.empty((frames[-1] + 1, knots[0].q.size))
    for a, b in zip(knots[:-1], knots[1:]):
        steps = np.arange(b.frame - a.frame + 1)
        out[a.frame : b.frame + 1] = quintic(a.q, a.v_out, b.q, b.v_in, (b.frame - a.frame) / fps, steps / fps)
    return out


def hand_tool_points(q: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Head and handle (T, 3) from ``q = (hand_x, hand_y, hand_z, beta, psi)`` (T, 5), metres/rad."""
    hand, beta, psi = q[:, :3], q[:, 3], q[:, 4]
    direction = np.stack([np.cos(beta) * np.cos(psi), np.cos(beta) * np.sin(psi), -np.sin(beta)], axis=1)
    return hand + length * direction, hand.copy()


def hand_from_head(head, beta: float, psi: float, length: float) -> np.ndarray:
    """``q`` (5,) whose head is at ``head`` (3,) with the tool at angles ``beta``, ``psi``."""
    direction = np.array([np.cos(beta) * np.cos(psi), np.cos(beta) * np.sin(psi), -np.sin(beta)])
    return np.concatenate([np.asarray(head, dtype=float) - length * direction, [beta, psi]])


#: What a tool's generator returns: the knots of its motion, in its own coordinates ``q``; the
#: function ``points(q) -> (head, handle)`` turning sampled coordinates (T, n) into the tool's
#: head and handle points (T, 3), local frame, metres; its events (see :class:`SyntheticMotion`);
#: and its sampled task quantities.
KnotMotion = tuple[list[Knot], Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], dict[str, list], dict[str, float]]
#: A tool's generator (its record's ``synthetic_motion``): ``generator(rng, fps) -> KnotMotion``,
#: every random draw from ``rng``.
KnotGenerator = Callable[[np.random.Generator, float], KnotMotion]


@dataclass(frozen=True)
class SyntheticMotion:
    """A generated demonstration with what was put in it.

    Attributes:
        clean: the motion without noise (world frame, metres).
        noisy: ``clean`` plus jitter and outlier frames (same frames).
        outlier_frames: sorted indices of the frames made outliers.
        jitter: standard deviation of the per-frame Gaussian jitter, metres.
        events: tool-specific frame indices: spade ``scoop`` (entry, end of push), ``carry``
            (start, end), ``dump`` (start, end); hammer ``impacts`` (frames at the nail) and
            ``nail_height`` is in ``params``; scythe ``sweeps`` (start, end) pairs.
        params: the sampled task quantities (heights, speeds, counts) for tests and notebooks.
    """

    clean: ToolDemo
    noisy: ToolDemo
    outlier_frames: np.ndarray
    jitter: float
    events: dict[str, list] = field(default_factory=dict)
    params: dict[str, float] = field(default_factory=dict)


def _frames(rng: np.random.Generator, low_s: float, high_s: float, fps: float, minimum: int = 2) -> int:
    """A seeded duration drawn in [low_s, high_s] seconds, as a whole number of frames."""
    return max(minimum, int(round(rng.uniform(low_s, high_s) * fps)))


# --- spade -------------------------------------------------------------------------------------
def spade_knots(rng: np.random.Generator, fps: float) -> KnotMotion:
    """Rest, reach down, scoop (push forward at ground level), lift, carry level, tip (dump), return."""
    L = tool_spec("spade").length
    deg = np.deg2rad
    beta_rest, beta_scoop, beta_carry = deg(rng.uniform(30, 45)), deg(rng.uniform(15, 30)), deg(rng.uniform(10, 25))
    beta_tip = deg(rng.uniform(70, 88))

    def psi() -> float:
        """A small yaw of the tool out of the motion plane, rad."""
        return deg(rng.uniform(-4, 4))

    def y() -> float:
        """A small sideways drift of the head, metres."""
        return rng.uniform(-0.02, 0.02)

    z_rest = rng.uniform(0.25, 0.35)
    x_entry, z_entry = rng.uniform(0.25, 0.40), rng.uniform(0.01, 0.04)
    push = rng.uniform(0.15, 0.25)
    z_push_end = max(0.005, z_entry - rng.uniform(0.0, 0.01))
    z_carry = rng.uniform(0.34, 0.46)
    carry = rng.uniform(0.4, 0.9)
    dump_height = rng.uniform(0.27, 0.40)

    f = 0
    knots = [_knot(f, hand_from_head([0.0, y(), z_rest], beta_rest, psi(), L))]
    f += _frames(rng, 0.15, 0.35, fps)
    knots.append(_knot(f, knots[-1].q))  # still at the start
    f += _frames(rng, 0.45, 0.7, fps)
    entry_frame = f
    push_duration = _frames(rng, 0.3, 0.45, fps, 4) / fps
    push_speed = 0.8 * push / push_duration
    entry = hand_from_head([x_entry, y(), z_entry], beta_scoop, 0.0, L)
    knots.append(_knot(f, entry, [push_speed, 0, 0, 0, 0]))
    f += int(round(push_duration * fps))
    push_end_frame = f
    pushed = hand_from_head([x_entry + push, entry[1], z_push_end], beta_scoop, 0.0, L)
    knots.append(_knot(f, pushed, [push_speed, 0, 0, 0, 0]))
    f += _frames(rng, 0.4, 0.6, fps)
    carry_start_frame = f
    lift_x = x_entry + push + rng.uniform(0.03, 0.08)
    carry_duration = _frames(rng, 0.7, 1.1, fps, 6) / fps
    carry_speed = 0.6 * carry / carry_duration
    knots.append(_knot(f, hand_from_head([lift_x, y(), z_carry], beta_carry, 0.0, L), [carry_speed, 0, 0, 0, 0]))
    f += int(round(carry_duration * fps))
    carry_end_frame = f
    carried = hand_from_head([lift_x + carry, y(), z_carry + rng.uniform(-0.015, 0.015)], beta_carry, psi(), L)
    knots.append(_knot(f, carried))
    f += _frames(rng, 0.3, 0.45, fps, 4)
    dump_end_frame = f
    # Tip over the target: the blade turns down to pour while the hand rises and pushes forward,
    # so the blade stays within a few cm of where the carry ended.
    tipped = carried.copy()
    carried_head = hand_tool_points(carried[None], L)[0][0]
    tipped[0] = carried_head[0] - L * np.cos(beta_tip) * np.cos(carried[4]) + rng.uniform(-0.05, 0.03)
    tipped[2] = dump_height + L * np.sin(beta_tip)
    tipped[3] = beta_tip
    knots.append(_knot(f, tipped))
    f += _frames(rng, 0.15, 0.3, fps)
    knots.append(_knot(f, tipped))  # sand pours out
    f += _frames(rng, 0.5, 0.8, fps)
    back = hand_from_head([lift_x + carry - rng.uniform(0.1, 0.3), y(), rng.uniform(0.25, 0.35)], beta_rest, psi(), L)
    knots.append(_knot(f, back))
    f += _frames(rng, 0.15, 0.35, fps)
    knots.append(_knot(f, back))
    events = {
        "scoop": [entry_frame, push_end_frame],
        "carry": [carry_start_frame, carry_end_frame],
        "dump": [carry_end_frame, dump_end_frame],
    }
    params = {
        "scoop_height": z_entry,
        "push_length": push,
        "carry_height": z_carry,
        "carry_length": carry,
        "dump_height": dump_height,
    }
    return knots, lambda q: hand_tool_points(q, L), events, params


# --- hammer ------------------------------------------------------------------------------------
def hammer_knots(rng: np.random.Generator, fps: float) -> KnotMotion:
    """Aim above the nail, then 2-4 strikes: raise, strike the nail head at speed, short rebound."""
    L = tool_spec("hammer").length
    deg = np.deg2rad
    n_strikes = int(rng.integers(2, 5))
    nail = np.array([rng.uniform(0.35, 0.5), 0.0, rng.uniform(0.06, 0.12)])
    dt = 1.0 / fps

    def impact_pose() -> np.ndarray:
        head = nail + [rng.uniform(-0.004, 0.004), rng.uniform(-0.004, 0.004), 0.0]
        return hand_from_head(head, deg(rng.uniform(0, 8)), deg(rng.uniform(-3, 3)), L)

    def raised_pose(impact: np.ndarray) -> tuple[np.ndarray, float]:
        """Head 0.22-0.33 m above the nail, hand about 2-9 cm higher and up to 6 cm further back."""
        raise_height, hand_rise = rng.uniform(0.22, 0.33), rng.uniform(0.02, 0.09)
        sin_up = np.clip((raise_height - hand_rise) / L - np.sin(impact[3]), 0.2, 0.95)
        q = impact.copy()
        q[0] -= rng.uniform(0.0, 0.06)
        q[2] = nail[2] + raise_height - L * sin_up
        q[3] = -np.arcsin(sin_up)
        return q, raise_height

    f = 0
    aim_head = nail + [-rng.uniform(0.02, 0.06), 0.0, rng.uniform(0.04, 0.08)]
    aim = hand_from_head(aim_head, deg(rng.uniform(8, 20)), 0.0, L)
    knots = [_knot(f, aim)]
    f += _frames(rng, 0.25, 0.45, fps)
    knots.append(_knot(f, aim))
    impacts, speeds, raises = [], [], []
    for _ in range(n_strikes):
        impact = impact_pose()
        raised, raise_height = raised_pose(impact)
        raises.append(raise_height)
        f += _frames(rng, 0.35, 0.55, fps, 6)
        knots.append(_knot(f, raised))
        f += _frames(rng, 0.0, 0.12, fps, 0) if rng.random() < 0.6 else 0
        if f != knots[-1].frame:
            knots.append(_knot(f, raised))
        # Strike: the head arrives at the nail height moving down at 2.7-3.6 m/s.
        speed = rng.uniform(2.7, 3.6)
        drop = hand_tool_points(raised[None], L)[0][0, 2] - nail[2]
        n = max(3, int(round(1.8 * drop / (speed * dt))))
        duration = n * dt
        v = np.zeros(5)
        v[0] = 1.5 * (impact[0] - raised[0]) / duration
        v[2] = -1.5 * (raised[2] - impact[2]) / duration if raised[2] > impact[2] else 0.0
        # Head's vertical speed = hand_z' - L cos(beta) beta'  ->  the beta' that gives ``speed``.
        v[3] = (speed + v[2]) / (L * np.cos(impact[3]))
        rebound = np.zeros(5)
        rebound[3] = -rng.uniform(0.1, 0.25) * speed / (L * np.cos(impact[3]))
        f += n
        knots.append(_knot(f, impact, v, rebound))
        impacts.append(f)
        speeds.append(speed)
        settle = impact.copy()
        settle[3] -= rng.uniform(0.02, 0.05) / L
        f += _frames(rng, 0.1, 0.18, fps, 3)
        knots.append(_knot(f, settle))
        f += _frames(rng, 0.05, 0.2, fps, 1)
        knots.append(_knot(f, settle))
    rest_head = nail + [-rng.uniform(0.05, 0.12), 0.0, rng.uniform(0.06, 0.14)]
    rest = hand_from_head(rest_head, deg(rng.uniform(20, 40)), 0.0, L)
    f += _frames(rng, 0.4, 0.6, fps)
    knots.append(_knot(f, rest))
    f += _frames(rng, 0.2, 0.35, fps)
    knots.append(_knot(f, rest))
    params = {
        "nail_height": float(nail[2]),
        "strikes": n_strikes,
        "impact_speed_min": min(speeds),
        "impact_speed_max": max(speeds),
        "raise_height_min": min(raises),
        "raise_height_max": max(raises),
    }
    return knots, lambda q: hand_tool_points(q, L), {"impacts": impacts}, params


# --- scythe ------------------------------------------------------------------------------------
#: Head to hands of the demonstrator's scythe, m: a real scythe, longer than the simulated one
#: (``tool_spec("scythe").length``, the authors' 0.68 m). The video shows the demonstrator's tool;
#: alignment uses its head path and axis only, as the authors' does.
DEMONSTRATOR_SCYTHE_LENGTH = 1.0


def scythe_knots(rng: np.random.Generator, fps: float) -> KnotMotion:
    """1-2 mowing strokes from right to left, the mower stepping forward between them.

    A stroke, as a mower makes it: the blade swung in from the right, low, then drawn through the
    grass in front of the body (the *draw*: the body turns left while the arms pull the snath in,
    so the blade slides along its length and moves towards the hands at 1.6-2.2 m/s), then
    carried on to the left and lifted. What the authors' tool and cut rule need
    (:mod:`toolimit.scenes.scythe_cut`): their blade lies in the snath's plane and the edge's
    normal is the snath, so the snath is held 5-20 degrees above horizontal (a real scythe's snath
    rises 35-45 degrees over a blade hafted flat) and the draw moves the edge towards the hands.

    Coordinates ``q = (theta, radius, head_z, elevation, pivot_x, pivot_y)``: the head (the blade's
    root on the snath) at angle ``theta`` (rad, from local +x, counter-clockwise) and ``radius``
    (m) around the body's vertical axis through ``(pivot_x, pivot_y)``, ``head_z`` m above the
    ground; the snath points from the head towards that axis, ``elevation`` rad above horizontal.
    """
    L = DEMONSTRATOR_SCYTHE_LENGTH
    deg = np.deg2rad
    elevation = deg(rng.uniform(5, 20))
    hands_in = rng.uniform(0.15, 0.3)  # hands from the body axis at the end of the draw, m
    radius_in = hands_in + L * np.cos(elevation)
    z_cut = rng.uniform(0.02, 0.05)
    n_strokes = int(rng.integers(1, 3))

    def rest(theta: float, radius: float, z: float, pivot: np.ndarray) -> np.ndarray:
        return np.array([theta, radius, z, elevation + deg(rng.uniform(-2, 2)), *pivot])

    pivot = np.zeros(2)
    f = 0
    knots: list[Knot] = []
    draws, pull_speeds, turn_speeds = [], [], []
    for i in range(n_strokes):
        pull_speed, turn_speed = rng.uniform(1.6, 2.2), rng.uniform(0.4, 0.8)  # m/s at the head
        draw_frames = max(3, int(round(rng.uniform(0.2, 0.3) / pull_speed * fps)))
        pull = pull_speed * draw_frames / fps  # the draw's length along the snath, m
        radius_out = radius_in + pull
        omega = turn_speed / (radius_out - pull / 2)  # rad/s
        centre = deg(rng.uniform(-15, 15))  # where the draw crosses in front of the body
        draw_start = np.array([centre - omega * draw_frames / fps / 2, radius_out, z_cut, elevation, *pivot])
        draw_end = draw_start + [omega * draw_frames / fps, -pull, 0.0, 0.0, 0.0, 0.0]
        velocity = np.array([omega, -pull_speed, 0.0, 0.0, 0.0, 0.0])
        lead_frames = _frames(rng, 0.45, 0.6, fps, 6)
        # Swung in from the right and a little further out: the quintic ramps the draw's speed up.
        wind_up = rest(
            draw_start[0] - deg(rng.uniform(10, 25)),
            radius_out + 0.3 * pull_speed * lead_frames / fps,
            z_cut + rng.uniform(0.0, 0.03),
            pivot,
        )
        if i == 0:
            knots.append(_knot(f, wind_up))
            f += _frames(rng, 0.2, 0.35, fps)
        knots.append(_knot(f, wind_up))
        f += lead_frames
        knots.append(_knot(f, draw_start, velocity))
        draws.append([f, f + draw_frames])
        f += draw_frames
        knots.append(_knot(f, draw_end, velocity))
        follow_frames = _frames(rng, 0.35, 0.5, fps, 5)
        f += follow_frames
        follow = rest(
            draw_end[0] + 0.5 * omega * follow_frames / fps + deg(rng.uniform(15, 30)),
            radius_in - 0.3 * pull_speed * follow_frames / fps,
            rng.uniform(0.08, 0.15),
            pivot,
        )
        knots.append(_knot(f, follow))
        pull_speeds.append(pull_speed)
        turn_speeds.append(turn_speed)
        if i < n_strokes - 1:
            pivot = pivot + rng.uniform(0.15, 0.3) * np.array([np.cos(centre), np.sin(centre)])
            f += _frames(rng, 0.8, 1.0, fps, 6)  # back to the right, raised, stepping forward
    f += _frames(rng, 0.2, 0.35, fps)
    knots.append(_knot(f, knots[-1].q))

    def points(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        theta, r, z, b = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
        radial = np.stack([np.cos(theta), np.sin(theta), np.zeros_like(theta)], axis=1)
        head = np.concatenate([q[:, 4:6], np.zeros((len(q), 1))], axis=1) + r[:, None] * radial
        head[:, 2] = z
        inward = np.stack([-np.cos(b) * np.cos(theta), -np.cos(b) * np.sin(theta), np.sin(b)], axis=1)
        return head, head + L * inward

    params = {
        "cut_height": z_cut,
        "snath_elevation": elevation,
        "strokes": n_strokes,
        "pull_speed_min": min(pull_speeds),
        "pull_speed_max": max(pull_speeds),
        "turn_speed_min": min(turn_speeds),
        "turn_speed_max": max(turn_speeds),
    }
    return knots, points, {"sweeps": draws}, params


# --- noise -------------------------------------------------------------------------------------
def add_reconstruction_noise(
    head: np.ndarray, handle: np.ndarray, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Noise like a monocular reconstruction's: jitter plus a few percent of outlier frames.

    * jitter: Gaussian, sigma 2-5 mm per coordinate, independent for head and handle;
    * outliers: 2-5 % of the frames (at least one), in runs of 1-2 frames, away from the ends and
      from each other; each run is a rigid jump of the tool by 6-30 cm (60 %), a flip (rotation
      of the tool about its middle by 0.9-pi rad: pi swaps head and handle, 25 %), or one end
      alone off by 10-25 cm (at most half the tool's length, 15 %).

    ``head``, ``handle`` (T, 3) metres. Returns noisy head, noisy handle, outlier frame indices,
    jitter sigma (m).
    """
    T = len(head)
    sigma = rng.uniform(0.002, 0.005)
    head = head + rng.normal(0.0, sigma, head.shape)
    handle = handle + rng.normal(0.0, sigma, handle.shape)
    n_outliers = max(1, int(round(rng.uniform(0.02, 0.05) * T)))
    taken = np.zeros(T, dtype=bool)
    outliers: list[int] = []
    for _attempt in range(50 * n_outliers):
        if len(outliers) >= n_outliers:
            break
        start, run = int(rng.integers(3, T - 4)), min(1 + int(rng.random() < 0.2), n_outliers - len(outliers))
        if taken[max(0, start - 4) : start + run + 4].any():
            continue
        frames = np.arange(start, start + run)
        taken[frames] = True
        outliers.extend(frames.tolist())
        kind = rng.random()
        if kind < 0.6:
            direction = rng.normal(size=3)
            offset = direction / np.linalg.norm(direction) * rng.uniform(0.06, 0.30)
            head[frames] += offset
            handle[frames] += offset
        elif kind < 0.85:
            angle = rng.uniform(0.9, np.pi)
            for i in frames:
                middle, half = 0.5 * (head[i] + handle[i]), 0.5 * (handle[i] - head[i])
                axis = np.cross(half, rng.normal(size=3))
                axis /= np.linalg.norm(axis)
                # Rodrigues rotation of the half segment about an axis across the tool.
                rotated = half * np.cos(angle) + np.cross(axis, half) * np.sin(angle)
                head[i], handle[i] = middle - rotated, middle + rotated
        else:
            length = np.linalg.norm(handle[frames[0]] - head[frames[0]])
            which = head if rng.random() < 0.5 else handle
            direction = rng.normal(size=3)
            offset = direction / np.linalg.norm(direction) * min(rng.uniform(0.10, 0.25), 0.5 * length)
            which[frames] += offset
    return head, handle, np.array(sorted(outliers), dtype=int), float(sigma)


# --- public API --------------------------------------------------------------------------------
def synthetic_tools() -> list[str]:
    """The registered tools with a synthetic-demonstration generator, sorted."""
    return sorted(record.name for record in tool_records() if record.synthetic_motion is not None)


def synthetic_generator(tool: str) -> KnotGenerator:
    """The generator of ``tool``'s synthetic motions (its record's ``synthetic_motion``); DemoError
    for a tool without one."""
    record = find_tool(tool)
    entry_point = None if record is None else record.synthetic_motion
    if entry_point is None:
        raise DemoError(f"tool: no synthetic demonstrations for {tool!r}; known: {', '.join(synthetic_tools())}")
    return load_entry_point(entry_point)


def synthesize_motion(tool: str, seed: int, fps: float = 24) -> SyntheticMotion:
    """A seeded synthetic demonstration of ``tool``, clean and noisy, with its events.

    The local motion is turned by a yaw drawn in [-pi, pi) and shifted by up to 0.2 m in x and y
    (world frame, metres, z up, ground z = 0). 2.5-6 s long, starting and ending at rest.
    """
    generator = synthetic_generator(tool)
    if problem := frame_rate_problem(fps):
        raise DemoError(f"fps: {problem}")
    motion_rng, noise_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
    knots, points, events, params = generator(motion_rng, float(fps))
    minimum_frames = int(np.ceil(MIN_DURATION * fps)) + 1
    if knots[-1].frame + 1 < minimum_frames:  # hold the last pose a little longer
        knots.append(_knot(minimum_frames - 1, knots[-1].q))
    head, handle = points(sample_knots(knots, float(fps)))
    yaw = motion_rng.uniform(-np.pi, np.pi)
    offset = np.array([*motion_rng.uniform(-0.2, 0.2, 2), 0.0])
    source = f"toolimit.demos.synthetic seed={seed} fps={fps}"
    clean = ToolDemo(head, handle, fps, tool, source=source + " clean").rotated_yaw(yaw).translated(offset)
    noisy_head, noisy_handle, outliers, sigma = add_reconstruction_noise(clean.head, clean.handle, noise_rng)
    noisy = replace(clean, head=noisy_head, handle=noisy_handle, source=source + " noisy")
    return SyntheticMotion(clean, noisy, outliers, sigma, events, {**params, "yaw": float(yaw)})


def synthesize_demo(tool: str, seed: int, fps: float = 24, noise: bool = True) -> ToolDemo:
    """A seeded synthetic demonstration (see :func:`synthesize_motion`); ``noise=False`` gives the
    same motion without jitter and outliers."""
    motion = synthesize_motion(tool, seed, fps)
    return motion.noisy if noise else motion.clean
