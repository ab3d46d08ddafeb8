"""Learning a policy for a task, end to end: cloning, value warm-up, PPO, with checkpoints.

``learn_policy(task, out_dir, LearningConfig(...))`` writes into ``out_dir``:
``task.npz`` (the task), ``cloning.json`` (data and losses), ``checkpoint.safetensors/.json`` (every
few updates, and the last update's model once finished; without ``keep_best``, ``checkpoint.json``
then names ``policy.safetensors``, the one copy of the final model), ``best.json`` and
``best-<steps>.safetensors``
(the best check's model, :mod:`toolimit.learn.kept_policy`), ``curve.jsonl`` (one line per
update: env steps, mean return, success rate, goal reward, standard deviation, KL; under ADR the
goal box bounds ``adr_low``, ``adr_high`` the update's episodes were drawn in), ``policy.safetensors``
(the run's policy, an SB3 model without pickle, :mod:`toolimit.learn.policy_file`: with ``keep_best`` the best check's or the last update's,
the better on episodes of their own) and ``learning.json`` (settings,
env steps, wall time split between simulation and learning; under ADR the final bounds and every
boundary test, :meth:`toolimit.learn.adr.AdrState.record`). Run again on the same folder, it
resumes from the last checkpoint; a finished run returns at once.
"""

from __future__ import annotations

import inspect
import json
import numbers
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, cast

import numba
import numpy as np
import torch
from gymnasium.spaces import Box
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from tqdm.std import tqdm

from toolimit.artifacts import save_json
from toolimit.errors import InputError, InvalidLearningConfig
from toolimit.learn.adr import EVERY as ADR_EVERY
from toolimit.learn.adr import RULE_VERSION, goal_box_spec
from toolimit.learn.adr_callback import AdrCallback
from toolimit.learn.cloning import AUTHORS_ACTION_STD, clone, collect_demonstrations
from toolimit.learn.early_stop import EarlyStop, StopRule
from toolimit.learn.env import BOX_OFFSET_BOUND
from toolimit.learn.evaluate import evaluate, observes_goal_box
from toolimit.learn.kept_policy import KeptPolicy
from toolimit.learn.policy_file import load_model, load_sb3_zip, model_task
from toolimit.learn.ppo import (
    CHECKPOINT_MODEL,
    CHECKPOINT_STATE,
    POLICY_MODEL,
    PRESETS,
    PpoSettings,
    blind_to_goal_box,
    checkpoint_elapsed,
    make_ppo,
    resume_or_start,
    train,
)
from toolimit.learn.simulator import REWARDS
from toolimit.learn.task import TASK_NPZ, LearningTask, action_limit_problem
from toolimit.learn.vec_env import BatchedTaskVecEnv
from toolimit.progress import progress_bar
from toolimit.scenes.registry import make_scene, scene_class
from toolimit.workers import cores_given

LEARNING_JSON = "learning.json"
#: The cloned policy's deterministic episodes before PPO (``cloning.json``'s ``clone_check``), seeded
#: ``CLONE_CHECK_SEED + seed``, apart from the training, early-stopping and evaluation seeds.
CLONE_CHECK_EPISODES = 20
CLONE_CHECK_SEED = 4000
CLONING_JSON = "cloning.json"
CURVE_JSONL = "curve.jsonl"
#: The fields of :class:`LearningConfig` that, when given, replace the preset's
#: :class:`~toolimit.learn.ppo.PpoSettings` field of the same name.
PRESET_OVERRIDES = ("learning_rate", "target_kl")


