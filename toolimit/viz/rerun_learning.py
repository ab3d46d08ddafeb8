"""rerun recording of a learning run's curves (``curve.jsonl`` of :mod:`toolimit.learn.training`).

Entities (timeline ``env_steps``): ``curves/return``, ``curves/success_rate``,
``curves/goal_reward``, ``curves/action_std`` (normalised action units), ``curves/approx_kl``;
under ADR (:mod:`toolimit.learn.adr`) the goal box bounds ``adr/x_low``, ``adr/x_high``,
``adr/y_low``, ``adr/y_high`` (world frame, m).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import rerun as rr

from toolimit.viz.rerun_file import recording_file

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
