"""The whole pipeline, demonstration to trained policy, resumable stage by stage: :func:`run_pipeline`.

demonstration -> alignment (OUT/alignment) -> trajectory with selection by robot execution
(OUT/trajectory) -> learning: cloning and PPO (OUT/learning) -> evaluation (OUT/evaluation.json)
-> the policy's deterministic rollout (OUT/policy_rollout) and its export (OUT/export; robots
with published limits). Called again on the same folder, it skips every finished stage and resumes
the first unfinished one from its checkpoint (the alignment and the learning save theirs).
OUT/run.json keeps each stage's wall time; OUT/evaluation.json has ``success_rate``,
``goal_reward_mean``, ``episodes``, ``env_steps`` (training, cloning rollouts included),
``wall_time_s`` (alignment to evaluation, over every call) and ``early_stop`` (the rule and the PPO
steps where it ended learning, None if it ran its whole budget; None when off).
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from toolimit.align.outputs import ALIGNMENT_JSON, alignment_finished
from toolimit.artifacts import save_json
from toolimit.demos import ToolDemo
from toolimit.deploy.export import SUMMARY_JSON
from toolimit.distributed import RayTarget, ray_cluster
from toolimit.errors import InputError
from toolimit.learn.task import TASK_NPZ, LearningTask
from toolimit.pipeline.settings import PipelineSettings
from toolimit.pipeline.shortlist import read_shortlist, shortlist_action_limit
from toolimit.pipeline.stages import (
    EVALUATION_JSON,
    align_stage,
    describe_alignment,
    describe_trajectory,
    evaluate_stage,
    export_stage,
    learn_stage,
    learning_finished,
    learning_record,
    trajopt_stage,
)
from toolimit.trajopt.result import TRAJECTORY_JSON, TRAJECTORY_NPZ

RUN_JSON = "run.json"
#: The stages in order: their folders under OUT and their names in ``run.json``.
STAGES = ("alignment", "trajectory", "learning")

#: ``on_stage(stage, line)``: a line for a person about ``stage`` (``print`` them, log them).
StageReport = Callable[[str, str], None]


@dataclass(frozen=True)
class PipelineResult:
    """What :func:`run_pipeline` made.

    Attributes:
        folder: OUT, one sub-folder per stage.
        evaluation: the record of OUT/evaluation.json (see the module docstring).
        export: OUT/export, or None for a robot without published limits.
    """

    folder: Path
    evaluation: dict[str, Any]
    export: Path | None

    @property
    def success_rate(self) -> float:
        """The policy's deterministic success rate (the paper's criterion)."""
        return float(self.evaluation["success_rate"])


def run_pipeline(
    demo: ToolDemo | str | Path,
    out: str | Path,
    tool: str,
    robot: str,
    world: str = "3d",
    settings: PipelineSettings | None = None,
    progress: bool = True,
    on_stage: StageReport | None = None,
    ray: RayTarget = False,
) -> PipelineResult:
    """Run (or resume) every stage for ``tool`` and ``robot`` in ``world`` from ``demo`` (a
    ToolDemo or a demonstration file) into ``out``; see the module docstring.

    ``settings`` default to :meth:`PipelineSettings.for_world` (the world's, with the tool's own).
    ``on_stage`` receives each stage's lines for a person. ``ray``
    (:data:`~toolimit.distributed.RayTarget`): the alignment's samples and the robot selection's
    candidates run on a Ray cluster instead of local worker processes (same results); the learning
    run is one process, here. Raises InputError when a finished stage in ``out`` was made for
    another tool, world or robot (or its shortlist tracked with another action limit than
    ``settings.learning``'s), StageFoundNothing when the alignment or the robot's selection
    finds nothing, and KeyboardInterrupt (:mod:`toolimit.interrupts`) after the interrupted stage
    saved its checkpoint.
    """
    out = Path(out)
    settings = settings if settings is not None else PipelineSettings.for_world(world, tool=tool)
    with ray_cluster(ray) if ray else contextlib.nullcontext():  # stopped before learning, which runs here
        run_stages(demo, out, tool, robot, world, settings, progress, on_stage, STAGES[:2], ray=ray)
    run_stages(demo, out, tool, robot, world, settings, progress, on_stage, STAGES[2:])
    learning = out / "learning"
    evaluation = _timed(out, "evaluation", lambda: evaluate_stage(learning, settings.evaluation))
    learned = learning_record(learning)
    times = _stage_times(out)
    record = evaluation.record | {
        "env_steps": learned["env_steps"],
        "wall_time_s": sum(times.values()),
        "stage_times_s": times,
        "simulation_time_s": learned["simulation_time_s"],
        "learning_time_s": learned["learning_time_s"],
        "early_stop": learned.get("early_stop"),
    }
    export = export_stage(evaluation, out, settings.export)
    report = on_stage or (lambda stage, line: None)
    if export is None:
        report(
            "export",
            f"skipped: the {robot} has no published acceleration and jerk limits (its rollout: {out / 'policy_rollout'})",
        )
    else:
        summary = json.loads((export / SUMMARY_JSON).read_text())
        record["exported"] = summary["open_loop"]
        report(
            "export",
            f"retimed within the {robot}'s limits ({summary['duration_s']:.2f} s for the rollout's "
            f"{summary['optimised_duration_s']:.2f} s): {export}; replayed open-loop: success "
            f"{summary['open_loop']['success_rate']:.2f} over {summary['open_loop']['episodes']} episodes",
        )
    save_json(out / EVALUATION_JSON, record)
    return PipelineResult(out, record, export)


def run_stages(
    demo: ToolDemo | str | Path,
    out: Path,
    tool: str,
    robot: str,
    world: str,
    settings: PipelineSettings,
    progress: bool = True,
    on_stage: StageReport | None = None,
    stages: Sequence[str] = STAGES,
    ray: RayTarget = False,
) -> None:
    """Run (or skip, when finished earlier) the first ``stages`` of :data:`STAGES` in order into
    ``out``, each one's wall time added to OUT/run.json (:func:`run_pipeline` runs them all; a
    reproduction on a cluster runs the stages before learning in a task of their own). ``ray``: the
    alignment's samples and the selection's candidates on a Ray cluster (:data:`~toolimit.distributed.RayTarget`)."""
    report = on_stage or (lambda stage, line: None)
    alignment, trajectory, learning = (out / stage for stage in STAGES)
    finished = {
        "alignment": alignment_finished(alignment),
        "trajectory": (trajectory / TRAJECTORY_NPZ).is_file(),
        "learning": learning_finished(learning),
    }
    for stage in stages:
        if finished[stage]:
            _check_same_run(out / stage, {"tool": tool, "world": world, "robot": robot})
            if stage == "trajectory":
                _check_same_shortlist_span(out / stage, settings.learning.action_limit)
            report(stage, f"done earlier: {out / stage}")
            continue
        report(stage, "started")
        if stage == "alignment":
            result = _timed(
                out, stage, lambda: align_stage(demo, tool, world, alignment, settings.align, progress, ray)
            )
            lines = describe_alignment(result)
        elif stage == "trajectory":
            made = _timed(
                out,
                stage,
                lambda: trajopt_stage(
                    alignment, robot, trajectory, settings.trajopt, progress, tool, ray, settings.learning.action_limit
                ),
            )
            lines = describe_trajectory(made)
        else:
            outcome = _timed(
                out, stage, lambda: learn_stage(alignment, trajectory, learning, settings.learning, progress)
            )
            record = outcome.record
            stopped = (record.get("early_stop") or {}).get("stopped_at_ppo_env_steps")
            lines = [
                f"{record['env_steps']} env steps ({record['cloning_env_steps']} cloning), {record['wall_time_s']:.0f} s"
                + ("" if stopped is None else ", stopped early: learnt")
            ]
        for line in lines:
            report(stage, line)


def _timed(out: Path, stage: str, work: Callable[[], Any]) -> Any:
    """``work()``, its wall time added to ``stage``'s in OUT/run.json (also when it is interrupted or
    finds nothing); not when it refuses its input (an InputError): the stage did not run, and a
    command refused in one line leaves nothing written."""
    started = time.perf_counter()
    try:
        result = work()
    except InputError:
        raise
    except BaseException:
        _add_stage_time(out, stage, time.perf_counter() - started)
        raise
    _add_stage_time(out, stage, time.perf_counter() - started)
    return result


def _add_stage_time(out: Path, stage: str, seconds: float) -> None:
    """Add ``seconds`` to ``stage``'s wall time in OUT/run.json."""
    times = _stage_times(out)
    times[stage] = times.get(stage, 0.0) + seconds
    save_json(out / RUN_JSON, {"stage_times_s": times})


