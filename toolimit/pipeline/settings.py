"""The pipeline's settings: one frozen dataclass per stage, each default written once.

A stage's settings hold the library's defaults by reference (``AlignmentConfig``,
``TrackingWeights``, ``TrackOptions``, ``LearningConfig`` and the export's constants are the one
place each number is written); where a world needs its own value, :data:`WORLD_PRESETS` holds it,
where a tool needs its own, the tool's record (``ToolRecord.settings``), and :data:`QUICK` the tiny
budgets of a first try or CI. The ``toolimit`` command's flags are
built from these fields, so the command and a Python caller start from the same values.
"""

from __future__ import annotations

import dataclasses
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, TypeVar

from toolimit.align.config import AlignmentConfig
from toolimit.deploy.export import DEFAULT_RATE_HZ, RATE_RANGE_HZ
from toolimit.deploy.open_loop import OPEN_LOOP_EPISODES
from toolimit.deploy.retime import MAX_SUBDIVISIONS
from toolimit.errors import InputError, InvalidSetting
from toolimit.learn.evaluate import EVALUATION_SEED
from toolimit.learn.training import LearningConfig
from toolimit.robots.limits import Margins
from toolimit.tools import tool_record, tool_records
from toolimit.trajopt.problem import TrackingWeights
from toolimit.trajopt.track import INITIALISATIONS, TrackOptions

Settings = TypeVar("Settings")

#: ``TrajoptSettings.init`` values and the joint initialisations each runs (``TrackOptions``).
INIT_CHOICES: dict[str, tuple[str, ...]] = {"both": INITIALISATIONS, **{name: (name,) for name in INITIALISATIONS}}


