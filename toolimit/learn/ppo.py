"""PPO fine-tuning with stable-baselines3: presets, the policy of the paper, checkpoints and resume.

The policy (docs/method.md#the-policy, docs/original_setup.md#ppo): Gaussian over the normalised joint velocities, mean and
value from separate 400-300 tanh MLPs. Its standard deviation is fixed at the authors' 0.2 rad/s
after cloning (:func:`toolimit.learn.cloning.fix_action_std`); without cloning (the sparse-reward
baseline) it is learned from 0.2 rad/s.

Presets (:data:`PRESETS`): ``"authors"`` are the original settings (one epoch of 4 minibatches,
clip 0.05, gradient norm clipped at 0.001, gamma 0.999, lambda 1, no advantage normalisation);
``"toolimit"`` clips the gradient less and warms Adam up (RAdam; see :data:`PRESETS` for the
measured trade-off). Rollouts hold whole episodes (``episodes_per_update`` x H steps per
environment), so an update boundary is an episode boundary: a checkpoint there, with the
environments' and torch's random states, resumes the run exactly. A learned standard deviation is
kept above the authors' floor of 0.01 rad/s.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback, CallbackList

from toolimit.artifacts import inside_folder, save_json
from toolimit.errors import InputError
from toolimit.learn.cloning import AUTHORS_ACTION_STD, fix_action_std, normalised_action_std
from toolimit.learn.policy_file import MODEL_SUFFIX, load_model, save_model
from toolimit.learn.vec_env import BatchedTaskVecEnv

#: The model files (:mod:`toolimit.learn.policy_file`): the last checkpoint's and the run's policy.
CHECKPOINT_MODEL = "checkpoint" + MODEL_SUFFIX
CHECKPOINT_STATE = "checkpoint.json"
POLICY_MODEL = "policy" + MODEL_SUFFIX


@dataclass(frozen=True)
class PpoSettings:
    """PPO's hyper-parameters (SB3 names) and the rollout shape.

    Attributes:
        learning_rate: Adam step size. n_epochs: passes over each rollout. minibatches: per epoch.
        clip_range: PPO's ratio clip. max_grad_norm: gradient-norm clip. gamma, gae_lambda: returns.
        ent_coef, vf_coef: loss weights. normalize_advantage: per minibatch.
        episodes_per_update: whole episodes per environment in one rollout.
        target_kl: stop an update's epochs early above this KL (None: never).
        optimizer: ``"adam"`` (SB3's default, eps 1e-5) or ``"radam"`` (torch's rectified Adam, the
            same eps), a key of :data:`OPTIMIZERS`. Adam's first steps move every weight by about
            the learning rate whatever the gradient's size; RAdam warms up instead (Liu et al.,
            "On the variance of the adaptive learning rate and beyond", ICLR 2020).
    """

    learning_rate: float = 3e-4
    n_epochs: int = 1
    minibatches: int = 4
    clip_range: float = 0.05
    max_grad_norm: float = 0.001
    gamma: float = 0.999
    gae_lambda: float = 1.0
    ent_coef: float = 0.0
    vf_coef: float = 1.0
    normalize_advantage: bool = False
    episodes_per_update: int = 2
    target_kl: float | None = None
    optimizer: str = "adam"

    def __post_init__(self) -> None:
        if self.optimizer not in OPTIMIZERS:
            raise ValueError(f"unknown PPO optimizer {self.optimizer!r}; choose one of {', '.join(OPTIMIZERS)}")

    def sb3_kwargs(self) -> dict[str, Any]:
        """The settings SB3's ``PPO`` takes under their own names: all but the rollout shape
        (``minibatches``, ``episodes_per_update``), which give its ``n_steps`` and ``batch_size``,
        and the optimiser, which goes to the policy (:meth:`policy_optimizer`)."""
        kwargs = asdict(self)
        del kwargs["minibatches"], kwargs["episodes_per_update"], kwargs["optimizer"]
        return kwargs

    def policy_optimizer(self) -> dict[str, Any]:
        """The optimiser's entries of SB3's ``policy_kwargs``."""
        return {"optimizer_class": OPTIMIZERS[self.optimizer], "optimizer_kwargs": {"eps": ADAM_EPS}}


#: SB3's Adam epsilon for its policies, kept for every optimiser.
ADAM_EPS = 1e-5
#: The optimisers PPO may use, by :attr:`PpoSettings.optimizer` name.
OPTIMIZERS: dict[str, type[torch.optim.Optimizer]] = {"adam": torch.optim.Adam, "radam": torch.optim.RAdam}


#: ``authors``: docs/original_setup.md#ppo, the default. ``toolimit``: the same with the gradient norm
#: clipped at 0.5 instead of 0.001, one episode per update and RAdam: faster on the stochastic
#: policy, less steady on the deterministic one; RAdam because Adam's first steps after cloning,
#: with the looser clip, broke the clone (measurements: docs/learning.md#ppo-presets).
PRESETS: dict[str, PpoSettings] = {
    "authors": PpoSettings(),
    "toolimit": PpoSettings(max_grad_norm=0.5, episodes_per_update=1, optimizer="radam"),
}


def make_ppo(
    env: BatchedTaskVecEnv,
    settings: PpoSettings,
    seed: int = 0,
    learn_std: bool = False,
    action_std: float = AUTHORS_ACTION_STD,
) -> PPO:
    """A PPO model on ``env`` with the paper's policy; its standard deviation is ``action_std``
    rad/s (the authors' 0.2) on every joint, frozen unless ``learn_std`` (the baselines without
    cloning)."""
    std = normalised_action_std(env.simulator.action_scale, action_std)
    n_steps = settings.episodes_per_update * env.simulator.horizon
    model = PPO(
        "MlpPolicy",
        env,
        n_steps=n_steps,
        batch_size=max(1, n_steps * env.num_envs // settings.minibatches),
        **settings.sb3_kwargs(),
        seed=seed,
        device="cpu",
        verbose=0,
        policy_kwargs={
            "net_arch": {"pi": [400, 300], "vf": [400, 300]},
            "activation_fn": torch.nn.Tanh,
            **settings.policy_optimizer(),
        },
    )
    fix_action_std(model.policy, std)
    model.policy.log_std.requires_grad_(learn_std)
    return model


#: The authors' floor of a learned standard deviation, rad/s.
STD_FLOOR = 0.01


class _StdFloor(BaseCallback):
    """Keeps a learned standard deviation at or above STD_FLOOR rad/s after every update."""

    def _on_rollout_start(self) -> None:
        self._clamp()

    def _on_training_end(self) -> None:
        self._clamp()

    def _clamp(self) -> None:
        log_std = cast(torch.Tensor, self.model.policy.log_std)
        if log_std.requires_grad:
            floor = np.log(STD_FLOOR / cast(BatchedTaskVecEnv, self.training_env).simulator.action_scale)
            with torch.no_grad():
                log_std.copy_(torch.maximum(log_std, torch.as_tensor(floor, dtype=torch.float32)))

    def _on_step(self) -> bool:
        return True


#: The run's elapsed times so far, across its sittings (``wall_time_s``, ``simulation_time_s``).
Elapsed = Callable[[], dict[str, float]]


class _Checkpoints(BaseCallback):
    """Saves the model and the random states every ``every`` updates, at the update's start (an
    episode boundary), so that :func:`train` can resume exactly."""

    def __init__(self, directory: Path, every: int, elapsed: Elapsed | None):
        super().__init__()
        self.directory, self.every, self.elapsed, self.updates = directory, every, elapsed, 0

    def _on_rollout_start(self) -> None:
        if self.updates and self.updates % self.every == 0:
            save_checkpoint(cast(PPO, self.model), self.directory, elapsed=self.elapsed)
        self.updates += 1

    def _on_step(self) -> bool:
        return True


def save_checkpoint(
    model: PPO, directory: Path, model_file: str = CHECKPOINT_MODEL, elapsed: Elapsed | None = None
) -> None:
    """Write the model (parameters, optimiser: :func:`~toolimit.learn.policy_file.save_model`) to ``model_file`` and ``checkpoint.json`` (that
    file's name, steps done, the environment's generator state before its last reset, torch's random
    state, the ADR state, ``elapsed()``'s times: a resumed run's record counts its earlier sittings)
    atomically. The final checkpoint of :func:`train` is ``policy.safetensors`` itself, so that a finished
    run keeps one copy of its model (``checkpoint.safetensors`` is then removed)."""
    env: BatchedTaskVecEnv = model.get_env()  # type: ignore[assignment]
    state = {
        "model": model_file,
        "num_timesteps": int(model.num_timesteps),
        "env_rng": env.rng_state_at_reset,
        "torch_rng": torch.get_rng_state().tolist(),
        "numpy_rng": _numpy_global_state(),
        "learn_std": bool(model.policy.log_std.requires_grad),
    }
    if env.adr is not None:
        state["adr"] = env.adr.state_dict()
    if elapsed is not None:
        state["elapsed"] = elapsed()
    save_model(model, directory / model_file)
    save_json(directory / CHECKPOINT_STATE, state)
    if model_file != CHECKPOINT_MODEL:
        (directory / CHECKPOINT_MODEL).unlink(missing_ok=True)


def load_checkpoint(directory: Path, env: BatchedTaskVecEnv, settings: PpoSettings) -> PPO | None:
    """The model of ``directory``'s checkpoint with ``env`` and random states restored, or None.
    InputError if it was written with PPO settings other than ``settings``: SB3's checkpoint keeps
    its own, so a resume would silently ignore the new ones."""
    state_path = directory / CHECKPOINT_STATE
    if not state_path.is_file():
        return None
    state = json.loads(state_path.read_text())
    model_path = inside_folder(directory, state.get("model", CHECKPOINT_MODEL), f"{state_path}: model")
    if model_path.suffix != MODEL_SUFFIX:
        raise InputError(
            f"{state_path}: its model {model_path.name} is not a {MODEL_SUFFIX} file (a stable-baselines3 zip of an "
            "earlier toolimit, whose loading can run code); start a new output folder"
        )
    if not model_path.is_file():
        return None
    if env.adr is not None:  # before the model: a checkpoint of an earlier ADR rule is refused first
        if "adr" not in state:
            raise InputError(f"{state_path}: this checkpoint was written without --adr; start a new output folder")
        env.adr.load_state_dict(state["adr"], str(state_path))
    model = load_model(model_path, env)
    if changed := _changed_settings(model, settings):
        raise InputError(
            f"{state_path}: this checkpoint was written with other PPO settings ({'; '.join(changed)}); "
            "give the flags it was written with, or start a new output folder"
        )
    model.num_timesteps = int(state["num_timesteps"])
    model.policy.log_std.requires_grad_(bool(state["learn_std"]))
    env.restore_rng_state(state["env_rng"])
    torch.set_rng_state(torch.tensor(state["torch_rng"], dtype=torch.uint8))
    name, keys, position, has_gauss, gauss = state["numpy_rng"]
    np.random.set_state((name, np.array(keys, dtype=np.uint32), position, has_gauss, gauss))
    return model


def _changed_settings(model: PPO, settings: PpoSettings) -> list[str]:
    """The settings of SB3's own (:meth:`PpoSettings.sb3_kwargs`) whose value in a loaded
    ``model`` is not ``settings``', as "name: was, now" texts."""
    changed = []
    for name, value in settings.sb3_kwargs().items():
        loaded = getattr(model, name)
        loaded = loaded(1.0) if callable(loaded) else loaded  # SB3 keeps the clip range as a schedule
        if loaded != value:
            changed.append(f"{name}: {loaded!r}, now {value!r}")
    return changed


