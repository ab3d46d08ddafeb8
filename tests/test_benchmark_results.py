"""benchmarks/ can be trusted at a glance: every script listed, every result naming its commit.

``benchmarks/README.md`` names every script of ``benchmarks/``; ``benchmarks/results/`` holds results
only (no experiment patch, ``*.diff`` or ``*.txt``: git keeps those, docs/history.md says where), and
every results JSON that is an object records the commit it was made with (``commit``; with a
``commit_note`` when that is only the commit that wrote the file).
"""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BENCHMARKS = REPO / "benchmarks"
RESULTS = BENCHMARKS / "results"


def test_the_benchmarks_readme_names_every_script():
    listed = (BENCHMARKS / "README.md").read_text(encoding="utf-8")
    missing = [path.name for path in sorted(BENCHMARKS.glob("*.py")) if f"`{path.name}`" not in listed]
    assert not missing, f"benchmarks/README.md does not list: {missing}"


def test_results_hold_no_experiment_patches():
    patches = [str(path.relative_to(REPO)) for path in RESULTS.rglob("*") if path.suffix in (".diff", ".patch", ".txt")]
    assert not patches, f"experiment patches are not results (git keeps them; say where in docs/history.md): {patches}"


def test_every_results_json_names_its_commit():
    known = set(
        subprocess.run(
            ["git", "rev-list", "--all", "--abbrev-commit"], cwd=REPO, capture_output=True, text=True
        ).stdout.split()
    )
    problems = []
    for path in sorted(RESULTS.rglob("*.json")):
        record = json.loads(path.read_text(encoding="utf-8"))
        name = str(path.relative_to(REPO))
        if not isinstance(record, dict) or "commit" not in record:
            problems.append(f"{name}: no commit")
            continue
        commits = re.findall(r"\b[0-9a-f]{7,40}\b", str(record["commit"]))
        if record["commit"] != "per run" and not commits:
            problems.append(f"{name}: commit {record['commit']!r} is not a commit hash")
        if known:
            problems += [
                f"{name}: commit {c} is not in this repository"
                for c in commits
                if not any(k.startswith(c) or c.startswith(k) for k in known)
            ]
    assert not problems, "\n".join(problems)
