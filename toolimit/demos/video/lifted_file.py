"""The lifted demonstration's file: a project ``.npz`` demonstration plus the lift's per-frame record.

Beside ``head``, ``handle``, ``fps``, ``tool``, ``source`` (any loader of demonstrations reads it),
the file holds, per frame: ``head_sigma``, ``handle_sigma`` (metres, 1 sigma, the side taken as
right), ``head_filled``, ``handle_filled`` (bool, interpolated frames), ``handle_far`` (bool),
``side_source`` (str: hint, crossing or negligible), ``side_margin`` (squared standard deviations)
and ``mirror_distance`` (metres): see :class:`~toolimit.demos.video.lift.LiftedDemo`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from toolimit.artifacts import load_npz
from toolimit.demos.npz_format import load_demo, save_demo
from toolimit.demos.tool_demo import ToolDemo
from toolimit.demos.video.lift import SIDE_SOURCES, LiftedDemo
from toolimit.errors import DemoError

#: The per-frame arrays of the lifted file, in the order written.
PER_FRAME = (
    "head_sigma",
    "handle_sigma",
    "head_filled",
    "handle_filled",
    "handle_far",
    "side_source",
    "side_margin",
    "mirror_distance",
)


@dataclass(frozen=True, eq=False)
class LiftedRecord:
    """A lifted file as read: the demonstration and its per-frame arrays (``PER_FRAME``, (T,) each)."""

    demo: ToolDemo
    arrays: dict[str, np.ndarray]

    def side_summary(self) -> str:
        """One line: where the handle's sides came from and what a wrong side would cost."""
        return side_summary(self.arrays["side_source"], self.arrays["side_margin"], self.arrays["mirror_distance"])


def side_summary(source: np.ndarray, margin: np.ndarray, mirror_distance: np.ndarray) -> str:
    """One line from the per-frame side record (see :class:`LiftedDemo`)."""
    counts = {name: int(np.sum(source == name)) for name in SIDE_SOURCES}
    parts = [f"{counts['hint']} frames from the hint"]
    if counts["crossing"]:
        crossed = margin[source == "crossing"]
        parts.append(
            f"{counts['crossing']} left it at a zero crossing of the depth offset "
            f"(evidence {np.min(crossed):.0f} to {np.max(crossed):.0f} squared standard deviations)"
        )
    else:
        parts.append("0 left it")
    if counts["negligible"]:
        parts.append(f"{counts['negligible']} where the two sides are within 1 cm")
    return (
        f"handle sides: {', '.join(parts)}; a frame on the wrong side would put the handle end "
        f"{100 * np.median(mirror_distance):.0f} cm off (median; up to {100 * np.max(mirror_distance):.0f} cm)"
    )


def write_lifted(lifted: LiftedDemo, demo: ToolDemo, path: str | os.PathLike[str]) -> None:
    """Write ``demo`` (the lift's demonstration, its source set by the caller) and ``lifted``'s
    per-frame record to ``path``, atomically."""
    save_demo(demo, path, **{name: getattr(lifted, name) for name in PER_FRAME})


def read_lifted(path: str | os.PathLike[str]) -> LiftedRecord:
    """The lifted file at ``path``; DemoError naming the file and the missing or malformed key."""
    path = Path(path)
    demo = load_demo(path)
    stored = load_npz(path, DemoError)
    arrays = {}
    for name in PER_FRAME:
        if name not in stored:
            raise DemoError(f"{path}: missing key {name!r}: not a file written by `toolimit demo lift`")
        if stored[name].shape != (demo.n_frames,):
            raise DemoError(f"{path}: key {name!r} must have shape ({demo.n_frames},), got {stored[name].shape}")
        arrays[name] = stored[name]
    unknown = sorted(set(arrays["side_source"].tolist()) - set(SIDE_SOURCES))
    if unknown:
        raise DemoError(f"{path}: key 'side_source' holds {unknown}; expected {', '.join(SIDE_SOURCES)}")
    return LiftedRecord(demo, arrays)