def _numpy_global_state() -> list[Any]:
    """numpy's global random state (SB3 shuffles minibatches with it) as JSON values."""
    state = cast(tuple[str, np.ndarray, int, int, float], np.random.get_state())
    name, keys, position, has_gauss, gauss = state
    return [name, keys.tolist(), int(position), int(has_gauss), float(gauss)]


def train(
    model: PPO,
    total_timesteps: int,
    directory: str | os.PathLike[str],
    checkpoint_every: int = 10,
    callbacks: list[BaseCallback] | None = None,
    final_file: str = POLICY_MODEL,
    elapsed: Elapsed | None = None,
) -> PPO:
    """Run PPO until ``model.num_timesteps`` reaches ``total_timesteps``, checkpointing into
    ``directory`` every ``checkpoint_every`` updates (with ``elapsed()``'s times, if given);
    ``final_file`` is the final model and the final checkpoint (a larger budget continues from it):
    ``policy.safetensors``, or ``checkpoint.safetensors`` when the run's policy is another one
    (:mod:`toolimit.learn.kept_policy`). Interrupted (Ctrl-C), the last checkpoint stays:
    :func:`resume_or_start` continues it."""
    directory = Path(directory)
    remaining = total_timesteps - model.num_timesteps
    if remaining > 0:
        model.learn(
            remaining,
            callback=CallbackList(
                [_StdFloor(), *(callbacks or []), _Checkpoints(directory, checkpoint_every, elapsed)]
            ),
            reset_num_timesteps=False,
            log_interval=1,
        )
    save_checkpoint(model, directory, final_file, elapsed)
    return model