def _check_integer(name: str, value: Any, lowest: int) -> None:
    """InvalidSetting unless ``value`` is an integer >= ``lowest``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < lowest:
        raise InvalidSetting(name, f"must be an integer >= {lowest}, got {value!r}")


@dataclass(frozen=True)
class AlignSettings:
    """Stage ii, the alignment search (``toolimit align``).

    Attributes:
        search: the search's budget and sampling (:class:`~toolimit.align.config.AlignmentConfig`).
        seed: sample i draws from ``default_rng([seed, i])``: same seed, same candidates.
        clean: clean the demonstration first (reconstruction outliers replaced, jitter smoothed).
        workers: processes evaluating samples (None: one per core, up to 4); the result does not
            depend on it.
    """

    search: AlignmentConfig = AlignmentConfig()
    seed: int = 0
    clean: bool = True
    workers: int | None = None

    def __post_init__(self) -> None:
        _check_integer("seed", self.seed, 0)
        if self.workers is not None:
            _check_integer("workers", self.workers, 1)


@dataclass(frozen=True)
class TrajoptSettings:
    """Stage iii, the robot's trajectory (``toolimit trajopt``).

    Attributes:
        weights: the cost's weights (:class:`~toolimit.trajopt.problem.TrackingWeights`).
        starts: base initialisations of the multi-start.
        init: joint initialisation of every start: ``hold`` (the rest pose held), ``rollout`` (a
            differential-IK rollout along the targets) or ``both`` (the better result is kept).
        time_scales: slow-down factors to try (1 = the demonstration's speed). From an alignment,
            each candidate keeps the scale whose robot replay earns most; from poses alone, the
            smallest whose median tracking error is under 1 cm. The demonstration's own speed by
            default: a slowed trajectory doubles the episode, and PPO's exploration noise then
            loses the sand (measured on the Panda spade, seed 0, 1.5 M steps: both selections that
            kept time scale 2 ended at deterministic success 0.80, both at real time at 1.0).
        select_by_robot: from an alignment, track every candidate, replay the robot in its scene
            and keep the one whose replay earns most (the paper's selection); False tracks the
            best tool-only candidate alone.
        shortlist: how many of the best candidates by robot reward are tracked in their learning
            tasks, where the one whose tracking succeeds most often is kept
            (:mod:`toolimit.pipeline.shortlist`); 0 keeps the best robot reward (the paper's rule).
        shortlist_episodes: tracking episodes per shortlisted candidate.
        seed: seed of the random starts, the robot replays and the shortlist's learning tasks.
        workers: processes tracking candidates side by side (None: one per core, up to 4); the
            selection does not depend on it.
    """

    weights: TrackingWeights = TrackingWeights()
    starts: int = TrackOptions.starts
    init: str = "both"
    time_scales: tuple[float, ...] = (1.0,)
    select_by_robot: bool = True
    shortlist: int = 8
    shortlist_episodes: int = 20
    seed: int = 0
    workers: int | None = None

    def __post_init__(self) -> None:
        _check_integer("starts", self.starts, 1)
        _check_integer("shortlist", self.shortlist, 0)
        _check_integer("shortlist_episodes", self.shortlist_episodes, 1)
        _check_integer("seed", self.seed, 0)
        if self.workers is not None:
            _check_integer("workers", self.workers, 1)
        if self.init not in INIT_CHOICES:
            raise InvalidSetting(
                "init", f"unknown initialisation {self.init!r}; choose one of {', '.join(INIT_CHOICES)}"
            )
        if not self.time_scales or not all(0 < scale < float("inf") for scale in self.time_scales):
            raise InvalidSetting("time_scales", f"every scale must be a positive finite number, got {self.time_scales}")

    def track_options(self, progress: bool = False) -> TrackOptions:
        """The options of :func:`~toolimit.trajopt.track.track` (at the first time scale)."""
        return TrackOptions(
            weights=self.weights,
            starts=self.starts,
            time_scale=self.time_scales[0],
            initialisations=INIT_CHOICES[self.init],
            progress=progress,
        )


@dataclass(frozen=True)
class EvaluationSettings:
    """The final evaluation of a policy (``toolimit evaluate``).

    Attributes:
        episodes: rollouts per mode (deterministic and stochastic).
        seed: seed of the evaluation episodes (apart from the training seeds).
    """

    episodes: int = 20
    seed: int = EVALUATION_SEED

    def __post_init__(self) -> None:
        _check_integer("episodes", self.episodes, 1)
        _check_integer("seed", self.seed, 0)


@dataclass(frozen=True)
class ExportSettings:
    """Export of a joint path for a real robot (``toolimit export``).

    Attributes:
        rate: command rate of the exported samples, Hz.
        subdivisions: pieces per step between optimised samples: more keeps closer to them at
            sharp turns, and turns there more slowly; by default 1 for a path that keeps the
            limits at its own timing (a learnt policy's), else 4.
        position_margin: rad the commands keep from each end of every joint's range.
        velocity_scale: fraction of the published velocity limits the commands stay within.
        acceleration_scale: fraction of the published acceleration limits the commands stay within.
        jerk_scale: fraction of the published jerk limits the commands stay within.
        check_episodes: episodes of the open-loop replay of the export in the task's scene.
    """

    rate: float = DEFAULT_RATE_HZ
    subdivisions: int | None = None
    position_margin: float = Margins().position
    velocity_scale: float = Margins().velocity
    acceleration_scale: float = Margins().acceleration
    jerk_scale: float = Margins().jerk
    check_episodes: int = OPEN_LOOP_EPISODES

    def __post_init__(self) -> None:
        low, high = RATE_RANGE_HZ
        if not low <= self.rate <= high:
            raise InvalidSetting("rate", f"must be between {low:g} and {high:g} Hz, got {self.rate:g}")
        if self.subdivisions is not None:
            _check_integer("subdivisions", self.subdivisions, 1)
            if self.subdivisions > MAX_SUBDIVISIONS:
                raise InvalidSetting("subdivisions", f"must be at most {MAX_SUBDIVISIONS}, got {self.subdivisions}")
        _check_integer("check_episodes", self.check_episodes, 1)
        try:
            Margins(self.position_margin, self.velocity_scale, self.acceleration_scale, self.jerk_scale)
        except InputError as error:
            field = {"position": "position_margin"}.get(str(error.args[0]), f"{error.args[0]}_scale")
            raise InvalidSetting(field, str(error.args[1])) from None

    @property
    def margins(self) -> Margins:
        """How far inside the robot's published limits the commands stay."""
        return Margins(self.position_margin, self.velocity_scale, self.acceleration_scale, self.jerk_scale)


@dataclass(frozen=True)
class PipelineSettings:
    """Every stage's settings (``toolimit run``); :meth:`for_world` gives the measured defaults of a world.

    Attributes:
        align: stage ii.
        trajopt: stage iii.
        learning: stage iv (:class:`~toolimit.learn.training.LearningConfig`).
        evaluation: the final evaluation.
        export: the export of the policy's rollout (robots with published limits).
    """

    align: AlignSettings = AlignSettings()
    trajopt: TrajoptSettings = TrajoptSettings()
    learning: LearningConfig = LearningConfig()
    evaluation: EvaluationSettings = EvaluationSettings()
    export: ExportSettings = ExportSettings()

    @classmethod
    def for_world(cls, world: str, quick: bool = False, tool: str | None = None) -> PipelineSettings:
        """The defaults with ``world``'s preset (:data:`WORLD_PRESETS`), then ``tool``'s own values
        in that world (``ToolRecord.settings``, :mod:`toolimit.tools.record`), then the tiny budgets
        of :data:`QUICK` when ``quick``; InvalidSetting for an unknown world, InputError for an
        unknown tool."""
        if world not in WORLD_PRESETS:
            raise InvalidSetting("world", f"unknown world {world!r}; choose one of {', '.join(WORLD_PRESETS)}")
        own = tool_record(tool).settings.get(world, {}) if tool is not None else {}
        return with_values(cls(), {**WORLD_PRESETS[world], **own, **(QUICK if quick else {})})

    def with_seed(self, seed: int) -> PipelineSettings:
        """The same settings with every stage seeded by ``seed`` (the evaluation at ``seed`` +
        :data:`~toolimit.learn.evaluate.EVALUATION_SEED`, apart from the training seeds)."""
        return with_values(
            self,
            {
                "align.seed": seed,
                "trajopt.seed": seed,
                "learning.seed": seed,
                "evaluation.seed": seed + EvaluationSettings.seed,
            },
        )


#: Each world's own values, by dotted path into :class:`PipelineSettings`. In 3D, 40 alignment
#: candidates give the robot's selection good ones to choose from (measured, seed 0: on spade_00
#: the best Panda replay of 5 candidates earns 6.5 spheres, of 20 candidates 9.7; on the authors'
#: real recording 11.7 of 40, whose policy then succeeds in 20 of 20 episodes), and PPO runs
#: 1.5 M steps (the Panda spade's training success reaches 1.0 between 0.7 and 1.2 M).
WORLD_PRESETS: dict[str, dict[str, Any]] = {
    "planar": {},
    "3d": {"align.search.candidates": 40, "learning.timesteps": 1_500_000},
}


def defaults_by_label() -> dict[str, PipelineSettings]:
    """The defaults a command starts from, by label: each world's (``"3d"``), and each tool's in a
    world where it has values of its own (``"3d scythe"``), for the help's defaults."""
    defaults = {world: PipelineSettings.for_world(world) for world in WORLD_PRESETS}
    for record in tool_records():
        for world in record.settings:
            defaults[f"{world} {record.name}"] = PipelineSettings.for_world(world, tool=record.name)
    return defaults


#: Budgets of a first try or CI (``toolimit run --quick``): minutes on a laptop.
QUICK: dict[str, Any] = {
    "align.search.samples": 3000,
    "align.search.candidates": 3,
    "trajopt.starts": 2,
    "trajopt.shortlist": 2,
    "trajopt.shortlist_episodes": 4,
    "learning.timesteps": 2_000,
    "learning.envs": 4,
    "learning.clone_steps": 300,
    "learning.value_steps": 200,
    "learning.clone_rollouts": 2,
    "evaluation.episodes": 4,
    "export.check_episodes": 4,
}


def get_value(settings: Any, path: str) -> Any:
    """The value at a dotted ``path`` of nested settings, e.g. ``"align.search.samples"``."""
    for name in path.split("."):
        settings = getattr(settings, name)
    return settings


def with_values(settings: Settings, values: Mapping[str, Any]) -> Settings:
    """A copy of nested frozen ``settings`` with the values at dotted paths replaced (each level
    rebuilt by ``dataclasses.replace``, so that every level checks its new values)."""
    nested: dict[str, dict[str, Any]] = {}
    direct: dict[str, Any] = {}
    for path, value in values.items():
        head, _, rest = path.partition(".")
        if rest:
            nested.setdefault(head, {})[rest] = value
        else:
            direct[head] = value
    for head, inner in nested.items():
        direct[head] = with_values(getattr(settings, head), inner)
    return dataclasses.replace(settings, **direct) if direct else settings  # type: ignore[type-var]


__all__ = [
    "AlignSettings",
    "EvaluationSettings",
    "ExportSettings",
    "INIT_CHOICES",
    "PipelineSettings",
    "QUICK",
    "TrajoptSettings",
    "WORLD_PRESETS",
    "defaults_by_label",
]
