"""Where a policy succeeds as the goal box moves: spheres delivered over a grid of box positions.

:func:`goal_box_heat_map` rolls the policy out deterministically (its mean action) with the goal
box at every point of a grid covering the ADR rectangle (:data:`toolimit.learn.adr.HALF_RANGE`:
100 x 90 cm around the aligned position) times :data:`COVER`, and keeps the goal reward at the
last step (spade: spheres in the box) and the paper's success per cell. A policy learned with ADR
observes the box; one learned without does not, and its map shows where its fixed motion happens to
deliver. Cells where the box cannot stand (on the deposit) are NaN. In the planar x-z world the box
has no y, so the grid is one row of x values spanning the rectangle's y range.

The robot's reach (:func:`tool_reach`) is the farthest horizontal distance from the robot's base of
the tool frame's origin (the blade tip) over the robot's joint ranges, with the tip above the
ground: the largest of :data:`REACH_SAMPLES` uniform joint samples, refined by a seeded local
search (random steps shrinking from 0.3 to 0.003 rad, kept when they reach farther). Beyond this
circle no motion of the arm can bring the blade over the box, so a cell whose box centre lies
outside it is not reachable (:attr:`HeatMap.reachable`), and the counts the ADR target is judged on
(:meth:`HeatMap.counts`: the rectangle's positions where the box can stand and the robot can reach)
leave it out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm

from toolimit.learn.adr import GOAL_BOX, HALF_RANGE, goal_box_spec
from toolimit.learn.evaluate import EVALUATION_SEED, observes_goal_box
from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.task import LearningTask
from toolimit.robots import RobotModel

#: Deterministic episodes per cell by default: the reset noise (start joints, deposit, sand) varies
#: between them, and one episode per cell let a single lucky or unlucky reset decide a cell.
EPISODES_PER_CELL = 4

#: The grid spans the ADR rectangle scaled by this factor (1.5: 150 x 135 cm).
COVER = 1.5
#: Uniform joint samples and local-search steps of :func:`tool_reach`.
REACH_SAMPLES = 4096
REACH_STEPS = 400


@dataclass(frozen=True)
class HeatMap:
    """A policy's goal reward over goal box positions (world frame, m).

    Attributes:
        x_edges, y_edges: (nx+1,), (ny+1,) cell edges; cell (j, i) has its box at the centre.
        goal_rewards: (ny, nx) mean goal reward at the last step (spade: spheres in the box), NaN
            where the box cannot stand.
        successes: (ny, nx) fraction of the cell's episodes that met the paper's success test.
        aligned: (2,) the task's box position. rectangle: (2, 2) rows low, high of the ADR range.
        base: (2,) the robot base's x, y. reach: the tool's reach around it (:func:`tool_reach`), m.
        deposit: (5,) the deposit's ground rectangle (cx, cy, half-length, half-width, yaw).
        episodes: episodes per cell. observes_box: whether the policy observes the box (ADR).
    """

    x_edges: np.ndarray
    y_edges: np.ndarray
    goal_rewards: np.ndarray
    successes: np.ndarray
    aligned: np.ndarray
    rectangle: np.ndarray
    base: np.ndarray
    reach: float
    deposit: np.ndarray
    episodes: int
    observes_box: bool

    @property
    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """(nx,), (ny,) the cells' box x and y, m."""
        return (self.x_edges[:-1] + self.x_edges[1:]) / 2, (self.y_edges[:-1] + self.y_edges[1:]) / 2

    @property
    def reachable(self) -> np.ndarray:
        """(ny, nx) bool: the cell's box centre is within the tool's reach of the robot base
        (horizontal distance <= :attr:`reach`)."""
        xs, ys = self.centres
        x, y = np.meshgrid(xs, ys)
        return np.hypot(x - self.base[0], y - self.base[1]) <= self.reach

    def counts(self) -> dict[str, int]:
        """How many cells the box can stand in (``standing``) and, of those, how many the policy
        succeeds in (``succeeding``: success in at least half of the cell's episodes); the same
        inside the ADR rectangle (``*_in_rectangle``: cell centres within it, 1 mm tolerance), and
        inside it where the robot can also reach (``*_reachable_in_rectangle``, :attr:`reachable`)."""
        xs, ys = self.centres
        x, y = np.meshgrid(xs, ys)
        low, high = self.rectangle[0] - 1e-3, self.rectangle[1] + 1e-3
        inside = (low[0] <= x) & (x <= high[0]) & (low[1] <= y) & (y <= high[1])
        standing = ~np.isnan(self.successes)
        succeeding = self.successes >= 0.5  # False where NaN (the box cannot stand)
        reachable = inside & self.reachable
        return {
            "standing": int(standing.sum()),
            "succeeding": int(succeeding.sum()),
            "standing_in_rectangle": int((standing & inside).sum()),
            "succeeding_in_rectangle": int((succeeding & inside).sum()),
            "standing_reachable_in_rectangle": int((standing & reachable).sum()),
            "succeeding_reachable_in_rectangle": int((succeeding & reachable).sum()),
        }

    def record(self) -> dict[str, Any]:
        """JSON-ready (NaN cells as null), with :meth:`counts`."""

        def listed(values: np.ndarray) -> list:
            return [[None if np.isnan(v) else float(v) for v in row] for row in values]

        return {
            "x_edges": self.x_edges.tolist(),
            "y_edges": self.y_edges.tolist(),
            "goal_rewards": listed(self.goal_rewards),
            "successes": listed(self.successes),
            "aligned": self.aligned.tolist(),
            "rectangle": self.rectangle.tolist(),
            "base": self.base.tolist(),
            "reach_m": self.reach,
            "reachable": self.reachable.tolist(),
            "episodes": self.episodes,
            "observes_box": self.observes_box,
            **self.counts(),
        }


