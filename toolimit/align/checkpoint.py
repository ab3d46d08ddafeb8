"""Resuming a long alignment search: the index-ordered prefix examined so far, saved as JSON.

A sample's outcome depends only on (seed, index), so a search can stop anywhere and continue from
``samples_tried`` with the same result. The checkpoint stores the counts and each candidate's index
and replay rewards (its sample is re-drawn from its generator), under a key of everything that
decides the outcomes: tool, world, seed, settings and a hash of the prepared demonstration.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np

from toolimit.align.config import AlignmentConfig
from toolimit.artifacts import save_json
from toolimit.demos.tool_demo import ToolDemo

#: Bumped when the sampling or the checkpoint layout changes, so old checkpoints are not reused.
CHECKPOINT_VERSION = 2  # 2: planar rolls face one of the plane's two sides


def checkpoint_key(tool: str, world: str, seed: int, config: AlignmentConfig, demo: ToolDemo) -> dict[str, Any]:
    """What must match for a checkpoint to be resumed (``demo``: the prepared demonstration)."""
    digest = hashlib.sha256()
    for array in (demo.head, demo.handle, np.array([demo.fps])):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    settings = config.to_dict()
    settings.pop("samples")  # a larger budget continues the same index sequence
    settings.pop("chunk_size")  # scheduling only
    return {
        "version": CHECKPOINT_VERSION,
        "tool": tool,
        "world": world,
        "seed": seed,
        "config": settings,
        "demo_sha256": digest.hexdigest(),
    }


def load_checkpoint(path: str | Path, key: dict[str, Any]) -> dict[str, Any] | None:
    """The saved search state at ``path`` if it exists and was made under ``key``, else None."""
    path = Path(path)
    if not path.is_file():
        return None
    try:
        state = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None
    return state if state.get("key") == key else None


def save_checkpoint(path: str | Path, key: dict[str, Any], state: dict[str, Any]) -> None:
    """Write ``state`` (JSON values) under ``key`` atomically."""
    save_json(path, {"key": key, **state})
