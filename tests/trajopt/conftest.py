"""Robots shared by the trajopt tests (built once per session)."""

from __future__ import annotations

import pytest

from toolimit.robots import make_robot


@pytest.fixture(scope="session")
def planar3():
    return make_robot("planar3")


@pytest.fixture(scope="session")
def panda():
    return make_robot("panda")
