"""``toolimit reproduce``: the paper's results figure, every cell measured and saved, resumable.

For each experiment of the preset (tool, world, robot, demonstration), ``toolimit run`` makes the
alignment, the robot's trajectory and the cloned-then-PPO policy (OUT/<experiment>/method); the
baselines learn from the same task with the same PPO budget, environments and seed, from a random
policy with a learned standard deviation: on the sparse goal reward (OUT/<experiment>/sparse_ppo)
and on the goal reward plus the appendix's dense shaping (OUT/<experiment>/dense_ppo). LfD, the
kinesthetic-demonstration baseline (OUT/<experiment>/lfd), tracks the scene's scripted motion with
the pipeline's stage iii settings in the same scene, slower where the arm cannot follow it at the
pipeline's pace (:mod:`toolimit.learn.kinesthetic`), and learns
from it with exactly the method's learning flags (cloning, then PPO). Each method is then measured
on the same footing (:mod:`toolimit.experiments.cells`) and saved as
OUT/cells/<cell>.json the moment it is known; run again, the command skips every saved cell and
each stage resumes from its checkpoint. OUT/results.json, OUT/results.md and OUT/results_<tool>.svg
are rewritten after every experiment.

Presets: ``quick`` (the planar spade, tiny budgets: a minute, for CI and a first look), ``planar``
(the same experiment with ``toolimit run``'s planar budgets: the paper's pattern in a quarter of an
hour) and ``full`` (the Panda with the 3D spade on the five shipped demonstrations and the authors'
real recording, the hammer and the scythe on one demonstration each, every method; the UR5 and
Talos with the spade on the real recording, the method's stages only; the default budgets of
``toolimit run``).
``--demo`` replaces the preset's demonstrations, ``--experiment`` keeps some of its experiments and
``--methods`` some of the methods (e.g. the method and the sparse baseline first, ``--methods
final,sparse_ppo``; the others on a later run into the same folder). ``--jobs N`` runs N experiments
at a time, each in a child ``toolimit reproduce`` whose output goes to OUT/logs/<experiment>.log
(the results do not depend on N: every experiment is seeded on its own). Exit codes: 0 done, 1 an
experiment's pipeline found nothing or its robot cannot track the scripted motion of LfD so that
it earns (those cells are missing from the results; a line says why), 2 bad input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from toolimit.cli import CliError, add_out_argument, add_seed_argument, check_count, check_output_folder
from toolimit.experiments.cells import METHODS, PIPELINE_METHODS, CellResult, Experiment

if TYPE_CHECKING:
    from toolimit.learn.task import LearningTask

#: Where ``full`` finds the authors' real spade recording: ``../shared`` beside the checkout.
REAL_SPADE_RECORDING = Path("../shared/data/video_demos/spade_video1_aligned.npz")
SHIPPED_DEMOS = Path("data/demos")
#: The baselines' rewards (``toolimit learn --reward``), both learnt from a random policy.
BASELINE_REWARDS = {"sparse_ppo": "sparse", "dense_ppo": "dense"}
#: The method's cloning flags (``toolimit learn``) that LfD learns with too, as learning.json's ``config`` keys.
CLONING = ("clone_rollouts", "clone_noise", "clone_steps", "value_steps", "action_std")
#: Seed of the evaluation episodes, added to ``--seed`` (``toolimit evaluate``'s default, unseen in training).
EVALUATION_SEED = 1000


@dataclass(frozen=True)
class Preset:
    """What ``toolimit reproduce`` runs: the experiments, flags of ``toolimit run`` and evaluation episodes."""

    experiments: tuple[Experiment, ...]
    run_flags: tuple[str, ...]
    episodes: int

    @property
    def starts(self) -> int:
        """The base initialisations of stage iii under ``run_flags`` (``toolimit run --starts``)."""
        from toolimit.cli.run import QUICK, STARTS

        return int(QUICK["starts"]) if "--quick" in self.run_flags else STARTS


def preset(name: str) -> Preset:
    """The preset ``name`` (module docstring); demonstrations relative to the working folder."""
    planar_spade = (Experiment("spade", "planar", "planar3", SHIPPED_DEMOS / "spade_03.npz"),)
    if name == "quick":
        return Preset(planar_spade, ("--quick",), episodes=4)
    if name == "planar":
        return Preset(planar_spade, (), episodes=20)
    spades = [SHIPPED_DEMOS / f"spade_{k:02d}.npz" for k in range(5)] + [REAL_SPADE_RECORDING]
    experiments = [Experiment("spade", "3d", "panda", demo) for demo in spades]
    experiments += [Experiment(tool, "3d", "panda", SHIPPED_DEMOS / f"{tool}_00.npz") for tool in ("hammer", "scythe")]
    experiments += [
        Experiment("spade", "3d", robot, REAL_SPADE_RECORDING, methods=PIPELINE_METHODS) for robot in ("ur5", "talos")
    ]
    return Preset(tuple(experiments), (), episodes=20)


PRESETS = ("quick", "planar", "full")


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "reproduce",
        help="the paper's results figure: every method on every demonstration",
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("--preset", choices=PRESETS, default="full", help="experiments and budgets (default: full)")
    parser.add_argument(
        "--demo",
        type=Path,
        action="append",
        default=None,
        help="a demonstration to run instead of the preset's (repeatable; the tool is read from the "
        "file name's prefix, spade_..., hammer_..., scythe_...; world and robot are the preset's first)",
    )
    parser.add_argument(
        "--experiment",
        action="append",
        default=None,
        help="run only the preset's experiment of this name, e.g. spade-3d-ur5-spade_video1_aligned (repeatable)",
    )
    parser.add_argument(
        "--methods",
        type=_methods,
        default=METHODS,
        help=f"comma-separated methods to measure (default: all, {','.join(METHODS)}); the others are left for a later run",
    )
    add_out_argument(parser, "output folder (one sub-folder per experiment, cells/, results.*)")
    add_seed_argument(parser)
    parser.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="experiments run at a time, each in its own process (default: 1; each also uses its own "
        "worker processes for stage iii's selection); results do not depend on it",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.set_defaults(func=run)


def _methods(text: str) -> tuple[str, ...]:
    """``--methods``: known method names, in the figure's order; argparse turns the error into one line."""
    names = [name.strip() for name in text.split(",") if name.strip()]
    unknown = [name for name in names if name not in METHODS]
    if unknown or not names:
        raise argparse.ArgumentTypeError(
            f"unknown method(s) {', '.join(unknown) or '(none given)'}; known: {', '.join(METHODS)}"
        )
    return tuple(m for m in METHODS if m in names)


