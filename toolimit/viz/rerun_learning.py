"""rerun recording of a learning run's curves (``curve.jsonl`` of :mod:`toolimit.learn.training`).

Entities (timeline ``env_steps``): ``curves/return``, ``curves/success_rate``,
``curves/goal_reward``, ``curves/action_std`` (normalised action units), ``curves/approx_kl``;
under ADR (:mod:`toolimit.learn.adr`) the goal box bounds ``adr/x_low``, ``adr/x_high``,
``adr/y_low``, ``adr/y_high`` (world frame, m).

Also, for notebook 04: :func:`save_tracking_recording` (a rollout's joints against the reference,
timeline ``step``) and :func:`save_goal_rewards_recording` (per-episode goal rewards as bar charts).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import rerun as rr

from toolimit.viz.rerun_file import recording_file, save_recording

CURVES = {
    "return": "return_mean",
    "success_rate": "success_rate",
    "goal_reward": "goal_reward_mean",
    "action_std": "action_std_mean",
    "approx_kl": "approx_kl",
}


def save_learning_recording(curve_file: str | Path, path: str | Path) -> Path | None:
    """Write the curves of ``curve_file`` (JSON lines) to ``path`` (.rrd); None when rerun is disabled."""
    records = [json.loads(line) for line in Path(curve_file).read_text().splitlines() if line.strip()]
    with recording_file(path, "toolimit_learning") as recording:
        if recording is None:
            return None
        for record in records:
            recording.set_time("env_steps", sequence=int(record["env_steps"]))
            for entity, key in CURVES.items():
                value = float(record[key])
                if math.isfinite(value):
                    recording.log(f"curves/{entity}", rr.Scalars(value))
            for side in ("low", "high") if "adr_low" in record else ():
                for axis, value in zip("xy", record[f"adr_{side}"], strict=True):
                    recording.log(f"adr/{axis}_{side}", rr.Scalars(float(value)))
    return Path(path)


def save_tracking_recording(
    path: str | os.PathLike[str],
    joint_names: Sequence[str],
    executed: np.ndarray,
    reference: np.ndarray,
    goal_rewards: np.ndarray,
    show_inline: bool = False,
) -> Path | None:
    """A rollout against its reference: ``executed`` (T+1, N) joints (rad) under
    ``joints/<name>/executed``, ``reference`` (R+1, N) under ``joints/<name>/reference`` (held at
    its last row after step R), and ``goal_rewards`` (T,) after each step under ``goal_reward``;
    timeline ``step``. None when rerun is disabled (``show_inline``: :func:`save_recording`)."""
    executed, reference = np.asarray(executed, dtype=float), np.asarray(reference, dtype=float)
    if executed.ndim != 2 or executed.shape[1] != len(joint_names) or reference.shape[1:] != executed.shape[1:]:
        raise ValueError(f"executed {executed.shape} and reference {reference.shape} must be (T+1, {len(joint_names)})")
    if len(goal_rewards) != len(executed) - 1:
        raise ValueError(f"{len(goal_rewards)} goal rewards for {len(executed) - 1} steps")

    def log(recording: rr.RecordingStream) -> None:
        for t, q in enumerate(executed):
            recording.set_time("step", sequence=t)
            held = reference[min(t, len(reference) - 1)]
            for j, name in enumerate(joint_names):
                recording.log(f"joints/{name}/executed", rr.Scalars(q[j]))
                recording.log(f"joints/{name}/reference", rr.Scalars(held[j]))
            if t > 0:
                recording.log("goal_reward", rr.Scalars(float(goal_rewards[t - 1])))

    return save_recording(path, log, "toolimit_tracking", show_inline=show_inline)


def save_goal_rewards_recording(
    path: str | os.PathLike[str], goal_rewards: Mapping[str, np.ndarray], show_inline: bool = False
) -> Path | None:
    """Per-episode goal rewards, one bar chart per name (``goal_reward_per_episode/<name>``); None
    when rerun is disabled."""

    def log(recording: rr.RecordingStream) -> None:
        for name, values in goal_rewards.items():
            recording.log(f"goal_reward_per_episode/{name}", rr.BarChart(np.asarray(values, dtype=float)), static=True)

    return save_recording(path, log, "toolimit_goal_rewards", show_inline=show_inline)
