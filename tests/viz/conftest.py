"""Helpers for the view tests: no meshcat server may start, and static pages can be decoded."""

from __future__ import annotations

import base64
import gzip
import os
import re
from collections.abc import Callable
from pathlib import Path

import meshcat
import pytest
import umsgpack

_COMMANDS = re.compile(r"run\(\[(.*?)\]\);", re.S)
_PAYLOAD = re.compile(r'"([A-Za-z0-9+/=]+)"')


def decode_html_commands(path: Path) -> list[dict]:
    """The meshcat commands (set_object, set_transform, set_animation, ...) of a static page, in
    the order the page runs them (each is gzip-compressed msgpack in base64)."""
    text = path.read_text(encoding="utf-8")
    block = _COMMANDS.search(text)
    assert block is not None, f"{path}: no command list"
    return [umsgpack.unpackb(gzip.decompress(base64.b64decode(p))) for p in _PAYLOAD.findall(block.group(1))]


@pytest.fixture
def html_commands() -> Callable[[Path], list[dict]]:
    return decode_html_commands


@pytest.fixture(autouse=True)
def no_meshcat_server(monkeypatch):
    """Fail loudly if anything tries to start meshcat's zmq server process."""

    def refuse(*args, **kwargs):
        raise AssertionError("a meshcat server process was started")

    monkeypatch.setattr(meshcat.visualizer, "start_zmq_server_as_subprocess", refuse)
    yield
    assert not _meshcat_server_children(), "a meshcat server process lingers"


def _meshcat_server_children() -> list[int]:
    """PIDs of this process's children running meshcat's zmq server (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmdline = (entry / "cmdline").read_bytes().decode(errors="replace")
        except OSError:
            continue
        parent = int(stat.rsplit(")", 1)[1].split()[1])
        if parent == os.getpid() and "meshcat.servers.zmqserver" in cmdline:
            found.append(int(entry.name))
    return found
