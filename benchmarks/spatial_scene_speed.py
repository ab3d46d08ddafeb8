"""Speed of the 3D scenes on one core: control steps per second and one alignment sample.

Run: ``python benchmarks/spatial_scene_speed.py [--repeats 3]``. Prints, for the spade world with
its default 200 spheres (and 50 for comparison) at B = 1 and B = 16, instance control steps per
CPU second (24 Hz steps, each 10 physics sub-steps; B instances stepped together count B) over a
scripted scoop-carry-tip motion, and the time of one alignment sample: 10 replays of a 92-frame
demonstration as one B = 10 batch (reset + 92 steps + reward). The demonstration is the paper
authors' aligned spade trajectory (``../shared/data/video_demos``) when present, else the first 92
frames of the scripted scoop. The hammer and scythe worlds are timed on a generic circular sweep.

Every figure is the minimum over ``--repeats`` runs, as wall time and as this process's CPU time
(the machine may be shared: the minimum is the least disturbed run, and CPU time excludes waiting).
The first run compiles the particle kernels if numba's cache is cold; a warm-up replay before the
timings keeps that out of the figures. Targets (issue 9): >= 2,000 instance steps per CPU second at
200 spheres, B = 16, on one core (learning steps this world a million times), and under 1 s per
10-replay sample. Last, the same motions are replayed untimed to print the deepest penetration of a
sphere into the ground or a wall over every step (the solver keeps it at 0).
"""

from __future__ import annotations

import os

for _name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import functools  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from toolimit.demos.npz_format import original_scene_params  # noqa: E402
from toolimit.scenes import make_scene  # noqa: E402
from toolimit.scenes.spatial.scoop import scripted_scoop  # noqa: E402
from toolimit.scenes.spatial.spade import SpatialSpadeScene  # noqa: E402
from toolimit.tools import ToolPose, tool_poses  # noqa: E402
from toolimit.trajopt import from_original_spade_tip, load_pose_targets  # noqa: E402

SHARED = Path(os.environ.get("TOOLIMIT_SHARED", Path(__file__).resolve().parents[2] / "shared"))
REAL_SPADE = SHARED / "data" / "video_demos" / "spade_video1_aligned.npz"
SCOOP_PARAMS = {"sand_position": np.zeros(3), "sand_yaw": 0.0, "goal_position": np.array([0.0, 0.9, 0.0])}


def real_spade_demo() -> tuple[ToolPose, dict] | None:
    """The authors' aligned spade poses as tool-frame poses, with their scene parameters, or None.

    The recording's tip frame is converted by :func:`toolimit.trajopt.from_original_spade_tip`.
    """
    if not REAL_SPADE.is_file():
        return None
    data = np.load(REAL_SPADE)
    targets = from_original_spade_tip(load_pose_targets(REAL_SPADE))
    params = original_scene_params(dict(data))
    return ToolPose(targets.positions, targets.rotations), params


def step_through(scene, motion: ToolPose) -> None:
    """Step ``scene`` through the poses ``motion`` ((T, 3), (T, 3, 3), world frame)."""
    for position, rotation in zip(motion.position, motion.rotation):
        scene.step(ToolPose(position, rotation))


def replay(scene, params: dict, motion: ToolPose, batch_size: int, seed: int = 0) -> np.ndarray:
    """Reset, step through ``motion`` and return the goal reward (B,)."""
    scene.reset(params, np.random.default_rng(seed), batch_size)
    step_through(scene, motion)
    return scene.goal_reward()


def best_of(repeats: int, run) -> tuple[float, float, object]:
    """Minimum wall time and minimum CPU time (s) of ``run()`` over ``repeats`` runs, and its last result.

    CPU time (this process only) is less disturbed than wall time by other jobs on a shared machine.
    """
    walls, cpus, result = [], [], None
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        result = run()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return min(walls), min(cpus), result


