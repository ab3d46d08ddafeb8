"""How a learnt scythe policy cuts, and how much of its failure is the cut test's 240 Hz sampling.

The authors' cut rule (``toolimit.scenes.scythe_cut``) is tested at the scene's sub-steps, 240 Hz
as in their code: a stalk is cut at a sampled instant where the edge is within 2 cm of it and
approaching it fast enough (velocity times offset above 0.02 m^2/s, 1 m/s at 2 cm). An edge that
approaches a stalk at just over 1 m/s meets the rule only in a thin slice of its path, which the
samples can step over. This script rolls a policy out (deterministic, ``--episodes`` episodes from
``--seed``), keeps the tool pose of every control step, and tests the same motion (constant
velocity between control poses, as the scene moves the tool) at the scene's 10 sub-steps and at
``--fine``. It prints and writes (``--out``, JSON):

- stalks cut and success at both rates (the 10-sub-step replay must equal the scene's own count);
- the stalks left uncut, by where they stood in the patch (x along its 0.4 m length, y along its
  0.1 m width, m from its centre), against all stalks;
- the success of the episodes with no stalk within ``--end-zone`` of either end of the patch's
  length, and of the others (a draw that does not reach the ends fails only where a stalk stands
  there);
- for each control step where stalks fall: how many, the edge centre's median velocity along the
  edge normal (the snath, towards the hands: the rule's approach) and along the blade, the
  normal's elevation above horizontal (the rule allows 30 degrees) and the edge's height;
- the commit and the command that made it.

About 10 s on one core for 200 episodes.

    python benchmarks/scythe_cut_sampling.py --policy runs/scythe_03/learning --out benchmarks/results/scythe_cut_sampling.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from toolimit.learn.simulator import TaskSimulator
from toolimit.learn.training import load_policy
from toolimit.scenes.spatial.scythe import SpatialScytheScene
from toolimit.scenes.spatial.tool_motion import interpolate_poses

from provenance import command, commit

#: Bins of the uncut stalks' patch coordinates: along the length (x) and the width (y).
X_BINS, Y_BINS = 8, 4


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policy", type=Path, required=True, help="a learnt scythe policy's folder (toolimit learn)")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--seed", type=int, default=5000)
    parser.add_argument("--fine", type=int, default=100, help="sub-steps per control step of the fine test")
    parser.add_argument("--end-zone", type=float, default=0.035, help="m from either end of the patch's length")
    parser.add_argument("--out", type=Path, required=True, help="JSON file written")
    args = parser.parse_args()
    try:
        model, task = load_policy(args.policy)
    except FileNotFoundError as error:
        parser.error(str(error))
    simulator = TaskSimulator(task, batch_size=args.episodes)
    scene = simulator.scene
    if not isinstance(scene, SpatialScytheScene):
        parser.error(f"{args.policy}: not a 3D scythe policy")
    observation = simulator.reset(np.random.default_rng(args.seed))
    positions, rotations = [], []  # the tool pose after each control step: (B, 3) m, (B, 3, 3) world from tool
    while not simulator.done:
        action, _ = model.predict(observation, deterministic=True)
        observation, _, _ = simulator.step(action)
        position, rotation = simulator.robot.tool_poses(simulator.q, task.base)
        positions.append(position)
        rotations.append(rotation)
    cut, stalks, patch = scene.cut.copy(), scene.stalks_xy, scene.grass_position
    rule, dt = scene.rule, task.control_dt

    def first_cut_step(substeps: int) -> np.ndarray:
        """(B, N) the control step (from 0, the tool's placement) of each stalk's first cut, -1 if none."""
        first = np.full(cut.shape, -1)
        fractions = np.arange(substeps + 1) / substeps
        for k in range(1, len(positions)):
            moving = interpolate_poses(positions[k - 1], rotations[k - 1], positions[k], rotations[k], fractions)
            cuts = rule.cuts(*moving, stalks, dt / substeps).any(axis=0)
            first = np.where(cuts & (first < 0), k, first)
        return first

    coarse, fine = first_cut_step(scene.substeps) >= 0, first_cut_step(args.fine)
    fine_cut = fine >= 0
    assert np.array_equal(coarse, cut), "the replay at the scene's sub-steps must cut what the scene cut"
    in_patch = stalks - patch[:, None, :2]  # (B, N, 2) m from the patch's centre
    half_length, half_width = np.array(scene.patch_size) / 2
    x_range, y_range = (-half_length, half_length), (-half_width, half_width)
    near_ends = (np.abs(in_patch[..., 0]) > half_length - args.end_zone).any(axis=1)  # (B,)
    success = coarse.all(axis=1)
    rows = []
    for k in sorted(set(fine[fine_cut].tolist())):
        edge = [
            p + np.einsum("bij,j->bi", r, rule.edge.mean(axis=0))
            for p, r in ((positions[k - 1], rotations[k - 1]), (positions[k], rotations[k]))
        ]
        velocity = (edge[1] - edge[0]) / dt  # (B, 3) m/s, the edge centre's
        normal = np.einsum("bij,j->bi", rotations[k], rule.normal)
        blade = np.einsum("bij,j->bi", rotations[k], (rule.edge[1] - rule.edge[0]) / rule.blade_length)
        rows.append(
            {
                "control_step": k,
                "stalks_falling_fine": int(np.sum(fine == k)),
                "edge_velocity_along_normal_m_s": float(np.median(np.sum(velocity * normal, axis=1))),
                "edge_velocity_along_blade_m_s": float(np.median(np.abs(np.sum(velocity * blade, axis=1)))),
                "normal_elevation_deg": float(np.median(np.degrees(np.arcsin(np.clip(normal[:, 2], -1, 1))))),
                "edge_height_m": float(np.median(edge[1][:, 2])),
            }
        )
    record = {
        "commit": commit(short=True),
        "command": command(),
        "policy": str(args.policy),
        "episodes": args.episodes,
        "seed": args.seed,
        "substeps": scene.substeps,
        "fine_substeps": args.fine,
        "stalks_cut_mean": float(coarse.sum(axis=1).mean()),
        "success_rate": float(success.mean()),
        "stalks_cut_mean_fine": float(fine_cut.sum(axis=1).mean()),
        "success_rate_fine": float(fine_cut.all(axis=1).mean()),
        "uncut": int((~coarse).sum()),
        "uncut_cut_by_fine": int((~coarse & fine_cut).sum()),
        "uncut_by_patch_x": np.histogram(in_patch[~coarse][:, 0], X_BINS, x_range)[0].tolist(),
        "all_by_patch_x": np.histogram(in_patch[..., 0], X_BINS, x_range)[0].tolist(),
        "uncut_by_patch_y": np.histogram(in_patch[~coarse][:, 1], Y_BINS, y_range)[0].tolist(),
        "all_by_patch_y": np.histogram(in_patch[..., 1], Y_BINS, y_range)[0].tolist(),
        "end_zone_m": args.end_zone,
        "episodes_no_stalk_in_end_zones": int((~near_ends).sum()),
        "success_no_stalk_in_end_zones": float(success[~near_ends].mean()) if (~near_ends).any() else None,
        "success_a_stalk_in_end_zones": float(success[near_ends].mean()) if near_ends.any() else None,
        "cutting_steps": rows,
    }
    print(
        f"{args.episodes} episodes: at {scene.substeps} sub-steps {record['stalks_cut_mean']:.2f} stalks, success "
        f"{record['success_rate']:.2f}; at {args.fine}: {record['stalks_cut_mean_fine']:.2f}, "
        f"{record['success_rate_fine']:.2f} ({record['uncut_cut_by_fine']} of the {record['uncut']} uncut stalks)"
    )
    print(
        f"uncut by patch x ({X_BINS} bins over the length): {record['uncut_by_patch_x']} of {record['all_by_patch_x']}"
    )
    print(
        f"uncut by patch y ({Y_BINS} bins over the width): {record['uncut_by_patch_y']} of {record['all_by_patch_y']}"
    )
    print(
        f"no stalk within {args.end_zone} m of either end: {record['episodes_no_stalk_in_end_zones']} episodes, "
        f"success {record['success_no_stalk_in_end_zones']}; the others: {record['success_a_stalk_in_end_zones']}"
    )
    for row in rows:
        print(
            f"step {row['control_step']}: {row['stalks_falling_fine']} stalks; edge velocity along the normal "
            f"{row['edge_velocity_along_normal_m_s']:.2f} m/s, along the blade {row['edge_velocity_along_blade_m_s']:.2f}; "
            f"normal {row['normal_elevation_deg']:.0f} deg above horizontal; edge {row['edge_height_m']:.3f} m high"
        )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