def grid_edges(centre: float, half: float, count: int) -> np.ndarray:
    """(count+1,) edges of ``count`` equal cells whose centres run from centre - half to centre + half."""
    if count == 1:
        return np.array([centre - half, centre + half])
    step = 2 * half / (count - 1)
    return centre - half - step / 2 + step * np.arange(count + 1)


def goal_box_heat_map(
    model: BaseAlgorithm,
    task: LearningTask,
    grid: int = 9,
    episodes: int = EPISODES_PER_CELL,
    seed: int = EVALUATION_SEED,
    scene_kwargs: dict[str, Any] | None = None,
    batch_size: int = 32,
) -> HeatMap:
    """The heat map of ``model`` on ``task`` over ``grid`` x ``grid`` box positions (module
    docstring), ``episodes`` deterministic episodes per cell, in batches of ``batch_size``."""
    if grid < 2 or episodes < 1 or batch_size < 1:
        raise ValueError(f"need grid >= 2, episodes >= 1 and batch_size >= 1, got {grid}, {episodes}, {batch_size}")
    simulator = TaskSimulator(task, batch_size, scene_kwargs=scene_kwargs, adr=observes_goal_box(model, task))
    axes = goal_box_spec(simulator.scene).axes
    aligned = np.asarray(task.params[GOAL_BOX], dtype=float)[:2]
    half = COVER * HALF_RANGE
    x_edges = grid_edges(aligned[0], half[0], grid)
    y_edges = grid_edges(aligned[1], half[1], grid if 1 in axes else 1)
    xs, ys = (x_edges[:-1] + x_edges[1:]) / 2, (y_edges[:-1] + y_edges[1:]) / 2
    cells = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)  # (ny * nx, 2), row-major in y
    valid = np.array([simulator.box_validity(dict(task.params))(cell) for cell in cells])
    todo = np.repeat(np.flatnonzero(valid), episodes)
    goal, success = np.zeros(len(todo)), np.zeros(len(todo))
    rng = np.random.default_rng(seed)
    for start in range(0, len(todo), batch_size):
        chosen = todo[start : start + batch_size]
        positions = np.repeat(aligned[None], batch_size, axis=0)  # padding at the aligned position
        positions[: len(chosen)] = cells[chosen]
        observation = simulator.reset(rng, positions)
        while not simulator.done:
            action, _ = model.predict(observation, deterministic=True)
            observation, _, rewards = simulator.step(action)
        goal[start : start + len(chosen)] = rewards[: len(chosen)]
        success[start : start + len(chosen)] = simulator.is_success()[: len(chosen)]
    goal_rewards, successes = np.full(len(cells), np.nan), np.full(len(cells), np.nan)
    for values, per_episode in ((goal_rewards, goal), (successes, success)):
        values[valid] = per_episode.reshape(-1, episodes).mean(axis=1)
    return HeatMap(
        x_edges=x_edges,
        y_edges=y_edges,
        goal_rewards=goal_rewards.reshape(len(ys), len(xs)),
        successes=successes.reshape(len(ys), len(xs)),
        aligned=aligned,
        rectangle=np.stack([aligned - HALF_RANGE, aligned + HALF_RANGE]),
        base=np.asarray(task.base[:2], dtype=float),
        reach=tool_reach(simulator.robot, task.base, np.random.default_rng(seed)),
        deposit=simulator.scene.footprints(task.params)[0],
        episodes=episodes,
        observes_box=simulator.adr,
    )


def tool_reach(robot: RobotModel, base: np.ndarray, rng: np.random.Generator) -> float:
    """The tool's horizontal reach around the base's x, y with the tip above the ground, m
    (module docstring)."""

    def reach(q: np.ndarray) -> np.ndarray:
        positions, _ = robot.tool_poses(q, base)
        distance = np.linalg.norm(positions[:, :2] - base[:2], axis=1)
        return np.where(positions[:, 2] >= 0.0, distance, -np.inf)

    samples = rng.uniform(robot.lower, robot.upper, size=(REACH_SAMPLES, len(robot.lower)))
    distances = reach(samples)
    best_q, best = samples[np.argmax(distances)], float(distances.max())
    for sigma in np.geomspace(0.3, 0.003, REACH_STEPS):
        candidate = np.clip(best_q + rng.normal(0.0, sigma, best_q.shape), robot.lower, robot.upper)
        distance = float(reach(candidate[None])[0])
        if distance > best:
            best_q, best = candidate, distance
    return best
