"""How often to test ADR's bounds: the bounds and the success at them, run by run, at equal PPO steps.

Each RUN is a ``toolimit learn --adr`` folder (finished or still running: the learning record, or
else the last checkpoint, holds the boundary tests; ``curve.jsonl`` the bounds and training
success per update). The runs should differ only in ``--adr-every``. For each, up to the first
``--at`` PPO steps (default: as far as the shortest run got), the script prints and saves:

* the boundary tests made, the decisions among them (push, pull, hold) and the share that pushed;
* the range reached (x, y, m) and its area as a share of the paper's 100 x 90 cm rectangle;
* the success of the boundary episodes over all tests and over the last ten;
* the training success (randomised boxes, stochastic policy) over the last 20 updates;
* the extra episodes the tests cost (one batch per test, per training episode), and a finished
  run's wall time (the runs share two cores with other jobs: the episode count is the firm cost).

A schedule is too slow when its runs push at nearly every decision (the bounds wait for tests,
not for the policy), too fast when most decisions hold or pull while the tests cost simulation.
``--pick`` states the choice this measurement makes (:func:`pick`), from the fastest and the slowest
schedule measured: while the tests limit the growth, pushes per PPO step scale as 1 / every, so the
longest period that still grows the bounds as fast as the fastest schedule did is
``every_slow * pushes_slow / pushes_fast`` (per PPO step), rounded and kept between the two; the
docs/domain_randomisation.md reads the figures. The measurement:

    toolimit learn --env toolimit/Spade3D-v0 --adr --preset toolimit --timesteps 1500000 \\
        --adr-every K --out runs/adr_everyK          # K = 2 and 10, seed 0
    python benchmarks/adr_schedule.py runs/adr_every2 runs/adr_every10 \\
        --json benchmarks/results/adr_schedule.json --pick
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from toolimit.artifacts import save_json
from toolimit.learn.adr import HALF_RANGE
from toolimit.learn.ppo import CHECKPOINT_STATE
from toolimit.learn.training import CURVE_JSONL, LEARNING_JSON

#: Updates of the training-success average and tests of the recent boundary success.
LAST_UPDATES = 20
LAST_TESTS = 10


def run_state(run: Path, every: int | None) -> tuple[list[dict[str, Any]], dict[str, Any], int]:
    """The curve's lines, the ADR record (or a running run's checkpoint state, with its tests) and
    the test period of a run folder (``every`` for a run still going: its checkpoint lacks it)."""
    curve = [json.loads(line) for line in (run / CURVE_JSONL).read_text().splitlines() if line.strip()]
    if (run / LEARNING_JSON).is_file():
        record = json.loads((run / LEARNING_JSON).read_text())
        return curve, record, int(record["config"]["adr_every"])
    if every is None:
        raise SystemExit(f"{run} is still running: give its --every")
    return curve, json.loads((run / CHECKPOINT_STATE).read_text()), every


def summary(run: Path, at: int | None, every: int | None = None) -> dict[str, Any]:
    """The figures of the module docstring for ``run`` up to ``at`` PPO steps (None: all)."""
    curve, record, every = run_state(run, every)
    tests = record["adr"]["tests"]
    per_update = curve[0]["env_steps"]
    lines = [line for line in curve if at is None or line["env_steps"] <= at]
    last_update = lines[-1]["env_steps"] // per_update
    made = [t for k, t in enumerate(tests) if (k + 1) * every < last_update]  # tests before the last update
    decided = [t for t in made if t.get("decision") is not None]
    count = {kind: sum(t["decision"] == kind for t in decided) for kind in ("push", "pull", "hold")}
    low, high = lines[-1]["adr_low"], lines[-1]["adr_high"]
    span = [h - lo for lo, h in zip(low, high, strict=True)]
    episodes = sum(t["episodes"] for t in made)
    recent = made[-LAST_TESTS:]
    return {
        "run": str(run),
        "every": every,
        "ppo_env_steps": lines[-1]["env_steps"],
        "updates": len(lines),
        "tests": len(made),
        "decisions": count,
        "push_share": count["push"] / len(decided) if decided else None,
        "range_m": span,
        "area_share": span[0] * span[1] / (4 * HALF_RANGE[0] * HALF_RANGE[1]),
        "boundary_success": sum(t["successes"] for t in made) / episodes if episodes else None,
        "boundary_success_last": (
            sum(t["successes"] for t in recent) / sum(t["episodes"] for t in recent) if recent else None
        ),
        "training_success_last": sum(line["success_rate"] for line in lines[-LAST_UPDATES:])
        / len(lines[-LAST_UPDATES:]),
        "test_episodes_per_training_episode": episodes / (len(lines) * made[0]["episodes"]) if made else 0.0,
        "wall_time_s": record.get("wall_time_s"),
    }


def pushes_per_million(row: dict[str, Any]) -> float:
    """Pushes per million PPO steps of a :func:`summary` row."""
    return row["decisions"]["push"] / row["ppo_env_steps"] * 1e6


def pick(rows: list[dict[str, Any]]) -> int:
    """The test period the measurement chooses (module docstring)."""
    fast = min(rows, key=lambda row: row["every"])
    slow = max(rows, key=lambda row: row["every"])
    if pushes_per_million(fast) <= 0.0:
        return int(slow["every"])
    matched = slow["every"] * pushes_per_million(slow) / pushes_per_million(fast)
    return int(min(max(round(matched), fast["every"]), slow["every"]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, help="toolimit learn --adr folders")
    parser.add_argument("--at", type=int, default=None, help="PPO steps to compare at (default: the shortest run's)")
    parser.add_argument("--every", type=int, default=None, help="the test period of runs still going")
    parser.add_argument("--json", type=Path, default=None, help="also save the figures here")
    parser.add_argument("--pick", action="store_true", help="print the chosen period last, alone on its line")
    args = parser.parse_args()
    at = args.at
    if at is None:
        at = min(run_state(run, args.every)[0][-1]["env_steps"] for run in args.runs)
    rows = [summary(run, at, args.every) for run in args.runs]
    for row in rows:
        decisions = row["decisions"]
        print(
            f"every {row['every']:3d}: {row['ppo_env_steps'] / 1e6:.2f} M steps, {row['tests']} tests, "
            f"{decisions['push']} push / {decisions['pull']} pull / {decisions['hold']} hold "
            f"(push share {row['push_share'] if row['push_share'] is None else round(row['push_share'], 2)}); "
            f"range {row['range_m'][0]:.2f} x {row['range_m'][1]:.2f} m ({row['area_share']:.0%} of the rectangle); "
            f"boundary success {row['boundary_success']:.2f} (last {LAST_TESTS} tests "
            f"{row['boundary_success_last']:.2f}); training success {row['training_success_last']:.2f}; "
            f"test episodes {row['test_episodes_per_training_episode']:.2f} per training episode; "
            f"{pushes_per_million(row):.1f} pushes per M steps"
        )
    chosen = pick(rows) if args.pick else None
    if args.json is not None:
        save_json(args.json, {"at_ppo_env_steps": at, "runs": rows, "picked_every": chosen})
    if chosen is not None:
        print(chosen)


if __name__ == "__main__":
    main()
