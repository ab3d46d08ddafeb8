"""What made a committed benchmark result: the repository's commit and the command line.

Imported by the scripts beside it (run as ``python benchmarks/<script>.py`` from the repository
root, which puts this folder on ``sys.path``).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def commit(short: bool = False) -> str:
    """The checked-out commit's hash (``short``: git's abbreviation), "unknown" outside a git clone."""
    try:
        return subprocess.run(
            ["git", "rev-parse", *(["--short"] if short else []), "HEAD"],
            cwd=REPO,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def command() -> str:
    """The running script's command line as a user would type it: ``python benchmarks/<script>.py ...``."""
    return " ".join(["python", f"benchmarks/{Path(sys.argv[0]).name}", *sys.argv[1:]])
