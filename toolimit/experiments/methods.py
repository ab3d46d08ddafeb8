"""One experiment's cells: which are still missing (:func:`missing_methods`) and how each is
measured (:func:`measure_method`, learning a baseline's policy first), for a local reproduction
(:mod:`toolimit.experiments.reproduce`) and one on a cluster (:mod:`toolimit.experiments.on_cluster`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path

from toolimit.errors import BaseInsideFootprint, NoKinestheticDemonstration, NoScriptedMotion, SolverFailure
from toolimit.experiments.cells import CellResult, Experiment
from toolimit.experiments.measure import measure_policy, measure_tool_only, measure_trajopt
from toolimit.learn.kinesthetic import kinesthetic_task
from toolimit.learn.task import LearningTask
from toolimit.learn.training import learn_policy
from toolimit.pipeline.settings import PipelineSettings

#: The baselines' rewards (``LearningConfig.reward``), both learnt from a random policy.
BASELINE_REWARDS = {"sparse_ppo": "sparse", "dense_ppo": "dense"}

#: ``report(experiment name, line)``: a line for a person about one experiment.
Report = Callable[[str, str], None]


def missing_methods(experiment: Experiment, out: Path, methods: Sequence[str]) -> list[str]:
    """The methods of ``methods`` measured on ``experiment`` whose cell is not saved in OUT/cells yet."""
    cells_dir = out / "cells"
    return [
        m for m in methods if m in experiment.methods and not (cells_dir / f"{experiment.cell_key(m)}.json").is_file()
    ]


def measure_method(
    experiment: Experiment,
    method: str,
    folder: Path,
    task: LearningTask,
    settings: PipelineSettings,
    progress: bool,
    say: Report,
    pipeline_wall_time_s: float = 0.0,
) -> CellResult | None:
    """The cell of ``method`` on ``experiment`` whose folder is ``folder`` (the pipeline's policy
    in folder/method, learnt already; ``pipeline_wall_time_s`` its wall time), learning the
    baselines into their folders first; None (the report says why) when LfD has no kinesthetic
    demonstration."""
    episodes, evaluation_seed = settings.evaluation.episodes, settings.evaluation.seed
    if method == "tool_only":
        return measure_tool_only(experiment, task, episodes, evaluation_seed)
    if method == "trajopt":
        return measure_trajopt(experiment, task, episodes, evaluation_seed)
    if method == "final":
        cell = measure_policy(experiment, method, folder / "method" / "learning", episodes, evaluation_seed)
        return dataclasses.replace(cell, wall_time_s=pipeline_wall_time_s)
    learning = folder / method / "learning" if method == "lfd" else folder / method
    if method == "lfd":
        try:
            learned_task = kinesthetic_task(
                task,
                folder / method,
                settings.trajopt.track_options(),
                settings.trajopt.time_scales,
                seed=settings.learning.seed,
            )
        except (BaseInsideFootprint, NoKinestheticDemonstration, SolverFailure, NoScriptedMotion) as refusal:
            say(experiment.name, f"lfd: no kinesthetic demonstration, no cell: {refusal}")
            return None
        config = settings.learning
    else:
        learned_task = task
        config = dataclasses.replace(settings.learning, clone=False, reward=BASELINE_REWARDS[method])
    say(experiment.name, f"{method}: learning in {learning}")
    learn_policy(learned_task, learning, config, progress=progress)
    return measure_policy(experiment, method, learning, episodes, evaluation_seed)
