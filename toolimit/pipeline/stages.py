"""The pipeline's stages as functions: each takes the previous stage's output and its settings,
writes its folder and returns a typed result.

- :func:`align_stage` (ii): demonstration -> ``alignment.json``, ``aligned_demo.npz``, ``candidates.npz``;
- :func:`trajopt_stage` (iii): alignment folder -> ``trajectory.npz``/``.json`` (recording the
  candidate it was tracked in) and ``selection.json``; :func:`trajopt_from_poses` for poses alone;
- :func:`learn_stage` (iv): alignment and trajectory folders -> ``learning/`` (cloning, PPO);
- :func:`evaluate_stage`: a policy folder -> the evaluation record;
- :func:`export_stage`: the policy's deterministic rollout -> ``policy_rollout/`` and ``export/``.

A stage that finds nothing to hand on raises :class:`~toolimit.errors.StageFoundNothing` after
writing its record; each one's lines for a person to read come from the ``describe_*`` functions.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm

from toolimit.align.outputs import ALIGNMENT_JSON, CHECKPOINT_JSON, write_alignment
from toolimit.align.search import AlignmentResult, align
from toolimit.artifacts import save_json
from toolimit.demos import ToolDemo, load_demo
from toolimit.distributed import RayTarget
from toolimit.errors import InputError, StageFoundNothing
from toolimit.learn.evaluate import Evaluation, evaluate, save_rollout_trajectory
from toolimit.learn.ppo import CHECKPOINT_STATE
from toolimit.learn.task import TASK_NPZ, LearningTask, task_from_pipeline
from toolimit.learn.training import (
    LEARNING_JSON,
    CloneRejected,
    LearningConfig,
    LearningOutcome,
    learn_policy,
    load_policy,
)
from toolimit.pipeline.settings import AlignSettings, EvaluationSettings, ExportSettings, TrajoptSettings
from toolimit.pipeline.shortlist import (
    CLONE_ATTEMPTS,
    SHORTLIST_ACTION_LIMIT,
    ShortlistEntry,
    best_to_learn,
    can_fall_back_on,
    clone_reproduces,
    read_shortlist,
    shortlist_folder,
    shortlist_in_learning_task,
)
from toolimit.robots import RobotModel, make_robot
from toolimit.trajopt.problem import PoseTargets
from toolimit.trajopt.result import TrackedScene, TrajectoryResult
from toolimit.trajopt.selection import (
    SELECTION_JSON,
    AlignedCandidate,
    RobotSelection,
    load_candidates,
    select_by_robot_execution,
)
from toolimit.trajopt.time_scale import choose_time_scale
from toolimit.trajopt.track import track
from toolimit.workers import worker_count

#: The evaluation record beside a policy (``toolimit evaluate``) and in a pipeline's folder.
EVALUATION_JSON = "evaluation.json"
#: The clones the learning stage set aside, and why (:func:`learn_stage`).
CLONE_ATTEMPTS_JSON = "clone_attempts.json"


def align_stage(
    demo: ToolDemo | str | Path,
    tool: str,
    world: str,
    out: str | Path,
    settings: AlignSettings = AlignSettings(),
    progress: bool = True,
    ray: RayTarget = False,
) -> AlignmentResult:
    """Stage ii: align ``tool``'s scene in ``world`` to ``demo`` (a ToolDemo or a demonstration
    file) and write ``out``. An interrupted search saves ``out/alignment_checkpoint.json`` and the
    same call resumes it (:class:`~toolimit.align.search.SearchInterrupted`). ``ray``: the samples
    on a Ray cluster (:data:`~toolimit.distributed.RayTarget`), same result. InputError for a
    demonstration of another tool; StageFoundNothing when no sample earned a reward (the record is
    written, with no candidate)."""
    out = Path(out)
    source = str(demo) if isinstance(demo, (str, Path)) else demo.source or "(in memory)"
    if isinstance(demo, (str, Path)):
        demo = load_demo(demo, tool=tool)  # also names the tool of files that do not store it
    workers = worker_count(settings.workers)
    result = align(
        demo,
        tool,
        world,
        settings.search,
        seed=settings.seed,
        workers=workers,
        progress=progress,
        checkpoint=out / CHECKPOINT_JSON,
        clean=settings.clean,
        ray=ray,
    )
    write_alignment(result, out, source, cleaned=settings.clean, workers=workers)
    if result.best is None:
        raise StageFoundNothing(
            f"no candidate: no sample earned a goal reward within {settings.search.samples} samples "
            f"(record: {out / ALIGNMENT_JSON}); try more samples or another seed"
        )
    return result


def describe_alignment(result: AlignmentResult) -> list[str]:
    """Lines for a person: cleaning, samples, candidates, the best one."""
    lines = []
    if result.cleaning is not None:
        lines.append(
            f"cleaned demo: {len(result.cleaning.replaced_frames)} frames replaced "
            f"({len(result.cleaning.head_replaced_frames)} of them with the head's position)"
        )
    rejected = result.samples_rejected / max(result.samples_tried, 1)
    lines.append(
        f"{len(result.candidates)} candidate(s) in {result.samples_tried} samples ({rejected:.0%} rejected), "
        f"{result.wall_time_s:.1f} s"
    )
    if result.best is not None:
        best = result.best
        lines.append(
            f"best: sample {best.index}, mean goal reward {best.reward:.3f} "
            f"(scale {best.sample.scale}, z offset {best.sample.z_offset:+.3f} m)"
        )
    return lines


@dataclass(frozen=True)
class TrajectoryStage:
    """What :func:`trajopt_stage` made.

    Attributes:
        trajectory: the kept trajectory; ``trajectory.scene`` names its candidate.
        candidates: the alignment's candidates.
        selection: the robot's selection among them (None when ``select_by_robot`` is off).
        shortlist: the best candidates by robot reward tracked in their learning tasks
            (:mod:`toolimit.pipeline.shortlist`; empty when ``shortlist`` is 0 or without a selection).
    """

    trajectory: TrajectoryResult
    candidates: list[AlignedCandidate]
    selection: RobotSelection | None
    shortlist: list[ShortlistEntry] = field(default_factory=list)


def trajopt_stage(
    alignment: str | Path,
    robot: str,
    out: str | Path,
    settings: TrajoptSettings = TrajoptSettings(),
    progress: bool = True,
    tool: str | None = None,
    ray: RayTarget = False,
    action_limit: float | None = None,
) -> TrajectoryStage:
    """Stage iii from an alignment folder: with ``settings.select_by_robot``, every candidate is
    tracked by ``robot`` and replayed in its scene, the ``settings.shortlist`` whose replays earn
    most are tracked in their learning tasks, and the one whose tracking succeeds most often there
    is kept (:mod:`toolimit.pipeline.shortlist`; with a shortlist of 0, the one whose replay earns
    most; ``out/selection.json`` lists them all); otherwise the best tool-only candidate is tracked.
    Writes ``out/trajectory.npz``/``.json``, which record the candidate. ``ray``: the candidates
    tracked on a Ray cluster (:data:`~toolimit.distributed.RayTarget`). InputError when ``tool``
    is given and the alignment is another tool's; StageFoundNothing when no robot replay earns a
    reward. ``action_limit``: the learner's (:attr:`LearningConfig.action_limit
    <toolimit.learn.training.LearningConfig.action_limit>`), for the shortlist's learning tasks."""
    out = Path(out)
    aligned_tool, world, candidates = load_candidates(alignment)
    if tool is not None and tool != aligned_tool:
        raise InputError(f"the alignment in {alignment} is for the {aligned_tool}, not the {tool}")
    robot_model = make_robot(robot, tool=aligned_tool)
    selection = None
    shortlist: list[ShortlistEntry] = []
    if settings.select_by_robot:
        selection = select_by_robot_execution(
            robot_model,
            candidates,
            aligned_tool,
            world,
            settings.track_options(),  # no bar per tracking: the selection shows one over the candidates
            seed=settings.seed,
            progress=progress,
            time_scales=settings.time_scales,
            workers=worker_count(settings.workers),
            ray=ray,
        )
        record = selection.record(candidates)
        if selection.best is None:
            save_json(out / SELECTION_JSON, record)
            raise StageFoundNothing(
                f"no candidate's robot replay earned a goal reward (record: {out / SELECTION_JSON})"
            )
        kept = selection.best
        if settings.shortlist > 0:
            shortlist = shortlist_in_learning_task(
                selection,
                candidates,
                robot_model,
                aligned_tool,
                world,
                settings.shortlist,
                settings.shortlist_episodes,
                settings.seed,
                progress,
                action_limit,
            )
            kept = best_to_learn(shortlist).candidate
            record["shortlist"] = [entry.record() for entry in shortlist]
            record[SHORTLIST_ACTION_LIMIT] = action_limit
            for entry in shortlist:  # the learner may fall back to any of them (learn_stage)
                shortlisted = selection.trajectories[entry.candidate]
                assert shortlisted is not None  # shortlisted candidates have a robot reward
                shortlisted.save(shortlist_folder(out, entry.candidate))
        record["kept"] = kept
        save_json(out / SELECTION_JSON, record)
        trajectory = selection.trajectories[kept]
        assert trajectory is not None  # a candidate with a robot reward was tracked
    else:
        best = max(range(len(candidates)), key=lambda k: (candidates[k].alignment_reward, -k))
        tracked = _track(robot_model, candidates[best].targets, settings, progress)
        trajectory = replace(tracked, scene=TrackedScene(world, best, candidates[best].params))
    trajectory.save(out)
    return TrajectoryStage(trajectory, candidates, selection, shortlist)


def trajopt_from_poses(
    targets: PoseTargets,
    robot: str,
    tool: str,
    out: str | Path,
    *,
    settings: TrajoptSettings = TrajoptSettings(),
    progress: bool = True,
) -> TrajectoryResult:
    """Stage iii from tool poses alone (no scene: the trajectory records none); writes ``out``."""
    trajectory = _track(make_robot(robot, tool=tool), targets, settings, progress)
    trajectory.save(out)
    return trajectory


def _track(robot: RobotModel, targets: PoseTargets, settings: TrajoptSettings, progress: bool) -> TrajectoryResult:
    """``targets`` tracked at the first time scale, or the first of several that tracks within 1 cm."""
    rng = np.random.default_rng(settings.seed)
    options = settings.track_options(progress)
    if len(settings.time_scales) > 1:
        return choose_time_scale(robot, targets, options, grid=settings.time_scales, rng=rng)
    return track(robot, targets, options, rng=rng)


def describe_trajectory(stage: TrajectoryStage) -> list[str]:
    """Lines for a person: each candidate's robot replay (with a selection) and the kept trajectory."""
    lines = []
    selection = stage.selection
    if selection is not None:
        for k, (trajectory, reward) in enumerate(zip(selection.trajectories, selection.robot_rewards)):
            if trajectory is None:
                lines.append(f"candidate {k}: refused ({selection.refusals[k]})")
            else:
                lines.append(f"candidate {k}: robot replay reward {reward:.1f}; {trajectory.describe()}")
        for entry in stage.shortlist:
            lines.append(
                f"shortlisted candidate {entry.candidate}, in the learning task ({entry.horizon} steps): tracking succeeds in "
                f"{entry.success_rate:.0%} of the episodes, {entry.goal_reward_mean:.1f} goal reward"
            )
    scene = stage.trajectory.scene
    assert scene is not None  # trajopt_stage records it
    reward = "" if selection is None else f", robot reward {selection.robot_rewards[scene.candidate]:.1f}"
    lines.append(
        f"kept candidate {scene.candidate} (alignment reward "
        f"{stage.candidates[scene.candidate].alignment_reward:.1f}{reward}): {stage.trajectory.describe()}"
    )
    return lines


def learn_stage(
    alignment: str | Path,
    trajectory: str | Path,
    out: str | Path,
    config: LearningConfig = LearningConfig(),
    progress: bool = True,
) -> LearningOutcome:
    """Stage iv: the learning task of the trajectory in the scene it was tracked in
    (:func:`~toolimit.learn.task.task_from_pipeline`), learnt by cloning then PPO into ``out``
    (resumed from its checkpoint).

    With stage iii's shortlist (:mod:`toolimit.pipeline.shortlist`), the clone is checked before
    PPO: where it does not reproduce its expert's success, the next shortlisted candidate whose own
    tracking succeeds at all is cloned instead (:func:`~toolimit.pipeline.shortlist.can_fall_back_on`),
    up to :data:`CLONE_ATTEMPTS`. When
    every clone is set aside, the one that succeeded most often is cloned again (the same clone:
    cloning is seeded) and learnt. ``out/clone_attempts.json`` lists the clones set aside;
    ``task.npz`` names the candidate learnt."""
    out = Path(out)
    if (out / CHECKPOINT_STATE).is_file():  # PPO started: resume the candidate it started on
        return learn_policy(LearningTask.load(out / TASK_NPZ), out, config, progress=progress)
    folders = [Path(trajectory)]
    if config.clone:  # without a clone (the baselines) there is nothing to check
        others = [entry for entry in read_shortlist(trajectory)[1:] if can_fall_back_on(entry)]
        folders += [shortlist_folder(trajectory, entry.candidate) for entry in others[: CLONE_ATTEMPTS - 1]]
    if len(folders) == 1:  # nothing to fall back on: no check
        return learn_policy(task_from_pipeline(alignment, folders[0], seed=config.seed), out, config, progress=progress)
    attempts_path = out / CLONE_ATTEMPTS_JSON
    attempts: list[dict[str, Any]] = json.loads(attempts_path.read_text()) if attempts_path.is_file() else []
    for folder in folders[len(attempts) :]:
        task = task_from_pipeline(alignment, folder, seed=config.seed)
        try:
            return learn_policy(task, out, config, progress=progress, accept_clone=clone_reproduces)
        except CloneRejected as rejected:
            attempts.append({"candidate": int(task.source["candidate"]), **rejected.record["clone_check"]})
            save_json(attempts_path, attempts)
    best = max(range(len(attempts)), key=lambda k: (attempts[k]["success_rate"], -k))
    return learn_policy(task_from_pipeline(alignment, folders[best], seed=config.seed), out, config, progress=progress)


def learning_finished(folder: str | Path) -> bool:
    """A learning folder whose run ended (its final policy and record written)."""
    from toolimit.learn.ppo import POLICY_MODEL

    folder = Path(folder)
    return (folder / POLICY_MODEL).is_file() and (folder / LEARNING_JSON).is_file()


@dataclass(frozen=True)
class PolicyEvaluation:
    """What :func:`evaluate_stage` measured.

    Attributes:
        record: the JSON record (``evaluation.json``): tool, world, robot, seed, the deterministic
            rollouts' ``success_rate``, ``goal_reward_mean``, ``goal_reward``, ``episodes``, and the
            stochastic ones under ``stochastic``.
        deterministic: the deterministic rollouts (their joints feed the export).
        model: the policy evaluated (SB3 model).
        task: the policy's task.
    """

    record: dict[str, Any]
    deterministic: Evaluation
    model: BaseAlgorithm
    task: LearningTask


def evaluate_stage(
    policy: str | Path, settings: EvaluationSettings = EvaluationSettings(), trust_sb3_zip: bool = False
) -> PolicyEvaluation:
    """Deterministic and stochastic rollouts of the policy in the folder ``policy``
    (``toolimit learn``'s), ``settings.episodes`` each from seeded resets; a stable-baselines3
    ``policy.zip`` only with ``trust_sb3_zip`` (:func:`~toolimit.learn.training.load_policy`)."""
    model, task = load_policy(policy, trust_sb3_zip)
    deterministic = evaluate(model, task, settings.episodes, deterministic=True, seed=settings.seed)
    stochastic = evaluate(model, task, settings.episodes, deterministic=False, seed=settings.seed)
    record = {
        "tool": task.tool,
        "world": task.world,
        "robot": task.robot,
        "seed": settings.seed,
        **deterministic.record(),
        "stochastic": stochastic.record(),
    }
    return PolicyEvaluation(record, deterministic, model, task)


def export_stage(
    evaluation: PolicyEvaluation, out: str | Path, settings: ExportSettings = ExportSettings()
) -> Path | None:
    """The policy's first deterministic episode, joints (H+1, N) rad, saved in stage iii's format to
    ``out/policy_rollout`` and, for a robot with published limits, retimed, replayed open-loop in
    the policy's task (its record in the export's JSON) and written to ``out/export``
    (:func:`~toolimit.deploy.export_trajectory`); the export folder, or None for a robot without
    published limits."""
    from toolimit.deploy import SUPPORTED_ROBOTS, export_trajectory, load_trajectory

    out = Path(out)
    task = evaluation.task
    rollout = save_rollout_trajectory(evaluation.deterministic.joint_positions[0], task, out / "policy_rollout")
    if task.robot not in SUPPORTED_ROBOTS:
        return None
    export_trajectory(
        load_trajectory(rollout),
        task.robot,
        out / "export",
        rate=settings.rate,
        subdivisions=settings.subdivisions,
        margins=settings.margins,
        source=str(rollout),
        check=task,
        check_episodes=settings.check_episodes,
    )
    return out / "export"


def learning_record(folder: str | Path) -> dict[str, Any]:
    """The ``learning.json`` of a finished learning folder."""
    return json.loads((Path(folder) / LEARNING_JSON).read_text())
