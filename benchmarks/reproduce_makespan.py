"""The full preset's makespan on N Ray nodes, by list scheduling of the measured cells.

Reads the per-cell ``wall_time_s`` of a full reproduction (benchmarks/results/reproduce/results.json)
and schedules ``toolimit reproduce --ray``'s tasks on ``nodes`` x ``cpus`` one-CPU slots, longest
first among those ready (LPT list scheduling): per experiment a preparation (alignment and robot
selection: ``--prep-s`` seconds, which results.json does not hold apart; it is inside the final
cell's time), then its learning runs, released when the preparation ends: the method's (the final
cell's time less the preparation) and each baseline's. Prints the makespan for 1, 2, 4 and
``nodes`` nodes and its two lower bounds: the longest single run with its preparation (whatever
the number of nodes) and the total work divided by the slots.

The cells' times were measured two or three runs at a time on two cores (docs/results/paper_figure.md, "The paper's
experiments"), not one at a time on an idle machine: a run alone on its own core is, if anything,
faster, so the figure is an upper estimate for nodes as fast as this machine's cores. The domain
randomisation runs (``toolimit learn --adr``) are one learning run each, which no cluster splits:
they are listed apart with their own wall time.

    python benchmarks/reproduce_makespan.py [--nodes 8] [--cpus 2] [--prep-s 100]
"""

from __future__ import annotations

import argparse
import heapq
import json
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "benchmarks" / "results" / "reproduce" / "results.json"
ADR_RUNS = tuple(REPO / "benchmarks" / "results" / f"adr_spade3d_box_offset_seed{seed}" for seed in (0, 1, 2))
#: The Panda spade_00 run's alignment and trajectory stages, 96 s (notebook 06, docs/learning.md,
#: its run.json: 12.7 s + 83.2 s), rounded up: the preparation of a 3D experiment.
PREPARATION_S = 100.0


def tasks(cells: list[dict], preparation_s: float) -> list[tuple[str, str, float]]:
    """(experiment, task, seconds) of every task: each experiment's preparation and learning runs."""
    experiments = sorted({(c["tool"], c["robot"], c["demo"]) for c in cells})
    found = []
    for experiment in experiments:
        name = "-".join(experiment)
        found.append((name, "prepare", preparation_s))
        for cell in cells:
            if (cell["tool"], cell["robot"], cell["demo"]) != experiment or cell["wall_time_s"] <= 0:
                continue  # the tool alone and the trajectory: measured in the preparation
            seconds = cell["wall_time_s"] - preparation_s if cell["method"] == "final" else cell["wall_time_s"]
            found.append((name, cell["method"], seconds))
    return found


def makespan(work: list[tuple[str, str, float]], slots: int) -> float:
    """End of the last task when ``slots`` one-CPU slots run ``work`` by LPT list scheduling, each
    experiment's learning runs released when its preparation ends."""
    free = [0.0] * slots  # when each slot is free (a heap)
    prepared: dict[str, float] = {}
    for name, _, seconds in sorted((w for w in work if w[1] == "prepare"), key=lambda w: -w[2]):
        start = heapq.heappop(free)
        prepared[name] = start + seconds
        heapq.heappush(free, start + seconds)
    ready = sorted((w for w in work if w[1] != "prepare"), key=lambda w: (prepared[w[0]], -w[2]))
    end = max(prepared.values(), default=0.0)
    while ready:
        slot_free = heapq.heappop(free)
        released = [w for w in ready if prepared[w[0]] <= slot_free] or [min(ready, key=lambda w: prepared[w[0]])]
        chosen = max(released, key=lambda w: w[2])  # the longest of the tasks ready when the slot frees
        ready.remove(chosen)
        finish = max(slot_free, prepared[chosen[0]]) + chosen[2]
        end = max(end, finish)
        heapq.heappush(free, finish)
    return end


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=8)
    parser.add_argument("--cpus", type=int, default=2, help="CPUs per node (one learning run each)")
    parser.add_argument("--prep-s", type=float, default=PREPARATION_S, help="an experiment's preparation, s")
    parser.add_argument("--results", type=Path, default=RESULTS)
    args = parser.parse_args()
    cells = json.loads(args.results.read_text())["cells"]
    work = tasks(cells, args.prep_s)
    slots = args.nodes * args.cpus
    longest = max(work, key=lambda w: w[2] + (args.prep_s if w[1] != "prepare" else 0.0))
    total = sum(seconds for _, _, seconds in work)
    print(
        f"{args.results.relative_to(REPO) if args.results.is_relative_to(REPO) else args.results}: {len(cells)} cells, "
        f"{len(work)} tasks ({sum(w[1] == 'prepare' for w in work)} preparations of {args.prep_s:.0f} s)"
    )
    print(f"one slot: {total / 3600:.2f} h of work")
    for nodes in sorted({1, 2, 4, args.nodes}):
        span = makespan(work, nodes * args.cpus)
        print(f"{nodes} node(s) x {args.cpus} CPUs: makespan {span / 60:.1f} min")
    print(
        f"bounds from below on {args.nodes} x {args.cpus} CPUs: the longest single run, {longest[0]} {longest[1]}, "
        f"{(longest[2] + args.prep_s) / 60:.1f} min with its preparation; the work per slot, {total / slots / 60:.1f} min"
    )
    print("apart (one learning run each, not split by a cluster):")
    for folder in ADR_RUNS:
        record = json.loads((folder / "learning.json").read_text())
        print(f"  {folder.relative_to(REPO)}: {record['env_steps']:,} env steps, {record['wall_time_s'] / 60:.1f} min")


if __name__ == "__main__":
    main()
