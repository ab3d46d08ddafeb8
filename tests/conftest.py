"""Shared fixtures: the real video demonstrations in ../shared (skipped where absent)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
VIDEO_DEMOS = Path(os.environ.get("TOOLIMIT_SHARED", REPO_ROOT.parent / "shared")) / "data" / "video_demos"


@pytest.fixture(scope="session")
def video_demos_dir() -> Path:
    """The folder of the paper authors' real trajectories; skip the test when it is absent."""
    if not (VIDEO_DEMOS / "spade_video1_aligned.npz").is_file():
        pytest.skip(
            f"real video demonstrations not found at {VIDEO_DEMOS} "
            "(they live in ../shared beside the checkout; set TOOLIMIT_SHARED to point elsewhere)"
        )
    return VIDEO_DEMOS


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO_ROOT