def _experiments(args: argparse.Namespace, chosen: Preset) -> tuple[Experiment, ...]:
    """The preset's experiments, or those of ``--demo``, kept by ``--experiment``; CliError names a
    missing file, an unknown tool or an unknown experiment."""
    if args.demo is None:
        experiments = chosen.experiments
    else:
        from toolimit.tools import TOOLS

        first = chosen.experiments[0]
        for demo in args.demo:
            if demo.stem.split("_")[0] not in TOOLS:
                raise CliError(f"--demo {demo}: the file name must start with one of {', '.join(TOOLS)} and '_'")
        experiments = tuple(Experiment(d.stem.split("_")[0], first.world, first.robot, d) for d in args.demo)
    if args.experiment is not None:
        names = [e.name for e in experiments]
        unknown = [name for name in args.experiment if name not in names]
        if unknown:
            raise CliError(f"--experiment: unknown {', '.join(unknown)}; the preset's: {', '.join(names)}")
        experiments = tuple(e for e in experiments if e.name in args.experiment)
    for experiment in experiments:
        if not experiment.demo.is_file():
            raise CliError(f"{experiment.name}: no such demonstration file: {experiment.demo}")
    return experiments


def run(args: argparse.Namespace) -> int:
    from toolimit.cli import main as toolimit
    from toolimit.experiments.report import write_results

    chosen = preset(args.preset)
    experiments = _experiments(args, chosen)
    check_count("--jobs", args.jobs)
    check_output_folder(args.out, "--out")
    quiet = ["--quiet"] if args.quiet else []

    def results() -> list[Path]:
        cells = [CellResult.load(path) for path in sorted((args.out / "cells").glob("*.json"))]
        return write_results(
            args.out, cells, {"name": args.preset, "run_flags": list(chosen.run_flags), "seed": args.seed}
        )

    code = 0
    if args.jobs > 1 and len(experiments) > 1:
        code = _run_children(experiments, args, results)
    else:
        for experiment in experiments:
            code = max(code, _reproduce_experiment(experiment, chosen, args, toolimit, quiet))
            results()
    print(f"wrote {', '.join(str(path) for path in results())}")
    return code


