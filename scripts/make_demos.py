"""Write the shipped synthetic demonstrations: data/demos/{spade,hammer,scythe}_{00..04}.npz.

Each file is the generator's *noisy* output (jitter and outlier frames, as a video reconstruction
gives), so that cleaning has work to do; the clean motion and the injected outliers ride along as
extra keys for checks. Same code, same numbers: rerun it and every array matches the shipped one
(integers and strings exactly, floats within ``FLOAT_TOLERANCE``; numpy does not promise the same
last bits on every CPU, e.g. with or without AVX-512, so bytes may differ in the last place).

    python scripts/make_demos.py [--out DIR]      # write the demonstrations
    python scripts/make_demos.py --check [--out DIR]   # regenerate into a temporary folder, compare with DIR
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from toolimit.demos import save_demo, synthesize_motion

TOOLS = ("spade", "hammer", "scythe")
N_PER_TOOL = 5
#: Frame rate of demo i: the paper's 24 fps, except one per tool at 30 fps (a common video rate).
FPS = (24, 24, 24, 24, 30)
DEFAULT_OUT = Path(__file__).resolve().parents[1] / "data" / "demos"
#: Largest accepted difference between a regenerated float array and the shipped one, metres (or
#: the array's own unit): a nanometre, far above last-bit noise (measured 4.8e-15 m between an AVX-512
#: and a plain x86-64 run) and far below the demonstrations' millimetre jitter.
FLOAT_TOLERANCE = 1e-9


def demo_seed(tool: str, index: int) -> int:
    """Seed of ``{tool}_{index:02d}``: 1000 x (tool's rank) + index, so tools never share a seed."""
    return 1000 * (TOOLS.index(tool) + 1) + index


def write_demos(out: Path) -> list[Path]:
    """Generate and write all demonstrations to ``out``; returns the written paths."""
    written = []
    for tool in TOOLS:
        for index in range(N_PER_TOOL):
            motion = synthesize_motion(tool, demo_seed(tool, index), fps=FPS[index])
            events = {f"event_{name}": np.asarray(frames, dtype=np.int64) for name, frames in motion.events.items()}
            path = out / f"{tool}_{index:02d}.npz"
            save_demo(
                motion.noisy,
                path,
                clean_head=motion.clean.head,
                clean_handle=motion.clean.handle,
                outlier_frames=motion.outlier_frames.astype(np.int64),
                jitter=np.float64(motion.jitter),
                **events,
            )
            written.append(path)
    return written


def demo_names() -> list[str]:
    """File names of the shipped demonstrations, in the order ``write_demos`` writes them."""
    return [f"{tool}_{index:02d}.npz" for tool in TOOLS for index in range(N_PER_TOOL)]


def differences(fresh: Path, shipped: Path, atol: float = FLOAT_TOLERANCE) -> list[str]:
    """How ``shipped`` differs from ``fresh`` (same file name), one line per differing array; empty if none.

    Keys, dtypes and shapes must match; integer, boolean and string arrays exactly; float arrays
    within ``atol`` (absolute).
    """
    if not shipped.is_file():
        return [f"{shipped} missing: run python scripts/make_demos.py"]
    found = []
    with np.load(fresh) as new, np.load(shipped) as old:
        if sorted(new.files) != sorted(old.files):
            return [f"{shipped.name}: keys {sorted(old.files)}, regeneration gives {sorted(new.files)}"]
        for key in new.files:
            a, b = new[key], old[key]
            if a.dtype != b.dtype or a.shape != b.shape:
                found.append(f"{shipped.name}[{key}]: {b.dtype}{b.shape}, regeneration gives {a.dtype}{a.shape}")
            elif a.dtype.kind == "f":
                gap = float(np.max(np.abs(a - b), initial=0.0))
                if not gap <= atol:  # also catches NaN
                    found.append(f"{shipped.name}[{key}]: differs by up to {gap:.3g} (tolerance {atol:g})")
            elif not np.array_equal(a, b):
                found.append(f"{shipped.name}[{key}]: differs from a fresh regeneration")
    return found


def check(shipped_dir: Path) -> list[str]:
    """Regenerate every demonstration into a temporary folder; how ``shipped_dir`` differs (empty if not)."""
    with tempfile.TemporaryDirectory() as tmp:
        written = write_demos(Path(tmp))
        assert [p.name for p in written] == demo_names()
        return [line for path in written for line in differences(path, shipped_dir / path.name)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"output folder (default {DEFAULT_OUT})")
    parser.add_argument("--check", action="store_true", help="write nothing: compare a regeneration with --out")
    args = parser.parse_args(argv)
    if args.check:
        found = check(args.out)
        for line in found:
            print(line, file=sys.stderr)
        if found:
            return 1
        print(f"all {len(demo_names())} files in {args.out} match a regeneration (floats within {FLOAT_TOLERANCE:g})")
        return 0
    for path in write_demos(args.out):
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
