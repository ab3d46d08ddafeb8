"""``toolimit learn``: learn a robot's policy for a task (stage iv): cloning, then PPO.

The task comes from a pipeline run (``--alignment DIR --trajectory DIR``: the outputs of
``toolimit align`` and ``toolimit trajopt``), a task file (``--task``), or a registered
environment's shipped task (``--env toolimit/SpadePlanar-v0``). Writes OUT/task.npz,
OUT/cloning.json, OUT/curve.jsonl, OUT/checkpoint.*, OUT/policy.zip and OUT/learning.json
(:mod:`toolimit.learn.training`). Interrupted (Ctrl-C: exit 130), the same command resumes from the
last checkpoint. Exit codes: 0 done, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from toolimit.cli import (
    CliError,
    add_out_argument,
    add_seed_argument,
    check_output_file,
    check_output_folder,
)


def add_learning_arguments(parser: argparse.ArgumentParser, timesteps: int | None) -> None:
    """The budget and learner flags shared by ``toolimit learn`` and ``toolimit run``."""
    from toolimit.learn.adr import EVERY as ADR_EVERY
    from toolimit.learn.ppo import PRESETS
    from toolimit.learn.simulator import REWARDS

    parser.add_argument(
        "--timesteps",
        type=int,
        default=timesteps,
        help=f"PPO environment steps (default: {timesteps or '300000 planar, 1500000 3d'})",
    )
    parser.add_argument("--envs", type=int, default=16, help="instances stepped together (default: 16)")
    parser.add_argument(
        "--preset",
        choices=sorted(PRESETS),
        default="authors",
        help="PPO settings: the authors' or the project's looser gradient clip (default: authors)",
    )
    parser.add_argument(
        "--no-clone",
        action="store_true",
        help="no behaviour cloning: sparse-reward PPO from a random policy (learned std)",
    )
    parser.add_argument(
        "--clone-rollouts",
        type=int,
        default=8,
        help="tracking-controller rollouts to clone (1 = the authors'; default: 8)",
    )
    parser.add_argument(
        "--clone-noise",
        type=float,
        default=0.3,
        help="action noise of rollouts 2.. (fraction of the velocity limit), relabelled by the "
        "controller (default: 0.3)",
    )
    parser.add_argument("--clone-steps", type=int, default=6000, help="cloning Adam steps (default: 6000)")
    parser.add_argument(
        "--value-steps",
        type=int,
        default=2000,
        help="Adam steps of the value network's warm-up after cloning (default: 2000)",
    )
    parser.add_argument(
        "--action-std",
        type=float,
        default=0.2,
        help="the policy's standard deviation on every joint, rad/s: fixed after cloning, the start of the "
        "learned one with --no-clone (default: 0.2, the authors')",
    )
    parser.add_argument(
        "--reward",
        choices=REWARDS,
        default="sparse",
        help="sparse: the paper's goal reward; dense: plus the appendix's shaping, the dense-reward "
        "baseline (default: sparse)",
    )
    parser.add_argument(
        "--adr",
        action="store_true",
        help="domain randomisation of the goal box (spades): the box drawn per episode inside bounds grown from "
        "the aligned position by the authors' boundary test, and observed by the policy",
    )
    parser.add_argument(
        "--adr-every",
        type=int,
        default=ADR_EVERY,
        help=f"with --adr: PPO updates between two boundary tests (default: {ADR_EVERY})",
    )
    parser.add_argument("--checkpoint-every", type=int, default=5, help="PPO updates between checkpoints (default: 5)")
    add_seed_argument(parser)


def learning_config(args: argparse.Namespace, scene_kwargs: dict | None = None):
    """The LearningConfig of the flags of :func:`add_learning_arguments`; CliError naming the flag of a
    value the config refuses."""
    from toolimit.errors import InvalidLearningConfig
    from toolimit.learn.training import LearningConfig

    try:
        return LearningConfig(
            timesteps=args.timesteps,
            envs=args.envs,
            preset=args.preset,
            clone=not args.no_clone,
            clone_rollouts=args.clone_rollouts,
            clone_noise=args.clone_noise,
            clone_steps=args.clone_steps,
            value_steps=args.value_steps,
            action_std=args.action_std,
            checkpoint_every=args.checkpoint_every,
            seed=args.seed,
            scene_kwargs=scene_kwargs,
            reward=args.reward,
            adr=args.adr,
            adr_every=args.adr_every,
        )
    except InvalidLearningConfig as error:  # every field set here has the flag --field-name
        raise CliError(f"--{error.field.replace('_', '-')}: {error.problem}") from None


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "learn", help="learn the robot's policy: cloning then PPO (stage iv)", description=__doc__.splitlines()[0]
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--task", type=Path, help="a task file (task.npz)")
    source.add_argument("--alignment", type=Path, help="`toolimit align` output folder (with --trajectory)")
    source.add_argument("--env", help="a registered id, e.g. toolimit/SpadePlanar-v0 (its shipped task)")
    parser.add_argument("--trajectory", type=Path, help="`toolimit trajopt` output folder (with --alignment)")
    parser.add_argument("--robot", default=None, help="with --env: another robot's shipped task")
    add_out_argument(parser)
    add_learning_arguments(parser, timesteps=200_000)
    parser.add_argument("--rerun", type=Path, default=None, help="also save the learning curves as a rerun .rrd")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.set_defaults(func=run)


def load_task(args: argparse.Namespace):
    """The LearningTask named by --task, --alignment/--trajectory or --env."""
    from toolimit.learn import LearningTask, shipped_task, task_from_pipeline
    from toolimit.learn.env import ENV_TOOLS, ENV_WORLDS, env_id

    if args.task is not None:
        return LearningTask.load(args.task)
    if args.alignment is not None:
        if args.trajectory is None:
            raise CliError("--alignment: needs --trajectory DIR (the `toolimit trajopt` output)")
        return task_from_pipeline(args.alignment, args.trajectory)
    ids = {env_id(tool, world): (tool, world) for tool in ENV_TOOLS for world in ENV_WORLDS}
    if args.env not in ids:
        raise CliError(f"--env: unknown id {args.env!r}; known: {', '.join(sorted(ids))}")
    return shipped_task(*ids[args.env], robot=args.robot)


def check_adr(adr: bool, tool: str, world: str) -> None:
    """With --adr, InputError (one line) unless the tool's scene has a goal box to move."""
    if adr:
        from toolimit.learn.adr import goal_box_spec
        from toolimit.scenes.registry import make_scene

        goal_box_spec(make_scene(tool, world))


