"""``--ray``: the missing extra's error, the private Ray on the loopback only, the alignment on a
two-node loopback cluster with the local candidates, and an interrupted reproduction on Ray that
keeps its finished cells, ends every process and continues."""

from __future__ import annotations

import contextlib
import ipaddress
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from toolimit.cli import main as toolimit

REPO = Path(__file__).resolve().parents[1]
EXPERIMENT = "spade-planar-planar3-spade_03"


def test_ray_without_the_extra_is_a_one_line_error_before_any_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # what an environment without Ray gives: ImportError
    demo = str(REPO / "data/demos/spade_03.npz")
    for command in (
        ["align", "--tool", "spade", "--world", "planar", "--demo", demo],
        ["run", "--tool", "spade", "--robot", "planar3", "--world", "planar", "--demo", demo, "--quick"],
        ["reproduce", "--preset", "quick", "--demo", demo],
    ):
        out = tmp_path / command[0]
        assert toolimit([*command, "--out", str(out), "--ray"]) == 2
        error = capsys.readouterr().err.strip()
        assert error.count("\n") == 0 and 'pip install "toolimit[ray]"' in error, error
        assert not out.exists()


def _listening(pids: list[int]) -> list[tuple[str, int, str]]:
    """(address, port, process name) of every listening TCP socket of ``pids``."""
    import psutil

    sockets = []
    for pid in pids:
        try:
            process = psutil.Process(pid)
            for connection in process.net_connections(kind="inet"):
                if connection.status == psutil.CONN_LISTEN:
                    sockets.append((connection.laddr.ip, connection.laddr.port, process.name()))
        except psutil.NoSuchProcess:
            continue
    return sockets


def _is_loopback(address: str) -> bool:
    ip = ipaddress.ip_address(address)
    mapped = getattr(ip, "ipv4_mapped", None)  # '::ffff:127.0.0.1': an IPv6 socket bound to 127.0.0.1
    return (mapped or ip).is_loopback


def test_the_private_ray_listens_on_the_loopback_only_and_ends_with_the_block() -> None:
    pytest.importorskip("ray", reason='Ray is not installed (the extra: pip install -e ".[ray]")')
    import psutil
    import ray

    from toolimit.distributed import node_name, ray_cluster

    assert not ray.is_initialized()
    earlier = set(psutil.Process().children(recursive=True))  # e.g. multiprocessing's resource tracker
    with ray_cluster(True, cpus=2) as cluster:
        assert cluster.private and cluster.address.startswith("127.0.0.1:")
        nodes = ray.get([ray.remote(node_name).remote() for _ in range(2)])  # start the workers
        assert all(name.startswith("127.0.0.1/") for name in nodes)
        processes = [p for p in psutil.Process().children(recursive=True) if p not in earlier]
        sockets = _listening([os.getpid(), *(p.pid for p in processes)])
        names = {name for _, _, name in sockets}
        assert {"gcs_server", "raylet"} <= names and len(sockets) >= 4, sockets
        outside = [s for s in sockets if not _is_loopback(s[0])]
        assert not outside, f"listening outside the loopback: {outside}"
    assert not ray.is_initialized()
    psutil.wait_procs(processes, timeout=60)  # generous: that they end, not how fast
    assert not [p for p in processes if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]


def test_alignment_on_a_two_node_cluster_finds_the_local_candidates(loopback_ray_cluster: str) -> None:
    from toolimit.align.config import AlignmentConfig
    from toolimit.align.search import align
    from toolimit.demos import load_demo

    demo = load_demo(REPO / "data/demos/spade_03.npz")
    config = AlignmentConfig(samples=300, candidates=3)
    local = align(demo, "spade", "planar", config, workers=1, progress=False)
    on_ray = align(demo, "spade", "planar", config, progress=False, ray=loopback_ray_cluster)
    assert [c.index for c in on_ray.candidates] == [c.index for c in local.candidates] and local.candidates
    for here, there in zip(local.candidates, on_ray.candidates):
        np.testing.assert_allclose(there.replay_rewards, here.replay_rewards, rtol=1e-9)
    assert (on_ray.samples_tried, on_ray.rejection_reasons) == (local.samples_tried, local.rejection_reasons)


