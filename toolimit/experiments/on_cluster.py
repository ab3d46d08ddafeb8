"""The paper's figure on a Ray cluster: :func:`reproduce_on_cluster` (``toolimit reproduce --ray``).

Each experiment becomes Ray tasks of one CPU each, the same work as a local run with the same
seeds: its preparation (the alignment and the robot's selection, with the tool-alone and
trajectory cells measured on the learning task they make), then, once it is done, each learning
run side by side: the method's (the pipeline's learning, evaluation and export: the final cell)
and every baseline's (sparse, dense, LfD). Inside a task the alignment and the selection use one
process (the task's CPU); their results do not depend on it.

No shared filesystem is assumed: the driver sends each task the files of the experiment's folder
it needs (the stages finished earlier, a learning run's checkpoint) and writes the files the task
made when it comes back, then the cell, which the driver alone writes. Interrupted (SIGINT,
SIGTERM), the driver cancels every task; those running send back what they saved (a learning run:
its last checkpoint, every few updates), and the same command resumes from there. A task whose
node is lost is run again by Ray from the files the driver sent it (a learning run: from the start,
or from the checkpoint the driver held).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from toolimit.artifacts import save_json
from toolimit.demos import ToolDemo, load_demo
from toolimit.distributed import FolderTasks, RayTarget, TaskOutcome, ray_cluster, read_files, write_files
from toolimit.errors import StageFoundNothing
from toolimit.experiments.cells import CellResult, Experiment
from toolimit.experiments.methods import Report, measure_method, missing_methods
from toolimit.interrupts import Interrupted, interruptible
from toolimit.learn.task import LearningTask, task_from_pipeline
from toolimit.pipeline.run import STAGES, StageReport, run_pipeline, run_stages
from toolimit.pipeline.settings import PipelineSettings
from toolimit.progress import progress_bar

#: The cells the preparation measures; the others each come from one learning run.
PREPARED_METHODS = ("tool_only", "trajopt")
#: What a task needs from the experiment's folder: the finished stages before learning.
PREPARED_FILES = ("method/alignment", "method/trajectory", "method/run.json")


@dataclass(frozen=True)
class TaskReport:
    """What a task of :func:`reproduce_on_cluster` sends back besides files.

    Attributes:
        lines: its lines for a person, in order.
        cells: the cells it measured.
        task: the learning task the preparation made (None for a learning run, or when the
            pipeline found nothing).
        failed: a cell is missing for a reason the lines give (nothing found, no LfD demonstration).
    """

    lines: list[str]
    cells: list[CellResult]
    task: LearningTask | None = None
    failed: bool = False


def reproduce_on_cluster(
    experiments: Mapping[Experiment, PipelineSettings],
    out: Path,
    methods: Sequence[str],
    target: RayTarget,
    progress: bool,
    say: Report,
    results: Callable[[], object],
) -> int:
    """Measure every missing cell of ``experiments`` (each with its pipeline settings) for
    ``methods`` into ``out`` on the Ray cluster of ``target`` (module docstring), ``results()``
    after each cell. 0, or 1 when a cell is missing
    for a reason the report gives; :class:`~toolimit.interrupts.Interrupted` after the running
    tasks sent back their progress."""
    todo = {experiment: missing_methods(experiment, out, methods) for experiment in experiments}
    for experiment in [e for e, missing in todo.items() if not missing]:
        say(experiment.name, "done earlier")
        del todo[experiment]
    if not todo:
        return 0
    demos = {experiment: load_demo(experiment.demo, tool=experiment.tool) for experiment in todo}
    code = 0
    with ray_cluster(target) as cluster, interruptible():
        say("cluster", cluster.describe())
        tasks = FolderTasks()
        for experiment, missing in todo.items():
            folder = out / experiment.name
            inputs = read_files(folder, PREPARED_FILES)
            settings = _one_process(experiments[experiment])
            tasks.submit((experiment, "prepare"), _prepare, inputs, experiment, settings, missing, demos[experiment])
        cells = sum(len(missing) for missing in todo.values())
        bar = progress_bar(total=cells, desc=f"cells on {cluster.summary()}", unit="cell", disable=not progress)
        try:
            with bar:
                while len(tasks):
                    (experiment, step), outcome = tasks.next_done()
                    report = _take(outcome, out, experiment, step, say)
                    code = max(code, int(report.failed))
                    for cell in report.cells:
                        save_json(out / "cells" / f"{experiment.cell_key(cell.method)}.json", cell.record())
                    bar.update(1 if step != "prepare" else len(report.cells))  # a learning run: its cell, or none
                    if step == "prepare" and report.task is not None:
                        settings = _one_process(experiments[experiment])
                        for method in [m for m in todo[experiment] if m not in PREPARED_METHODS]:
                            inputs = read_files(out / experiment.name, ("method" if method == "final" else method,))
                            arguments = (experiment, method, settings, report.task, demos[experiment])
                            tasks.submit((experiment, method), _learn, inputs, *arguments)
                    elif step == "prepare":
                        bar.update(len(todo[experiment]))  # the pipeline found nothing: no cells
                    results()
        except Interrupted:
            for (experiment, step), outcome in tasks.cancel():
                write_files(out / experiment.name, outcome.files)
                say(
                    experiment.name,
                    f"{step}: interrupted on {outcome.node}, its progress saved ({len(outcome.files)} files)",
                )
            results()
            raise
    return code


def _take(outcome: TaskOutcome, out: Path, experiment: Experiment, step: str, say: Report) -> TaskReport:
    """Write a finished task's files into the experiment's folder and say its lines and cells,
    naming the node that ran it."""
    write_files(out / experiment.name, outcome.files)
    report: TaskReport = outcome.value
    for line in report.lines:
        say(experiment.name, line.replace(outcome.folder, str(out / experiment.name)))
    for cell in report.cells:
        say(
            experiment.name,
            f"{cell.method}: goal reward {cell.goal_reward:.1f}, success {cell.success_rate:.2f} "
            f"(node {outcome.node}, {outcome.seconds:.0f} s)",
        )
    if not report.cells:
        say(experiment.name, f"{step}: ended on node {outcome.node} after {outcome.seconds:.0f} s")
    return report


def _one_process(settings: PipelineSettings) -> PipelineSettings:
    """``settings`` with one process for the alignment and the selection: a task has one CPU."""
    return dataclasses.replace(
        settings,
        align=dataclasses.replace(settings.align, workers=1),
        trajopt=dataclasses.replace(settings.trajopt, workers=1),
    )


def _pipeline_arguments(
    experiment: Experiment, folder: Path, settings: PipelineSettings, demo: ToolDemo, lines: list[str]
) -> tuple[ToolDemo, Path, str, str, str, PipelineSettings, bool, StageReport]:
    """The pipeline's arguments in a task: folder/method, no progress bars, its lines into ``lines``."""
    method = folder / "method"
    report: StageReport = lambda stage, line: lines.append(f"[{stage}] {line}")  # noqa: E731
    return demo, method, experiment.tool, experiment.robot, experiment.world, settings, False, report


