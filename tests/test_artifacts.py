import os
import stat

import numpy as np
import pytest

from toolimit.artifacts import atomic_path, load_npz, save_json, save_npz
from toolimit.cli import main as toolimit
from toolimit.errors import DemoError, InputError


def test_failed_write_leaves_nothing(tmp_path):
    target = tmp_path / "out.json"
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
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


def test_load_npz_reads_back_what_save_npz_wrote(tmp_path):
    save_npz(tmp_path / "a.npz", x=np.arange(3), name=np.array("spade"))
    arrays = load_npz(tmp_path / "a.npz")
    assert sorted(arrays) == ["name", "x"] and np.array_equal(arrays["x"], np.arange(3))
    assert str(arrays["name"]) == "spade"


def _corrupted(path):
    save_npz(path, x=np.arange(1000.0))
    data = bytearray(path.read_bytes())
    data[3000:3010] = b"0123456789"  # inside x's bytes: the archive opens, its checksum fails
    path.write_bytes(bytes(data))


@pytest.mark.parametrize(
    ("make", "said"),
    [
        (lambda path: path.write_text("not a zip"), "cannot read as .npz (not a zip archive)"),
        (_corrupted, "cannot read as .npz (Bad CRC-32 for file 'x.npy')"),
        (lambda path: np.savez(path, x=np.array([{"a": 1}], dtype=object)), "cannot read as .npz (unreadable array"),
    ],
    ids=["not-a-zip", "corrupted", "pickled-objects"],
)
def test_load_npz_names_the_file_it_cannot_read(tmp_path, make, said):
    path = tmp_path / "broken.npz"
    make(path)
    with pytest.raises(InputError) as refused:
        load_npz(path)
    assert str(refused.value).startswith(f"{path}: {said}") and "\n" not in str(refused.value)


def test_load_npz_raises_the_callers_kind_and_says_what_the_file_should_be(tmp_path):
    (tmp_path / "junk.npz").write_text("not a zip")
    with pytest.raises(DemoError, match="junk.npz: not a demonstration \\(not a zip archive\\)$"):
        load_npz(tmp_path / "junk.npz", DemoError, what="demonstration")
    with pytest.raises(FileNotFoundError, match="absent.npz: no such file"):
        load_npz(tmp_path / "absent.npz")


@pytest.mark.parametrize("command", ["export", "trajopt"])
def test_a_corrupt_input_file_is_one_line_and_exit_2(tmp_path, capsys, command):
    (tmp_path / "trajectory.npz").write_text("not a zip")
    argv = {
        "export": ["export", "--trajectory", str(tmp_path), "--robot", "panda", "--out", str(tmp_path / "out")],
        "trajopt": ["trajopt", "--robot", "panda", "--tool", "spade", "--poses", str(tmp_path / "trajectory.npz"),
                    "--out", str(tmp_path / "out")],
    }[command]
    assert toolimit(argv) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert error == [f"toolimit {command}: error: {tmp_path / 'trajectory.npz'}: cannot read as .npz (not a zip archive)"]
    assert not (tmp_path / "out").exists()


def test_load_npz_names_the_required_keys_a_file_lacks(tmp_path):
    save_npz(tmp_path / "a.npz", q=np.zeros(3))
    assert sorted(load_npz(tmp_path / "a.npz", required=("q",))) == ["q"]
    with pytest.raises(DemoError, match=r"a.npz: missing keys \['v', 'dt'\]$"):
        load_npz(tmp_path / "a.npz", DemoError, required=("q", "v", "dt"))