def circular_sweep(center: np.ndarray, n_frames: int = 92) -> ToolPose:
    """A generic tool motion: the head circles ``center`` at 0.3 m radius, 5 cm up, handle raised."""
    angle = np.linspace(0.0, 2.0 * np.pi, n_frames)
    head = center + np.stack([0.3 * np.cos(angle), 0.3 * np.sin(angle), np.full(n_frames, 0.05)], -1)
    handle = head + np.array([0.0, 0.0, 0.5]) - 0.2 * np.stack([np.cos(angle), np.sin(angle), 0 * angle], -1)
    return tool_poses(head, handle, roll=angle)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per figure; the minimum is reported")
    args = parser.parse_args()
    scoop = scripted_scoop(SCOOP_PARAMS)
    replay(SpatialSpadeScene(), SCOOP_PARAMS, ToolPose(scoop.position[:5], scoop.rotation[:5]), 1)  # warm-up
    print(f"spade world, scripted scoop-carry-tip ({len(scoop.position)} control steps), min of {args.repeats} runs:")
    for n_spheres in (200, 50):
        for batch in (1, 16):
            scene = SpatialSpadeScene(n_spheres=n_spheres)
            wall, cpu = [], []
            for _ in range(args.repeats):
                scene.reset(SCOOP_PARAMS, np.random.default_rng(0), batch)  # not timed
                seconds, cpu_seconds, _ = best_of(1, functools.partial(step_through, scene, scoop))
                wall.append(seconds)
                cpu.append(cpu_seconds)
            steps = len(scoop.position) * batch
            print(
                f"  N={n_spheres:3d} B={batch:2d}: {steps / min(cpu):6.0f} instance steps per CPU s "
                f"({steps / min(wall):6.0f} per wall s; goal reward mean {scene.goal_reward().mean():.1f})"
            )

    demos = [("scripted scoop, first 92 frames", ToolPose(scoop.position[:92], scoop.rotation[:92]), SCOOP_PARAMS)]
    real = real_spade_demo()
    if real is None:
        print(f"  (real spade demonstration not found at {REAL_SPADE}: skipped)")
    else:
        demos.insert(0, ("authors' aligned spade video 1 (92 frames)", real[0], real[1]))
    print("alignment sample = 10 replays as one B = 10 batch (reset + 92 steps + reward), 200 spheres:")
    for label, motion, params in demos:
        scene = SpatialSpadeScene()
        seconds, cpu_seconds, reward = best_of(args.repeats, functools.partial(replay, scene, params, motion, 10))
        print(f"  {label}: {seconds:.2f} s wall, {cpu_seconds:.2f} s CPU (mean goal reward {np.mean(reward):.1f})")
    print("static surfaces win: deepest sphere penetration into the ground or a wall over every step (B = 10):")
    for label, motion, params in demos + [("scripted scoop, whole", scoop, SCOOP_PARAMS)]:
        scene = SpatialSpadeScene()
        scene.reset(params, np.random.default_rng(0), 10)
        deepest = 0.0
        for position, rotation in zip(motion.position, motion.rotation):
            scene.step(ToolPose(position, rotation))
            deepest = max(deepest, float(scene.static_penetration().max()))
        print(f"  {label}: {1000 * deepest:.3f} mm")

    for tool in ("hammer", "scythe"):
        try:
            scene = make_scene(tool, "3d")
        except (ImportError, AttributeError) as error:
            print(f"{tool} 3d world: not available ({error}); skipped")
            continue
        params = {}
        for spec in scene.parameters:
            if spec.kind == "position":
                point = (np.asarray(spec.low, dtype=float) + np.asarray(spec.high, dtype=float)) / 2
                params[spec.name] = point * np.array([1.0, 1.0, 0.0 if spec.on_ground else 1.0])
            else:
                params[spec.name] = (spec.low + spec.high) / 2
        reason = scene.invalid_reason(params)
        if reason is not None:
            print(f"{tool} 3d world: the mid-range parameters are invalid ({reason}); skipped")
            continue
        first_position = next((v for v in params.values() if np.ndim(v) == 1), np.zeros(3))
        motion = circular_sweep(np.asarray(first_position, dtype=float) * np.array([1.0, 1.0, 0.0]))
        for batch in (1, 10):
            seconds, cpu_seconds, _ = best_of(args.repeats, functools.partial(replay, scene, params, motion, batch))
            print(
                f"{tool} 3d world, circular sweep ({len(motion.position)} steps incl. reset), B={batch:2d}: "
                f"{seconds:.3f} s wall, {cpu_seconds:.3f} s CPU = "
                f"{len(motion.position) / seconds:7.1f} control steps/s"
            )


if __name__ == "__main__":
    main()