def _prepare(
    folder: Path, experiment: Experiment, settings: PipelineSettings, missing: Sequence[str], demo: ToolDemo
) -> TaskReport:
    """A task: the alignment and the selection into folder/method, and the cells of the tool alone
    and the trajectory; returns the learning task the learning runs start from."""
    lines: list[str] = []
    method = folder / "method"
    try:
        run_stages(*_pipeline_arguments(experiment, folder, settings, demo, lines), stages=STAGES[:2])
    except StageFoundNothing as nothing:
        lines.append(f"the pipeline found nothing, no cells for this experiment: {nothing}")
        return TaskReport(lines, [], failed=True)
    task = task_from_pipeline(method / "alignment", method / "trajectory", seed=settings.learning.seed)
    cells = [
        cell
        for m in missing
        if m in PREPARED_METHODS
        and (cell := measure_method(experiment, m, folder, task, settings, False, lambda _, line: None)) is not None
    ]
    return TaskReport(lines, cells, task=task)


def _learn(
    folder: Path,
    experiment: Experiment,
    method: str,
    settings: PipelineSettings,
    task: LearningTask,
    demo: ToolDemo,
) -> TaskReport:
    """A task: one learning run and its cell (``final``: the pipeline's learning, evaluation and
    export in folder/method, its earlier stages sent in)."""
    lines: list[str] = []
    say: Report = lambda _, line: lines.append(line)  # noqa: E731
    wall_time_s = 0.0
    if method == "final":
        pipeline = run_pipeline(*_pipeline_arguments(experiment, folder, settings, demo, lines))
        wall_time_s = pipeline.evaluation["wall_time_s"]
    cell = measure_method(experiment, method, folder, task, settings, False, say, wall_time_s)
    return TaskReport(lines, [] if cell is None else [cell], failed=cell is None)
