"""Fixtures of the learning tests: the shipped planar spade task (the cheapest real task)."""

from __future__ import annotations

import pytest

from toolimit.learn import LearningTask, shipped_task


@pytest.fixture(scope="session")
def spade_task() -> LearningTask:
    """The shipped planar spade task of the planar 3-link arm."""
    return shipped_task("spade", "planar")
