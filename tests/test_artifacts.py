import os
import stat

import numpy as np
import pytest

from toolimit.artifacts import atomic_path, save_json, save_npz


def test_failed_write_leaves_nothing(tmp_path):
    target = tmp_path / "out.json"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_written_files_have_the_usual_mode(tmp_path):
    save_json(tmp_path / "a.json", {"x": np.arange(3), "y": np.float64(1.5)})
    save_npz(tmp_path / "a.npz", x=np.arange(3))
    mask = os.umask(0)
    os.umask(mask)
    for name in ("a.json", "a.npz"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o666 & ~mask
    assert np.array_equal(np.load(tmp_path / "a.npz")["x"], np.arange(3))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "a.npz"]
