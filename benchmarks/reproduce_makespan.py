"""The full preset's makespan for several training seeds, on one node and on N Ray nodes.

Reads the per-cell ``wall_time_s`` of a full reproduction (``--results``, by default
benchmarks/results/reproduce/results.json, either layout; with several seeds, the first's), the
cells it lacks from ``--fill-from`` (e.g. the baselines of another figure, said in the output), and
takes every seed to do the same work. An experiment's preparation (its alignment and robot
selection) is read from ``--preparations``, a reproduction's seed folder
(``<experiment>/method/run.json``, its stage times), where given, else ``--prep-s``. Two schedules:

- one node, ``toolimit reproduce --seed 0,1,2 --jobs J``: each (seed, experiment) one child, in
  the preset's order, seed after seed in one queue, each started on the first of J slots to free;
  a child's time is its experiment's cells' times added up (the final cell's holds the whole
  ``toolimit run``: the alignment, the selection, the learning);
- N Ray nodes of ``cpus`` CPUs: ``toolimit reproduce --ray``'s tasks on N x cpus one-CPU slots,
  longest first among those ready (LPT list scheduling): per experiment a preparation (alignment
  and robot selection, which results.json does not hold apart; it is inside the final cell's
  time), then its learning runs, released when the preparation ends: the method's
  (the final cell's time less the preparation) and each baseline's. Once with the seeds one after
  another (one command: it runs its seeds in turn) and once all at once (one command per seed,
  started side by side), with the two lower bounds of the latter: the longest single run with its
  preparation, and the total work divided by the slots.

The cells' times were measured two or three runs at a time on two cores (docs/results/paper_figure.md, "The paper's
experiments"), not one at a time on an idle machine: a run alone on its own core is, if anything,
faster, so the figures are upper estimates for nodes as fast as this machine's cores. The domain
randomisation runs (``toolimit learn --adr``) are one learning run each, which no cluster splits:
they are listed apart with their own wall time.

    python benchmarks/reproduce_makespan.py [--seeds 3] [--jobs 2] [--nodes 8] [--cpus 2] [--prep-s 100]
        [--results R.json] [--fill-from R.json] [--preparations runs/figure/seed_0]
    python benchmarks/reproduce_makespan.py --each-seed --results R.json [--preparations runs/figure]

``--each-seed`` takes every seed's own cells and preparations instead of the first seed's times
for all: the measured work of a reproduction whose seeds are all in.
"""

from __future__ import annotations

import argparse
import heapq
import json
from collections.abc import Callable
from pathlib import Path

from toolimit.experiments.report import read_results
from toolimit.experiments.reproduce import preset

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "benchmarks" / "results" / "reproduce" / "results.json"
ADR_RUNS = tuple(REPO / "benchmarks" / "results" / f"adr_spade3d_box_offset_seed{seed}" for seed in (0, 1, 2))
#: The Panda spade_00 run's alignment and trajectory stages, 96 s (notebook 06, docs/learning.md,
#: its run.json: 12.7 s + 83.2 s), rounded up: the preparation of a 3D experiment.
PREPARATION_S = 100.0


def tasks(cells: list[dict], preparation_s: Callable[[dict], float]) -> list[tuple[str, str, float]]:
    """(experiment, task, seconds) of every task: each experiment's preparation (``preparation_s``
    of one of its cells) and learning runs."""
    experiments = sorted({(c["tool"], c["robot"], c["demo"]) for c in cells})
    found = []
    for experiment in experiments:
        name = "-".join(experiment)
        ours = [cell for cell in cells if (cell["tool"], cell["robot"], cell["demo"]) == experiment]
        preparation = preparation_s(ours[0])
        found.append((name, "prepare", preparation))
        for cell in ours:
            if cell["wall_time_s"] <= 0:
                continue  # the tool alone and the trajectory: measured in the preparation
            seconds = cell["wall_time_s"] - preparation if cell["method"] == "final" else cell["wall_time_s"]
            found.append((name, cell["method"], seconds))
    return found


def measured_preparation(folder: Path | None, default_s: float) -> Callable[[dict], float]:
    """A cell's experiment's alignment and trajectory stage times from ``folder``/<experiment>/method/run.json
    (a reproduction's seed folder), ``default_s`` where it is not there."""

    def seconds(cell: dict) -> float:
        if folder is None:
            return default_s
        run = folder / "-".join((cell["tool"], cell["world"], cell["robot"], cell["demo"])) / "method" / "run.json"
        if not run.is_file():
            return default_s
        stages = json.loads(run.read_text())["stage_times_s"]
        return float(stages.get("alignment", 0.0) + stages.get("trajectory", 0.0))

    return seconds


def seed_cells(path: Path) -> dict[int, list[dict]]:
    """Every seed of a results.json with its cells' records, in the seeds' order."""
    _, runs = read_results(json.loads(path.read_text()))
    return {seed: [cell.record() for cell in runs[seed]] for seed in sorted(runs)}


def first_seed_cells(path: Path) -> tuple[int, list[dict]]:
    """The first seed of a results.json and its cells' records."""
    return next(iter(seed_cells(path).items()))


def each_seed(args: argparse.Namespace) -> None:
    """The schedules of every seed's own measured work (``--each-seed``): ``--preparations`` is the
    reproduction's folder, holding each seed's ``seed_S/``."""
    by_seed = seed_cells(args.results)
    works: dict[int, list[tuple[str, str, float]]] = {}
    for seed, cells in by_seed.items():
        folder = args.preparations / f"seed_{seed}" if args.preparations is not None else None
        works[seed] = tasks(cells, measured_preparation(folder, args.prep_s))
        print(f"seed {seed}: {len(cells)} cells, {sum(w[2] for w in works[seed]) / 3600:.2f} h of work")
    total = sum(w[2] for work in works.values() for w in work)
    local = [seconds for cells in by_seed.values() for seconds in children(cells)]
    print(
        f"{len(by_seed)} seeds: {total / 3600:.2f} h; one node, --jobs {args.jobs}: {in_order(local, args.jobs) / 60:.0f} min"
    )
    every = for_seeds(works)
    for nodes in sorted({1, 2, 4, args.nodes}):
        slots = nodes * args.cpus
        print(f"{nodes} Ray node(s) x {args.cpus} CPUs, the seeds side by side: {makespan(every, slots) / 60:.1f} min")