def checkpoint_elapsed(directory: str | os.PathLike[str]) -> dict[str, float]:
    """The elapsed times ``directory``'s checkpoint recorded (:func:`save_checkpoint`); empty without
    a checkpoint or for one written before checkpoints held them."""
    state_path = Path(directory) / CHECKPOINT_STATE
    if not state_path.is_file():
        return {}
    return {key: float(value) for key, value in json.loads(state_path.read_text()).get("elapsed", {}).items()}


def blind_to_goal_box(model: PPO) -> None:
    """Zero the first layer's weights on the goal box's observation (the last 2 columns under ADR)
    in the policy and value networks: a clone, which saw the box at offset 0 only, keeps its output
    there and starts PPO blind to the box elsewhere (:mod:`toolimit.learn.adr`, "What the policy
    observes")."""
    extractor = model.policy.mlp_extractor
    with torch.no_grad():
        for network in (extractor.policy_net, extractor.value_net):
            cast(torch.nn.Linear, network[0]).weight[:, -2:] = 0.0


def resume_or_start(
    directory: str | os.PathLike[str], env: BatchedTaskVecEnv, start: Any, settings: PpoSettings
) -> tuple[PPO, bool]:
    """(model, resumed): the checkpoint in ``directory`` if there is one (written with ``settings``:
    :func:`load_checkpoint`), else ``start()``'s model."""
    model = load_checkpoint(Path(directory), env, settings)
    return (model, True) if model is not None else (start(), False)


def settings_record(settings: PpoSettings) -> dict[str, Any]:
    """The settings as a JSON-ready dict."""
    return asdict(settings)
