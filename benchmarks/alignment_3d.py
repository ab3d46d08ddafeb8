"""Benchmark of stage (ii) in the 3D worlds: alignment of the shipped and the real demonstrations.

Runs ``toolimit.align.search.align`` with world "3d" on the 15 shipped synthetic demos
(data/demos/{spade,hammer,scythe}_0{0..4}.npz, cleaned as ``toolimit align`` does) and on the
paper authors' real trajectories (../shared/data/video_demos: spade_video1_aligned.npz and
spade_example_aligned.npz in the spade world, hammer_video1_aligned.npz in the hammer world, loaded
with ``toolimit.demos.load_demo`` and used as they are). Each search tries at most ``--samples``
samples (the paper: 20,000) and stops at the first ``--candidates`` samples with a non-zero mean
goal reward. Sample i depends only on (seed, i), so a run with a smaller budget sees exactly the
first samples of a run with a larger one, whatever ``--workers``.

Prints a table (samples to the first candidate, samples tried, rejected share, best mean reward,
wall time and CPU time) and writes benchmarks/results/alignment_3d.json atomically after every run, with the
machine's load average before and after each run (the timings are only comparable at equal load).
``--resume`` keeps the runs already in that file that used the same settings.

    python benchmarks/alignment_3d.py [--samples 20000] [--candidates 5] [--workers 2]
                                      [--tools spade,hammer] [--only 00] [--no-real] [--resume]
                                      [--z-offset-std 0.5]

``--z-offset-std`` departs from the sampler's default vertical offset (a diagnostic: such runs are
recorded under their own key, e.g. "video_demos/hammer_video1_aligned.npz [z_offset_std=0.5]").
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import resource
import sys
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "benchmarks" / "results" / "alignment_3d.json"
SHARED = Path(os.environ.get("TOOLIMIT_SHARED", REPO.parent / "shared")) / "data" / "video_demos"
TOOL_NAMES = ("spade", "hammer", "scythe")
#: The real trajectories and the world they are aligned in (their tool comes from the file name).
REAL_FILES = ("spade_video1_aligned.npz", "spade_example_aligned.npz", "hammer_video1_aligned.npz")
#: Sources whose content decides an alignment's outcome (fingerprinted in every run's record).
OUTCOME_SOURCES = ("toolimit/align", "toolimit/scenes", "toolimit/demos", "toolimit/tools")


def code_fingerprint() -> str:
    """First 12 hex digits of the SHA-256 of the sources that decide the outcome (at start-up).

    A run is only comparable (and only resumed) with runs of the same fingerprint: the alignment
    and scene code may change between runs.
    """
    digest = hashlib.sha256()
    for source in OUTCOME_SOURCES:
        root = REPO / source
        for path in sorted([root] if root.is_file() else root.rglob("*.py")):
            digest.update(str(path.relative_to(REPO)).encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


@dataclass(frozen=True)
class DemoRun:
    """One demonstration to align: its file, tool, and whether it is cleaned first."""

    path: Path
    tool: str
    clean: bool

    @property
    def key(self) -> str:
        """Name of the run in the results file (repository-relative for shipped demos)."""
        return str(self.path.relative_to(REPO)) if self.path.is_relative_to(REPO) else f"video_demos/{self.path.name}"


def demo_runs(tools: tuple[str, ...], only: str, real: bool) -> list[DemoRun]:
    """The shipped demos (cleaned, as the CLI does), then the real trajectories (as they are)."""
    runs = [
        DemoRun(REPO / "data" / "demos" / f"{tool}_0{i}.npz", tool, clean=True) for tool in tools for i in range(5)
    ]
    if real:
        runs += [DemoRun(SHARED / name, name.split("_")[0], clean=False) for name in REAL_FILES]
    return [run for run in runs if run.tool in tools and only in run.path.name]


def run_one(run: DemoRun, args: argparse.Namespace) -> dict:
    """Align one demonstration; a JSON-ready record of the search's figures."""
    from toolimit.align.config import AlignmentConfig
    from toolimit.align.search import align
    from toolimit.demos import clean_demo, load_demo

    demo = load_demo(run.path, tool=run.tool)
    replaced = None
    if run.clean:
        demo, report = clean_demo(demo)
        replaced = len(report.replaced_frames)
    config = AlignmentConfig(samples=args.samples, candidates=args.candidates, z_offset_std=args.z_offset_std)
    load_before, cpu_before = os.getloadavg()[0], cpu_seconds()
    result = align(demo, run.tool, "3d", config, seed=args.seed, workers=args.workers, progress=not args.quiet,
                   clean=False)  # cleaned above when run.clean
    cpu_time = cpu_seconds() - cpu_before
    best = result.best
    return {
        "demo": run.key,
        "variant": variant_of(args),
        "tool": run.tool,
        "cleaned_frames_replaced": replaced,
        "settings": settings_of(args),
        "frames": result.demo.n_frames,
        "keypoints": len(result.keypoints),
        "min_element_distance_m": result.min_distance,
        "samples_to_first_candidate": result.samples_to_first_candidate,
        "samples_tried": result.samples_tried,
        "samples_rejected": result.samples_rejected,
        "rejected_share": result.samples_rejected / max(result.samples_tried, 1),
        "candidates": len(result.candidates),
        "candidate_rewards": [c.reward for c in result.candidates],
        "best_reward": None if best is None else best.reward,
        "best_index": None if best is None else best.index,
        "best_sample": None if best is None else best.sample.to_dict(),
        "wall_time_s": result.wall_time_s,
        "seconds_per_sample": result.wall_time_s / max(result.samples_tried, 1),
        "cpu_time_s": cpu_time,
        "workers": args.workers,
        "load_average_1min": [load_before, os.getloadavg()[0]],
        "rejection_reasons": dict(sorted(result.rejection_reasons.items(), key=lambda kv: -kv[1])),
    }