def for_seeds(works: dict[int, list[tuple[str, str, float]]]) -> list[tuple[str, str, float]]:
    """Every seed's ``work`` in one list, each experiment named with its seed."""
    return [(f"seed_{seed}/{name}", task, seconds) for seed, work in works.items() for name, task, seconds in work]


def children(cells: list[dict]) -> list[float]:
    """Each experiment's time as one child of ``toolimit reproduce --jobs``: its cells' times added
    up, in the full preset's order."""
    seconds: dict[tuple[str, str, str], float] = {}
    for cell in cells:
        key = (cell["tool"], cell["robot"], cell["demo"])
        seconds[key] = seconds.get(key, 0.0) + cell["wall_time_s"]
    order = [(e.tool, e.robot, e.demo.stem) for e in preset("full").experiments]
    return [seconds[key] for key in sorted(seconds, key=lambda key: order.index(key) if key in order else len(order))]


def in_order(durations: list[float], slots: int) -> float:
    """End of the last of ``durations`` run in their order, each on the first of ``slots`` to free."""
    free = [0.0] * slots
    for seconds in durations:
        heapq.heappush(free, heapq.heappop(free) + seconds)
    return max(free)


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
    parser.add_argument("--seeds", type=int, default=3, help="training seeds, each the same work")
    parser.add_argument("--jobs", type=int, default=2, help="children at a time on one node")
    parser.add_argument("--nodes", type=int, default=8)
    parser.add_argument("--cpus", type=int, default=2, help="CPUs per node (one learning run each)")
    parser.add_argument("--prep-s", type=float, default=PREPARATION_S, help="an experiment's preparation, s")
    parser.add_argument("--results", type=Path, default=RESULTS)
    parser.add_argument("--fill-from", type=Path, help="a results.json whose cells fill those --results lacks")
    parser.add_argument(
        "--preparations", type=Path, help="a reproduction's seed folder with each experiment's run.json"
    )
    parser.add_argument(
        "--each-seed",
        action="store_true",
        help="every seed of --results with its own measured work (--preparations: the reproduction's folder)",
    )
    args = parser.parse_args()
    if args.each_seed:
        each_seed(args)
        return
    seed, cells = first_seed_cells(args.results)
    print(f"{_shown(args.results)}: seed {seed}'s {len(cells)} cells")
    if args.fill_from is not None:
        key = ("tool", "world", "robot", "demo", "method")
        have = {tuple(cell[k] for k in key) for cell in cells}
        other_seed, others = first_seed_cells(args.fill_from)
        filled = [cell for cell in others if tuple(cell[k] for k in key) not in have]
        cells += filled
        print(f"  and {len(filled)} cells it lacks from {_shown(args.fill_from)} (seed {other_seed})")
    work = tasks(cells, measured_preparation(args.preparations, args.prep_s))
    total = sum(seconds for _, _, seconds in work)
    preparations = [seconds for _, task, seconds in work if task == "prepare"]
    print(
        f"{len(work)} tasks ({len(preparations)} preparations, {sum(preparations) / 3600:.2f} h: "
        f"{'measured in ' + _shown(args.preparations) if args.preparations else f'{args.prep_s:.0f} s each'}), "
        f"{total / 3600:.2f} h of work a seed; {args.seeds} seeds: {args.seeds * total / 3600:.2f} h"
    )
    local = children(cells)
    print(
        f"one node, --jobs {args.jobs}: one seed {in_order(local, args.jobs) / 60:.0f} min, "
        f"{args.seeds} seeds {in_order(local * args.seeds, args.jobs) / 60:.0f} min"
    )
    every = for_seeds({seed: work for seed in range(args.seeds)})
    for nodes in sorted({1, 2, 4, args.nodes}):
        slots = nodes * args.cpus
        print(
            f"{nodes} Ray node(s) x {args.cpus} CPUs: one seed {makespan(work, slots) / 60:.1f} min; {args.seeds} seeds "
            f"one after another {args.seeds * makespan(work, slots) / 60:.1f} min, side by side "
            f"{makespan(every, slots) / 60:.1f} min"
        )
    preparation_of = {name: seconds for name, task, seconds in work if task == "prepare"}
    longest = max(work, key=lambda w: w[2] + (preparation_of[w[0]] if w[1] != "prepare" else 0.0))
    print(
        f"bounds from below, {args.seeds} seeds side by side on {args.nodes} x {args.cpus} CPUs: the longest single "
        f"run, {longest[0]} {longest[1]}, {(longest[2] + preparation_of[longest[0]]) / 60:.1f} min with its preparation; the work "
        f"per slot, {args.seeds * total / (args.nodes * args.cpus) / 60:.1f} min"
    )
    print("apart (one learning run each, not split by a cluster):")
    for folder in ADR_RUNS:
        record = json.loads((folder / "learning.json").read_text())
        print(f"  {folder.relative_to(REPO)}: {record['env_steps']:,} env steps, {record['wall_time_s'] / 60:.1f} min")


def _shown(path: Path) -> str:
    return str(path.relative_to(REPO) if path.is_absolute() and path.is_relative_to(REPO) else path)


if __name__ == "__main__":
    main()