@dataclass(frozen=True)
class LearningConfig:
    """Budgets and choices of :func:`learn_policy`.

    Attributes:
        timesteps: PPO environment steps (cloning rollouts come on top). 300,000 suits the planar
            world; the 3D world's preset (:data:`toolimit.pipeline.settings.WORLD_PRESETS`) gives
            1.5 M (docs/learning.md#learning-stage-iv).
        envs: B, instances stepped together.
        preset: PPO settings: the authors' or the project's (a looser gradient clip and RAdam), a
            key of :data:`toolimit.learn.ppo.PRESETS`.
        learning_rate: PPO's optimiser step size, replacing the preset's (None keeps it). An Adam
            or RAdam step moves each weight by about it, whatever the gradient's size.
        target_kl: a bound on each PPO update's approximate KL divergence, replacing the preset's
            (None keeps it; neither preset has one): SB3 skips an update's remaining minibatches
            once one's KL exceeds 1.5 times it. PPO's ratio clip does not bound a step's size.
        clone: behaviour cloning before PPO (without it: PPO from a random policy with a learned std, the
            sparse-reward baseline).
        clone_rollouts: tracking-controller rollouts to clone (1 = the authors' single rollout).
        clone_noise: std of the action noise of rollouts 2.. (fraction of the action scale), each
            noisy state relabelled with the controller's action.
        clone_steps: Adam steps of cloning.
        value_steps: Adam steps of the value network's warm-up after cloning.
        action_std: the policy's standard deviation on every joint, rad/s (fixed after cloning,
            the start of the learned one without).
        action_limit: every joint's commanded speed is clipped at this many rad/s (the authors': 3,
            beyond the Panda's limits) instead of the robot's own velocity limits (None); the
            penalty above 0.9 of the robot's limits stays. The learnt task (OUT/task.npz) keeps
            it, so that evaluation and export roll the policy out as it learnt.
        checkpoint_every: updates between checkpoints.
        seed: seeds everything (environments, torch, PPO).
        scene_kwargs: the scene's constructor arguments.
        reward: sparse (the paper's goal reward) or dense (plus the appendix's shaping: the
            dense-reward baseline); :data:`toolimit.learn.simulator.REWARDS`.
        torch_threads: torch's intra-op threads while learning. One by default: the networks are
            small, and a second thread competes with the simulation for the cores.
        adr: domain randomisation of the goal box (spades, :mod:`toolimit.learn.adr`): the box is
            observed, cloned at the aligned position, then moved by the boundary tests.
        adr_every: PPO updates between two boundary tests of ADR.
        early_stop: end PPO once the policy has learnt (``stop``'s rule,
            :mod:`toolimit.learn.early_stop`) instead of spending the whole budget (the paper's
            fixed budget when off); never under ADR.
        stop: the early-stopping rule (checks every few updates, success to hold).
        keep_best: the run's policy is the one of its best check (:mod:`toolimit.learn.kept_policy`:
            the highest success, the latest among equals) when it does better than the last
            update's on ``selection_episodes`` episodes of their own; with ``early_stop`` only (its
            checks).
        selection_episodes: deterministic episodes on which each of the two candidates of
            ``keep_best`` is rolled out at the end of a run whose best check is not its last update.
        sim_processes: processes stepping the B instances (3D tasks; the same numbers whatever
            their count, :mod:`toolimit.learn.split_simulator`). One by default: two were slower
            on a shared machine (benchmarks/learning_throughput.py; docs/results/performance.md).
        sim_threads: threads stepping each process's instances in a scene that takes them (the 3D
            spade's sand; the same numbers whatever their count, tests/scenes/test_sand_threads.py).
            None: :meth:`threads_per_process`, the cores this process may use shared among the
            ``sim_processes``: on two idle cores two threads train the 3D spade faster than one
            (docs/results/performance.md).
    """

    timesteps: int = 300_000
    envs: int = 16
    preset: str = "authors"
    learning_rate: float | None = None
    target_kl: float | None = None
    clone: bool = True
    clone_rollouts: int = 8
    clone_noise: float = 0.3
    clone_steps: int = 6000
    value_steps: int = 2000
    action_std: float = AUTHORS_ACTION_STD
    action_limit: float | None = None
    checkpoint_every: int = 5
    seed: int = 0
    scene_kwargs: dict[str, Any] | None = None
    reward: str = "sparse"
    torch_threads: int = 1
    adr: bool = False
    adr_every: int = ADR_EVERY
    early_stop: bool = True
    stop: StopRule = StopRule()
    keep_best: bool = True
    selection_episodes: int = 200
    sim_processes: int = 1
    sim_threads: int | None = None

    def __post_init__(self) -> None:
        """InvalidLearningConfig, naming the field, for a value no run can use: refused here, before
        :func:`learn_policy` writes anything."""
        for field, lowest in (
            ("timesteps", 0),
            ("envs", 1),
            ("clone_rollouts", 1),
            ("clone_steps", 0),
            ("value_steps", 0),
            ("checkpoint_every", 1),
            ("seed", 0),
            ("torch_threads", 1),
            ("adr_every", 1),
            ("selection_episodes", 1),
        ):
            value = getattr(self, field)
            if not isinstance(value, numbers.Integral) or value < lowest:
                raise InvalidLearningConfig(field, f"must be an integer >= {lowest}, got {value!r}")
        if not 0.0 <= self.clone_noise < float("inf"):
            raise InvalidLearningConfig("clone_noise", f"must be a finite number >= 0, got {self.clone_noise!r}")
        for field in PRESET_OVERRIDES:
            value = getattr(self, field)
            if value is not None and not 0.0 < value < float("inf"):
                raise InvalidLearningConfig(field, f"must be a finite number > 0, got {value!r}")
        if not 0.0 < self.action_std < float("inf"):
            raise InvalidLearningConfig("action_std", f"must be a finite number > 0 (rad/s), got {self.action_std!r}")
        if problem := action_limit_problem(self.action_limit):
            raise InvalidLearningConfig("action_limit", problem)
        if not isinstance(self.sim_processes, numbers.Integral) or not 1 <= self.sim_processes <= self.envs:
            raise InvalidLearningConfig(
                "sim_processes", f"must be an integer in 1..envs ({self.envs}), got {self.sim_processes!r}"
            )
        if self.sim_threads is not None and (
            not isinstance(self.sim_threads, numbers.Integral)
            or not 1 <= self.sim_threads <= numba.config.NUMBA_NUM_THREADS
        ):
            raise InvalidLearningConfig(
                "sim_threads",
                f"must be an integer in 1..{numba.config.NUMBA_NUM_THREADS} (numba's NUMBA_NUM_THREADS), "
                f"got {self.sim_threads!r}",
            )
        if self.scene_kwargs is not None and "threads" in self.scene_kwargs:
            raise InvalidLearningConfig("scene_kwargs", "give the simulation's threads as sim_threads")
        if self.preset not in PRESETS:
            raise InvalidLearningConfig("preset", f"unknown preset {self.preset!r}; choose one of {', '.join(PRESETS)}")
        if self.reward not in REWARDS:
            raise InvalidLearningConfig("reward", f"unknown reward {self.reward!r}; choose one of {', '.join(REWARDS)}")
        if isinstance(self.stop, Mapping):  # as ``asdict`` and learning.json write it
            object.__setattr__(self, "stop", StopRule(**self.stop))
        if not isinstance(self.stop, StopRule):
            raise InvalidLearningConfig("stop", f"must be a StopRule, got {self.stop!r}")

    def settings(self) -> PpoSettings:
        """The PPO settings of the preset, with ``learning_rate`` and ``target_kl`` where given."""
        given = {field: value for field in PRESET_OVERRIDES if (value := getattr(self, field)) is not None}
        return replace(PRESETS[self.preset], **given)

    def threads_per_process(self) -> int:
        """``sim_threads``, or when None the cores this process is given
        (:func:`~toolimit.workers.cores_given`) shared among the ``sim_processes``, at most
        numba's thread count (``NUMBA_NUM_THREADS``, which ``reproduce --jobs`` sets for its
        children) and a process's instances."""
        if self.sim_threads is not None:
            return int(self.sim_threads)
        processes = int(self.sim_processes)
        return max(1, min(cores_given() // processes, numba.get_num_threads(), self.envs // processes))

    def simulation_kwargs(self, task: LearningTask) -> dict[str, Any] | None:
        """The scene's constructor arguments for this learning's simulations: ``scene_kwargs``,
        with :meth:`threads_per_process` as ``threads`` where the task's scene takes them."""
        if "threads" not in inspect.signature(scene_class(task.tool, task.world)).parameters:
            return self.scene_kwargs
        return (self.scene_kwargs or {}) | {"threads": self.threads_per_process()}


@dataclass(frozen=True)
class LearningOutcome:
    """What :func:`learn_policy` returns: the model, its folder and the learning record."""

    model: PPO
    directory: Path
    record: dict[str, Any]


class _Curve(BaseCallback):
    """Appends one line per update to ``curve.jsonl`` (with the early-stopping check of the update,
    if one was made) and hands it to ``on_record`` (e.g. rerun); tells the early stopping each
    update's training success."""

    def __init__(
        self,
        path: Path,
        total: int,
        on_record: Callable[[dict[str, Any]], None] | None,
        progress: bool,
        checks: EarlyStop | None,
    ):
        super().__init__()
        self.path, self.on_record, self.checks = path, on_record, checks
        self.total, self.progress = total, progress
        self.bar: tqdm  # made when training starts, from the steps already done
        self.returns: list[float] = []
        self.successes: list[bool] = []
        self.goals: list[float] = []
        self.pending: dict[str, Any] | None = None

    def _on_training_start(self) -> None:
        # A resumed run's earlier steps are the bar's start, not progress of this sitting: tqdm's
        # rate (and so the ETA) counts only the steps made since.
        self.bar = progress_bar(
            total=self.total,
            initial=self.model.num_timesteps,
            desc="PPO",
            unit="step",
            disable=not self.progress,
            leave=False,
        )

    def _on_step(self) -> bool:
        self.bar.update(self.training_env.num_envs)
        for info in self.locals["infos"]:
            if "episode" in info:
                self.returns.append(info["episode"]["r"])
                self.successes.append(info["is_success"])
                self.goals.append(info["goal_reward"])
        return True

    def _on_rollout_end(self) -> None:
        self.pending = (
            {
                "env_steps": int(self.model.num_timesteps),
                "return_mean": float(np.mean(self.returns)),
                "success_rate": float(np.mean(self.successes)),
                "goal_reward_mean": float(np.mean(self.goals)),
            }
            if self.returns
            else None
        )
        if self.pending is not None:
            if self.checks is not None:
                self.checks.add_training_success(self.pending["env_steps"], self.pending["success_rate"])
            self.bar.set_postfix(
                success=f"{self.pending['success_rate']:.2f}",
                goal=f"{self.pending['goal_reward_mean']:.1f}",
                refresh=False,
            )
        self.returns, self.successes, self.goals = [], [], []

    def _on_rollout_start(self) -> None:
        self._write()

    def _write(self) -> None:
        """Write the last rollout's record with the update PPO then made from it (its KL, the std
        after it): called when the next rollout starts, or when training ends."""
        if self.pending is None:
            return
        logged = self.model.logger.name_to_value
        adr = cast(BatchedTaskVecEnv, self.training_env).adr
        record = self.pending | {
            "action_std_mean": float(torch.exp(cast(torch.Tensor, self.model.policy.log_std).detach()).mean()),
            "approx_kl": float(logged.get("train/approx_kl", float("nan"))),
            **(adr.bounds.record() if adr is not None else {}),
            **(self.checks.take_record() if self.checks is not None else {}),
        }
        with open(self.path, "a") as handle:
            handle.write(json.dumps(record) + "\n")
        if self.on_record is not None:
            self.on_record(record)
        self.pending = None

    def _on_training_end(self) -> None:
        self._write()
        self.bar.close()


class CloneRejected(Exception):
    """The cloned policy failed the caller's check (:func:`learn_policy`'s ``accept_clone``); PPO
    was not started and no checkpoint written. ``record``: the cloning record (``cloning.json``)."""

    def __init__(self, record: dict[str, Any]) -> None:
        super().__init__(f"the cloned policy was not accepted: {record.get('clone_check')}")
        self.record = record


def learn_policy(
    task: LearningTask,
    out_dir: str | Path,
    config: LearningConfig = LearningConfig(),
    on_record: Callable[[dict[str, Any]], None] | None = None,
    progress: bool = True,
    accept_clone: Callable[[dict[str, Any]], bool] | None = None,
) -> LearningOutcome:
    """Clone (optional), warm the value up and fine-tune by PPO; see the module docstring.
    ``accept_clone(cloning record)``: False raises :class:`CloneRejected` before PPO starts."""
    threads = torch.get_num_threads()
    torch.set_num_threads(config.torch_threads)
    try:
        return _learn_policy(task, Path(out_dir), config, on_record, progress, accept_clone)
    finally:
        torch.set_num_threads(threads)


def _learn_policy(
    task: LearningTask,
    out_dir: Path,
    config: LearningConfig,
    on_record: Callable[[dict[str, Any]], None] | None,
    progress: bool,
    accept_clone: Callable[[dict[str, Any]], bool] | None,
) -> LearningOutcome:
    started = time.perf_counter()
    settings = config.settings()
    task = replace(task, action_limit=config.action_limit)
    _check_action_limit(out_dir, task)
    if config.adr:  # a scene without a goal box to move is refused before anything is written
        goal_box_spec(make_scene(task.tool, task.world))
    torch.manual_seed(config.seed)
    scene_kwargs = config.simulation_kwargs(task)
    env = BatchedTaskVecEnv(
        task,
        config.envs,
        seed=config.seed,
        scene_kwargs=scene_kwargs,
        reward=config.reward,
        adr=config.adr,
        processes=config.sim_processes,
    )
    cloning_record: dict[str, Any] = {}

    def start() -> PPO:
        model = make_ppo(env, settings, seed=config.seed, learn_std=not config.clone, action_std=config.action_std)
        if config.clone:
            cloning_record.update(_clone(model, task, config, settings, scene_kwargs, progress))
            save_json(out_dir / CLONING_JSON, cloning_record)
            if accept_clone is not None and not accept_clone(cloning_record):
                raise CloneRejected(cloning_record)
        return model

    previous = _previous_record(out_dir)
    try:
        model, resumed = resume_or_start(out_dir, env, start, settings)
    except BaseException:  # a refused checkpoint or clone: the simulation's workers end here too
        env.close()
        raise
    task.save(out_dir / TASK_NPZ)  # once the checkpoint is accepted: a refused resume writes nothing
    curve = out_dir / CURVE_JSONL
    lines = _truncate_curve(curve, model.num_timesteps)
    checked = config.early_stop and not config.adr
    kept = KeptPolicy(out_dir, task, config.selection_episodes, scene_kwargs) if checked and config.keep_best else None
    checks = EarlyStop(task, config.stop, lines, scene_kwargs, config.reward, kept) if checked else None
    callbacks: list[BaseCallback] = [] if checks is None else [checks]  # before the curve: its line holds the check
    callbacks.append(_Curve(curve, config.timesteps, on_record, progress, checks))
    if config.adr:  # after the curve: a line holds the bounds its episodes were drawn in
        callbacks.append(AdrCallback(env, config.adr_every))
    learnt = checks is not None and checks.stopped_at is not None  # a resumed run that had stopped
    budget = model.num_timesteps if learnt else config.timesteps

    def elapsed() -> dict[str, float]:
        """The run's times so far, its earlier sittings' included (the checkpoints keep them)."""
        return {
            "wall_time_s": previous.get("wall_time_s", 0.0) * resumed + time.perf_counter() - started,
            "simulation_time_s": previous.get("simulation_time_s", 0.0) * resumed + env.simulation_time_s,
        }

    try:
        final_file = POLICY_MODEL if kept is None else CHECKPOINT_MODEL
        train(model, budget, out_dir, config.checkpoint_every, callbacks, final_file, elapsed)
    finally:
        env.close()  # ends the simulation's worker processes (multiprocessing's exit hook, if earlier)
    policy, choice = (
        (model, None) if kept is None else kept.install(out_dir / POLICY_MODEL, model, out_dir / CHECKPOINT_MODEL)
    )
    cloning_steps = previous.get("cloning_env_steps", 0) if resumed else cloning_record.get("env_steps", 0)
    times = elapsed()
    wall, simulation = times["wall_time_s"], times["simulation_time_s"]
    record = {
        "tool": task.tool,
        "world": task.world,
        "robot": task.robot,
        "config": asdict(config),
        "sim_threads": (scene_kwargs or {}).get("threads"),
        "ppo": asdict(settings),
        "ppo_env_steps": int(model.num_timesteps),
        "cloning_env_steps": int(cloning_steps),
        "env_steps": int(model.num_timesteps + cloning_steps),
        "wall_time_s": wall,
        "simulation_time_s": simulation,
        "learning_time_s": wall - simulation,
        "resumed": resumed,
    }
    if checks is not None:
        record["early_stop"] = {"stopped_at_ppo_env_steps": checks.stopped_at, "rule": asdict(config.stop)}
    if choice is not None:
        record["kept_policy"] = choice
    if env.adr is not None:
        record["adr"] = env.adr.record(config.adr_every)
    save_json(out_dir / LEARNING_JSON, record)
    return LearningOutcome(policy, out_dir, record)


def _check_action_limit(out_dir: Path, task: LearningTask) -> None:
    """InputError when ``out_dir`` holds a checkpoint learnt with another action limit than
    ``task``'s: a resume would roll the policy out at another scale than it learnt."""
    if not (out_dir / CHECKPOINT_STATE).is_file() or not (out_dir / TASK_NPZ).is_file():
        return
    learnt = LearningTask.load(out_dir / TASK_NPZ).action_limit
    if learnt != task.action_limit:
        given = "the robot's limits" if learnt is None else f"--action-limit {learnt:g}"
        raise InputError(
            f"{out_dir / TASK_NPZ}: this checkpoint was learnt with {given}; give it again or start a new output folder"
        )


def _clone(
    model: PPO,
    task: LearningTask,
    config: LearningConfig,
    settings: PpoSettings,
    scene_kwargs: dict[str, Any] | None,
    progress: bool,
) -> dict[str, Any]:
    """Collect the demonstrations, clone, warm up and check the clone (in the scene built with
    ``scene_kwargs``); the JSON record."""
    demonstrations = collect_demonstrations(
        task,
        config.clone_rollouts,
        config.clone_noise,
        settings.gamma,
        config.seed,
        scene_kwargs,
        config.reward,
        config.adr,
    )
    report = clone(
        model.policy,
        demonstrations,
        config.clone_steps,
        value_steps=config.value_steps,
        seed=config.seed,
        progress=progress,
    )
    if config.adr:
        blind_to_goal_box(model)
    check = evaluate(
        model,
        task,
        CLONE_CHECK_EPISODES,
        deterministic=True,
        seed=CLONE_CHECK_SEED + config.seed,
        scene_kwargs=scene_kwargs,
    )
    return {
        "rollouts": config.clone_rollouts,
        "action_noise": config.clone_noise,
        "env_steps": demonstrations.env_steps + CLONE_CHECK_EPISODES * task.horizon,
        "pairs": len(demonstrations.actions),
        "controller_goal_rewards": demonstrations.goal_rewards.tolist(),
        "controller_successes": demonstrations.successes.tolist(),
        "clone_check": {
            "episodes": CLONE_CHECK_EPISODES,
            "success_rate": float(np.mean(check.successes)),
            "goal_reward_mean": float(np.mean(check.goal_rewards)),
        },
        **asdict(report),
    }


def _previous_record(out_dir: Path) -> dict[str, Any]:
    """The learning record of a run to resume (its cloning steps and times), if the checkpoint
    exists; the cloning record stands in for a run interrupted before its first record. The times
    are the checkpoint's (up to it, whether the run was interrupted or ended), else the record's."""
    if not (out_dir / CHECKPOINT_STATE).is_file():
        return {}
    record: dict[str, Any] = {}
    for name, key in ((LEARNING_JSON, None), (CLONING_JSON, "env_steps")):
        path = out_dir / name
        if path.is_file():
            data = json.loads(path.read_text())
            record = data if key is None else {"cloning_env_steps": data[key]}
            break
    return record | checkpoint_elapsed(out_dir)


def _truncate_curve(path: Path, env_steps: int) -> list[dict[str, Any]]:
    """Drop curve lines beyond ``env_steps`` (written after the checkpoint a run resumes from);
    the lines kept."""
    if not path.is_file():
        return []
    lines = [json.loads(line) for line in path.read_text().splitlines()]
    kept = [line for line in lines if line["env_steps"] <= env_steps]
    path.write_text("".join(json.dumps(line) + "\n" for line in kept))
    return kept


#: A stable-baselines3 zip an earlier toolimit wrote as a folder's policy: read only on request.
SB3_POLICY_ZIP = "policy.zip"


def load_policy(directory: str | Path, trust_sb3_zip: bool = False) -> tuple[PPO, LearningTask]:
    """The final model and task of a :func:`learn_policy` folder (``policy.safetensors``, read
    without pickle); FileNotFoundError names what is missing, InputError a model of another task or
    an ADR policy of an earlier observation. A folder holding only a stable-baselines3
    ``policy.zip`` is refused unless ``trust_sb3_zip`` (its loading unpickles it and can run code;
    :func:`~toolimit.learn.policy_file.load_sb3_zip` warns)."""
    directory = Path(directory)
    policy, zip_policy = directory / POLICY_MODEL, directory / SB3_POLICY_ZIP
    if policy.is_file():
        model = load_model(policy)
        task = LearningTask.load(directory / TASK_NPZ)
        recorded = model_task(policy)
        names = (task.tool, task.world, task.robot)
        if recorded is not None and (recorded["tool"], recorded["world"], recorded["robot"]) != names:
            learnt = "/".join(str(recorded[key]) for key in ("tool", "world", "robot"))
            raise InputError(f"{policy}: learnt on {learnt}, not on {TASK_NPZ}'s {'/'.join(names)}")
    elif zip_policy.is_file():
        if not trust_sb3_zip:
            raise InputError(
                f"{zip_policy}: a stable-baselines3 zip, whose loading unpickles it and can run code; toolimit reads "
                f"{POLICY_MODEL}. If you trust the file's author, load it explicitly (--trust-sb3-zip)"
            )
        task = LearningTask.load(directory / TASK_NPZ)
        policy, model = zip_policy, load_sb3_zip(zip_policy)
    else:
        raise FileNotFoundError(f"{policy}: no such file (run `toolimit learn` first)")
    space = cast(Box, model.observation_space)
    if observes_goal_box(model, task) and space.high[-1] != np.float32(BOX_OFFSET_BOUND):
        raise InputError(
            f"{policy}: this ADR policy observes the goal box in world metres (before ADR rule {RULE_VERSION}, "
            "which observes its offset); learn it again"
        )
    return model, task
