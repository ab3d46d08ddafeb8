"""`toolimit align` stopped by real signals on a real worker pool: every process ends (within a
generous bound: how fast is not a test's figure, a busy machine may delay it), exit code 130 (SIGINT) / 143 (SIGTERM), no traceback, a true message, the checkpoint written when
samples finished. The command runs in its own session so that the signal can go to its whole
process group (what Ctrl-C, `timeout -s INT` and job controllers do) or to the main process only."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import psutil
import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads child processes from /proc")


#: How long (s) the processes may take to end after the signal before the test calls them stuck.
ENDING_BOUND_S = 60.0
#: How long (s) the command may take to start its workers (and finish samples) on a busy machine.
STARTING_BOUND_S = 300.0


def _children(pid: int) -> list[int]:
    try:
        return [int(x) for x in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []


def _running(process: psutil.Process) -> bool:
    """Whether ``process`` still runs: not ended, not a zombie, and not another process that was
    given its pid since (a busy machine reuses pids within the generous bounds of these tests)."""
    try:
        return process.is_running() and process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


@pytest.mark.parametrize(
    ("signum", "to_group", "count", "after_progress"),
    [
        (signal.SIGINT, True, 1, True),
        (signal.SIGTERM, False, 2, True),
        (signal.SIGINT, True, 2, False),
        (signal.SIGTERM, True, 1, False),
    ],
    ids=["sigint-group-once-saved", "sigterm-main-twice-saved", "sigint-group-twice-at-start", "sigterm-group-at-start"],
)
def test_an_interrupt_ends_every_process(repo_root, tmp_path, signum, to_group, count, after_progress):
    out = tmp_path / "align"
    command = [shutil.which("toolimit", path=os.path.dirname(sys.executable)) or "toolimit", "align",
               "--tool", "spade", "--world", "planar", "--demo", str(repo_root / "data/demos/spade_00.npz"),
               "--out", str(out), "--workers", "2", "--candidates", "10000"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    stderr = bytearray()
    reader = threading.Thread(target=lambda: [stderr.extend(b) for b in iter(lambda: process.stderr.read1(4096), b"")])
    reader.start()
    try:
        deadline = time.monotonic() + STARTING_BOUND_S
        while time.monotonic() < deadline and process.poll() is None:  # workers started (and samples done)
            done = re.findall(rb"samples=(\d+)/20000", bytes(stderr))
            if len(_children(process.pid)) >= 2 and (not after_progress or (done and int(done[-1]) > 0)):
                break
            time.sleep(0.02)
        processes = [psutil.Process(pid) for pid in (process.pid, *_children(process.pid))]
        assert process.poll() is None and len(processes) >= 3, bytes(stderr).decode()
        for _ in range(count):
            os.killpg(process.pid, signum) if to_group else os.kill(process.pid, signum)
            time.sleep(0.1)
        sent = time.monotonic() - 0.1 * count
        while any(_running(p) for p in processes) and time.monotonic() - sent < ENDING_BOUND_S:
            time.sleep(0.02)
        assert not [p.pid for p in processes if _running(p)], f"processes still running {ENDING_BOUND_S} s after the signal"
        code = process.wait(timeout=ENDING_BOUND_S)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        reader.join(timeout=5)
    text = bytes(stderr).decode()
    assert code == 128 + signum, text
    assert "Traceback" not in text and "Error" not in text, text
    last = text.replace("\r", "\n").strip().splitlines()[-1]
    checkpoint = out / "alignment_checkpoint.json"
    name = signal.Signals(signum).name
    if after_progress:
        tried = int(re.search(rf"interrupted \({name}\) after (\d+) samples examined", last).group(1))
        assert f"progress saved to {checkpoint}; run the same command again to resume" in last
        assert tried > 0 and json.loads(checkpoint.read_text())["samples_tried"] == tried
    else:
        assert last == f"interrupted ({name}) before any sample finished: nothing was saved"
        assert not checkpoint.exists()
