"""``toolimit learn``: learn a robot's policy for a task (stage iv): cloning, then PPO.

The task comes from a pipeline run (``--alignment DIR --trajectory DIR``: the outputs of
``toolimit align`` and ``toolimit trajopt``), a task file (``--task``), or a registered
environment's shipped task (``--env toolimit/SpadePlanar-v0``). Writes OUT/task.npz,
OUT/cloning.json, OUT/curve.jsonl, OUT/checkpoint.*, OUT/policy.safetensors and OUT/learning.json
(:mod:`toolimit.learn.training`). Interrupted (Ctrl-C: exit 130), the same command resumes from the
last checkpoint. Exit codes: 0 done, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from toolimit.cli import (
    CliError,
    add_out_argument,
    check_output_file,
    check_output_folder,
)
from toolimit.cli.flags import Flag, add_flags, apply_flags
from toolimit.learn.ppo import PRESETS
from toolimit.learn.simulator import REWARDS
from toolimit.pipeline.settings import PipelineSettings, defaults_by_label

if TYPE_CHECKING:
    from toolimit.learn.task import LearningTask
    from toolimit.learn.training import LearningConfig


def show_preset_override(value: float | None) -> str:
    """The help's text of the default of a flag that overrides the PPO preset (None: the preset's)."""
    return "the preset's" if value is None else str(value)


#: The budget and learner flags, shared by ``toolimit learn`` and ``toolimit run`` (fields of
#: :class:`~toolimit.learn.training.LearningConfig`).
LEARNING_FLAGS = (
    Flag("timesteps"),
    Flag("envs"),
    Flag("preset", choices=tuple(sorted(PRESETS))),
    Flag("learning_rate", show=show_preset_override),
    Flag("target_kl", show=show_preset_override),
    Flag("clone"),
    Flag("clone_rollouts"),
    Flag("clone_noise"),
    Flag("clone_steps"),
    Flag("value_steps"),
    Flag("action_std"),
    Flag("action_limit", show=lambda limit: "the robot's velocity limits" if limit is None else str(limit)),
    Flag("reward", choices=REWARDS),
    Flag("adr"),
    Flag("adr_every"),
    Flag("early_stop"),
    Flag("stop.every", name="--stop-every"),
    Flag("stop.episodes", name="--stop-episodes"),
    Flag("keep_best"),
    Flag("selection_episodes"),
    Flag("sim_processes"),
    Flag(
        "sim_threads", show=lambda threads: "the cores, shared among the processes" if threads is None else str(threads)
    ),
    Flag("checkpoint_every"),
    Flag("seed"),
)


def learning_config(args: argparse.Namespace, world: str | None = None, tool: str | None = None) -> LearningConfig:
    """The LearningConfig of the flags: ``world``'s preset with ``tool``'s own values (the plain
    defaults when ``world`` is None) with the flags given; CliError naming the flag of a value the
    config refuses."""
    from toolimit.learn.training import LearningConfig

    base = LearningConfig() if world is None else PipelineSettings.for_world(world, tool=tool).learning
    return apply_flags(base, LEARNING_FLAGS, args)


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
    add_flags(parser, LEARNING_FLAGS, {label: settings.learning for label, settings in defaults_by_label().items()})
    parser.add_argument("--rerun", type=Path, default=None, help="also save the learning curves as a rerun .rrd")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.set_defaults(func=run)


def load_task(args: argparse.Namespace) -> LearningTask:
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


def run(args: argparse.Namespace) -> int:
    from toolimit.learn.ppo import CHECKPOINT_STATE, POLICY_MODEL
    from toolimit.learn.training import CURVE_JSONL, learn_policy

    learning_config(args)  # checks the flags before any work
    if args.trajectory is not None and args.alignment is None:
        raise CliError("--trajectory: needs --alignment DIR")
    check_output_folder(args.out, "--out")
    check_output_file(args.rerun, "--rerun", ".rrd")
    task = load_task(args)
    config = learning_config(args, task.world, task.tool)
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
        f"({record['simulation_time_s']:.0f} s simulation); wrote {args.out / POLICY_MODEL}. "
        f"Next: toolimit evaluate --policy {args.out}"
    )
    return 0
