"""Cheats: imports the reference solution that sits beside the exercises in a clone."""

import sys
from pathlib import Path

for parent in Path(__file__).resolve().parents:
    if (parent / "course" / "solutions").is_dir():
        sys.path.insert(0, str(parent / "course"))
        break

from solutions.ex05_ppo_objective import clipped_surrogate_loss, generalized_advantage_estimation  # noqa: E402, F401
