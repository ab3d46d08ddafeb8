"""Export retiming: exported duration, closeness to the optimised samples and CPU time.

For a trajectory optimised by ``toolimit trajopt`` (DIR/trajectory.npz), retimes its joint path
within the Panda's published limits for several ``subdivisions`` (pieces per step of the control
polygon: more stays closer to the samples at sharp turns and turns there more slowly), at the
optimised timing and, to show how far the retiming slows a too-fast path down, with the same samples
played 5x faster. For each: exported duration against the optimised one, the largest gap between
the exported path and the optimised samples (rad), the peak |value| / limit of velocity,
acceleration and jerk measured by finite differences of the 1 kHz positions, and the CPU time.
A uniform slow-down of the same B-spline (one factor for the whole motion) is printed for
comparison.

    python benchmarks/export_retiming.py --trajectory runs/panda [--out benchmarks/results/export_retiming.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from toolimit.deploy import load_trajectory, published_limits, retime
from toolimit.deploy.retime import DEGREE, _ratios, _spline

RATE_HZ = 1000.0


def uniform_duration(q: np.ndarray, dt: float, limits) -> float:
    """Duration of the same B-spline (one sample per control point) slowed down by one factor."""
    control = np.concatenate([np.repeat(q[:1], DEGREE - 1, axis=0), q, np.repeat(q[-1:], DEGREE - 1, axis=0)])
    spans = np.full(len(control) - DEGREE, dt)
    spline = _spline(control, spans)
    bounds = (limits.velocity, limits.acceleration, limits.jerk)
    factor = max(max(1.0, _ratios(spline, order, bound).max() ** (1.0 / order)) for order, bound in enumerate(bounds, 1))
    return float(spans.sum() * factor)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trajectory", type=Path, required=True, help="folder holding trajectory.npz (Panda)")
    parser.add_argument("--out", type=Path, default=None, help="also write the figures to this JSON file")
    args = parser.parse_args()
    trajectory = load_trajectory(args.trajectory)
    limits = published_limits("panda")
    rows = []
    for speed_up in (1.0, 5.0):
        dt = trajectory.dt / speed_up
        optimised = dt * (len(trajectory.q) - 1)
        uniform = uniform_duration(trajectory.q, dt, limits)
        for subdivisions in (1, 2, 4, 8, 16):
            started = time.process_time()
            path = retime(trajectory.q, dt, limits, subdivisions)
            cpu = time.process_time() - started
            position = path.sample(RATE_HZ).position
            peaks = {name: float((np.abs(np.diff(position, order, axis=0)) * RATE_HZ**order / bound).max())
                     for order, (name, bound) in enumerate(
                         (("velocity", limits.velocity), ("acceleration", limits.acceleration), ("jerk", limits.jerk)), 1)}
            row = {"speed_up": speed_up, "subdivisions": subdivisions, "optimised_s": optimised,
                   "exported_s": path.duration, "uniform_slow_down_s": uniform,
                   "path_deviation_rad": path.path_deviation, "cpu_s": cpu, "finite_difference_peaks": peaks}
            rows.append(row)
            print(f"samples x{speed_up:g} faster, subdivisions {subdivisions:2d}: {path.duration:6.2f} s exported for "
                  f"{optimised:6.2f} s optimised (uniform slow-down {uniform:6.2f} s), path within "
                  f"{path.path_deviation:.4f} rad, peaks v {peaks['velocity']:.3f} a {peaks['acceleration']:.3f} "
                  f"j {peaks['jerk']:.3f}, CPU {cpu * 1e3:.1f} ms")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps({"trajectory": str(args.trajectory), "rows": rows}, indent=2) + "\n")
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
