"""Shared fixtures: the real video demonstrations in ../shared (skipped where absent), a loopback
Ray cluster (skipped where Ray is absent)."""

from __future__ import annotations

import os
from collections.abc import Iterator
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


@pytest.fixture(scope="module")
def loopback_ray_cluster() -> Iterator[str]:
    """The address of a Ray cluster of two nodes of one CPU each, on 127.0.0.1 only, for one test
    module (this process does not join it: a test passes the address, as ``--ray ADDRESS`` does);
    skip where Ray is absent. One per module, not per session: a cluster shared from
    tests/experiments through tests/test_distributed.py's private-Ray test failed the alignment
    test that followed (its actors "cancelled before they started"), a fresh one did not (see the
    docs/ray.md#on-a-ray-cluster)."""
    pytest.importorskip("ray", reason='Ray is not installed (the extra: pip install -e ".[ray]")')
    from ray.cluster_utils import Cluster

    from toolimit.distributed import loopback_environment

    with loopback_environment():
        cluster = Cluster(
            initialize_head=True, connect=False, head_node_args={"num_cpus": 1, "include_dashboard": False}
        )
        cluster.add_node(num_cpus=1)
    yield cluster.address
    cluster.shutdown()
