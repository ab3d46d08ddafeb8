"""The paper's results figure, every cell measured and saved, resumable: :func:`reproduce`.

For each experiment of the preset (tool, world, robot, demonstration), :func:`~toolimit.pipeline.run_pipeline`
makes the alignment, the robot's trajectory and the cloned-then-PPO policy (OUT/<experiment>/method);
the baselines learn from the same task with the same PPO budget, environments and seed, from a
random policy with a learned standard deviation: on the sparse goal reward
(OUT/<experiment>/sparse_ppo) and on the goal reward plus the appendix's dense shaping
(OUT/<experiment>/dense_ppo). LfD, the kinesthetic-demonstration baseline (OUT/<experiment>/lfd),
tracks the scene's scripted motion with the pipeline's stage iii settings in the same scene, slower
where the arm cannot follow it at the pipeline's pace (:mod:`toolimit.learn.kinesthetic`), and
learns from it with exactly the method's learning settings (cloning, then PPO). Each method is then
measured on the same footing (:mod:`toolimit.experiments.measure`) and saved as
OUT/seed_<S>/cells/<cell>.json the moment it is known; run again, every saved cell is skipped and
each stage resumes from its checkpoint.

Each training seed S is a reproduction of its own in OUT/seed_<S>/ (its experiments' folders, cells/,
logs/ and results), so that seeds can be run in separate sittings or on separate machines and put
side by side after (copying the seed folders into one OUT). OUT/seed_<S>/results.* (that seed's
cells) and OUT/results.json, OUT/results.md and OUT/results_<tool>.svg (every seed folder's cells,
each cell with its intervals over the seeds that measured it, :mod:`toolimit.experiments.report`)
are rewritten after every experiment. A folder of the earlier single-seed layout (OUT/cells/) is
refused with the command that moves it into OUT/seed_<S>/.

Presets: ``quick`` (the planar spade, tiny budgets: a minute, for CI and a first look), ``planar``
(the same experiment with the planar world's default settings: the paper's pattern in a quarter of
an hour) and ``full`` (the Panda with the 3D spade on the five shipped demonstrations and the
authors' real recording, every method; with the hammer and the scythe on their five shipped
demonstrations, every method on ``_00`` and the method's stages on the others, and the method's
stages on the authors' real hammer recording; the UR5 and Talos with the spade on the real
recording, the method's stages only; the 3D world's default settings: every learner within the
robot's own limits, as the paper says its policies are, :class:`~toolimit.robots.motion_bound.MotionBound`)
and ``full-authors-span`` (the same, every learner's actions spanning the authors' 3 rad/s on every
joint with no acceleration bound, :data:`AUTHORS_ACTION_LIMIT`: the authors' environment, a
variant). A reproduction
continues in its output folder only with the preset and settings its results were made with (and a
seed folder only with its seed). ``jobs`` > 1 runs experiments at a time, seeds one after another in
the same queue, each in a child ``toolimit reproduce`` process whose output goes to
OUT/seed_<S>/logs/<experiment>.log (the results do not depend on it: every experiment is seeded on
its own), with its share of the cores for its simulation's threads (:func:`child_environment`). On a
Ray cluster the seeds run one after another; one command per seed, started side by side into the
same OUT, shares the cluster among them.
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from toolimit.artifacts import save_json
from toolimit.distributed import RayTarget
from toolimit.errors import InputError, StageFoundNothing
from toolimit.experiments.cells import METHODS, PIPELINE_METHODS, CellResult, Experiment
from toolimit.experiments.methods import Report, measure_method, missing_methods
from toolimit.experiments.on_cluster import reproduce_on_cluster
from toolimit.experiments.report import RESULTS_JSON, write_results
from toolimit.interrupts import SIGNALS, Interrupted
from toolimit.learn.task import TASK_NPZ, LearningTask
from toolimit.pipeline.run import run_pipeline
from toolimit.pipeline.settings import PipelineSettings, with_values
from toolimit.workers import cores_given

#: Where ``full`` finds the authors' real spade and hammer recordings: ``../shared`` beside the checkout.
REAL_SPADE_RECORDING = Path("../shared/data/video_demos/spade_video1_aligned.npz")
REAL_HAMMER_RECORDING = Path("../shared/data/video_demos/hammer_video1_aligned.npz")
#: The alignment's z offset spread (m) for that recording, whose heights are not ground-referenced:
#: with the default 0.1 m every sample puts the nail's board off the ground (no candidate).
REAL_HAMMER_Z_OFFSET_STD = 0.5
SHIPPED_DEMOS = Path("data/demos")
#: The span of the actions in ``full-authors-span`` (rad/s on every joint,
#: ``LearningConfig.action_limit``): the authors' environment clips the commanded velocities there
#: (pyphysx_envs ``RobotEnv.step``), beyond the Panda's limits, and bounds no acceleration
#: (docs/results/scythe.md#the-authors-action-clip).
AUTHORS_ACTION_LIMIT = 3.0
PRESETS = ("quick", "planar", "full", "full-authors-span")


@dataclass(frozen=True)
class Preset:
    """What :func:`reproduce` runs: the experiments, whether with the quick budgets, and the
    settings changed for every experiment (dotted paths of :class:`PipelineSettings`, values)."""

    name: str
    experiments: tuple[Experiment, ...]
    quick: bool = False
    settings_changes: tuple[tuple[str, Any], ...] = ()

    def settings(self, experiment: Experiment, seed: int) -> PipelineSettings:
        """The pipeline settings of ``experiment``: its world's with its tool's own (the evaluation's
        episodes are the cells'), seeded, with the preset's changes and then the experiment's own."""
        settings = PipelineSettings.for_world(experiment.world, self.quick, experiment.tool).with_seed(seed)
        return with_values(settings, dict(self.settings_changes + experiment.settings_changes))

    def record(self, seed: int | None) -> dict[str, Any]:
        """What results.json says of the preset, and what a resumed reproduction must match: with the
        seed in a seed's folder, without it (None) in the folder of every seed."""
        record = {"name": self.name, "quick": self.quick, "settings_changes": dict(self.settings_changes)}
        return record if seed is None else record | {"seed": seed}


def preset(name: str) -> Preset:
    """The preset ``name`` (module docstring); demonstrations relative to the working folder."""
    planar_spade = (Experiment("spade", "planar", "planar3", SHIPPED_DEMOS / "spade_03.npz"),)
    if name == "quick":
        return Preset(name, planar_spade, quick=True)
    if name == "planar":
        return Preset(name, planar_spade)
    if name not in ("full", "full-authors-span"):
        raise InputError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}")
    spades = [SHIPPED_DEMOS / f"spade_{k:02d}.npz" for k in range(5)] + [REAL_SPADE_RECORDING]
    experiments = [Experiment("spade", "3d", "panda", demo) for demo in spades]
    for tool in ("hammer", "scythe"):  # every method on _00, the method's stages on the others
        experiments.append(Experiment(tool, "3d", "panda", SHIPPED_DEMOS / f"{tool}_00.npz"))
        experiments += [
            Experiment(tool, "3d", "panda", SHIPPED_DEMOS / f"{tool}_{k:02d}.npz", methods=PIPELINE_METHODS)
            for k in range(1, 5)
        ]
        if tool == "hammer":
            experiments.append(
                Experiment(
                    "hammer",
                    "3d",
                    "panda",
                    REAL_HAMMER_RECORDING,
                    methods=PIPELINE_METHODS,
                    settings_changes=(("align.search.z_offset_std", REAL_HAMMER_Z_OFFSET_STD),),
                )
            )
    experiments += [
        Experiment("spade", "3d", robot, REAL_SPADE_RECORDING, methods=PIPELINE_METHODS) for robot in ("ur5", "talos")
    ]
    if name == "full":
        return Preset(name, tuple(experiments))
    return Preset(name, tuple(experiments), settings_changes=(("learning.action_limit", AUTHORS_ACTION_LIMIT),))


