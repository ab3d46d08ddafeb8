"""``toolimit reproduce``: the paper's results figure, every cell measured and saved, resumable.

The command line of :func:`toolimit.experiments.reproduce.reproduce` (its docstring says what each
preset runs and where each cell goes). ``--demo`` replaces the preset's demonstrations,
``--experiment`` keeps some of its experiments and ``--methods`` some of the methods (e.g. the method
and the sparse baseline first, ``--methods final,sparse_ppo``; the others on a later run into the
same folder). ``--jobs N`` runs N experiments at a time, each in a child process whose output goes
to OUT/seed_<S>/logs/<experiment>.log. ``--ray [ADDRESS]`` runs them on a Ray cluster instead
(:mod:`toolimit.experiments.on_cluster`), the log naming the node of each cell. ``--seed 0,1,2``
runs several training seeds, each a reproduction of its own in OUT/seed_<S>/, and OUT/results.*
put them side by side, each cell with its intervals over seeds and episodes. Exit codes: 0 done, 1 an experiment's pipeline found nothing or its
robot cannot track the scripted motion of LfD so that it earns (those cells are missing from the
results; a line says why), 2 bad input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from toolimit.cli import (
    CliError,
    add_out_argument,
    add_ray_argument,
    check_count,
    check_output_folder,
    check_ray,
)
from toolimit.experiments.cells import METHODS, Experiment
from toolimit.experiments.reproduce import PRESETS, Preset, preset


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
    add_out_argument(parser, "output folder (seed_<S>/ for each seed, results.* of every seed)")
    parser.add_argument(
        "--seed",
        "--seeds",
        type=_seeds,
        default=(0,),
        help="training seed, or comma-separated seeds, e.g. 0,1,2, each in OUT/seed_<S>/ (default: 0)",
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="experiments run at a time, each in its own process (default: 1; each also uses its own "
        "worker processes for stage iii's selection); results do not depend on it",
    )
    add_ray_argument(parser, "every experiment's preparation and learning runs as tasks")
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


def _seeds(text: str) -> tuple[int, ...]:
    """``--seed``: distinct non-negative integers, comma-separated, in the order given; argparse
    turns the error into one line."""
    names = [name.strip() for name in text.split(",")]
    if not all(name.isdigit() for name in names):
        raise argparse.ArgumentTypeError(
            f"expected non-negative integers separated by commas, e.g. 0,1,2, got {text!r}"
        )
    seeds = tuple(int(name) for name in names)
    twice = sorted({seed for seed in seeds if seeds.count(seed) > 1})
    if twice:
        raise argparse.ArgumentTypeError(f"seed {', '.join(map(str, twice))} given twice in {text!r}")
    return seeds


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
    from toolimit.experiments.reproduce import reproduce

    chosen = preset(args.preset)
    chosen = dataclasses.replace(chosen, experiments=_experiments(args, chosen))
    check_count("--jobs", args.jobs)
    check_output_folder(args.out, "--out")
    check_ray(args.ray)
    return reproduce(
        chosen,
        args.out,
        seeds=args.seed,
        methods=args.methods,
        jobs=args.jobs,
        progress=not args.quiet,
        report=lambda name, line: print(f"[{name}] {line}", flush=True),
        ray=args.ray,
    )
