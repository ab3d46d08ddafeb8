"""Benchmark of ``toolimit reproduce --ray``: the quick preset locally and on a private Ray, same cells?

Runs ``toolimit reproduce --preset quick`` twice into fresh folders, in this order: locally
(``--jobs 1``, the default) and with ``--ray`` (a private Ray of this machine's cores, started and
stopped by the command: its start-up and shut-down are in the figure). Prints each wall time, their
ratio (the overhead of Ray on one machine, and of running each learning run as its own task) and
whether every cell's per-episode goal rewards agree (to 1e-6) and its success rates are equal.
Run it alone on the machine (``python benchmarks/reproduce_on_ray.py``):
the two runs share the cores with nothing else.

    python benchmarks/reproduce_on_ray.py [--out /tmp/reproduce_on_ray]
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def timed_reproduce(out: Path, *extra: str) -> float:
    """Seconds one ``toolimit reproduce --preset quick`` into ``out`` took (a fresh folder)."""
    shutil.rmtree(out, ignore_errors=True)
    command = [sys.executable, "-m", "toolimit", "reproduce", "--preset", "quick", "--out", str(out), "--quiet", *extra]
    started = time.perf_counter()
    subprocess.run(command, cwd=REPO, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - started


def cells(out: Path) -> dict[str, dict]:
    """The cells of ``out/results.json`` by method."""
    return {cell["method"]: cell for cell in json.loads((out / "results.json").read_text())["cells"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("/tmp/reproduce_on_ray"))
    args = parser.parse_args()
    local_s = timed_reproduce(args.out / "local")
    ray_s = timed_reproduce(args.out / "ray", "--ray")
    local, on_ray = cells(args.out / "local"), cells(args.out / "ray")
    same = local.keys() == on_ray.keys() and all(
        len(local[m]["goal_rewards"]) == len(on_ray[m]["goal_rewards"])
        and all(abs(a - b) <= 1e-6 for a, b in zip(local[m]["goal_rewards"], on_ray[m]["goal_rewards"]))
        and local[m]["success_rate"] == on_ray[m]["success_rate"]
        for m in local
    )
    print(f"quick preset, local (--jobs 1): {local_s:.1f} s")
    print(f"quick preset, --ray (private Ray, start-up included): {ray_s:.1f} s ({ray_s / local_s:.2f} x local)")
    print(f"cells: {len(local)} local, {len(on_ray)} on Ray; the same goal rewards and success rates: {same}")
    for method in local:
        print(
            f"  {method:10s} local {local[method]['goal_reward']:6.2f} ({local[method]['success_rate']:.2f})"
            f"  ray {on_ray[method]['goal_reward']:6.2f} ({on_ray[method]['success_rate']:.2f})"
        )


if __name__ == "__main__":
    main()