def seed_folder(out: Path, seed: int) -> Path:
    """The folder of seed ``seed``'s reproduction in ``out``: OUT/seed_<S>."""
    return out / f"seed_{seed}"


def reproduce(
    chosen: Preset,
    out: str | Path,
    seeds: Sequence[int] = (0,),
    methods: Sequence[str] = METHODS,
    jobs: int = 1,
    progress: bool = True,
    report: Report | None = None,
    ray: RayTarget = False,
) -> int:
    """Measure every missing cell of ``chosen``'s experiments for ``methods`` and each of ``seeds``
    into ``out`` and write the results (module docstring). ``ray``: on a Ray cluster instead, every
    preparation and learning run a task (:mod:`toolimit.experiments.on_cluster`; ``jobs``
    unused), same cells. Returns 0, or 1 when an experiment's pipeline found nothing or its robot
    cannot track LfD's scripted motion so that it earns (those cells are missing; the report says
    why). Raises :class:`~toolimit.interrupts.Interrupted` when a step (or a child, or a task) was
    interrupted, after every finished cell was saved."""
    out = Path(out)
    say = report or (lambda name, line: None)
    _check_folders(out, chosen, seeds)

    def results(seed: int) -> list[Path]:
        folder = seed_folder(out, seed)
        written = write_results(folder, {seed: _cells(folder)}, chosen.record(seed))
        every = {seed: _cells(folder) for seed, folder in _seed_folders(out).items()}
        return written + write_results(out, every, chosen.record(None))

    def said(seed: int) -> Report:
        return lambda name, line: say(_label(name, seed, seeds), line)

    code = 0
    if ray:
        for seed in seeds:
            settings = {e: chosen.settings(e, seed) for e in chosen.experiments}
            folder = seed_folder(out, seed)
            after = functools.partial(results, seed)
            code = max(code, reproduce_on_cluster(settings, folder, methods, ray, progress, said(seed), after))
    elif jobs > 1 and len(chosen.experiments) * len(seeds) > 1:
        code = _run_children(chosen, out, seeds, methods, jobs, say, results)
    else:
        for seed in seeds:
            for experiment in chosen.experiments:
                folder = seed_folder(out, seed)
                code = max(code, reproduce_experiment(experiment, chosen, folder, seed, methods, progress, said(seed)))
                results(seed)
    for seed in seeds:
        written = results(seed)
    say("results", f"wrote {', '.join(str(path) for path in written)}")
    return code


