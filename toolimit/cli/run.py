"""``toolimit run``: the whole pipeline, demonstration to trained policy, resumable stage by stage.

demonstration -> ``align`` (OUT/alignment) -> ``trajopt`` with selection by robot execution
(OUT/trajectory) -> ``learn``: cloning and PPO (OUT/learning) -> ``evaluate`` (OUT/evaluation.json)
-> the policy's deterministic rollout (OUT/policy_rollout, stage iii's format) -> ``export``
(OUT/export: retimed and limit-checked for open-loop execution; robots with published limits).
Each stage is the command of the same name with the flags below, so a stage's folder is exactly
what that command writes. Run again, the command skips every stage whose output is complete and
resumes the first one that is not (alignment and learning continue from their checkpoints).
OUT/run.json keeps each stage's wall time; OUT/evaluation.json has ``success_rate``,
``goal_reward_mean``, ``episodes``, ``env_steps`` (training, cloning rollouts included) and
``wall_time_s`` (alignment to evaluation, over every invocation). Exit codes: 0 done, 1 a stage found nothing
(no alignment candidate, no robot replay with a reward), 2 bad input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from toolimit.cli import CliError, add_out_argument, add_tool_argument, add_world_argument, check_output_folder
from toolimit.cli.learn import add_learning_arguments, check_adr, learning_config
from toolimit.cli.trajopt import parse_time_scales

if TYPE_CHECKING:
    import numpy as np

    from toolimit.learn.task import LearningTask

RUN_JSON = "run.json"
#: PPO steps by default, per world (measured: the planar spade succeeds after 300 k; the Panda
#: spade's training success climbs from 0.03 to 1.0 between 0.5 M and 1.2 M steps).
DEFAULT_TIMESTEPS = {"planar": 300_000, "3d": 1_500_000}
#: Alignment candidates by default, per world: the robot's selection needs good ones to choose from.
#: Measured on the 3D spade (seed 0, time scales 1, 1.5, 2): on spade_00 the best Panda replay of 5
#: candidates earns 6.5 spheres, of 20 candidates 9.7; on the authors' real recording, 7.2 of 20
#: (at time scale 2) and 11.7 of 40 (at real time; its policy then succeeds in 20 of 20 episodes).
#: The alignment takes under a minute for 40; the selection tracks them in worker processes.
DEFAULT_CANDIDATES = {"planar": 5, "3d": 40}
#: Time scales the robot's selection tries, per world (``toolimit trajopt --time-scale``): the
#: demonstration's own speed. A slowed trajectory can earn more in the robot's replay, but PPO then
#: learns from episodes twice as long, in which the policy's exploration noise (0.2 rad/s every
#: step) drifts twice as far: measured on the Panda spade (seed 0, 1.5 M steps), both selections
#: that kept time scale 2 (spade_00: robot replay 17.0 spheres; the real recording among 20
#: candidates: 7.2) ended at deterministic success 0.80 with stochastic rollouts that never
#: succeed, both that kept real time (spade_00: 9.7; the real recording among 40: 11.7) at 1.0.
SELECTION_TIME_SCALES = {"planar": "1", "3d": "1"}
#: Stage iii's settings in the pipeline (``toolimit trajopt --velocity-weight``, ``--starts``): w_v,
#: the weight of the joint velocities (rad/s)^2, and the base initialisations by default; the LfD
#: baseline of ``toolimit reproduce`` tracks its scripted motion with the same.
VELOCITY_WEIGHT = 1e-4
STARTS = 8
#: Budgets of --quick: minutes on a laptop, for CI and first tries.
QUICK = {
    "samples": 3000,
    "candidates": 3,
    "starts": 2,
    "timesteps": 2_000,
    "envs": 4,
    "clone_steps": 300,
    "value_steps": 200,
    "clone_rollouts": 2,
    "episodes": 4,
}


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "run", help="the whole pipeline: align, trajopt, learn, evaluate", description=__doc__.splitlines()[0]
    )
    add_tool_argument(parser)
    parser.add_argument("--robot", required=True, help="robot model (panda, ur5, talos, planar3)")
    parser.add_argument("--demo", required=True, type=Path, help="demonstration file")
    add_world_argument(parser, "3d")
    add_out_argument(parser, "output folder (one sub-folder per stage)")
    parser.add_argument("--samples", type=int, default=20_000, help="alignment sample budget (default: 20000)")
    parser.add_argument(
        "--candidates",
        type=int,
        default=None,
        help=f"alignment candidates (default: {DEFAULT_CANDIDATES['planar']} planar, {DEFAULT_CANDIDATES['3d']} in 3D)",
    )
    parser.add_argument(
        "--time-scale",
        default=None,
        help="time scales the robot's selection tries, as `toolimit trajopt --time-scale` (default: "
        f"{SELECTION_TIME_SCALES['planar']} planar, {SELECTION_TIME_SCALES['3d']} in 3D)",
    )
    parser.add_argument("--starts", type=int, default=STARTS, help=f"trajopt base initialisations (default: {STARTS})")
    parser.add_argument("--episodes", type=int, default=20, help="evaluation episodes (default: 20)")
    add_learning_arguments(parser, timesteps=None)
    parser.add_argument(
        "--quick", action="store_true", help=f"tiny budgets for a first try or CI (flags given explicitly win): {QUICK}"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.set_defaults(func=run, budget_defaults={name: parser.get_default(name) for name in QUICK})


def run(args: argparse.Namespace) -> int:
    from toolimit.cli import main as toolimit
    from toolimit.cli.evaluate import EVALUATION_JSON, evaluation_record
    from toolimit.learn.ppo import POLICY_ZIP
    from toolimit.learn.training import LEARNING_JSON
    from toolimit.trajopt.result import TRAJECTORY_NPZ

    if args.world not in DEFAULT_TIMESTEPS:
        raise CliError(f"--world: unknown world {args.world!r}; choose one of {', '.join(DEFAULT_TIMESTEPS)}")
    if args.quick:
        for name, value in QUICK.items():
            if getattr(args, name) == args.budget_defaults[name]:
                setattr(args, name, value)
    if args.timesteps is None:
        args.timesteps = DEFAULT_TIMESTEPS[args.world]
    if args.candidates is None:
        args.candidates = DEFAULT_CANDIDATES[args.world]
    learning_config(args)  # checks the learning flags before any work
    check_adr(args.adr, args.tool, args.world)
    time_scale = args.time_scale or SELECTION_TIME_SCALES[args.world]
    parse_time_scales(time_scale)
    if not args.demo.is_file():
        raise CliError(f"--demo: no such file: {args.demo}")
    check_output_folder(args.out, "--out")
    alignment, trajectory, learning = args.out / "alignment", args.out / "trajectory", args.out / "learning"
    quiet = ["--quiet"] if args.quiet else []
    stages: list[tuple[str, Callable[[], bool], list[str]]] = [
        (
            "alignment",
            lambda: _alignment_done(alignment),
            [
                "align",
                "--tool",
                args.tool,
                "--world",
                args.world,
                "--demo",
                str(args.demo),
                "--out",
                str(alignment),
                "--samples",
                str(args.samples),
                "--candidates",
                str(args.candidates),
                "--seed",
                str(args.seed),
                *quiet,
            ],
        ),
        (
            "trajectory",
            lambda: (trajectory / TRAJECTORY_NPZ).is_file(),
            [
                "trajopt",
                "--robot",
                args.robot,
                "--tool",
                args.tool,
                "--alignment",
                str(alignment),
                "--select-by-robot",
                "--velocity-weight",
                f"{VELOCITY_WEIGHT:g}",
                "--time-scale",
                time_scale,
                "--starts",
                str(args.starts),
                "--seed",
                str(args.seed),
                "--out",
                str(trajectory),
                *quiet,
            ],
        ),
        (
            "learning",
            lambda: (learning / POLICY_ZIP).is_file() and (learning / LEARNING_JSON).is_file(),
            [
                "learn",
                "--alignment",
                str(alignment),
                "--trajectory",
                str(trajectory),
                "--out",
                str(learning),
                "--timesteps",
                str(args.timesteps),
                "--envs",
                str(args.envs),
                "--preset",
                args.preset,
                "--clone-rollouts",
                str(args.clone_rollouts),
                "--clone-noise",
                str(args.clone_noise),
                "--clone-steps",
                str(args.clone_steps),
                "--value-steps",
                str(args.value_steps),
                "--action-std",
                str(args.action_std),
                "--reward",
                args.reward,
                "--checkpoint-every",
                str(args.checkpoint_every),
                "--seed",
                str(args.seed),
                "--adr-every",
                str(args.adr_every),
                *(["--no-clone"] if args.no_clone else []),
                *(["--adr"] if args.adr else []),
                *quiet,
            ],
        ),
    ]
    times = _stage_times(args.out)
    for name, done, command in stages:
        if done():
            _check_same_run(args, args.out / name)
            print(f"[{name}] done earlier: {args.out / name}")
            continue
        print(f"[{name}] toolimit {' '.join(command)}")
        started = time.perf_counter()
        try:
            code = toolimit(command)
        finally:
            times[name] = times.get(name, 0.0) + time.perf_counter() - started
            _save_stage_times(args.out, times)
        if code != 0:
            return code
    started = time.perf_counter()
    record, evaluation, task = evaluation_record(learning, args.episodes, seed=1000)
    times["evaluation"] = time.perf_counter() - started
    _save_stage_times(args.out, times)
    learned = json.loads((learning / LEARNING_JSON).read_text())
    record |= {
        "env_steps": learned["env_steps"],
        "wall_time_s": sum(times.values()),
        "stage_times_s": times,
        "simulation_time_s": learned["simulation_time_s"],
        "learning_time_s": learned["learning_time_s"],
    }
    from toolimit.artifacts import save_json

    save_json(args.out / EVALUATION_JSON, record)
    code = _export_rollout(args, evaluation.joint_positions[0], task, toolimit)
    print(
        f"success rate {record['success_rate']:.2f} over {record['episodes']} episodes, goal reward "
        f"{record['goal_reward_mean']:.1f}, {record['env_steps']} env steps, {record['wall_time_s']:.0f} s; "
        f"wrote {args.out / EVALUATION_JSON}"
    )
    return code


def _export_rollout(
    args: argparse.Namespace, joint_positions: np.ndarray, task: LearningTask, toolimit: Callable[[list[str]], int]
) -> int:
    """The policy's first deterministic evaluation episode, joints (H+1, N) rad, to
    OUT/policy_rollout (stage iii's format), exported by ``toolimit export`` to OUT/export for
    robots with published limits; the export's exit code."""
    from toolimit.deploy.limits import SUPPORTED_ROBOTS
    from toolimit.learn.evaluate import save_rollout_trajectory

    folder = save_rollout_trajectory(joint_positions, task, args.out / "policy_rollout")
    if args.robot not in SUPPORTED_ROBOTS:
        print(
            f"[export] skipped: {args.robot} has no published acceleration and jerk limits "
            f"(the policy's rollout is in {folder})"
        )
        return 0
    command = ["export", "--trajectory", str(folder), "--robot", args.robot, "--out", str(args.out / "export")]
    print(f"[export] toolimit {' '.join(command)}")
    return toolimit(command)


def _check_same_run(args: argparse.Namespace, folder: Path) -> None:
    """CliError if a finished stage's folder was made for another tool, world or robot."""
    from toolimit.align.outputs import ALIGNMENT_JSON
    from toolimit.learn.task import TASK_NPZ, LearningTask
    from toolimit.trajopt.result import TRAJECTORY_JSON

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
        if value != getattr(args, key):
            raise CliError(
                f"{folder} holds a finished stage for {key} {value!r}, not {getattr(args, key)!r}: "
                "choose another --out or remove that folder"
            )


def _alignment_done(folder: Path) -> bool:
    """An alignment that finished with candidates (no checkpoint of an interrupted search left)."""
    from toolimit.align.outputs import CANDIDATES_NPZ
    from toolimit.cli.align import CHECKPOINT_JSON

    return (folder / CANDIDATES_NPZ).is_file() and not (folder / CHECKPOINT_JSON).is_file()


def _stage_times(out: Path) -> dict[str, float]:
    path = out / RUN_JSON
    return json.loads(path.read_text())["stage_times_s"] if path.is_file() else {}


def _save_stage_times(out: Path, times: dict[str, float]) -> None:
    from toolimit.artifacts import save_json

    save_json(out / RUN_JSON, {"stage_times_s": times})