def _check_same_run(folder: Path, expected: dict[str, str]) -> None:
    """InputError if a finished stage's folder was made for another tool, world or robot."""
    found: dict[str, str] = {}
    if (folder / ALIGNMENT_JSON).is_file():
        record = json.loads((folder / ALIGNMENT_JSON).read_text())
        found = {"tool": record["tool"], "world": record["world"]}
    elif (folder / TRAJECTORY_JSON).is_file():
        record = json.loads((folder / TRAJECTORY_JSON).read_text())
        found = {"tool": record["tool"], "robot": record["robot"]}
    elif (folder / TASK_NPZ).is_file():
        task = LearningTask.load(folder / TASK_NPZ)
        found = {"tool": task.tool, "world": task.world, "robot": task.robot}
    for key, value in found.items():
        if value != expected[key]:
            raise InputError(
                f"{folder} holds a finished stage for {key} {value!r}, not {expected[key]!r}: "
                "choose another output folder or remove that one"
            )


def _check_same_shortlist_span(folder: Path, action_limit: float | None) -> None:
    """InputError if a finished trajectory stage's shortlist was tracked with another action limit
    than the learner's (the kept candidate and the learner's fall-backs would be another span's)."""
    if not read_shortlist(folder):
        return
    tracked = shortlist_action_limit(folder)
    if tracked != action_limit:
        raise InputError(
            f"{folder} holds a finished stage whose shortlist was tracked with an action limit of "
            f"{_span(tracked)}, not {_span(action_limit)}: choose another output folder or remove that one"
        )


def _span(action_limit: float | None) -> str:
    """An action limit for a person."""
    return "the robot's limits" if action_limit is None else f"{action_limit:g} rad/s"


def _stage_times(out: Path) -> dict[str, float]:
    """Each stage's wall time so far (s), from OUT/run.json."""
    path = out / RUN_JSON
    return json.loads(path.read_text())["stage_times_s"] if path.is_file() else {}