def _label(name: str, seed: int, seeds: Sequence[int]) -> str:
    """How a line names an experiment (or "results"): with its seed's folder when there are several seeds."""
    return name if len(seeds) == 1 else f"seed_{seed}/{name}"


def _seed_folders(out: Path) -> dict[int, Path]:
    """The seed folders in ``out`` by seed, ascending."""
    found = {int(f.name.removeprefix("seed_")): f for f in out.glob("seed_*") if f.name[5:].isdigit() and f.is_dir()}
    return dict(sorted(found.items()))


def _cells(folder: Path) -> list[CellResult]:
    """The cells saved in ``folder``/cells."""
    return [CellResult.load(path) for path in sorted((folder / "cells").glob("*.json"))]


def _check_folders(out: Path, chosen: Preset, seeds: Sequence[int]) -> None:
    """InputError when ``out`` is a folder of the earlier single-seed layout, or holds the results of
    another preset or settings, or a seed's folder (one of ``seeds``, or one already there, which
    the results take too) those of another seed: their cells would be taken for this
    reproduction's."""
    aggregate = out / RESULTS_JSON
    earlier = json.loads(aggregate.read_text()).get("preset", {}) if aggregate.is_file() else {}
    if (out / "cells").is_dir() or "seed" in earlier:
        seed = earlier.get("seed", "S")
        raise InputError(
            f"{out}: the results of one seed in the earlier layout ({out / 'cells'}); a seed's reproduction is now "
            f"{out}/seed_<S>/: move it there (mv {out} {out}.seed_{seed} && mkdir {out} && mv {out}.seed_{seed} "
            f"{out}/seed_{seed}) and run again"
        )
    _check_same_preset(aggregate, chosen.record(None))
    for seed in sorted(set(seeds) | set(_seed_folders(out))):  # those asked for, and those the results take
        _check_same_preset(seed_folder(out, seed) / RESULTS_JSON, chosen.record(seed))


def _check_same_preset(path: Path, preset: dict[str, Any]) -> None:
    """InputError when ``path`` (a results.json) was made with another preset, seed or settings."""
    if not path.is_file():
        return
    earlier = {"settings_changes": {}} | json.loads(path.read_text()).get("preset", {})
    changed = [key for key in ("name", "seed", "settings_changes") if key in preset and earlier.get(key) != preset[key]]
    if changed:
        said = "; ".join(f"{key} {earlier.get(key)!r}, now {preset[key]!r}" for key in changed)
        raise InputError(
            f"{path}: these results were made with another {' and '.join(changed)} ({said}); "
            "choose another output folder"
        )


