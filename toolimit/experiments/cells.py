"""The paper's results figure as cells: one tool, demonstration, robot and method each.

The paper's evidence (its results figure) is, for each tool and video, the goal reward of:

- ``tool_only``: the aligned tool motion alone in its scene (stage ii);
- ``trajopt``: the robot's optimised trajectory, executed by the tracking controller (stage iii);
- ``final``: the policy learnt by cloning that trajectory then PPO (stage iv, the method);
- ``sparse_ppo``: PPO on the sparse goal reward from a random policy (baseline iv);
- ``dense_ppo``: PPO from a random policy on the goal reward plus the appendix's dense shaping
  (baseline v);
- ``lfd``: learning from a kinesthetic demonstration, the scene's scripted motion tracked by the
  robot in the same scene (:mod:`toolimit.learn.kinesthetic`), cloned then PPO with the method's
  budget (the paper: comparable to the method).

An :class:`Experiment` is one (tool, world, robot, demonstration): ``toolimit run`` makes its
alignment, trajectory and policy, and the baselines learn from the same task (LfD: from its own
task in the same scene) with the same budget.
Every cell is measured on the same footing: ``episodes`` rollouts from seeded resets, the goal
reward at the last step (spade: spheres in the box) and the paper's success test over the episode.
The tool alone and the trajectory are replayed for the learning task's horizon H (the trajectory is
held at its last configuration after its end, the tool at its last pose), so that a motion whose
sand lands after its end is judged as the policy is.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

#: The methods of the figure, in its order.
METHODS = ("tool_only", "trajopt", "final", "sparse_ppo", "dense_ppo", "lfd")
#: The method's own stages (the paper's three-robot comparison measures these).
PIPELINE_METHODS = METHODS[:3]


@dataclass(frozen=True)
class Experiment:
    """One demonstration of one tool, for one robot in one world: a group of the figure, with the
    methods measured on it (all of them, or the method's stages only for the other robots)."""

    tool: str
    world: str
    robot: str
    demo: Path
    methods: tuple[str, ...] = METHODS
    #: (dotted settings path, value) pairs in which this experiment departs from its preset's
    #: settings, e.g. a wider z offset for a recording whose heights are not ground-referenced.
    settings_changes: tuple[tuple[str, Any], ...] = ()

    @property
    def name(self) -> str:
        """Folder and label, e.g. ``spade-3d-panda-spade_00``."""
        return f"{self.tool}-{self.world}-{self.robot}-{self.demo.stem}"

    def cell_key(self, method: str) -> str:
        """The file name stem of this experiment's cell of ``method``, e.g. ``spade-3d-panda-spade_00-final``."""
        return f"{self.name}-{method}"


@dataclass(frozen=True)
class CellResult:
    """One cell: a method's goal reward and success over ``episodes`` seeded rollouts.

    Attributes:
        tool, world, robot, demo, method: what was measured (``demo`` is the file's stem).
        goal_reward: mean goal reward at the last step (spade: spheres in the box).
        success_rate: fraction of episodes that pass the paper's success test.
        goal_rewards: (E,) per episode.
        successes: (E,) per episode, whether it passed the test (None in cells saved before they
            were recorded: :meth:`episode_successes` then rebuilds them from ``success_rate``).
        env_steps: environment steps the method learnt with (0 for tool_only and trajopt).
        wall_time_s: seconds the method's own work took (for the final policy: the whole
            ``toolimit run``; for the baselines: their learning).
        limits: for a learnt policy, how far its rollouts go past the robot's joint limits
            (:meth:`LimitUse.record <toolimit.learn.limit_use.LimitUse.record>`); None otherwise.
        exported: for the final policy on a robot with published limits, its first rollout
            exported and replayed open-loop from the same resets
            (:meth:`OpenLoopResult.record <toolimit.deploy.open_loop.OpenLoopResult.record>`);
            None otherwise.
    """

    tool: str
    world: str
    robot: str
    demo: str
    method: str
    goal_reward: float
    success_rate: float
    goal_rewards: list[float]
    env_steps: int
    wall_time_s: float
    limits: dict[str, Any] | None = None
    exported: dict[str, Any] | None = None
    successes: list[bool] | None = None

    @classmethod
    def of(
        cls,
        experiment: Experiment,
        method: str,
        goal_rewards: np.ndarray,
        successes: np.ndarray,
        env_steps: int = 0,
        wall_time_s: float = 0.0,
        limits: dict[str, Any] | None = None,
        exported: dict[str, Any] | None = None,
    ) -> CellResult:
        """The cell of ``experiment`` and ``method`` from per-episode goal rewards and successes (E,)."""
        if method not in METHODS:
            raise ValueError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
        return cls(
            tool=experiment.tool,
            world=experiment.world,
            robot=experiment.robot,
            demo=experiment.demo.stem,
            method=method,
            goal_reward=float(np.mean(goal_rewards)),
            success_rate=float(np.mean(successes)),
            goal_rewards=[float(g) for g in goal_rewards],
            env_steps=int(env_steps),
            wall_time_s=float(wall_time_s),
            limits=limits,
            exported=exported,
            successes=[bool(s) for s in successes],
        )

    def episode_successes(self) -> np.ndarray:
        """(E,) bool, whether each episode passed the success test; for a cell saved before they were
        recorded, ``success_rate`` x E successes then the failures: the same mean and spread, which is
        all an interval over episodes uses (the order of the episodes is lost)."""
        if self.successes is not None:
            return np.asarray(self.successes, dtype=bool)
        return successes_from_rate(self.success_rate, len(self.goal_rewards))

    def record(self) -> dict[str, Any]:
        """JSON-ready form (the ``cells`` entries of ``results.json``)."""
        return asdict(self)

    @classmethod
    def load(cls, path: Path) -> CellResult:
        """A cell saved by :func:`toolimit.artifacts.save_json` of :meth:`record`."""
        return cls(**json.loads(path.read_text()))


def successes_from_rate(rate: float, episodes: int) -> np.ndarray:
    """(E,) bool: ``round(rate * episodes)`` successes then failures, the episodes of a record that
    kept only its success rate over ``episodes`` episodes."""
    passed = round(rate * episodes)
    if not np.isclose(passed, rate * episodes, atol=1e-6):
        raise ValueError(f"a success rate of {rate} is not a count of {episodes} episodes")
    return np.arange(episodes) < passed
