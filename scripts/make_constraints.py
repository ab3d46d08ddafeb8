"""Write constraints.txt: the exact version of every distribution toolimit and its extras pull in,
as installed in the running environment (CI's versions; the README's figures were measured with them).

pyproject.toml gives ranges (what toolimit works with, for projects that import it); this file pins
the one set CI tests, for the README's Quick start (``pip install -c constraints.txt ...``). It walks
the requirements of pyproject.toml's dependencies and of the extras the Quick start installs through
the installed distributions' metadata, so that tools installed beside toolimit (documentation
builders, ...) stay out.

    python scripts/make_constraints.py [--extras test,compare,ray,video] [--out constraints.txt]
"""

from __future__ import annotations

import argparse
import importlib.metadata as metadata
import re
from pathlib import Path

import tomllib
from packaging.requirements import Requirement

REPO = Path(__file__).resolve().parents[1]


def _name(text: str) -> str:
    """A distribution's normalised name (PEP 503)."""
    return re.sub(r"[-_.]+", "-", text).lower()


def pinned_closure(requirements: list[Requirement]) -> dict[str, str]:
    """{name: installed version} of ``requirements`` and everything they require, with their extras,
    for this platform's markers."""
    versions: dict[str, str] = {}
    todo = [(requirement, frozenset(requirement.extras)) for requirement in requirements]
    seen: set[tuple[str, frozenset[str]]] = set()
    while todo:
        requirement, extras = todo.pop()
        key = (_name(requirement.name), extras)
        if key in seen:
            continue
        seen.add(key)
        try:
            distribution = metadata.distribution(requirement.name)
        except metadata.PackageNotFoundError:
            raise SystemExit(f"{requirement.name} is not installed: install every extra first") from None
        versions[key[0]] = distribution.version
        for text in distribution.requires or []:
            child = Requirement(text)
            if child.marker is None or any(child.marker.evaluate({"extra": extra}) for extra in extras or {""}):
                todo.append((child, frozenset(child.extras)))
    return versions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "constraints.txt")
    parser.add_argument("--extras", default="test,compare,ray,video", help="the extras CI installs (comma-separated)")
    args = parser.parse_args()
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    texts = [*project["dependencies"], *(text for name in args.extras.split(",") for text in extras[name])]
    versions = pinned_closure([Requirement(text) for text in texts])
    # a local label (torch's "+cpu") names the wheel's index, not the release: pins match any
    lines = [f"{name}=={version.split('+')[0]}" for name, version in sorted(versions.items())]
    header = "# Exact versions CI tests (scripts/make_constraints.py); pyproject.toml holds the ranges.\n"
    args.out.write_text(header + "\n".join(lines) + "\n")
    print(f"wrote {args.out}: {len(lines)} distributions")


if __name__ == "__main__":
    main()
