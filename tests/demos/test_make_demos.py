"""The shipped demonstrations are exactly what scripts/make_demos.py writes, and are usable."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from toolimit.demos import clean_demo, load_demo


@pytest.fixture(scope="module")
def make_demos(repo_root):
    spec = importlib.util.spec_from_file_location("make_demos", repo_root / "scripts" / "make_demos.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_regeneration_is_byte_identical(make_demos, repo_root, tmp_path):
    written = make_demos.write_demos(tmp_path)
    assert [p.name for p in written] == [f"{t}_{i:02d}.npz" for t in ("spade", "hammer", "scythe") for i in range(5)]
    for path in written:
        shipped = repo_root / "data" / "demos" / path.name
        assert shipped.is_file(), f"{shipped} missing: run python scripts/make_demos.py"
        assert path.read_bytes() == shipped.read_bytes(), f"{shipped.name} differs from a fresh regeneration"


@pytest.mark.parametrize("tool", ["spade", "hammer", "scythe"])
def test_shipped_demos_load_are_noisy_and_clean_up(repo_root, tool):
    for index in range(5):
        path = repo_root / "data" / "demos" / f"{tool}_{index:02d}.npz"
        demo = load_demo(path)
        assert demo.tool == tool and demo.fps in (24, 30) and 2.5 <= demo.duration <= 6.0
        with np.load(path) as raw:
            outliers = raw["outlier_frames"]
            clean_head = raw["clean_head"]
        assert outliers.size >= 1
        cleaned, report = clean_demo(demo)
        assert len(set(outliers.tolist()) - set(report.replaced_frames.tolist())) <= 1
        assert np.sqrt(np.mean(np.sum((cleaned.head - clean_head) ** 2, axis=1))) < 0.012