def test_an_interrupted_reproduction_on_ray_keeps_its_cells_ends_every_process_and_continues(tmp_path: Path) -> None:
    pytest.importorskip("ray", reason='Ray is not installed (the extra: pip install -e ".[ray]")')
    import psutil

    out = tmp_path / "reproduce"
    command = [sys.executable, "-m", "toolimit", "reproduce", "--preset", "quick", "--out", str(out), "--quiet"]
    command += ["--methods", "tool_only,trajopt,final", "--ray"]
    log = tmp_path / "log.txt"
    with open(log, "wb") as output:
        process = subprocess.Popen(command, cwd=REPO, stdout=output, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        prepared = out / "seed_0" / "cells" / f"{EXPERIMENT}-trajopt.json"
        deadline = time.monotonic() + 300
        while not prepared.is_file() and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        assert prepared.is_file() and process.poll() is None, log.read_text()
        time.sleep(2.0)  # the final cell's learning runs
        processes = psutil.Process(process.pid).children(recursive=True)
        assert process.poll() is None, "the final cell's learning ended before the interrupt: " + log.read_text()
        os.killpg(process.pid, signal.SIGINT)  # Ctrl-C in a terminal: the whole process group
        code = process.wait(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    said = log.read_text()
    assert code == 130, said
    assert "interrupted (SIGINT)" in said and "final: interrupted on 127.0.0.1/" in said, said
    assert {p.name for p in (out / "seed_0" / "cells").glob("*.json")} == {
        f"{EXPERIMENT}-tool_only.json",
        f"{EXPERIMENT}-trajopt.json",
    }
    psutil.wait_procs(processes, timeout=60)  # generous: that they end, not how fast
    assert not [p for p in processes if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
    # the same command continues: the preparation is done earlier, the final cell comes
    again = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stdout + again.stderr
    assert "[trajectory] done earlier" in again.stdout
    cells = json.loads((out / "results.json").read_text())["cells"]
    assert sorted(cell["method"] for cell in cells) == ["final", "tool_only", "trajopt"]


@pytest.mark.parametrize("name", ["../outside.txt", "/tmp/toolimit-absolute-never.txt", "a/../../outside.txt", "link/x.txt"])
def test_a_file_returned_by_a_task_is_written_inside_its_folder_or_refused(tmp_path: Path, name: str) -> None:
    """Names come from tasks run on other nodes: none may write outside the experiment's folder,
    and a refused set writes nothing."""
    from toolimit.distributed import write_files
    from toolimit.errors import InputError

    root, outside = tmp_path / "root", tmp_path / "elsewhere"
    root.mkdir(), outside.mkdir()
    (root / "link").symlink_to(outside)
    with pytest.raises(InputError) as error:
        write_files(root, {"fine.txt": b"1", name: b"planted"})
    assert "\n" not in str(error.value) and repr(name) in str(error.value)
    assert not (root / "fine.txt").exists() and not (tmp_path / "outside.txt").exists()
    assert not list(outside.iterdir()) and not Path("/tmp/toolimit-absolute-never.txt").exists()
    write_files(root, {"sub/fine.txt": b"1"})
    assert (root / "sub" / "fine.txt").read_bytes() == b"1"


def test_files_sent_to_a_task_stay_inside_their_folder(tmp_path: Path) -> None:
    from toolimit.distributed import read_files
    from toolimit.errors import InputError

    root, secret = tmp_path / "root", tmp_path / "secret.txt"
    (root / "method").mkdir(parents=True)
    (root / "method" / "task.npz").write_bytes(b"task")
    secret.write_text("not to be sent")
    assert read_files(root, ("method", "absent")) == {"method/task.npz": b"task"}
    (root / "method" / "leak.txt").symlink_to(secret)
    (root / "linked").symlink_to(tmp_path)
    for folders in (("method",), ("../secret.txt",), (str(secret),), ("linked",)):
        with pytest.raises(InputError, match="refused"):
            read_files(root, folders)


def _reproduce_on(address: str, out: Path) -> subprocess.Popen[str]:
    command = [sys.executable, "-m", "toolimit", "reproduce", "--preset", "quick", "--ray", address,
               "--out", str(out), "--quiet"]
    return subprocess.Popen(command, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=os.environ | {"PYTHONPATH": str(REPO)}, start_new_session=True)


def test_an_address_where_nothing_listens_ends_in_one_line(tmp_path: Path) -> None:
    """Ray retried such an address for minutes; the bound on how long is the command's figure
    (CONNECT_TIMEOUT_S + JOIN_TIMEOUT_S), the test checks that it ends with its line."""
    process = _reproduce_on("127.0.0.1:1", tmp_path / "out")
    _, err = process.communicate(timeout=600)
    assert process.returncode == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "--ray 127.0.0.1:1: no Ray cluster answers there" in lines[0], lines
    assert not (tmp_path / "out").exists()


def test_sigterm_while_joining_a_cluster_that_never_answers_ends_with_143(tmp_path: Path) -> None:
    """A loopback server that accepts connections and says nothing: Ray's join waits in its core;
    SIGTERM still ends the command as an interrupt (143, its line)."""
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    accepted: list[socket.socket] = []

    def accept() -> None:
        with contextlib.suppress(OSError):
            while True:
                accepted.append(server.accept()[0])

    threading.Thread(target=accept, daemon=True).start()
    try:
        process = _reproduce_on(f"127.0.0.1:{server.getsockname()[1]}", tmp_path / "out")
        deadline = time.monotonic() + 300
        while len(accepted) < 2 and time.monotonic() < deadline:  # toolimit's probe, then Ray's own join
            time.sleep(0.2)
        assert len(accepted) >= 2, "the command never joined the address"
        process.send_signal(signal.SIGTERM)
        _, err = process.communicate(timeout=600)
        assert process.returncode == 143, err
        assert "interrupted (SIGTERM)" in err
    finally:
        server.close()
        for connection in accepted:
            connection.close()


def test_the_ray_flag_says_how_to_authenticate(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        toolimit(["reproduce", "--help"])
    help_text = " ".join(capsys.readouterr().out.split()).replace("- ", "-")  # argparse wraps at hyphens
    assert "RAY_AUTH_MODE=token" in help_text and "ray get-auth-token --generate" in help_text
