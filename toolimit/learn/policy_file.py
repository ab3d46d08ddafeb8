"""A PPO model on disk without pickle: tensors in safetensors, everything else in JSON.

stable-baselines3's own ``save``/``load`` keep a model in a zip whose ``data`` entry is unpickled
with cloudpickle when it is loaded: a zip from someone else runs their code. toolimit writes a model
as one ``.safetensors`` file (a format that holds tensors and a JSON header, nothing executable):

- tensors ``policy/<name>``: the policy's ``state_dict()`` (mean and value networks, log std);
- tensors ``optimizer/<parameter>/<name>``: the optimiser's state (Adam's moments and step), so
  that a resumed run continues exactly;
- tensors ``space/observation/{low,high}``, ``space/action/{low,high}``: the Boxes' bounds;
- header metadata ``toolimit``: JSON with the format's version, the PPO hyper-parameters, the
  network's shape (``net_arch``, activation and optimiser names, the optimiser's settings and
  parameter groups), the steps done, and the task the model learnt on (tool, world, robot, action
  limit, the action scale in rad/s per unit action that normalises its outputs).

:func:`load_model` rebuilds SB3's own ``PPO`` and ``MlpPolicy`` from these and loads the tensors
into them (``load_state_dict``): nothing is unpickled. A file that is not one of these is an
:class:`~toolimit.errors.InputError` naming it.

:func:`load_sb3_zip` reads a stable-baselines3 zip (e.g. an earlier toolimit's ``policy.zip``)
only when asked for explicitly, with a warning: its loading can run code.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any, cast

import numpy as np
import torch
from gymnasium import spaces
from safetensors import SafetensorError, safe_open
from safetensors.torch import load_file, save_file
from stable_baselines3 import PPO
from stable_baselines3.common.utils import check_for_correct_spaces

from toolimit.artifacts import atomic_path
from toolimit.errors import InputError

#: The suffix of a model file.
MODEL_SUFFIX = ".safetensors"
#: The header entry that holds the JSON description, and the format's name and version in it.
HEADER_KEY = "toolimit"
FORMAT = "toolimit-ppo"
VERSION = 1
#: The PPO hyper-parameters (SB3's names) a model file records and its rebuilt model is made with.
HYPERPARAMETERS = (
    "learning_rate",
    "n_steps",
    "batch_size",
    "n_epochs",
    "gamma",
    "gae_lambda",
    "clip_range",
    "normalize_advantage",
    "ent_coef",
    "vf_coef",
    "max_grad_norm",
    "target_kl",
    "seed",
)
#: The activation functions and optimisers a model file may name.
ACTIVATIONS: dict[str, type[torch.nn.Module]] = {"Tanh": torch.nn.Tanh, "ReLU": torch.nn.ReLU}
OPTIMIZERS: dict[str, type[torch.optim.Optimizer]] = {"Adam": torch.optim.Adam, "RAdam": torch.optim.RAdam}


def save_model(model: PPO, path: str | Path) -> None:
    """Write ``model`` (its policy, optimiser, spaces, hyper-parameters and, when it has a toolimit
    environment, its task) to ``path`` (``.safetensors``) atomically."""
    policy = model.policy
    tensors: dict[str, torch.Tensor] = {f"policy/{k}": v.detach().cpu() for k, v in policy.state_dict().items()}
    optimizer = policy.optimizer.state_dict()
    for index, state in optimizer["state"].items():
        for name, value in state.items():
            tensors[f"optimizer/{index}/{name}"] = torch.as_tensor(value).detach().cpu()
    for which, space in (("observation", model.observation_space), ("action", model.action_space)):
        box = _box(space, which)
        tensors[f"space/{which}/low"] = torch.as_tensor(box.low)
        tensors[f"space/{which}/high"] = torch.as_tensor(box.high)
    kwargs = model.policy_kwargs
    known = {"net_arch", "activation_fn", "optimizer_class", "optimizer_kwargs"}
    if set(kwargs) - known:
        raise ValueError(f"policy_kwargs {sorted(set(kwargs) - known)} have no place in a model file")
    header = {
        "format": FORMAT,
        "version": VERSION,
        "hyperparameters": {name: _value(getattr(model, name)) for name in HYPERPARAMETERS},
        "net_arch": kwargs.get("net_arch"),
        "activation": kwargs.get("activation_fn", torch.nn.Tanh).__name__,
        "optimizer": kwargs.get("optimizer_class", torch.optim.Adam).__name__,
        "optimizer_kwargs": kwargs.get("optimizer_kwargs", {}),
        "param_groups": optimizer["param_groups"],
        "num_timesteps": int(model.num_timesteps),
        "task": _task_record(model),
    }
    with atomic_path(path) as tmp:
        save_file(tensors, str(tmp), metadata={HEADER_KEY: json.dumps(header)})


def load_model(path: str | Path, env: Any = None) -> PPO:
    """The model in ``path`` (:func:`save_model`'s file) as SB3's ``PPO``, on ``env`` (a
    ``BatchedTaskVecEnv`` whose spaces must be the file's) or without one (to predict). InputError
    names a file that is missing, not such a model file, or of other spaces than ``env``'s."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    try:
        with safe_open(str(path), framework="pt") as handle:
            metadata = handle.metadata() or {}
        header = json.loads(metadata[HEADER_KEY])
        tensors = load_file(str(path))
    except (SafetensorError, OSError, KeyError, ValueError) as error:
        raise InputError(f"{path}: not a toolimit model file ({type(error).__name__}: {error})") from None
    try:
        return _rebuild(header, tensors, env)
    except InputError as error:
        raise InputError(f"{path}: {error}") from None
    except (KeyError, TypeError, ValueError, RuntimeError, IndexError) as error:
        raise InputError(f"{path}: not a model this toolimit can read ({type(error).__name__}: {error})") from None


def model_task(path: str | Path) -> dict[str, Any] | None:
    """The task record of the model file ``path`` (tool, world, robot, ...), None if it has none."""
    with safe_open(str(path), framework="pt") as handle:
        return cast(dict[str, Any] | None, json.loads((handle.metadata() or {})[HEADER_KEY]).get("task"))


def _rebuild(header: dict[str, Any], tensors: dict[str, torch.Tensor], env: Any) -> PPO:
    """SB3's PPO built from a model file's ``header`` and ``tensors``, on ``env`` if given."""
    if header.get("format") != FORMAT or header.get("version") != VERSION:
        raise InputError(f"format {header.get('format')!r} version {header.get('version')!r}, not {FORMAT} {VERSION}")
    if header["activation"] not in ACTIVATIONS or header["optimizer"] not in OPTIMIZERS:
        raise InputError(f"unknown activation {header['activation']!r} or optimiser {header['optimizer']!r}")
    observation_space, action_space = (
        spaces.Box(
            tensors.pop(f"space/{which}/low").numpy(),
            tensors.pop(f"space/{which}/high").numpy(),
            dtype=np.float32,
        )
        for which in ("observation", "action")
    )
    policy_kwargs = {
        "net_arch": header["net_arch"],
        "activation_fn": ACTIVATIONS[header["activation"]],
        "optimizer_class": OPTIMIZERS[header["optimizer"]],
        "optimizer_kwargs": dict(header["optimizer_kwargs"]),
    }
    hyperparameters = {name: header["hyperparameters"][name] for name in HYPERPARAMETERS}
    if env is not None:
        try:
            check_for_correct_spaces(env, observation_space, action_space)
        except ValueError as error:
            raise InputError(f"written for other spaces than this task's ({error})") from None
    model = PPO(
        "MlpPolicy",
        env,
        device="cpu",
        verbose=0,
        policy_kwargs=policy_kwargs,
        _init_setup_model=False,
        **hyperparameters,
    )
    if env is None:
        model.observation_space, model.action_space, model.n_envs = observation_space, action_space, 1
    model._setup_model()
    model.num_timesteps = int(header["num_timesteps"])
    policy_state = {k.removeprefix("policy/"): v for k, v in tensors.items() if k.startswith("policy/")}
    model.policy.load_state_dict(policy_state, strict=True)
    optimizer_state: dict[int, dict[str, torch.Tensor]] = {}
    for key, value in tensors.items():
        if key.startswith("optimizer/"):
            _, index, name = key.split("/", 2)
            optimizer_state.setdefault(int(index), {})[name] = value
    groups = [
        group | {"betas": tuple(group["betas"])} if "betas" in group else group for group in header["param_groups"]
    ]
    model.policy.optimizer.load_state_dict({"state": optimizer_state, "param_groups": groups})
    return model


def load_sb3_zip(path: str | Path, env: Any = None) -> PPO:
    """A stable-baselines3 zip loaded with SB3's own ``PPO.load``, which unpickles its ``data``: it
    runs whatever code the file carries. Only for files the user trusts and asks for explicitly;
    warns on stderr. InputError for a file SB3 cannot read."""
    print(
        f"warning: loading {path} with stable-baselines3, which unpickles it: a zip from someone else "
        "can run code on this machine",
        file=sys.stderr,
    )
    try:
        return PPO.load(path, env=env, device="cpu")
    except Exception as error:  # whatever a foreign zip raises: SB3 checks little of it
        raise InputError(f"{path}: not a stable-baselines3 model ({type(error).__name__}: {error})") from None


def _box(space: Any, which: str) -> spaces.Box:
    if not isinstance(space, spaces.Box):
        raise ValueError(f"the {which} space is {type(space).__name__}, not a Box: no place in a model file")
    return space


def _value(value: Any) -> Any:
    """A hyper-parameter as JSON: SB3 keeps some as constant schedules (their value at the start)."""
    return value(1.0) if callable(value) else value


def _task_record(model: PPO) -> dict[str, Any] | None:
    """The task of ``model``'s toolimit environment (names, action limit, action scale in rad/s per
    unit action), None without one."""
    simulator = getattr(model.get_env(), "simulator", None)
    if simulator is None:
        return None
    task = simulator.task
    return {
        "tool": task.tool,
        "world": task.world,
        "robot": task.robot,
        "joint_names": list(task.joint_names),
        "action_limit": task.action_limit,
        "action_scale": np.asarray(simulator.action_scale, dtype=float).tolist(),
    }
