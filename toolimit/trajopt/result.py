"""The result of trajectory optimisation: joint trajectory, base, tracking errors, limits, statistics.

Saved as ``DIR/trajectory.npz`` (keys ``q`` (T+1, N) and ``v`` (T, N) for the robot's own joints,
radians and rad/s; ``base`` (3,) x, y (m), yaw (rad); ``joint_names`` (N,); ``dt`` (s); for a
trajectory tracked in an alignment candidate's scene, ``scene_world``, ``scene_candidate`` and the
scene parameters ``param_<name>``, :class:`TrackedScene`) and
``DIR/trajectory.json`` (robot, tool, errors, limit margins, velocity ratios, solver statistics,
time scale). Both files are written to temporary names and renamed together.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from toolimit.artifacts import atomic_path, json_text, load_npz
from toolimit.errors import InputError
from toolimit.scenes.base import SceneParams, pack_scene_params, unpack_scene_params
from toolimit.trajopt.problem import TrackingWeights

TRAJECTORY_NPZ = "trajectory.npz"
TRAJECTORY_JSON = "trajectory.json"


#: Median rotation error beyond which a result counts as tracking the tool upside down, rad.
UPSIDE_DOWN_RAD = np.pi / 2
#: |v - diff(q) / dt| allowed in trajectory.npz, rad/s.
_VELOCITY_CONSISTENCY_TOL = 1e-6


class UpsideDownTracking(UserWarning):
    """A trajectory tracks the tool's position with the tool turned upside down (a spade's blade
    facing the ground): its robot replay earns little whatever its position error says."""

    @classmethod
    def of(cls, result: TrajectoryResult) -> UpsideDownTracking:
        """The warning for ``result``, with its median rotation error."""
        return cls(
            f"the {result.tool} is tracked upside down by the {result.robot} (median rotation error "
            f"{np.degrees(np.median(result.rotation_error)):.0f} deg): its position follows the targets, its "
            "orientation does not (trajectory.json has the error at every step)"
        )


@dataclass(frozen=True)
class TrackedScene:
    """The scene a trajectory was tracked in: the alignment candidate whose scene stage iv learns in.

    Attributes:
        world: the scene's world (``"planar"`` or ``"3d"``).
        candidate: the candidate's index in the alignment's ``candidates.npz``.
        params: its scene parameters (position parameters (3,) m, world frame; uniform ones floats).
    """

    world: str
    candidate: int
    params: SceneParams

    def arrays(self) -> dict[str, np.ndarray]:
        """The keys this record adds to ``trajectory.npz``."""
        return {
            "scene_world": np.str_(self.world),
            "scene_candidate": np.int64(self.candidate),
            **pack_scene_params(self.params),
        }

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray]) -> TrackedScene | None:
        """The record in a loaded ``trajectory.npz``; None for a trajectory tracked without a scene."""
        if "scene_world" not in arrays:
            return None
        return cls(str(arrays["scene_world"]), int(arrays["scene_candidate"]), unpack_scene_params(arrays))


@dataclass(frozen=True)
class JointTrajectory:
    """A trajectory.npz: q (T+1, N) rad, v (T, N) rad/s, base (3,) (m, m, rad), joint names, dt s,
    and the scene it was tracked in (None: tracked from poses alone)."""

    q: np.ndarray
    v: np.ndarray
    base: np.ndarray
    joint_names: tuple[str, ...]
    dt: float
    scene: TrackedScene | None = None


def load_trajectory(directory: str | os.PathLike[str]) -> JointTrajectory:
    """Read and validate ``directory/trajectory.npz``, the one reader of that file (errors name the
    file and the field)."""
    path = Path(directory) / TRAJECTORY_NPZ
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file (expected the output of `toolimit trajopt`)")
    data = load_npz(path, required=("q", "v", "base", "joint_names", "dt"))
    q = np.asarray(data["q"], dtype=float)
    v = np.asarray(data["v"], dtype=float)
    base = np.asarray(data["base"], dtype=float)
    joint_names = tuple(str(name) for name in np.atleast_1d(data["joint_names"]))
    dt = float(data["dt"])
    if q.ndim != 2 or len(q) < 2:
        raise InputError(f"{path}: q must have shape (T+1, N) with T >= 1, got {q.shape}")
    n_steps, n_joints = len(q) - 1, q.shape[1]
    if v.shape != (n_steps, n_joints):
        raise InputError(f"{path}: v must have shape {(n_steps, n_joints)} to match q {q.shape}, got {v.shape}")
    if base.shape != (3,):
        raise InputError(f"{path}: base must have shape (3,), got {base.shape}")
    if len(joint_names) != n_joints:
        raise InputError(f"{path}: joint_names has {len(joint_names)} names for {n_joints} joints in q")
    if not (np.isfinite(dt) and dt > 0):
        raise InputError(f"{path}: dt must be a positive number of seconds, got {dt}")
    for name, array in (("q", q), ("v", v), ("base", base)):
        if not np.all(np.isfinite(array)):
            raise InputError(f"{path}: {name} contains non-finite values")
    mismatch = np.abs(np.diff(q, axis=0) / dt - v)
    if mismatch.max() > _VELOCITY_CONSISTENCY_TOL:
        t, j = np.unravel_index(np.argmax(mismatch), mismatch.shape)
        raise InputError(f"{path}: v[{t}, {j}] differs from (q[{t + 1}] - q[{t}]) / dt by {mismatch[t, j]:.3g} rad/s")
    return JointTrajectory(q=q, v=v, base=base, joint_names=joint_names, dt=dt, scene=TrackedScene.from_arrays(data))


@dataclass(frozen=True)
class TimeScaleSearch:
    """How :func:`~toolimit.trajopt.time_scale.choose_time_scale` chose the slow-down factor, kept
    so that a reader of trajectory.json sees what the other scales would have given.

    Attributes:
        median_position_error_m: median tool position error (m) of the kept run at each time scale
            tried, by scale, in the order tried (ascending; the search stops at the first that meets
            the threshold).
        threshold_m: the median position error a scale had to stay under, metres.
        threshold_met: whether the chosen scale stays under it (False: the best-tracking scale was kept).
    """

    median_position_error_m: dict[float, float]
    threshold_m: float
    threshold_met: bool

    def to_json(self) -> dict[str, Any]:
        """The JSON form (scales written as ``f"{scale:g}"``)."""
        errors = {f"{scale:g}": error for scale, error in self.median_position_error_m.items()}
        return {"median_position_error_m": errors, "threshold_m": self.threshold_m, "threshold_met": self.threshold_met}

    @classmethod
    def from_json(cls, record: dict[str, Any]) -> TimeScaleSearch:
        """The search written by :meth:`to_json`."""
        errors = {float(scale): float(error) for scale, error in record["median_position_error_m"].items()}
        return cls(errors, float(record["threshold_m"]), bool(record["threshold_met"]))


@dataclass(frozen=True)
class TrackingStatistics:
    """What :func:`~toolimit.trajopt.track.track` did to find a trajectory: the kept run's cost and
    solver figures and how the other starts ended, so that a result can be compared and traced.

    Attributes:
        cost: J of the kept run (dimensionless; see :mod:`toolimit.trajopt.problem`).
        initial_cost: J at the kept run's initialisation.
        cost_terms: J's terms by name (``pose``, ``velocity``, ``posture``) and their sum ``total``.
        iterations: SQP iterations of the kept run.
        qp_iterations: OSQP iterations of the kept run, all SQP iterations together.
        converged: the kept run stopped on its relative-decrease test (not its iteration limit).
        start_index: the kept run's row of the base guesses.
        roll_variant: 0 when the kept run tracks the targets, 1 when it tracks them turned by pi
            about the tool axis (a roll-symmetric tool).
        initialisation: the kept run's joint initialisation, ``"hold"`` or ``"rollout"``.
        start_costs: J of every run, ordered by roll variant, initialisation, start; None where the
            run's base stood inside a scene element.
        starts_rejected_in_footprints: runs discarded because their base stood inside an element.
        starts_merged: runs stopped early on joining a converged run's basin.
        wall_time_s: seconds of the whole multi-start.
        best_start_wall_time_s: seconds of the kept run.
        weights: the cost weights J was built with.
        time_scale_search: how the time scale was chosen, or None when it was given.
    """

    cost: float
    initial_cost: float
    cost_terms: dict[str, float]
    iterations: int
    qp_iterations: int
    converged: bool
    start_index: int
    roll_variant: int
    initialisation: str
    start_costs: tuple[float | None, ...]
    starts_rejected_in_footprints: int
    starts_merged: int
    wall_time_s: float
    best_start_wall_time_s: float
    weights: TrackingWeights
    time_scale_search: TimeScaleSearch | None = None

    def to_json(self) -> dict[str, Any]:
        """The JSON form, ``statistics`` of trajectory.json (no ``time_scale_search`` key when None)."""
        record = asdict(self) | {"start_costs": list(self.start_costs)}
        del record["time_scale_search"]
        if self.time_scale_search is not None:
            record["time_scale_search"] = self.time_scale_search.to_json()
        return record

    @classmethod
    def from_json(cls, record: dict[str, Any]) -> TrackingStatistics:
        """The statistics written by :meth:`to_json` (keys of older writers that it no longer writes,
        such as ``time_scale``, are ignored)."""
        search = record.get("time_scale_search")
        return cls(
            cost=float(record["cost"]),
            initial_cost=float(record["initial_cost"]),
            cost_terms={name: float(value) for name, value in record["cost_terms"].items()},
            iterations=int(record["iterations"]),
            qp_iterations=int(record["qp_iterations"]),
            converged=bool(record["converged"]),
            start_index=int(record["start_index"]),
            roll_variant=int(record["roll_variant"]),
            initialisation=str(record["initialisation"]),
            start_costs=tuple(None if cost is None else float(cost) for cost in record["start_costs"]),
            starts_rejected_in_footprints=int(record["starts_rejected_in_footprints"]),
            starts_merged=int(record["starts_merged"]),
            wall_time_s=float(record["wall_time_s"]),
            best_start_wall_time_s=float(record["best_start_wall_time_s"]),
            weights=TrackingWeights(**record["weights"]),
            time_scale_search=None if search is None else TimeScaleSearch.from_json(search),
        )


@dataclass(frozen=True)
class TrajectoryResult:
    """An optimised robot trajectory and how well it tracks its targets.

    Attributes:
        robot: robot name (``make_robot``); tool: tool name.
        joint_names: (N,) arm joint names.
        q: (T+1, N) joint positions, radians; q[0] is the start configuration.
        v: (T, N) joint velocities, rad/s; q[t] = q[t-1] + dt v[t-1].
        base: (3,) base x, y (m) and yaw (rad) in the world frame.
        dt: time step, seconds (= time_scale / demonstration fps).
        time_scale: slow-down factor of the demonstration (1 = real time).
        position_error: (T,) |p(q_t) - p_t|, metres, t = 1..T.
        rotation_error: (T,) |log3(R_t^T R(q_t))|, radians.
        limit_margin: (T+1, N) distance of each joint to its nearest position limit, radians
            (negative = violation).
        velocity_ratio: (T, N) |v| / velocity limit (above 1 = violation).
        statistics: how :func:`~toolimit.trajopt.track.track` found the trajectory; None for a
            trajectory made another way (by hand, in tests).
        scene: the alignment candidate whose scene the trajectory was tracked and replayed in
            (:func:`~toolimit.trajopt.selection.select_by_robot_execution`); None when tracked from
            poses alone.
    """

    robot: str
    tool: str
    joint_names: tuple[str, ...]
    q: np.ndarray
    v: np.ndarray
    base: np.ndarray
    dt: float
    time_scale: float
    position_error: np.ndarray
    rotation_error: np.ndarray
    limit_margin: np.ndarray
    velocity_ratio: np.ndarray
    statistics: TrackingStatistics | None = None
    scene: TrackedScene | None = None

    @property
    def cost(self) -> float:
        """J of the trajectory (see :mod:`toolimit.trajopt.problem`); NaN without statistics."""
        return float("nan") if self.statistics is None else self.statistics.cost

    @property
    def horizon(self) -> int:
        """T, the number of steps."""
        return len(self.v)

    @property
    def limit_violations(self) -> int:
        """Number of (step, joint) entries outside the position limits."""
        return int(np.sum(self.limit_margin < 0))

    @property
    def velocity_violations(self) -> int:
        """Number of (step, joint) velocities above their limits."""
        return int(np.sum(self.velocity_ratio > 1.0 + 1e-9))

    @property
    def upside_down(self) -> bool:
        """True when the tool is turned more than 90 degrees from its target orientation at the
        median step: the position may be tracked, but with the tool (a spade's blade) upside down."""
        return bool(np.median(self.rotation_error) > UPSIDE_DOWN_RAD)

    def describe(self) -> str:
        """One line: time scale, cost, median position and rotation errors, violations."""
        text = (
            f"time scale {self.time_scale:g}, J = {self.cost:.4f}, "
            f"position error median {np.median(self.position_error) * 100:.1f} cm, rotation error median "
            f"{np.degrees(np.median(self.rotation_error)):.0f} deg, limit violations {self.limit_violations}, "
            f"velocity violations {self.velocity_violations}"
        )
        if self.upside_down:
            text += "; UPSIDE DOWN: the tool is turned more than 90 deg from its target orientation at most steps"
        return text

    def summary(self) -> dict[str, Any]:
        """Scalar figures: errors (m, rad), margins, velocity ratio, statistics."""
        return {
            "robot": self.robot,
            "tool": self.tool,
            "horizon": self.horizon,
            "dt": self.dt,
            "time_scale": self.time_scale,
            "base": {"x": float(self.base[0]), "y": float(self.base[1]), "yaw": float(self.base[2])},
            "position_error_m": _stats(self.position_error),
            "rotation_error_rad": _stats(self.rotation_error),
            "upside_down": self.upside_down,
            "steps_position_error_over_1cm": int(np.sum(self.position_error > 0.01)),
            "min_limit_margin_rad": float(self.limit_margin.min()),
            "limit_violations": self.limit_violations,
            "max_velocity_ratio": float(self.velocity_ratio.max()),
            "velocity_violations": self.velocity_violations,
            "statistics": None if self.statistics is None else self.statistics.to_json(),
            "scene": None if self.scene is None else {"world": self.scene.world, "candidate": self.scene.candidate},
        }

    def save(self, directory: str | os.PathLike[str]) -> Path:
        """Write DIR/trajectory.npz and DIR/trajectory.json (both or neither); returns DIR."""
        directory = Path(directory)
        document = self.summary() | {
            "joint_names": list(self.joint_names),
            "position_error": self.position_error,
            "rotation_error": self.rotation_error,
            "limit_margin": self.limit_margin,
            "velocity_ratio": self.velocity_ratio,
        }
        text = json_text(document)
        with atomic_path(directory / TRAJECTORY_NPZ) as npz_tmp, atomic_path(directory / TRAJECTORY_JSON) as json_tmp:
            with open(npz_tmp, "wb") as handle:
                arrays: dict[str, Any] = {
                    "q": self.q,
                    "v": self.v,
                    "base": self.base,
                    "joint_names": np.array(self.joint_names),
                    "dt": np.float64(self.dt),
                    **({} if self.scene is None else self.scene.arrays()),
                }
                np.savez(handle, **arrays)
            json_tmp.write_text(text)
        return directory

    @classmethod
    def load(cls, directory: str | os.PathLike[str]) -> TrajectoryResult:
        """Read a result written by :meth:`save`; a clear error for a missing or malformed file.

        ``statistics`` written empty (``{}``, by older writers) or ``null`` reads as None."""
        arrays = load_trajectory(directory)
        json_path = Path(directory) / TRAJECTORY_JSON
        if not json_path.is_file():
            raise FileNotFoundError(f"{json_path}: no such file (expected a trajopt output directory)")
        q, v = arrays.q, arrays.v
        document = json.loads(json_path.read_text())
        try:
            statistics = TrackingStatistics.from_json(document["statistics"]) if document["statistics"] else None
        except KeyError as error:
            raise InputError(f"{json_path}: statistics lack the field {error}") from None
        return cls(
            robot=document["robot"],
            tool=document["tool"],
            joint_names=arrays.joint_names,
            q=q,
            v=v,
            base=arrays.base,
            dt=arrays.dt,
            time_scale=float(document["time_scale"]),
            position_error=np.asarray(document["position_error"], dtype=float),
            rotation_error=np.asarray(document["rotation_error"], dtype=float),
            limit_margin=np.asarray(document["limit_margin"], dtype=float).reshape(q.shape),
            velocity_ratio=np.asarray(document["velocity_ratio"], dtype=float).reshape(v.shape),
            statistics=statistics,
            scene=arrays.scene,
        )


def _stats(values: np.ndarray) -> dict[str, float]:
    return {"mean": float(np.mean(values)), "median": float(np.median(values)), "max": float(np.max(values))}