def _run_children(experiments: tuple[Experiment, ...], args: argparse.Namespace, results: Callable[[], object]) -> int:
    """Each experiment in a child ``toolimit reproduce``, ``args.jobs`` at a time, its output in
    OUT/logs/<experiment>.log; ``results()`` after each. The children share the terminal's process
    group, so a Ctrl-C reaches them too: each saves its progress and stops; a signal sent to this
    process alone is passed on. The exit code: the worst of the children's (an interrupted child
    interrupts the whole reproduction)."""
    import subprocess
    import sys
    import time

    from toolimit.interrupts import SIGNALS, Interrupted

    logs = args.out / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    pending = list(experiments)
    running: dict[subprocess.Popen[bytes], Experiment] = {}
    code = 0
    try:
        while pending or running:
            while pending and len(running) < args.jobs:
                experiment = pending.pop(0)
                selector = ["--demo", str(experiment.demo)] if args.demo else ["--experiment", experiment.name]
                command = [sys.executable, "-m", "toolimit", "reproduce", "--preset", args.preset, *selector]
                command += ["--methods", ",".join(args.methods), "--out", str(args.out), "--seed", str(args.seed)]
                log = logs / f"{experiment.name}.log"
                with open(log, "w") as output:
                    child = subprocess.Popen([*command, "--quiet"], stdout=output, stderr=subprocess.STDOUT)
                running[child] = experiment
                print(f"[{experiment.name}] started (log: {log})")
            time.sleep(0.5)
            for child in [c for c in running if c.poll() is not None]:
                experiment = running.pop(child)
                print(f"[{experiment.name}] ended (exit {child.returncode})")
                if child.returncode - 128 in SIGNALS:
                    raise Interrupted(child.returncode - 128)
                code = max(code, child.returncode)
                results()
    finally:
        for child in running:  # interrupted: pass the signal on, then let each child save and stop
            child.send_signal(SIGNALS[0])
        for child in running:
            child.wait()
    return code


