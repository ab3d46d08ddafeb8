"""Write the shipped synthetic demonstrations: data/demos/{spade,hammer,scythe}_{00..04}.npz.

Each file is the generator's *noisy* output (jitter and outlier frames, as a video reconstruction
gives), so that cleaning has work to do; the clean motion and the injected outliers ride along as
extra keys for checks. Same code, same bytes: rerun it and ``git diff`` shows nothing.

    python scripts/make_demos.py [--out DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from toolimit.demos import save_demo, synthesize_motion

TOOLS = ("spade", "hammer", "scythe")
N_PER_TOOL = 5
#: Frame rate of demo i: the paper's 24 fps, except one per tool at 30 fps (a common video rate).
FPS = (24, 24, 24, 24, 30)
DEFAULT_OUT = Path(__file__).resolve().parents[1] / "data" / "demos"


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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"output folder (default {DEFAULT_OUT})")
    args = parser.parse_args(argv)
    for path in write_demos(args.out):
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