def reproduce_experiment(
    experiment: Experiment,
    chosen: Preset,
    out: Path,
    seed: int,
    methods: Sequence[str],
    progress: bool,
    say: Report,
) -> int:
    """Run the pipeline and the baselines of one experiment and save its missing cells; 0, or 1
    when the pipeline found nothing or LfD has no kinesthetic demonstration."""
    missing = missing_methods(experiment, out, methods)
    if not missing:
        say(experiment.name, "done earlier")
        return 0
    settings = chosen.settings(experiment, seed)
    folder = out / experiment.name
    try:
        pipeline = run_pipeline(
            experiment.demo,
            folder / "method",
            experiment.tool,
            experiment.robot,
            experiment.world,
            settings,
            progress=progress,
            on_stage=lambda stage, line: say(experiment.name, f"[{stage}] {line}"),
        )
    except StageFoundNothing as nothing:
        say(experiment.name, f"the pipeline found nothing, no cells for this experiment: {nothing}")
        return 1
    task = LearningTask.load(folder / "method" / "learning" / TASK_NPZ)
    code = 0
    for method in missing:
        cell = measure_method(
            experiment, method, folder, task, settings, progress, say, pipeline.evaluation["wall_time_s"]
        )
        if cell is None:
            code = 1
            continue
        save_json(out / "cells" / f"{experiment.cell_key(method)}.json", cell.record())
        say(experiment.name, f"{method}: goal reward {cell.goal_reward:.1f}, success {cell.success_rate:.2f}")
    return code


def child_environment(jobs: int) -> dict[str, str]:
    """The environment of a child run beside ``jobs`` - 1 others: this one, with numba's threads
    (those a learning's simulation may use, ``LearningConfig.sim_threads``) set to the child's
    share of the cores, unless the user set them."""
    share = max(1, cores_given() // jobs)
    return {"NUMBA_NUM_THREADS": str(share)} | dict(os.environ)


def _run_children(
    chosen: Preset,
    out: Path,
    seeds: Sequence[int],
    methods: Sequence[str],
    jobs: int,
    say: Report,
    results: Callable[[int], object],
) -> int:
    """Each experiment of each seed in a child ``toolimit reproduce``, ``jobs`` at a time, seed
    after seed, its output appended to OUT/seed_<S>/logs/<experiment>.log (a resumed reproduction
    keeps the earlier sittings' lines); ``results(seed)`` after each. The children share the
    terminal's process group, so a Ctrl-C reaches them too: each saves its progress and stops; a
    signal sent to this process alone is passed on. The exit code: the worst of the children's (an
    interrupted child interrupts the whole reproduction)."""
    pending = [(seed, experiment) for seed in seeds for experiment in chosen.experiments]
    running: dict[subprocess.Popen[bytes], tuple[int, Experiment]] = {}
    from_preset = set(chosen.experiments) <= set(preset(chosen.name).experiments)

    code = 0
    try:
        while pending or running:
            while pending and len(running) < jobs:
                seed, experiment = pending.pop(0)
                selector = ["--experiment", experiment.name] if from_preset else ["--demo", str(experiment.demo)]
                command = [sys.executable, "-m", "toolimit", "reproduce", "--preset", chosen.name, *selector]
                command += ["--methods", ",".join(methods), "--out", str(out), "--seed", str(seed), "--quiet"]
                log = seed_folder(out, seed) / "logs" / f"{experiment.name}.log"
                log.parent.mkdir(parents=True, exist_ok=True)
                with open(log, "a") as output:
                    child = subprocess.Popen(
                        command, stdout=output, stderr=subprocess.STDOUT, env=child_environment(jobs)
                    )
                running[child] = (seed, experiment)
                say(_label(experiment.name, seed, seeds), f"started (log: {log})")
            time.sleep(0.5)
            for child in [c for c in running if c.poll() is not None]:
                seed, experiment = running.pop(child)
                say(_label(experiment.name, seed, seeds), f"ended (exit {child.returncode})")
                if child.returncode - 128 in SIGNALS:
                    raise Interrupted(child.returncode - 128)
                code = max(code, child.returncode)
                results(seed)
    finally:
        for child in running:  # interrupted: pass the signal on, then let each child save and stop
            child.send_signal(SIGNALS[0])
        for child in running:
            child.wait()
    return code
