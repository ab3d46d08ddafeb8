"""Helpers for the view tests: decode the meshcat commands embedded in a static HTML page."""

from __future__ import annotations

import base64
import re
from pathlib import Path
from typing import Callable

import pytest
import umsgpack

_PAYLOAD = re.compile(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)")


def decode_html_commands(path: Path) -> list[dict]:
    """The meshcat commands (set_object, set_transform, set_animation, ...) of a static page."""
    text = path.read_text(encoding="utf-8")
    return [umsgpack.unpackb(base64.b64decode(payload)) for payload in _PAYLOAD.findall(text)]


@pytest.fixture
def html_commands() -> Callable[[Path], list[dict]]:
    return decode_html_commands
