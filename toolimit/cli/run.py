"""``toolimit run``: the whole pipeline, demonstration to trained policy, resumable stage by stage.

The command line of :func:`toolimit.pipeline.run_pipeline` (its docstring says what each stage
writes under OUT): the flags are the fields of :class:`toolimit.pipeline.PipelineSettings`, their
defaults the world's preset (``--quick``: tiny budgets; flags given explicitly win). Run again, it
skips every finished stage and resumes the first one that is not. Exit codes: 0 done, 1 a stage
found nothing (no alignment candidate, no robot replay with a reward), 2 bad input, 130
interrupted.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from toolimit.cli import (
    CliError,
    add_out_argument,
    add_ray_argument,
    add_seed_argument,
    add_tool_argument,
    add_world_argument,
    check_output_folder,
    check_ray,
)
from toolimit.cli.align import SEARCH_FLAGS
from toolimit.cli.flags import Flag, add_flags, apply_flags, nested
from toolimit.cli.learn import LEARNING_FLAGS
from toolimit.cli.trajopt import TRAJOPT_FLAGS
from toolimit.pipeline.settings import QUICK, WORLD_PRESETS, PipelineSettings, defaults_by_label

#: The flags of ``toolimit run``: the stage commands' own (same names, help and defaults), but for
#: the seed, which ``--seed`` gives every stage (:meth:`PipelineSettings.with_seed`).
RUN_FLAGS = (
    *nested("align", SEARCH_FLAGS),
    *nested(
        "trajopt",
        [flag for flag in TRAJOPT_FLAGS if flag.path in ("weights.velocity", "starts", "time_scales", "shortlist")],
    ),
    *nested("learning", [flag for flag in LEARNING_FLAGS if flag.path != "seed"]),
    Flag("evaluation.episodes"),
)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "run", help="the whole pipeline: align, trajopt, learn, evaluate", description=__doc__.splitlines()[0]
    )
    add_tool_argument(parser)
    parser.add_argument("--robot", required=True, help="robot model (panda, ur5, talos, planar3)")
    parser.add_argument("--demo", required=True, type=Path, help="demonstration file")
    add_world_argument(parser, "3d")
    add_out_argument(parser, "output folder (one sub-folder per stage)")
    add_flags(parser, RUN_FLAGS, defaults_by_label())
    add_seed_argument(parser, "seed of every stage (the evaluation's: this + 1000)")
    parser.add_argument(
        "--quick", action="store_true", help=f"tiny budgets for a first try or CI (flags given explicitly win): {QUICK}"
    )
    add_ray_argument(parser, "the alignment's samples and the robot selection's candidates as tasks (learning here)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.set_defaults(func=run)


def pipeline_settings(args: argparse.Namespace) -> PipelineSettings:
    """The settings of ``toolimit run``'s flags: the world's preset (quick budgets with
    ``--quick``), every stage seeded by ``--seed``, the flags given applied; CliError names a flag
    whose value the settings refuse."""
    if args.world not in WORLD_PRESETS:
        raise CliError(f"--world: unknown world {args.world!r}; choose one of {', '.join(WORLD_PRESETS)}")
    if args.seed < 0:
        raise CliError(f"--seed: must be an integer >= 0, got {args.seed}")
    base = PipelineSettings.for_world(args.world, args.quick, args.tool).with_seed(args.seed)
    return apply_flags(base, RUN_FLAGS, args)


def run(args: argparse.Namespace) -> int:
    from toolimit.cli import check_scene
    from toolimit.pipeline import EVALUATION_JSON, run_pipeline
    from toolimit.robots import ROBOTS

    settings = pipeline_settings(args)
    check_scene(args.tool, args.world)
    if args.robot not in ROBOTS:
        raise CliError(f"--robot: unknown robot {args.robot!r}; choose one of {', '.join(ROBOTS)}")
    if settings.learning.adr:
        from toolimit.learn.adr import goal_box_spec
        from toolimit.scenes.registry import make_scene

        goal_box_spec(make_scene(args.tool, args.world))  # a scene without a goal box: one line
    if not args.demo.is_file():
        raise CliError(f"--demo: no such file: {args.demo}")
    check_output_folder(args.out, "--out")
    check_ray(args.ray)
    result = run_pipeline(
        args.demo,
        args.out,
        args.tool,
        args.robot,
        args.world,
        settings,
        progress=not args.quiet,
        on_stage=lambda stage, line: print(f"[{stage}] {line}", flush=True),
        ray=args.ray,
    )
    record = result.evaluation
    print(
        f"success rate {record['success_rate']:.2f} over {record['episodes']} episodes, goal reward "
        f"{record['goal_reward_mean']:.1f}, {record['env_steps']} env steps, {record['wall_time_s']:.0f} s; "
        f"wrote {args.out / EVALUATION_JSON}"
    )
    return 0