def cpu_seconds() -> float:
    """CPU seconds (user + system) used so far by this process and its finished worker processes.

    On a shared machine the wall time depends on the load; the CPU time much less.
    """
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def settings_of(args: argparse.Namespace) -> dict:
    """The settings that decide a run's outcome (not its speed): a resumed run must share them."""
    return {
        "samples": args.samples, "candidates": args.candidates, "seed": args.seed, "world": "3d",
        "z_offset_std": args.z_offset_std, "code": args.code_fingerprint,
    }


def variant_of(args: argparse.Namespace) -> str:
    """'' for the sampler's default settings, else a label of the departure (e.g. 'z_offset_std=0.5')."""
    from toolimit.align.config import AlignmentConfig

    default = AlignmentConfig().z_offset_std
    return "" if args.z_offset_std == default else f"z_offset_std={args.z_offset_std:g}"


def record_key(record: dict) -> str:
    """A run's key in the results file: its demo, plus its variant when the sampler was changed."""
    variant = record.get("variant", "")
    return record["demo"] + (f" [{variant}]" if variant else "")


def print_table(runs: list[dict]) -> None:
    header = (
        f"{'demo':56s} {'first':>6s} {'tried':>6s} {'cands':>5s} {'rejected':>8s} {'best':>6s} "
        f"{'time s':>7s} {'cpu s':>7s} {'load':>5s}"
    )
    print(header)
    print("-" * len(header))
    for run in runs:
        first = "-" if run["samples_to_first_candidate"] is None else str(run["samples_to_first_candidate"])
        best = "-" if run["best_reward"] is None else f"{run['best_reward']:.2f}"
        name = record_key(run)
        print(
            f"{name[-56:]:56s} {first:>6s} {run['samples_tried']:>6d} {run['candidates']:>5d} "
            f"{run['rejected_share']:>8.0%} {best:>6s} {run['wall_time_s']:>7.1f} "
            f"{run.get('cpu_time_s', float('nan')):>7.1f} {max(run['load_average_1min']):>5.1f}"
        )


def parse_arguments(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20_000, help="sample budget per demo (default: 20000)")
    parser.add_argument("--candidates", type=int, default=5, help="stop at this many candidates (default: 5)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=1, help="worker processes (results do not depend on it)")
    parser.add_argument("--tools", default=",".join(TOOL_NAMES), help="comma-separated tools (default: all)")
    parser.add_argument(
        "--z-offset-std", type=float, default=None,
        help="sampler's vertical offset std, m (default: AlignmentConfig's; the paper's videos: 0.5)",
    )
    parser.add_argument("--only", default="", help="run only demos whose file name contains this")
    parser.add_argument("--no-real", action="store_true", help="skip the real trajectories in ../shared")
    parser.add_argument("--resume", action="store_true", help="keep runs already in the results file with these settings")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    args = parser.parse_args(argv)
    args.tools = tuple(t.strip() for t in args.tools.split(",") if t.strip())
    unknown = sorted(set(args.tools) - set(TOOL_NAMES))
    if unknown:
        parser.error(f"--tools: unknown tool(s) {', '.join(unknown)}; choose among {', '.join(TOOL_NAMES)}")
    for name in ("samples", "candidates", "workers"):
        if getattr(args, name) <= 0:
            parser.error(f"--{name}: must be a positive integer, got {getattr(args, name)}")
    if args.z_offset_std is None:
        from toolimit.align.config import AlignmentConfig

        args.z_offset_std = AlignmentConfig().z_offset_std
    elif not args.z_offset_std >= 0:
        parser.error(f"--z-offset-std: must be a non-negative number, got {args.z_offset_std}")
    return args


def main(argv: list[str] | None = None) -> int:
    fingerprint = code_fingerprint()  # before importing the code it fingerprints
    args = parse_arguments(argv)
    args.code_fingerprint = fingerprint
    from toolimit.artifacts import save_json

    settings = settings_of(args)
    missing: list[str] = []
    for run in demo_runs(args.tools, args.only, real=not args.no_real):
        if not run.path.is_file():
            missing.append(str(run.path))
            print(f"missing: {run.path}", file=sys.stderr)
            continue
        key = record_key({"demo": run.key, "variant": variant_of(args)})
        if args.resume and recorded_runs().get(key, {}).get("settings") == settings:
            continue
        record = run_one(run, args)
        # Re-read just before writing: runs of other demos (possibly written meanwhile by another
        # invocation, e.g. one per tool) stay in the file; each run records its own settings.
        runs = recorded_runs()
        runs[record_key(record)] = record
        save_json(RESULTS, {"runs": list(runs.values()), "missing": missing})
    print_table(list(recorded_runs().values()))
    return 0


def recorded_runs() -> dict[str, dict]:
    """The runs in the results file by demo key (empty without a file)."""
    if not RESULTS.is_file():
        return {}
    return {record_key(run): run for run in json.loads(RESULTS.read_text()).get("runs", [])}


if __name__ == "__main__":
    sys.exit(main())