def run(args: argparse.Namespace) -> int:
    from toolimit.learn.ppo import CHECKPOINT_STATE
    from toolimit.learn.training import CURVE_JSONL, learn_policy

    config = learning_config(args)
    if args.trajectory is not None and args.alignment is None:
        raise CliError("--trajectory: needs --alignment DIR")
    check_output_folder(args.out, "--out")
    check_output_file(args.rerun, "--rerun", ".rrd")
    task = load_task(args)
    check_adr(args.adr, task.tool, task.world)
    try:
        outcome = learn_policy(task, args.out, config, progress=not args.quiet)
    except KeyboardInterrupt as stop:  # interrupts.Interrupted (SIGINT, SIGTERM) or a plain Ctrl-C
        saved = (args.out / CHECKPOINT_STATE).is_file()
        print(
            "interrupted: "
            + (
                f"run the same command again to resume from the checkpoint in {args.out}"
                if saved
                else "no checkpoint was written yet; the same command starts again"
            ),
            file=sys.stderr,
        )
        return int(getattr(stop, "exit_code", 130))
    if args.rerun is not None:
        from toolimit.viz.rerun_learning import save_learning_recording

        save_learning_recording(args.out / CURVE_JSONL, args.rerun)
    record = outcome.record
    print(
        f"{task.robot} {task.tool} ({task.world}): {record['env_steps']} env steps "
        f"({record['cloning_env_steps']} cloning), {record['wall_time_s']:.0f} s "
        f"({record['simulation_time_s']:.0f} s simulation); wrote {args.out / 'policy.zip'}. "
        f"Next: toolimit evaluate --policy {args.out}"
    )
    return 0