def _reproduce_experiment(
    experiment: Experiment,
    chosen: Preset,
    args: argparse.Namespace,
    toolimit: Callable[[list[str]], int],
    quiet: list[str],
) -> int:
    """Run the pipeline and the baselines of one experiment and save its missing cells; an exit code."""
    from toolimit.artifacts import save_json
    from toolimit.cli.run import RUN_JSON
    from toolimit.experiments.measure import measure_policy, measure_tool_only, measure_trajopt
    from toolimit.learn.task import TASK_NPZ, LearningTask
    from toolimit.learn.training import LEARNING_JSON

    cells_dir, folder = args.out / "cells", args.out / experiment.name
    methods = [m for m in args.methods if m in experiment.methods]
    missing = [m for m in methods if not (cells_dir / f"{experiment.cell_key(m)}.json").is_file()]
    if not missing:
        print(f"[{experiment.name}] done earlier")
        return 0
    method_dir = folder / "method"
    command = ["run", "--tool", experiment.tool, "--world", experiment.world, "--robot", experiment.robot]
    command += ["--demo", str(experiment.demo), "--out", str(method_dir), "--seed", str(args.seed)]
    command += [*chosen.run_flags, *quiet]
    print(f"[{experiment.name}] toolimit {' '.join(command)}")
    code = _nested(toolimit, command)
    if code != 0:
        print(f"[{experiment.name}] the pipeline stopped (exit {code}): no cells for this experiment")
        return code
    task = LearningTask.load(method_dir / "learning" / TASK_NPZ)
    learned = json.loads((method_dir / "learning" / LEARNING_JSON).read_text())["config"]
    stage_times = json.loads((method_dir / RUN_JSON).read_text())["stage_times_s"]
    episodes, seed = chosen.episodes, args.seed + EVALUATION_SEED
    code = 0
    for method in missing:
        if method == "tool_only":
            cell = measure_tool_only(experiment, task, episodes, seed)
        elif method == "trajopt":
            cell = measure_trajopt(experiment, task, episodes, seed)
        elif method == "final":
            cell = measure_policy(experiment, method, method_dir / "learning", episodes, seed)
            cell = replace(cell, wall_time_s=sum(stage_times.values()))
        else:
            if method == "lfd":
                learning = folder / method / "learning"
                task_file = _kinesthetic_task(experiment, task, chosen, folder / method, learned["seed"])
                if task_file is None:
                    code = 1
                    continue
                flags = ["--reward", learned["reward"], *(f"--{f.replace('_', '-')}={learned[f]}" for f in CLONING)]
            else:
                learning, task_file = folder / method, method_dir / "learning" / TASK_NPZ
                flags = ["--no-clone", "--reward", BASELINE_REWARDS[method]]
            command = ["learn", "--task", str(task_file), "--out", str(learning), *flags]
            command += [f"--{flag}={learned[flag]}" for flag in ("timesteps", "envs", "preset", "seed")] + quiet
            print(f"[{experiment.name}] toolimit {' '.join(command)}")
            learned_code = _nested(toolimit, command)
            if learned_code != 0:
                return learned_code
            cell = measure_policy(experiment, method, learning, episodes, seed)
        save_json(cells_dir / f"{experiment.cell_key(method)}.json", cell.record())
        print(f"[{experiment.name}] {method}: goal reward {cell.goal_reward:.1f}, success {cell.success_rate:.2f}")
    return code


def _nested(toolimit: Callable[[list[str]], int], command: list[str]) -> int:
    """The exit code of ``toolimit command``; when a signal stopped it (exit 128 + SIGINT or SIGTERM),
    :class:`~toolimit.interrupts.Interrupted`, so that the whole reproduction stops, not only this step."""
    from toolimit.interrupts import SIGNALS, Interrupted

    code = toolimit(command)
    if code - 128 in SIGNALS:
        raise Interrupted(code - 128)
    return code


def _kinesthetic_task(
    experiment: Experiment, task: LearningTask, chosen: Preset, folder: Path, seed: int
) -> Path | None:
    """The task file of LfD's kinesthetic demonstration in ``folder`` (made now or earlier), tracked
    with the pipeline's stage iii settings; None after a line saying why the robot cannot track
    the scripted motion so that it earns."""
    from toolimit.cli.run import SELECTION_TIME_SCALES, VELOCITY_WEIGHT
    from toolimit.cli.trajopt import parse_time_scales
    from toolimit.errors import BaseInsideFootprint, NoKinestheticDemonstration, NoScriptedMotion, SolverFailure
    from toolimit.learn.kinesthetic import kinesthetic_task
    from toolimit.learn.task import TASK_NPZ
    from toolimit.trajopt import TrackingWeights, TrackOptions

    options = TrackOptions(weights=TrackingWeights(velocity=VELOCITY_WEIGHT), starts=chosen.starts)
    time_scales = parse_time_scales(SELECTION_TIME_SCALES[experiment.world])
    try:
        kinesthetic_task(task, folder, options, time_scales, seed=seed)
    except (BaseInsideFootprint, NoKinestheticDemonstration, SolverFailure, NoScriptedMotion) as refusal:
        print(f"[{experiment.name}] lfd: no kinesthetic demonstration, no cell: {refusal}")
        return None
    return folder / TASK_NPZ
