"""The shipped demonstrations are what scripts/make_demos.py writes (on any x86-64 CPU), and are usable."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from toolimit.demos import clean_demo, load_demo


@pytest.fixture(scope="module")
def make_demos(repo_root):
    spec = importlib.util.spec_from_file_location("make_demos", repo_root / "scripts" / "make_demos.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


#: numpy's dispatch without AVX-512: the other code path an x86-64 CI machine may take. numpy reads
#: the variable when it is imported, hence a fresh interpreter per setting.
NO_AVX512 = "AVX512_ICL AVX512_SKX X86_V4"


@pytest.mark.parametrize("disabled", [None, NO_AVX512], ids=["native", "no-avx512"])
def test_regeneration_matches_the_shipped_files(repo_root, disabled):
    env = {k: v for k, v in os.environ.items() if k != "NPY_DISABLE_CPU_FEATURES"}
    if disabled is not None:
        env["NPY_DISABLE_CPU_FEATURES"] = disabled
    run = subprocess.run(
        [sys.executable, str(repo_root / "scripts" / "make_demos.py"), "--check"],
        check=False,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    assert "all 15 files" in run.stdout
    features = subprocess.run(
        [sys.executable, "-c", "import numpy; print(numpy._core._multiarray_umath.__cpu_features__['AVX512_SKX'])"],
        check=False,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    if disabled is not None:
        assert features.stdout.strip() == "False", "NPY_DISABLE_CPU_FEATURES did not reach numpy"


def test_check_reports_a_changed_float_and_a_changed_integer(make_demos, repo_root, tmp_path):
    shipped = repo_root / "data" / "demos"
    fresh, edited = tmp_path / "fresh", tmp_path / "edited"
    fresh.mkdir(), edited.mkdir()
    name = "spade_00.npz"
    shutil.copy(shipped / name, fresh / name)
    with np.load(shipped / name) as data:
        arrays = {key: data[key] for key in data.files}
    assert make_demos.differences(fresh / name, shipped / name) == []
    arrays["head"] = arrays["head"] + 1e-12  # last-bit noise: accepted
    np.savez(edited / name, **arrays)
    assert make_demos.differences(fresh / name, edited / name) == []
    arrays["head"][3, 2] += 1e-6
    arrays["outlier_frames"] = arrays["outlier_frames"] + 1
    np.savez(edited / name, **arrays)
    found = make_demos.differences(fresh / name, edited / name)
    assert len(found) == 2 and "[head]: differs by up to 1e-06" in found[0] and "[outlier_frames]" in found[1]


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
